"""A robot's side of SHIFT over Zenoh (DESIGN §5.4), with the official ``eclipse-zenoh`` binding.

A :class:`Robot` is one Zenoh peer connected to the daemon's endpoint (it listens on nothing and scouts
nothing: no multicast, no gossip). It declares its liveliness token ``…/robots/{name}/alive``, publishes JSON
odometry on ``…/odom`` and PointCloud2 CDR on ``…/cloud``, and keeps its current plan: whole plans arrive on
``…/plan`` (and are fetched with a Zenoh ``get`` on that key when it joins), corrections on ``…/corrections``.
A correction applies only to the version it names as its base; one that finds a gap (a missed correction, or a
plan not yet seen) makes the robot fetch the plan and apply what still follows.

Received messages are handled in order on one worker thread (a ``get`` must not run inside a Zenoh callback).
"""

from __future__ import annotations

import json
import logging
import math
import queue
import threading
import time
from typing import Callable, Iterable, List, Optional, Sequence, Tuple

import zenoh

from .cdr import encode_point_cloud2_xyz
from .keys import KeySpace, validate_name
from .types import Correction, PlanDocument, Point2, VersionGap

log = logging.getLogger(__name__)

DEFAULT_ENDPOINT = "tcp/127.0.0.1:7447"
"""The daemon's default Zenoh endpoint (``[zenoh] listen``)."""


def peer_config(endpoint: str) -> zenoh.Config:
    """A Zenoh peer configuration that connects to ``endpoint`` only: no listening, no multicast or gossip
    scouting (ECOSYSTEM.md: never the defaults, which listen on every interface and scout by multicast)."""
    conf = zenoh.Config()
    conf.insert_json5("mode", '"peer"')
    conf.insert_json5("listen/endpoints", "[]")
    conf.insert_json5("connect/endpoints", json.dumps([endpoint]))
    conf.insert_json5("scouting/multicast/enabled", "false")
    conf.insert_json5("scouting/gossip/enabled", "false")
    return conf


class Robot:
    """One robot of a fleet: liveliness, odometry and clouds out; plan and corrections in.

    ``name`` is the robot's id in its keys (validated like ``proto``'s ``validate_name``); ``endpoint`` the
    daemon's Zenoh endpoint; ``keys`` the fleet's key space (prefix and fleet). ``on_plan`` is called on the
    worker thread with every new current plan (a whole plan or a corrected one). ``fetch_timeout`` bounds each
    plan query, seconds. Use it as a context manager, or call :meth:`close`.
    """

    def __init__(
        self,
        name: str,
        endpoint: str = DEFAULT_ENDPOINT,
        *,
        keys: KeySpace = KeySpace(),
        on_plan: Optional[Callable[[PlanDocument], None]] = None,
        fetch_timeout: float = 5.0,
    ) -> None:
        validate_name("robot name", name)
        self.name = name
        self.keys = keys
        self._on_plan = on_plan
        self._fetch_timeout = fetch_timeout
        self._cond = threading.Condition()
        self._plan: Optional[PlanDocument] = None
        self._pending: List[Correction] = []
        self._applied: List[Correction] = []
        self._fetches = 0
        self._errors: List[str] = []
        self._inbox: "queue.Queue[Tuple[str, bytes]]" = queue.Queue()
        self._closed = False
        self._session = zenoh.open(peer_config(endpoint))
        try:
            self._token = self._session.liveliness().declare_token(keys.alive(name))
            self._subs = [
                self._session.declare_subscriber(keys.plan(name), self._enqueue("plan")),
                self._session.declare_subscriber(keys.corrections(name), self._enqueue("correction")),
            ]
            self._odom_pub = self._session.declare_publisher(keys.odom(name), encoding=zenoh.Encoding.APPLICATION_JSON)
            self._cloud_pub = self._session.declare_publisher(keys.cloud(name), encoding=zenoh.Encoding.APPLICATION_CDR)
        except BaseException:
            self._session.close()  # type: ignore[no-untyped-call]
            raise
        # A robot that (re)joins asks for its current plan; in order with what the subscribers bring.
        self._inbox.put(("fetch", b""))
        self._worker = threading.Thread(target=self._run, name=f"shift-robot-{name}", daemon=True)
        self._worker.start()

    # --- what it sends ----------------------------------------------------------------------------------------

    def publish_odom(
        self,
        x: float,
        y: float,
        yaw: float,
        *,
        vx: float = 0.0,
        vy: float = 0.0,
        wz: float = 0.0,
        stamp: Optional[float] = None,
        frame_id: Optional[str] = None,
    ) -> None:
        """Publishes JSON odometry ``{x, y, yaw, vx, vy, wz, stamp}``: pose in metres and radians in the map
        frame (or ``frame_id``), body velocities in m/s and rad/s, ``stamp`` in seconds (default: now, Unix
        time)."""
        body = {
            "x": float(x),
            "y": float(y),
            "yaw": float(yaw),
            "vx": float(vx),
            "vy": float(vy),
            "wz": float(wz),
            "stamp": time.time() if stamp is None else float(stamp),
        }
        for k, v in body.items():
            if not math.isfinite(v):
                raise ValueError(f"odometry {k} is not finite: {v}")
        if frame_id is not None:
            body["frame_id"] = frame_id  # type: ignore[assignment]
        self._odom_pub.put(json.dumps(body).encode("utf-8"))

    def publish_cloud(
        self, points: Iterable[Sequence[float]], *, frame_id: str = "map", stamp: Optional[float] = None
    ) -> None:
        """Publishes a sensor_msgs/PointCloud2 (CDR) of ``(x, y, z)`` points, metres, in ``frame_id`` (``map``:
        placed as they are; another frame: moved by the robot's odometry pose at ``stamp``, seconds, default
        now)."""
        payload = encode_point_cloud2_xyz(points, frame_id, time.time() if stamp is None else stamp)
        self._cloud_pub.put(payload)

    # --- what it holds ----------------------------------------------------------------------------------------

    @property
    def plan(self) -> Optional[PlanDocument]:
        """The current plan with every correction received applied, or ``None`` before one arrived."""
        with self._cond:
            return self._plan

    @property
    def path(self) -> List[Point2]:
        """The current path ``[(x, y), …]``, metres, map frame (empty without a plan)."""
        plan = self.plan
        return plan.path if plan is not None else []

    @property
    def corrections_applied(self) -> List[Correction]:
        """Corrections applied to the current plan's line so far (not those a fetched plan already held)."""
        with self._cond:
            return list(self._applied)

    @property
    def fetches(self) -> int:
        """Plan queries made (on joining, and on every version gap)."""
        with self._cond:
            return self._fetches

    @property
    def errors(self) -> List[str]:
        """Messages that could not be used (malformed payloads, corrections that never applied), oldest first."""
        with self._cond:
            return list(self._errors)

    def wait_for_plan(self, plan_id: Optional[str] = None, min_version: int = 1, timeout: float = 30.0) -> PlanDocument:
        """Blocks until the current plan is ``plan_id`` (any plan when ``None``) at ``min_version`` or later;
        returns it. Raises ``TimeoutError``."""

        def ok() -> bool:
            p = self._plan
            return p is not None and (plan_id is None or p.plan_id == plan_id) and p.version >= min_version

        with self._cond:
            if not self._cond.wait_for(ok, timeout=timeout):
                have = None if self._plan is None else (self._plan.plan_id, self._plan.version)
                raise TimeoutError(f"robot {self.name}: no plan {plan_id or '*'} v>={min_version} (have {have})")
            assert self._plan is not None
            return self._plan

    def fetch_plan(self) -> Optional[PlanDocument]:
        """Asks the daemon for this robot's plan now (a Zenoh ``get`` on its plan key) and adopts it when it is
        newer. Returns the current plan. Call it from any thread (``on_plan`` included) but not from inside a Zenoh
        callback, where a ``get`` would wait on the runtime it runs on."""
        doc = self._query_plan()
        if doc is not None:
            self._adopt(doc)
        return self.plan

    def close(self) -> None:
        """Stops the worker, drops the token (the daemon marks the robot lost) and closes the session."""
        if self._closed:
            return
        self._closed = True
        self._inbox.put(("stop", b""))
        self._worker.join(timeout=10.0)
        self._session.close()  # type: ignore[no-untyped-call]

    def __enter__(self) -> "Robot":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # --- the worker -------------------------------------------------------------------------------------------

    def _enqueue(self, kind: str) -> Callable[[zenoh.Sample], None]:
        def callback(sample: zenoh.Sample) -> None:
            self._inbox.put((kind, sample.payload.to_bytes()))

        return callback

    def _run(self) -> None:
        while True:
            kind, payload = self._inbox.get()
            if kind == "stop":
                return
            try:
                if kind == "fetch":
                    self.fetch_plan()
                elif kind == "plan":
                    self._adopt(PlanDocument.from_json(json.loads(payload)))
                elif kind == "correction":
                    self._correct(Correction.from_json(json.loads(payload)))
            except Exception as e:  # one bad message must not stop the robot
                self._error(f"{kind}: {e!r}")

    def _error(self, what: str) -> None:
        log.warning("robot %s: %s", self.name, what)
        with self._cond:
            self._errors.append(what)

    def _query_plan(self) -> Optional[PlanDocument]:
        """The newest plan any queryable answers for this robot, or ``None`` when none does."""
        with self._cond:
            self._fetches += 1
        best: Optional[PlanDocument] = None
        for reply in self._session.get(self.keys.plan(self.name), timeout=self._fetch_timeout):
            sample = reply.ok
            if sample is None:
                err = reply.err
                self._error(f"plan query: error reply {err.payload.to_bytes() if err is not None else b''!r}")
                continue
            doc = PlanDocument.from_json(json.loads(sample.payload.to_bytes()))
            if best is None or doc.version > best.version:
                best = doc
        return best

    def _adopt(self, doc: PlanDocument) -> None:
        """Takes ``doc`` as the current plan unless it is an older version of it, then applies what waits."""
        with self._cond:
            cur = self._plan
            if cur is not None and cur.plan_id == doc.plan_id and doc.version <= cur.version:
                return
            if cur is None or cur.plan_id != doc.plan_id:
                self._applied = []
            self._plan = doc
            self._drain_pending()
            new = self._plan
            self._cond.notify_all()
        if self._on_plan is not None:
            self._on_plan(new)

    def _correct(self, c: Correction) -> None:
        with self._cond:
            cur = self._plan
            if cur is not None and cur.plan_id == c.plan_id:
                if c.version <= cur.version:
                    return  # already in the plan we hold (a fetched plan included it)
                if c.base_version == cur.version:
                    self._plan = c.apply(cur)
                    self._applied.append(c)
                    self._drain_pending()
                    new = self._plan
                    self._cond.notify_all()
                    gap = False
                else:
                    gap = True
            else:
                gap = True
            if gap:
                self._pending.append(c)
        if gap:
            # A missed correction, or a plan not seen yet: fetch, then apply what still follows.
            log.info("robot %s: version gap at correction %s v%d; fetching the plan", self.name, c.plan_id, c.version)
            self.fetch_plan()
            with self._cond:
                stuck = [p for p in self._pending if p is c]
            if stuck:
                self._error(f"correction {c.plan_id} v{c.base_version}->v{c.version} waits: the plan query gave no base")
            return
        if self._on_plan is not None:
            self._on_plan(new)

    def _drain_pending(self) -> None:
        """Applies waiting corrections that follow the current plan; forgets those it already holds or that are
        for another plan. Call with the lock held."""
        progressed = True
        while progressed and self._plan is not None:
            progressed = False
            cur = self._plan
            keep: List[Correction] = []
            for p in sorted(self._pending, key=lambda p: p.base_version):
                if p.plan_id != cur.plan_id or p.version <= cur.version:
                    continue
                if p.base_version == cur.version and not progressed:
                    try:
                        cur = p.apply(cur)
                    except VersionGap:
                        keep.append(p)
                        continue
                    self._applied.append(p)
                    progressed = True
                else:
                    keep.append(p)
            self._plan = cur
            self._pending = keep
