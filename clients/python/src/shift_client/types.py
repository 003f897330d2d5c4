"""Typed forms of SHIFT's wire documents (DESIGN §5.1, §5.3, §5.4).

The contract is the Rust crate ``shift-proto`` (``proto/src/plan.rs``, ``api.rs``, ``correction.rs``,
``mission.rs``, ``listing.rs``); these
dataclasses mirror its field names. Parsing ignores fields it does not know, so a newer daemon that adds
optional fields keeps working. Positions are metres in the map frame, speeds m/s, accelerations m/s², times
seconds from the plan's start unless a name says otherwise (``*_ms``: milliseconds since the Unix epoch).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Dict, List, Literal, Mapping, Optional, Sequence, Tuple

Point2 = Tuple[float, float]

PlanStatus = Literal["queued", "planning", "ready", "active", "done", "failed", "cancelled"]
"""Lifecycle of a plan."""

FINAL_STATUSES: Tuple[str, ...] = ("ready", "active", "done", "failed", "cancelled")
"""Statuses after which nothing changes the plan's computation any more (``PlanStatus::is_final``)."""

STREAM_END_STATUSES: Tuple[str, ...] = ("done", "failed", "cancelled")
"""Statuses after which the daemon ends a plan's event stream."""

MissionStatus = Literal["queued", "planning", "ready", "active", "done", "failed", "cancelled"]
"""Lifecycle of a mission."""

MISSION_SETTLED_STATUSES: Tuple[str, ...] = ("done", "failed", "cancelled")
"""Statuses after which nothing changes a mission any more (``MissionStatus::is_settled``); its event stream
ends after one."""


def _points(raw: Optional[Sequence[Sequence[float]]]) -> List[Point2]:
    return [(float(p[0]), float(p[1])) for p in (raw or [])]


def _opt_float(raw: Any) -> Optional[float]:
    return None if raw is None else float(raw)


@dataclass(frozen=True)
class Waypoint:
    """One waypoint of a plan: position (m, map frame), speed ``v`` (m/s) and time ``t`` (s from the start)."""

    x: float
    y: float
    z: float
    v: float
    t: float
    kind: str
    """``cover`` (sweeping) or ``transit`` (moving between regions)."""
    region: Optional[int] = None
    """Region being covered (cover waypoints)."""

    @classmethod
    def from_json(cls, d: Mapping[str, Any]) -> "Waypoint":
        region = d.get("region")
        return cls(
            x=float(d["x"]),
            y=float(d["y"]),
            z=float(d.get("z", 0.0)),
            v=float(d["v"]),
            t=float(d["t"]),
            kind=str(d["kind"]),
            region=None if region is None else int(region),
        )

    def to_json(self) -> Dict[str, Any]:
        out: Dict[str, Any] = {"x": self.x, "y": self.y, "z": self.z, "v": self.v, "t": self.t, "kind": self.kind}
        if self.region is not None:
            out["region"] = self.region
        return out


@dataclass(frozen=True)
class Region:
    """A region of the plan: id and outer contour (m, map frame)."""

    id: int
    polygon: List[Point2]

    @classmethod
    def from_json(cls, d: Mapping[str, Any]) -> "Region":
        return cls(id=int(d["id"]), polygon=_points(d.get("polygon")))

    def to_json(self) -> Dict[str, Any]:
        return {"id": self.id, "polygon": [[x, y] for x, y in self.polygon]}


@dataclass(frozen=True)
class PlanMetrics:
    """Figures of merit of a plan (DESIGN §6)."""

    coverage_pct: float
    overlap_pct: float
    length_m: float
    turns: int
    collisions: int
    duration_s: float
    compute_ms: float
    dwell_cv: Optional[float] = None
    dwell_cv_const_speed: Optional[float] = None

    @classmethod
    def from_json(cls, d: Mapping[str, Any]) -> "PlanMetrics":
        return cls(
            coverage_pct=float(d["coverage_pct"]),
            overlap_pct=float(d["overlap_pct"]),
            length_m=float(d["length_m"]),
            turns=int(d["turns"]),
            collisions=int(d.get("collisions", 0)),
            duration_s=float(d["duration_s"]),
            compute_ms=float(d["compute_ms"]),
            dwell_cv=_opt_float(d.get("dwell_cv")),
            dwell_cv_const_speed=_opt_float(d.get("dwell_cv_const_speed")),
        )

    def to_json(self) -> Dict[str, Any]:
        out: Dict[str, Any] = {
            "coverage_pct": self.coverage_pct,
            "overlap_pct": self.overlap_pct,
            "length_m": self.length_m,
            "turns": self.turns,
            "collisions": self.collisions,
            "duration_s": self.duration_s,
            "compute_ms": self.compute_ms,
        }
        if self.dwell_cv is not None:
            out["dwell_cv"] = self.dwell_cv
        if self.dwell_cv_const_speed is not None:
            out["dwell_cv_const_speed"] = self.dwell_cv_const_speed
        return out


@dataclass(frozen=True)
class PlanDocument:
    """The plan JSON of DESIGN §5.1 (``GET /v1/plans/{id}/path`` and the Zenoh plan key)."""

    plan_id: str
    version: int
    """Incremented by every correction (1 as computed)."""
    frame: str
    waypoints: List[Waypoint]
    """The path: straight segments between consecutive waypoints."""
    regions: List[Region]
    metrics: Optional[PlanMetrics]

    @classmethod
    def from_json(cls, d: Mapping[str, Any]) -> "PlanDocument":
        metrics = d.get("metrics")
        return cls(
            plan_id=str(d["plan_id"]),
            version=int(d["version"]),
            frame=str(d.get("frame", "map")),
            waypoints=[Waypoint.from_json(w) for w in d.get("waypoints", [])],
            regions=[Region.from_json(r) for r in d.get("regions", [])],
            metrics=None if metrics is None else PlanMetrics.from_json(metrics),
        )

    def to_json(self) -> Dict[str, Any]:
        """The wire form (DESIGN §5.1)."""
        return {
            "plan_id": self.plan_id,
            "version": self.version,
            "frame": self.frame,
            "waypoints": [w.to_json() for w in self.waypoints],
            "regions": [r.to_json() for r in self.regions],
            "metrics": None if self.metrics is None else self.metrics.to_json(),
        }

    @property
    def path(self) -> List[Point2]:
        """The waypoints' ``(x, y)``, metres, map frame."""
        return [(w.x, w.y) for w in self.waypoints]


@dataclass(frozen=True)
class Correction:
    """A correction (DESIGN §5.4 ``…/corrections``): replace ``waypoints[from_:to)`` of ``base_version`` with
    ``waypoints``, giving ``version`` = ``base_version + 1``; later waypoints' ``t`` move by ``dt_after_s``."""

    plan_id: str
    robot: str
    base_version: int
    version: int
    from_: int
    """First replaced index (``from`` on the wire)."""
    to: int
    """One past the last replaced index."""
    waypoints: List[Waypoint]
    reason: str
    """``obstacle``, ``detour`` or ``skipped``."""
    compute_us: int
    dt_after_s: float = 0.0
    skipped: List[Point2] = field(default_factory=list)
    """For ``skipped``: the left-out stretch of the old path."""

    @classmethod
    def from_json(cls, d: Mapping[str, Any]) -> "Correction":
        return cls(
            plan_id=str(d["plan_id"]),
            robot=str(d.get("robot", "")),
            base_version=int(d["base_version"]),
            version=int(d["version"]),
            from_=int(d["from"]),
            to=int(d["to"]),
            waypoints=[Waypoint.from_json(w) for w in d.get("waypoints", [])],
            reason=str(d["reason"]),
            compute_us=int(d.get("compute_us", 0)),
            dt_after_s=float(d.get("dt_after_s", 0.0)),
            skipped=_points(d.get("skipped")),
        )

    def apply(self, doc: PlanDocument) -> PlanDocument:
        """``doc`` with this correction applied (the rule of ``proto/src/correction.rs``).

        Raises :class:`VersionGap` when ``doc`` is not at ``base_version`` (a robot then fetches the plan), and
        :class:`CorrectionError` for another plan, a version that does not follow the base, or a range outside
        the document.
        """
        if doc.plan_id != self.plan_id:
            raise CorrectionError(f"correction for plan {self.plan_id} applied to plan {doc.plan_id}")
        if doc.version != self.base_version:
            raise VersionGap(self.base_version, doc.version)
        if self.version != self.base_version + 1:
            raise CorrectionError(f"correction version {self.version} does not follow base version {self.base_version}")
        n = len(doc.waypoints)
        if not 0 <= self.from_ <= self.to <= n:
            raise CorrectionError(f"correction range {self.from_}..{self.to} outside a path of {n} waypoints")
        shifted = [
            Waypoint(w.x, w.y, w.z, w.v, w.t + self.dt_after_s, w.kind, w.region) for w in doc.waypoints[self.to :]
        ]
        return PlanDocument(
            plan_id=doc.plan_id,
            version=self.version,
            frame=doc.frame,
            waypoints=list(doc.waypoints[: self.from_]) + list(self.waypoints) + shifted,
            regions=doc.regions,
            metrics=doc.metrics,
        )


class CorrectionError(ValueError):
    """A correction does not apply to a plan document."""


class VersionGap(CorrectionError):
    """The document is not at the correction's base version."""

    def __init__(self, base: int, have: int) -> None:
        super().__init__(f"correction from version {base} applied to version {have}")
        self.base = base
        self.have = have


@dataclass(frozen=True)
class RobotSpec:
    """The robot a plan is for: footprint radius and tool width (m), speed limits (m/s), acceleration (m/s²).

    A robot that is not a disc gives ``footprint`` instead of ``radius`` (``radius=0``): a convex polygon
    ``[(x, y), ...]`` in the robot frame (Nav2's convention: x forward, metres, the origin inside).
    """

    radius: float
    tool_width: float
    v_min: float = 0.1
    v_max: float = 1.0
    a_max: float = 0.5
    footprint: Optional[Sequence[Tuple[float, float]]] = None

    def to_json(self) -> Dict[str, Any]:
        out: Dict[str, Any] = {
            "radius": self.radius,
            "tool_width": self.tool_width,
            "v_min": self.v_min,
            "v_max": self.v_max,
            "a_max": self.a_max,
        }
        if self.footprint is not None:
            out["footprint"] = [[float(x), float(y)] for x, y in self.footprint]
        return out


@dataclass(frozen=True)
class PlanOptions:
    """Planner choices; ``None`` leaves the daemon's default."""

    decomposition: Optional[str] = None
    """``auto``, ``bcd``, ``walls``, ``voronoi``, ``grid``, ``none``."""
    order: Optional[str] = None
    """``rrt``, ``two-opt``, ``anneal``."""
    pattern: Optional[str] = None
    """``lanes``, ``spiral``."""
    seed: Optional[int] = None

    def to_json(self) -> Dict[str, Any]:
        raw = {"decomposition": self.decomposition, "order": self.order, "pattern": self.pattern, "seed": self.seed}
        return {k: v for k, v in raw.items() if v is not None}


@dataclass(frozen=True)
class AttributeBlob:
    """A Gaussian blob of attribute (dirtiness, dryness): centre (m), sigma (m), peak amplitude."""

    x: float
    y: float
    sigma: float
    amplitude: float


@dataclass(frozen=True)
class PlanRequest:
    """``POST /v1/plans``: the site, the start/dock ``(x, y)`` and the robot; optionally an attribute map as
    blobs, a polygon to cover inside of, and planner options."""

    site: str
    start: Optional[Point2]
    robot: RobotSpec
    attribute: Optional[List[AttributeBlob]] = None
    region: Optional[List[Point2]] = None
    options: Optional[PlanOptions] = None
    #: ``(lon, lat)`` degrees instead of ``start``, on a site uploaded as a field (``Client.upload_field``).
    start_wgs84: Optional[Point2] = None

    def to_json(self) -> Dict[str, Any]:
        out: Dict[str, Any] = {"site": self.site, "robot": self.robot.to_json()}
        if self.start is not None:
            out["start"] = [float(self.start[0]), float(self.start[1])]
        if self.start_wgs84 is not None:
            out["start_wgs84"] = [float(self.start_wgs84[0]), float(self.start_wgs84[1])]
        if self.attribute is not None:
            out["attribute"] = _blobs_json(self.attribute)
        if self.region is not None:
            out["region"] = [[float(x), float(y)] for x, y in self.region]
        if self.options is not None:
            out["options"] = self.options.to_json()
        return out


@dataclass(frozen=True)
class PlanAccepted:
    """The 202 answer to ``POST /v1/plans``."""

    plan_id: str
    status: str

    @classmethod
    def from_json(cls, d: Mapping[str, Any]) -> "PlanAccepted":
        return cls(plan_id=str(d["plan_id"]), status=str(d["status"]))


@dataclass(frozen=True)
class ProgressJump:
    """Progress found away from where the robot was expected: metres along the path before and after."""

    from_m: float
    to_m: float
    backwards: bool
    at_ms: int

    @classmethod
    def from_json(cls, d: Mapping[str, Any]) -> "ProgressJump":
        return cls(float(d["from_m"]), float(d["to_m"]), bool(d["backwards"]), int(d["at_ms"]))


@dataclass(frozen=True)
class PlanInfo:
    """``GET /v1/plans/{id}``: status, progress (0-1), version, metrics once ready, robot and progress once
    assigned."""

    plan_id: str
    site: str
    status: str
    progress: float
    version: int
    regions_ready: int
    created_ms: int
    updated_ms: int
    metrics: Optional[PlanMetrics] = None
    error: Optional[str] = None
    warnings: List[str] = field(default_factory=list)
    robot: Optional[str] = None
    driven_fraction: Optional[float] = None
    missed: List[List[Point2]] = field(default_factory=list)
    corrections: int = 0
    watch: Optional[str] = None
    """``watching``, ``blind`` or ``blocked`` (the path is blocked to its end; the plan waits) while a robot drives it."""
    progress_jumps: List[ProgressJump] = field(default_factory=list)
    mission: Optional[str] = None
    """The mission this plan is a part of (``/v1/missions/{id}``)."""

    @classmethod
    def from_json(cls, d: Mapping[str, Any]) -> "PlanInfo":
        metrics = d.get("metrics")
        return cls(
            plan_id=str(d["plan_id"]),
            site=str(d["site"]),
            status=str(d["status"]),
            progress=float(d["progress"]),
            version=int(d["version"]),
            regions_ready=int(d.get("regions_ready", 0)),
            created_ms=int(d.get("created_ms", 0)),
            updated_ms=int(d.get("updated_ms", 0)),
            metrics=None if metrics is None else PlanMetrics.from_json(metrics),
            error=d.get("error"),
            warnings=[str(w) for w in d.get("warnings", [])],
            robot=d.get("robot"),
            driven_fraction=_opt_float(d.get("driven_fraction")),
            missed=[_points(m) for m in d.get("missed", [])],
            corrections=int(d.get("corrections", 0)),
            watch=d.get("watch"),
            progress_jumps=[ProgressJump.from_json(j) for j in d.get("progress_jumps", [])],
            mission=d.get("mission"),
        )

    @property
    def is_final(self) -> bool:
        """True when nothing will change the plan's computation any more (ready, active, done, failed,
        cancelled)."""
        return self.status in FINAL_STATUSES


@dataclass(frozen=True)
class SpeedSample:
    """One waypoint of a speed profile: arc length ``s`` (m), speed ``v`` (m/s), time ``t`` (s)."""

    s: float
    v: float
    t: float


@dataclass(frozen=True)
class SpeedProfile:
    """``GET /v1/plans/{id}/speed-profile``: one sample per waypoint of ``version``."""

    plan_id: str
    version: int
    samples: List[SpeedSample]

    @classmethod
    def from_json(cls, d: Mapping[str, Any]) -> "SpeedProfile":
        return cls(
            plan_id=str(d["plan_id"]),
            version=int(d["version"]),
            samples=[SpeedSample(float(s["s"]), float(s["v"]), float(s["t"])) for s in d.get("samples", [])],
        )


@dataclass(frozen=True)
class SiteSummary:
    """``GET /v1/sites/{site}`` and the answer to a map upload: grid size (cells), resolution (m/cell), origin
    (m), free cells, points in the live map and its update rate."""

    site: str
    width: int
    height: int
    resolution: float
    origin: Point2
    free_cells: int
    points_in_tree: int
    updated_ms: int
    updates_per_s: float = 0.0
    dropped_clouds: int = 0
    warnings: List[str] = field(default_factory=list)
    #: For a field site: its map frame as a PROJ string, and the frame's (0, 0) as ``(lon, lat)``.
    crs: Optional[str] = None
    origin_wgs84: Optional[Point2] = None

    @classmethod
    def from_json(cls, d: Mapping[str, Any]) -> "SiteSummary":
        origin = d.get("origin", [0.0, 0.0])
        return cls(
            site=str(d["site"]),
            width=int(d["width"]),
            height=int(d["height"]),
            resolution=float(d["resolution"]),
            origin=(float(origin[0]), float(origin[1])),
            free_cells=int(d["free_cells"]),
            points_in_tree=int(d["points_in_tree"]),
            updated_ms=int(d.get("updated_ms", 0)),
            updates_per_s=float(d.get("updates_per_s", 0.0)),
            dropped_clouds=int(d.get("dropped_clouds", 0)),
            warnings=[str(w) for w in d.get("warnings", [])],
            crs=str(d["crs"]) if d.get("crs") is not None else None,
            origin_wgs84=(float(d["origin_wgs84"][0]), float(d["origin_wgs84"][1]))
            if d.get("origin_wgs84") is not None
            else None,
        )


@dataclass(frozen=True)
class OccupancyGrid:
    """A JSON grid map (DESIGN §5.3), like nav_msgs/OccupancyGrid: ``cells`` row-major from the origin row,
    0 free, 100 occupied, -1 unknown; ``resolution`` m/cell; ``origin`` the map-frame position of cell (0, 0)'s
    outer corner (m)."""

    resolution: float
    origin: Point2
    width: int
    height: int
    cells: List[int]

    def __post_init__(self) -> None:
        if len(self.cells) != self.width * self.height:
            raise ValueError(f"{len(self.cells)} cells for a {self.width} × {self.height} grid")

    @classmethod
    def from_json(cls, d: Mapping[str, Any]) -> "OccupancyGrid":
        """A grid the daemon serves (``GET /v1/sites/{site}/map``, ``…/coverage``)."""
        origin = d.get("origin", [0.0, 0.0])
        return cls(
            resolution=float(d["resolution"]),
            origin=(float(origin[0]), float(origin[1])),
            width=int(d["width"]),
            height=int(d["height"]),
            cells=[int(c) for c in d["cells"]],
        )

    def cell(self, column: int, row: int) -> Optional[int]:
        """The value of cell (``column``, ``row``) (row 0 at the origin), ``None`` outside the grid."""
        if not (0 <= column < self.width and 0 <= row < self.height):
            return None
        return self.cells[row * self.width + column]

    def to_json(self) -> Dict[str, Any]:
        return {
            "resolution": self.resolution,
            "origin": [float(self.origin[0]), float(self.origin[1])],
            "width": self.width,
            "height": self.height,
            "cells": list(self.cells),
        }


def _blobs_json(blobs: List[AttributeBlob]) -> Dict[str, Any]:
    return {"blobs": [{"x": b.x, "y": b.y, "sigma": b.sigma, "amplitude": b.amplitude} for b in blobs]}


def _blobs(raw: Optional[Mapping[str, Any]]) -> Optional[List[AttributeBlob]]:
    if raw is None:
        return None
    return [
        AttributeBlob(float(b["x"]), float(b["y"]), float(b["sigma"]), float(b["amplitude"]))
        for b in raw.get("blobs", [])
    ]


@dataclass(frozen=True)
class MissionRobot:
    """One robot of ``POST /v1/missions``: its ``id`` (as in its Zenoh keys), its dock ``start`` ``(x, y)`` (m,
    map frame; where it starts and returns), footprint radius and tool width (m), speed limits (m/s),
    acceleration (m/s²)."""

    id: str
    start: Point2
    radius: float
    tool_width: float
    v_min: float = 0.1
    v_max: float = 1.0
    a_max: float = 0.5

    @classmethod
    def from_json(cls, d: Mapping[str, Any]) -> "MissionRobot":
        start = d["start"]
        return cls(
            id=str(d["id"]),
            start=(float(start[0]), float(start[1])),
            radius=float(d["radius"]),
            tool_width=float(d["tool_width"]),
            v_min=float(d.get("v_min", 0.1)),
            v_max=float(d.get("v_max", 1.0)),
            a_max=float(d.get("a_max", 0.5)),
        )

    def to_json(self) -> Dict[str, Any]:
        return {
            "id": self.id,
            "start": [float(self.start[0]), float(self.start[1])],
            "radius": self.radius,
            "tool_width": self.tool_width,
            "v_min": self.v_min,
            "v_max": self.v_max,
            "a_max": self.a_max,
        }


@dataclass(frozen=True)
class MissionRequest:
    """``POST /v1/missions``: one site covered by a fleet (at least one robot, ids unique, at most 64). The site
    is divided among the robots and each part planned; ``attribute`` (blobs, one map for the whole fleet),
    ``options`` and ``objective`` (``time``, ``length``, ``overlap``, ``turns``) apply to every part."""

    site: str
    robots: List[MissionRobot]
    attribute: Optional[List[AttributeBlob]] = None
    options: Optional[PlanOptions] = None
    objective: Optional[str] = None

    MAX_ROBOTS = 64
    """Most robots one mission may hold."""

    @classmethod
    def from_json(cls, d: Mapping[str, Any]) -> "MissionRequest":
        o = d.get("options")
        return cls(
            site=str(d["site"]),
            robots=[MissionRobot.from_json(r) for r in d.get("robots", [])],
            attribute=_blobs(d.get("attribute")),
            options=None
            if o is None
            else PlanOptions(o.get("decomposition"), o.get("order"), o.get("pattern"), o.get("seed")),
            objective=d.get("objective"),
        )

    def to_json(self) -> Dict[str, Any]:
        out: Dict[str, Any] = {"site": self.site, "robots": [r.to_json() for r in self.robots]}
        if self.attribute is not None:
            out["attribute"] = _blobs_json(self.attribute)
        if self.options is not None:
            out["options"] = self.options.to_json()
        if self.objective is not None:
            out["objective"] = self.objective
        return out


@dataclass(frozen=True)
class MissionAccepted:
    """The 202 answer to ``POST /v1/missions``."""

    mission_id: str
    status: str

    @classmethod
    def from_json(cls, d: Mapping[str, Any]) -> "MissionAccepted":
        return cls(mission_id=str(d["mission_id"]), status=str(d["status"]))


@dataclass(frozen=True)
class MissionPlanView:
    """One robot's plan within a mission: an ordinary plan (``/v1/plans/{plan_id}``), its status and version (0
    until planned), planned duration (s) and area of its part (m²) once known, fraction of its path driven."""

    robot: str
    plan_id: str
    status: str
    version: int
    driven_fraction: float
    planned_duration_s: Optional[float] = None
    area_m2: Optional[float] = None

    @classmethod
    def from_json(cls, d: Mapping[str, Any]) -> "MissionPlanView":
        return cls(
            robot=str(d["robot"]),
            plan_id=str(d["plan_id"]),
            status=str(d["status"]),
            version=int(d.get("version", 0)),
            driven_fraction=float(d.get("driven_fraction", 0.0)),
            planned_duration_s=_opt_float(d.get("planned_duration_s")),
            area_m2=_opt_float(d.get("area_m2")),
        )


@dataclass(frozen=True)
class MissionCoverage:
    """Planned and measured coverage of a mission, percent of its site's coverable area: ``planned_pct`` by the
    union of the planned paths (once planned), ``measured_pct`` swept by the robots' tools since the plans were
    assigned, ``seam_pct`` planned by two robots or more."""

    measured_pct: float = 0.0
    planned_pct: Optional[float] = None
    seam_pct: Optional[float] = None

    @classmethod
    def from_json(cls, d: Mapping[str, Any]) -> "MissionCoverage":
        return cls(
            measured_pct=float(d.get("measured_pct", 0.0)),
            planned_pct=_opt_float(d.get("planned_pct")),
            seam_pct=_opt_float(d.get("seam_pct")),
        )


@dataclass(frozen=True)
class MissionView:
    """``GET /v1/missions/{id}`` (and each ``mission`` event of its stream): status, ``progress`` 0-1 (of the
    planning while planning, then of the planned work driven), one plan per robot in the request's order,
    coverage, ``eta_s`` (planned time left of the last robot to finish) once planned."""

    mission_id: str
    site: str
    status: str
    progress: float
    plans: List[MissionPlanView]
    coverage: MissionCoverage
    created_ms: int
    updated_ms: int
    eta_s: Optional[float] = None
    error: Optional[str] = None
    warnings: List[str] = field(default_factory=list)

    @classmethod
    def from_json(cls, d: Mapping[str, Any]) -> "MissionView":
        return cls(
            mission_id=str(d["mission_id"]),
            site=str(d["site"]),
            status=str(d["status"]),
            progress=float(d.get("progress", 0.0)),
            plans=[MissionPlanView.from_json(p) for p in d.get("plans", [])],
            coverage=MissionCoverage.from_json(d.get("coverage") or {}),
            created_ms=int(d.get("created_ms", 0)),
            updated_ms=int(d.get("updated_ms", 0)),
            eta_s=_opt_float(d.get("eta_s")),
            error=d.get("error"),
            warnings=[str(w) for w in d.get("warnings", [])],
        )

    @property
    def is_settled(self) -> bool:
        """True when nothing will change the mission any more (done, failed, cancelled)."""
        return self.status in MISSION_SETTLED_STATUSES


@dataclass(frozen=True)
class Pose:
    """A robot's last pose: ``x``, ``y`` (m, map frame), ``yaw`` (rad, counter-clockwise from +x), and the
    stamp of its odometry (ns, robot clock)."""

    x: float
    y: float
    yaw: float
    stamp_ns: int


@dataclass(frozen=True)
class LastCorrection:
    """The last correction sent to a robot."""

    plan_id: str
    version: int
    reason: str
    at_ms: int
    compute_us: int


@dataclass(frozen=True)
class RobotSensors:
    """What became of a robot's sensor data: placed messages and points, waiting ones, drops by reason."""

    placed: int
    points: int
    waiting: int
    dropped: Dict[str, int]
    last_drop: Optional[str] = None


@dataclass(frozen=True)
class RobotView:
    """``GET /v1/robots/{id}``: alive or lost, last pose, plan and progress, the site its data feeds."""

    robot: str
    alive: bool
    last_seen_ms: int
    pose: Optional[Pose] = None
    plan_id: Optional[str] = None
    driven_fraction: Optional[float] = None
    driven_m: Optional[float] = None
    last_correction: Optional[LastCorrection] = None
    site: Optional[str] = None
    sensors: Optional[RobotSensors] = None

    @classmethod
    def from_json(cls, d: Mapping[str, Any]) -> "RobotView":
        p, c, s = d.get("pose"), d.get("last_correction"), d.get("sensors")
        return cls(
            robot=str(d["robot"]),
            alive=bool(d["alive"]),
            last_seen_ms=int(d.get("last_seen_ms", 0)),
            pose=None if p is None else Pose(float(p["x"]), float(p["y"]), float(p["yaw"]), int(p["stamp_ns"])),
            plan_id=d.get("plan_id"),
            driven_fraction=_opt_float(d.get("driven_fraction")),
            driven_m=_opt_float(d.get("driven_m")),
            last_correction=None
            if c is None
            else LastCorrection(str(c["plan_id"]), int(c["version"]), str(c["reason"]), int(c["at_ms"]), int(c["compute_us"])),
            site=d.get("site"),
            sensors=None
            if s is None
            else RobotSensors(
                placed=int(s["placed"]),
                points=int(s["points"]),
                waiting=int(s["waiting"]),
                dropped={str(k): int(v) for k, v in s.get("dropped", {}).items()},
                last_drop=s.get("last_drop"),
            ),
        )
