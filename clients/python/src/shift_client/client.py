"""Synchronous REST client of shiftd's HTTP API (DESIGN §5.3), over httpx."""

from __future__ import annotations

import re
import time
from urllib.parse import quote
from pathlib import Path
from typing import Any, Dict, Generic, Iterator, List, Mapping, Optional, TypeVar, Union

import httpx

from .errors import ShiftError, error_for
from .events import PlanEvent, decode_messages, decode_mission_messages, iter_sse
from .types import (
    MissionAccepted,
    MissionRequest,
    MissionRobot,
    MissionView,
    OccupancyGrid,
    PlanAccepted,
    PlanDocument,
    PlanInfo,
    PlanRequest,
    RobotView,
    SiteSummary,
    SpeedProfile,
)

DEFAULT_URL = "http://127.0.0.1:7878"


def _seg(value: str) -> str:
    """One path segment, percent-encoded (a name with `/` cannot reach another route)."""
    return quote(value, safe="")


T = TypeVar("T")


class _EventStream(Generic[T]):
    """An open Server-Sent Events answer, iterated as typed items; closed when iteration ends."""

    def __init__(self, response: httpx.Response, items: Iterator[T]) -> None:
        self._response = response
        self._items = items

    def __iter__(self) -> Iterator[T]:
        return self

    def __next__(self) -> T:
        try:
            return next(self._items)
        except StopIteration:
            self.close()
            raise

    def close(self) -> None:
        """Hangs up."""
        self._response.close()


class PlanEvents(_EventStream[PlanEvent]):
    """An open ``GET /v1/plans/{id}/events`` stream: iterate it for typed events; close it (or use it as a
    context manager) to hang up. Iteration ends when the daemon ends the stream (after a ``done``, ``failed``
    or ``cancelled`` status, or on shutdown). Close it from the thread that iterates (break, then close): a
    thread blocked waiting for the next event is not woken by a close from elsewhere until an event or a
    keep-alive comes."""

    def __init__(self, response: httpx.Response) -> None:
        super().__init__(response, decode_messages(iter_sse(response.iter_lines())))

    def __enter__(self) -> "PlanEvents":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class MissionEvents(_EventStream[MissionView]):
    """An open ``GET /v1/missions/{id}/events`` stream: iterate it for :class:`MissionView` s (first the
    current one, then one per change); close it (or use it as a context manager) to hang up. Iteration ends
    when the daemon ends the stream (after ``done``, ``failed`` or ``cancelled``, or on shutdown). Close it
    from the thread that iterates, as :class:`PlanEvents`."""

    def __init__(self, response: httpx.Response) -> None:
        super().__init__(response, decode_mission_messages(iter_sse(response.iter_lines())))

    def __enter__(self) -> "MissionEvents":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class Client:
    """shiftd's HTTP API.

    ``base_url`` is the daemon's address (default ``http://127.0.0.1:7878``); ``token`` is sent as
    ``Authorization: Bearer …`` (the daemon asks for it on mutating routes when ``[http] auth_token`` is set);
    ``timeout`` is seconds per request (event streams wait for events without limit). Every method raises
    :class:`ShiftError` when the daemon answers with an error.

    >>> with Client("http://127.0.0.1:7878") as api:                            # doctest: +SKIP
    ...     plan = api.create_plan(PlanRequest("demo", (0.5, 0.5), RobotSpec(0.15, 0.3)))
    ...     info = api.wait_for_plan(plan.plan_id)
    ...     doc = api.get_path(plan.plan_id)
    """

    def __init__(
        self,
        base_url: str = DEFAULT_URL,
        token: Optional[str] = None,
        timeout: float = 30.0,
        transport: Optional[httpx.BaseTransport] = None,
    ) -> None:
        headers = {"Accept": "application/json"}
        if token:
            headers["Authorization"] = f"Bearer {token}"
        self._http = httpx.Client(base_url=base_url.rstrip("/"), headers=headers, timeout=timeout, transport=transport)

    def close(self) -> None:
        """Closes the connection pool."""
        self._http.close()

    def __enter__(self) -> "Client":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _request(self, method: str, path: str, **kwargs: Any) -> Any:
        r = self._http.request(method, path, **kwargs)
        err = error_for(r.status_code, r.content, r.headers)
        if err is not None:
            raise err
        return r.json()

    # --- operations -------------------------------------------------------------------------------------------

    def healthy(self) -> bool:
        """``GET /healthz``: the daemon answers."""
        return self._http.get("/healthz").status_code == 200

    def ready(self) -> bool:
        """``GET /readyz``: store open and Zenoh session up."""
        return self._http.get("/readyz").status_code == 200

    def metrics_text(self) -> str:
        """``GET /metrics``: Prometheus exposition text."""
        r = self._http.get("/metrics", headers={"Accept": "text/plain"})
        err = error_for(r.status_code, r.content)
        if err is not None:
            raise err
        return r.text

    # --- sites ------------------------------------------------------------------------------------------------

    def upload_map(self, site: str, yaml: Union[str, bytes], image: bytes, image_name: str = "map.pgm") -> SiteSummary:
        """``POST /v1/sites/{site}/map``, multipart: a ROS map_server ``yaml`` and its ``image`` (PGM or PNG
        bytes). Replaces the site's map; returns its summary."""
        yaml_bytes = yaml.encode("utf-8") if isinstance(yaml, str) else yaml
        files = {
            "yaml": ("map.yaml", yaml_bytes, "application/yaml"),
            "image": (image_name, image, "application/octet-stream"),
        }
        return SiteSummary.from_json(self._request("POST", f"/v1/sites/{_seg(site)}/map", files=files))

    def upload_map_file(self, site: str, yaml_path: Union[str, Path]) -> SiteSummary:
        """Uploads the map_server YAML at ``yaml_path`` and the image its ``image:`` key names (relative to the
        YAML's folder)."""
        yaml_path = Path(yaml_path)
        text = yaml_path.read_text(encoding="utf-8")
        m = re.search(r"^\s*image\s*:\s*['\"]?([^'\"#\n]+?)['\"]?\s*(?:#.*)?$", text, re.MULTILINE)
        if m is None:
            raise ValueError(f"{yaml_path}: no `image:` key")
        image_path = Path(m.group(1))
        if not image_path.is_absolute():
            image_path = yaml_path.parent / image_path
        return self.upload_map(site, text, image_path.read_bytes(), image_name=image_path.name)

    def upload_grid(self, site: str, grid: OccupancyGrid) -> SiteSummary:
        """``POST /v1/sites/{site}/map`` with a JSON grid (nav_msgs/OccupancyGrid-like). Returns the summary."""
        return SiteSummary.from_json(self._request("POST", f"/v1/sites/{_seg(site)}/map", json=grid.to_json()))

    def upload_field(
        self,
        site: str,
        field: Mapping[str, Any],
        *,
        no_go: Optional[List[Mapping[str, Any]]] = None,
        tool_width: Optional[float] = None,
        resolution_m: Optional[float] = None,
    ) -> SiteSummary:
        """``POST /v1/sites/{site}/field`` with a GeoJSON field (Polygon, MultiPolygon, Feature or
        FeatureCollection in ``[lon, lat]`` degrees; holes and ``no_go`` polygons are obstacles). The site's map
        frame is a transverse Mercator centred on the field: the summary names it (``crs``, ``origin_wgs84``)."""
        body: Dict[str, Any] = {"field": dict(field)}
        if no_go:
            body["no_go"] = [dict(p) for p in no_go]
        if tool_width is not None:
            body["tool_width"] = float(tool_width)
        if resolution_m is not None:
            body["resolution_m"] = float(resolution_m)
        return SiteSummary.from_json(self._request("POST", f"/v1/sites/{_seg(site)}/field", json=body))

    def get_site(self, site: str) -> SiteSummary:
        """``GET /v1/sites/{site}``: size, resolution, free cells, points in the live map."""
        return SiteSummary.from_json(self._request("GET", f"/v1/sites/{_seg(site)}"))

    # --- plans ------------------------------------------------------------------------------------------------

    def create_plan(self, request: PlanRequest, busy_wait_s: float = 0.0) -> PlanAccepted:
        """``POST /v1/plans``: the plan is queued (202); follow it with :meth:`wait_for_plan` or
        :meth:`plan_events`.

        A full queue answers 429 (``queue_full``) with ``Retry-After``. With ``busy_wait_s`` > 0 the request is
        sent again after the wait the daemon asks for (1 s when it names none) for up to that many seconds in
        all; the last 429 is raised when the time is up.
        """
        deadline = time.monotonic() + max(0.0, busy_wait_s)
        while True:
            try:
                return PlanAccepted.from_json(self._request("POST", "/v1/plans", json=request.to_json()))
            except ShiftError as e:
                wait = e.retry_after_s if e.retry_after_s is not None else 1.0
                if e.status != 429 or time.monotonic() + wait > deadline:
                    raise
                time.sleep(wait)

    def get_plan(self, plan_id: str) -> PlanInfo:
        """``GET /v1/plans/{id}``: status, progress 0-1, version, metrics once ready."""
        return PlanInfo.from_json(self._request("GET", f"/v1/plans/{_seg(plan_id)}"))

    def wait_for_plan(self, plan_id: str, timeout: float = 120.0, poll_s: float = 0.1) -> PlanInfo:
        """Polls the plan until its status is final (``ready``, ``active``, ``done``, ``failed`` or
        ``cancelled``) and returns it; check ``.status``. Raises ``TimeoutError`` after ``timeout`` seconds."""
        deadline = time.monotonic() + timeout
        delay = poll_s
        while True:
            info = self.get_plan(plan_id)
            if info.is_final:
                return info
            if time.monotonic() >= deadline:
                raise TimeoutError(f"plan {plan_id} still {info.status} after {timeout} s")
            time.sleep(min(delay, max(0.0, deadline - time.monotonic())))
            delay = min(delay * 1.5, 1.0)

    def get_path(self, plan_id: str) -> PlanDocument:
        """``GET /v1/plans/{id}/path``: the plan document, current version with every correction applied (409
        ``not_ready`` while it is computed)."""
        return PlanDocument.from_json(self._request("GET", f"/v1/plans/{_seg(plan_id)}/path"))

    def get_path_geojson(self, plan_id: str) -> Dict[str, Any]:
        """``GET /v1/plans/{id}/path?crs=wgs84``: the path of a plan on a field site as a GeoJSON Feature whose
        LineString holds ``[lon, lat]``, with the waypoints' ``v``, ``t`` and ``kind`` as properties."""
        return dict(self._request("GET", f"/v1/plans/{_seg(plan_id)}/path", params={"crs": "wgs84"}))

    def get_speed_profile(self, plan_id: str) -> SpeedProfile:
        """``GET /v1/plans/{id}/speed-profile``: per waypoint arc length (m), speed (m/s), time (s)."""
        return SpeedProfile.from_json(self._request("GET", f"/v1/plans/{_seg(plan_id)}/speed-profile"))

    def cancel_plan(self, plan_id: str) -> PlanInfo:
        """``DELETE /v1/plans/{id}``: cancels a queued or planning plan (409 once it finished)."""
        return PlanInfo.from_json(self._request("DELETE", f"/v1/plans/{_seg(plan_id)}"))

    def assign_plan(self, plan_id: str, robot: str) -> PlanInfo:
        """``POST /v1/plans/{id}/assign``: publishes the plan to ``robot`` over Zenoh and watches its path."""
        return PlanInfo.from_json(self._request("POST", f"/v1/plans/{_seg(plan_id)}/assign", json={"robot": robot}))

    def plan_events(self, plan_id: str) -> PlanEvents:
        """``GET /v1/plans/{id}/events``: an open stream of typed events (first the current status). Raises
        :class:`ShiftError` at once for an unknown plan."""
        return PlanEvents(self._open_stream(f"/v1/plans/{_seg(plan_id)}/events"))

    def _open_stream(self, path: str) -> httpx.Response:
        """``GET path`` as an event stream without a read timeout; raises :class:`ShiftError` for an error
        answer."""
        timeout = httpx.Timeout(self._http.timeout.connect, read=None, write=self._http.timeout.write, pool=None)
        req = self._http.build_request("GET", path, headers={"Accept": "text/event-stream"}, timeout=timeout)
        r = self._http.send(req, stream=True)
        if not 200 <= r.status_code < 300:
            try:
                body = r.read()
            finally:
                r.close()
            raise ShiftError.from_response(r.status_code, body, r.headers)
        return r

    # --- missions ---------------------------------------------------------------------------------------------

    def create_mission(self, request: MissionRequest) -> MissionAccepted:
        """``POST /v1/missions``: the mission is queued (202): its site is divided among the robots and each part
        planned as an ordinary plan. The whole request is checked first: a 400 names the field (``robots[1].id
        …``) and nothing is stored; an unknown site is 404, a full queue 429. Follow it with
        :meth:`mission_events`."""
        return MissionAccepted.from_json(self._request("POST", "/v1/missions", json=request.to_json()))

    def get_mission(self, mission_id: str) -> MissionView:
        """``GET /v1/missions/{id}``: status, one plan per robot, planned and measured coverage, progress, ETA."""
        return MissionView.from_json(self._request("GET", f"/v1/missions/{_seg(mission_id)}"))

    def assign_mission(self, mission_id: str) -> MissionView:
        """``POST /v1/missions/{id}/assign``: every part's plan to its robot, all or none (409 while a plan is
        not computed). Returns the mission, now ``active``."""
        return MissionView.from_json(self._request("POST", f"/v1/missions/{_seg(mission_id)}/assign", json={}))

    def replan_mission(self, mission_id: str) -> MissionView:
        """``POST /v1/missions/{id}/replan``: what the mission has left (its swept cells left out) is divided
        again among its robots that are not lost, each from where it is; each plan then gets its next version.
        Answers at once (202) with the mission's view. 409 before it is planned and once done or cancelled."""
        return MissionView.from_json(self._request("POST", f"/v1/missions/{_seg(mission_id)}/replan", json={}))

    def join_mission(self, mission_id: str, robot: MissionRobot) -> MissionView:
        """``POST /v1/missions/{id}/robots``: ``robot`` joins the mission and takes a balanced share of what is
        left (a replan of the whole fleet, each robot from where it is). 400 names ``robots[n]``; 409 while the
        mission is being planned or once it ended."""
        path = f"/v1/missions/{_seg(mission_id)}/robots"
        return MissionView.from_json(self._request("POST", path, json=robot.to_json()))

    def cancel_mission(self, mission_id: str) -> MissionView:
        """``DELETE /v1/missions/{id}``: cancels the mission and its plans not yet driven (a robot driving its
        part finishes it); 409 once it is done, failed or cancelled."""
        return MissionView.from_json(self._request("DELETE", f"/v1/missions/{_seg(mission_id)}"))

    def mission_events(self, mission_id: str) -> MissionEvents:
        """``GET /v1/missions/{id}/events``: an open stream of :class:`MissionView` s, the current one first.
        Raises :class:`ShiftError` at once for an unknown mission.

        >>> with api.mission_events(accepted.mission_id) as views:           # doctest: +SKIP
        ...     for view in views:
        ...         if view.status not in ("queued", "planning"):
        ...             break
        """
        return MissionEvents(self._open_stream(f"/v1/missions/{_seg(mission_id)}/events"))

    def site_coverage(self, site: str) -> OccupancyGrid:
        """``GET /v1/sites/{site}/coverage``: what robots' tools swept on the site over its map, one value per
        cell: 100 swept, 0 free and not swept, -1 not free."""
        return OccupancyGrid.from_json(self._request("GET", f"/v1/sites/{_seg(site)}/coverage"))

    def site_coverage_png(self, site: str) -> bytes:
        """``GET /v1/sites/{site}/coverage?format=png``: the same raster as PNG bytes (the map in greys, swept
        cells green, one pixel per cell, the map's top row first)."""
        r = self._http.get(
            f"/v1/sites/{_seg(site)}/coverage", params={"format": "png"}, headers={"Accept": "image/png"}
        )
        err = error_for(r.status_code, r.content, r.headers)
        if err is not None:
            raise err
        return r.content

    # --- robots -----------------------------------------------------------------------------------------------

    def list_robots(self) -> List[RobotView]:
        """``GET /v1/robots``: every robot seen, alive or lost."""
        return [RobotView.from_json(r) for r in self._request("GET", "/v1/robots")]

    def get_robot(self, robot: str) -> RobotView:
        """``GET /v1/robots/{id}``: pose, plan, progress, last correction, the site its data feeds."""
        return RobotView.from_json(self._request("GET", f"/v1/robots/{_seg(robot)}"))
