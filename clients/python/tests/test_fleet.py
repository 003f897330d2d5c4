"""Robots over Zenoh against the real shiftd on loopback: a robot joins, is seen alive, reports its pose,
receives the plan assigned to it, drives it, finds it again by query after a restart, and receives and applies
the correction the daemon makes when an obstacle appears on its path ahead."""

from __future__ import annotations

import math
import threading
import time
from typing import Callable, Iterator, List, Optional, Sequence, Tuple, TypeVar

import pytest

from shift_client import (
    Client,
    CorrectionEvent,
    OccupancyGrid,
    PlanRequest,
    Robot,
    RobotSpec,
    ShiftError,
    Waypoint,
)

from conftest import Daemon
from conftest import poll as conftest_poll

RADIUS = 0.15
LONG = 120.0
T = TypeVar("T")


@pytest.fixture()
def api(daemon: Daemon) -> Iterator[Client]:
    with Client(daemon.url) as c:
        yield c


def poll(f: Callable[[], Optional[T]], what: str, timeout: float = LONG) -> T:
    """:func:`conftest.poll` with this module's default timeout."""
    return conftest_poll(f, what, timeout)


def robot_alive(api: Client, name: str) -> Optional[bool]:
    try:
        return True if api.get_robot(name).alive else None
    except ShiftError as e:
        if e.status == 404:
            return None
        raise


def test_a_robot_receives_its_plan_drives_it_and_fetches_it_again(daemon: Daemon, api: Client) -> None:
    with Robot("py-r1", daemon.zenoh_endpoint) as robot:
        poll(lambda: robot_alive(api, "py-r1"), "robot py-r1 alive")
        robot.publish_odom(0.5, 0.5, 0.0)
        pose = poll(lambda: api.get_robot("py-r1").pose, "a pose")
        assert (pose.x, pose.y) == (0.5, 0.5)

        accepted = api.create_plan(PlanRequest("demo", (0.5, 0.5), RobotSpec(RADIUS, 0.3)))
        assert api.wait_for_plan(accepted.plan_id, timeout=LONG).status == "ready"
        info = api.assign_plan(accepted.plan_id, "py-r1")
        assert (info.status, info.robot) == ("active", "py-r1")
        doc = robot.wait_for_plan(accepted.plan_id, timeout=LONG)
        assert doc == api.get_path(accepted.plan_id), "the plan on Zenoh is the served one"
        assert robot.path == [(w.x, w.y) for w in doc.waypoints]

        # Driving along the plan advances its progress.
        eighth = doc.waypoints[: len(doc.waypoints) // 8 + 1]
        for w in eighth:
            robot.publish_odom(w.x, w.y, 0.0)
            time.sleep(0.005)
        st = poll(
            lambda: (lambda s: s if (s.driven_fraction or 0.0) > 0.0 else None)(api.get_plan(accepted.plan_id)),
            "progress along the plan",
        )
        assert st.robot == "py-r1" and st.driven_fraction is not None and st.driven_fraction < 0.5
        view = poll(
            lambda: (lambda r: r if r.pose and (r.pose.x, r.pose.y) == (eighth[-1].x, eighth[-1].y) else None)(
                api.get_robot("py-r1")
            ),
            "the last pose",
        )
        assert view.plan_id == accepted.plan_id and (view.driven_m or 0.0) > 0.0

    # The robot restarts: it asks for its plan and gets the same one.
    with Robot("py-r1", daemon.zenoh_endpoint) as again:
        assert again.wait_for_plan(accepted.plan_id, timeout=LONG) == doc
        assert again.fetches >= 1
    # Its token is gone: the robot is lost.
    poll(lambda: True if not api.get_robot("py-r1").alive else None, "robot py-r1 lost")


def _dist(a: Waypoint, b: Waypoint) -> float:
    return math.hypot(b.x - a.x, b.y - a.y)


def _seg_dist(p: Tuple[float, float], a: Tuple[float, float], b: Tuple[float, float]) -> float:
    dx, dy = b[0] - a[0], b[1] - a[1]
    l2 = dx * dx + dy * dy
    t = 0.0 if l2 == 0 else max(0.0, min(1.0, ((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / l2))
    return math.hypot(p[0] - a[0] - t * dx, p[1] - a[1] - t * dy)


def longest_straight(w: Sequence[Waypoint]) -> Tuple[int, int]:
    """Indices (i, j) of the longest straight stretch of the path (every waypoint between on the line)."""
    best, i = (0, 1), 0
    while i + 1 < len(w):
        j = i + 1
        while j + 1 < len(w) and all(
            _seg_dist((w[k].x, w[k].y), (w[i].x, w[i].y), (w[j + 1].x, w[j + 1].y)) < 1e-6 for k in range(i + 1, j + 1)
        ):
            j += 1
        if _dist(w[i], w[j]) > _dist(w[best[0]], w[best[1]]):
            best = (i, j)
        i = j
    return best


def along(w: Sequence[Waypoint], seg: Tuple[int, int], s: float) -> Tuple[float, float, float]:
    """The point ``s`` metres from waypoint seg[0] towards seg[1], and the heading."""
    a, b = w[seg[0]], w[seg[1]]
    length = _dist(a, b)
    ux, uy = (b.x - a.x) / length, (b.y - a.y) / length
    return a.x + ux * s, a.y + uy * s, math.atan2(uy, ux)


def clearance(w: Sequence[Waypoint], lo: int, hi: int, pts: Sequence[Sequence[float]]) -> float:
    """Smallest distance between the path's segments lo..hi (waypoint indices) and the points."""
    return min(
        _seg_dist((p[0], p[1]), (w[i].x, w[i].y), (w[i + 1].x, w[i + 1].y))
        for i in range(max(lo, 0), min(hi, len(w) - 1))
        for p in pts
    )


def test_an_obstacle_ahead_gets_a_correction_the_robot_applies(daemon: Daemon, api: Client) -> None:
    # An open 8 m × 4 m room.
    cells = [100 if r in (0, 79) or c in (0, 159) else 0 for r in range(80) for c in range(160)]
    api.upload_grid("py-room", OccupancyGrid(0.05, (0.0, 0.0), 160, 80, cells))
    with Robot("py-r2", daemon.zenoh_endpoint) as robot:
        poll(lambda: robot_alive(api, "py-r2"), "robot py-r2 alive")
        accepted = api.create_plan(PlanRequest("py-room", (0.5, 0.5), RobotSpec(RADIUS, 0.3)))
        assert api.wait_for_plan(accepted.plan_id, timeout=LONG).status == "ready"
        api.assign_plan(accepted.plan_id, "py-r2")
        doc = robot.wait_for_plan(accepted.plan_id, timeout=LONG)
        assert doc.version == 1

        # Follow the plan's events from here on, up to the first correction: it shows up there too.
        seen: List[CorrectionEvent] = []
        stream = api.plan_events(accepted.plan_id)

        def follow() -> None:
            with stream:
                for e in stream:
                    if isinstance(e, CorrectionEvent):
                        seen.append(e)
                        return

        follower = threading.Thread(target=follow, daemon=True)
        follower.start()

        w = doc.waypoints
        seg = longest_straight(w)
        assert _dist(w[seg[0]], w[seg[1]]) > 4.0, "a lane long enough to drive along"
        # Drive the plan up to the lane, then onto its first metre.
        for k in range(0, seg[0], 4):
            robot.publish_odom(w[k].x, w[k].y, 0.0)
        for k in range(5):
            x, y, yaw = along(w, seg, 0.2 * k)
            robot.publish_odom(x, y, yaw, vx=0.3)
            time.sleep(0.03)
        # A 0.2 m post, 0.1-0.5 m high, on the lane 2 m ahead of the robot.
        ox, oy, _ = along(w, seg, 0.8 + 2.0)
        post = [
            (ox - 0.1 + 0.05 * i, oy - 0.1 + 0.05 * j, 0.1 + 0.2 * k) for i in range(5) for j in range(5) for k in range(3)
        ]
        assert clearance(w, seg[0], seg[1], post) < RADIUS, "the old path runs into the post"
        robot.publish_cloud(post)

        new = robot.wait_for_plan(accepted.plan_id, min_version=2, timeout=LONG)
        first = robot.corrections_applied[0]
        assert (first.plan_id, first.robot, first.base_version, first.version) == (accepted.plan_id, "py-r2", 1, 2)
        assert first.reason != "skipped", "an open room leaves room to pass"
        assert seg[0] < first.from_ and first.to <= seg[1], "the patch is on the lane with the post"
        assert first.compute_us > 0
        v2 = first.apply(doc)
        assert v2.waypoints[: first.from_] == w[: first.from_], "kept before the patch"
        lo, hi = first.from_ - 1, first.from_ + len(first.waypoints) + 1
        assert clearance(v2.waypoints, lo, hi, post) >= RADIUS - 1e-6, "the patch keeps clear of the post"
        assert all(p.v > 0 and math.isfinite(p.t) for p in first.waypoints)
        assert new.version >= 2 and robot.errors == []

        # The robot, the API and the plan query agree (the daemon may correct the window again at once).
        def settled() -> Optional[int]:
            mine, served = robot.plan, api.get_path(accepted.plan_id)
            return served.version if mine == served else None

        version = poll(settled, "robot and API on one version", timeout=30)
        assert api.get_plan(accepted.plan_id).version == version
        assert api.get_plan(accepted.plan_id).corrections == version - 1
        last = api.get_robot("py-r2").last_correction
        assert last is not None and (last.plan_id, last.version) == (accepted.plan_id, version)
        assert robot.fetch_plan() == api.get_path(accepted.plan_id)
        follower.join(timeout=30)
        assert [e.correction for e in seen] == [first], "the first correction event is the robot's first correction"
