"""The Robot's version rules over real Zenoh sessions, against a scripted server peer on loopback: it adopts
published plans, applies corrections whose base matches, fetches the plan with a ``get`` when it sees a gap,
ignores stale messages, and finds its plan by query when it joins."""

from __future__ import annotations

import json
import threading
import time
from typing import Callable, Dict, Iterator, List

import pytest
import zenoh

from shift_client import KeySpace, PlanDocument, Robot
from shift_client.types import Correction

from conftest import free_port


def _wp(x: float) -> Dict[str, object]:
    return {"x": x, "y": 0.0, "z": 0.0, "v": 0.5, "t": x, "kind": "cover", "region": 1}


def _plan(plan_id: str, version: int, xs: List[float]) -> Dict[str, object]:
    return {
        "plan_id": plan_id, "version": version, "frame": "map",
        "waypoints": [_wp(x) for x in xs], "regions": [],
        "metrics": {"coverage_pct": 99.0, "overlap_pct": 1.0, "length_m": 9.0, "turns": 0, "collisions": 0,
                    "duration_s": 9.0, "compute_ms": 1.0},
    }


def _correction(plan_id: str, base: int, frm: int, to: int, xs: List[float]) -> Dict[str, object]:
    return {"plan_id": plan_id, "robot": "r9", "base_version": base, "version": base + 1, "from": frm, "to": to,
            "waypoints": [_wp(x) for x in xs], "reason": "obstacle", "compute_us": 3}


class ScriptedServer:
    """A peer listening on a free loopback port that plays the daemon's part for robot r9: it publishes plans
    and corrections and answers plan queries with ``served``."""

    def __init__(self) -> None:
        self.endpoint = f"tcp/127.0.0.1:{free_port()}"
        conf = zenoh.Config()
        conf.insert_json5("mode", '"peer"')
        conf.insert_json5("listen/endpoints", json.dumps([self.endpoint]))
        conf.insert_json5("scouting/multicast/enabled", "false")
        conf.insert_json5("scouting/gossip/enabled", "false")
        self.session = zenoh.open(conf)
        self.keys = KeySpace()
        self.served: Dict[str, object] = {}
        self.queries = 0
        self._lock = threading.Lock()
        self.alive: List[str] = []
        self._tokens = self.session.liveliness().declare_subscriber(
            "shift/default/robots/*/alive", lambda s: self.alive.append(f"{s.kind}:{s.key_expr}")
        )
        self._queryable = self.session.declare_queryable(self.keys.plan("r9"), self._answer)

    def _answer(self, query: zenoh.Query) -> None:
        with self._lock:
            self.queries += 1
            served = self.served
        if served:
            query.reply(self.keys.plan("r9"), json.dumps(served).encode(), encoding=zenoh.Encoding.APPLICATION_JSON)

    def publish_plan(self, doc: Dict[str, object]) -> None:
        self.session.put(self.keys.plan("r9"), json.dumps(doc).encode(), encoding=zenoh.Encoding.APPLICATION_JSON)

    def publish_correction(self, c: Dict[str, object]) -> None:
        self.session.put(self.keys.corrections("r9"), json.dumps(c).encode(), encoding=zenoh.Encoding.APPLICATION_JSON)

    def close(self) -> None:
        self.session.close()


@pytest.fixture()
def server() -> Iterator[ScriptedServer]:
    s = ScriptedServer()
    yield s
    s.close()


def _until(cond: Callable[[], bool], timeout: float = 10.0) -> None:
    deadline = time.monotonic() + timeout
    while not cond():
        assert time.monotonic() < deadline, "timed out"
        time.sleep(0.02)


def _connected(server: ScriptedServer, robot: Robot) -> None:
    """Waits until the server sees the robot's token (the two sessions are linked)."""
    _until(lambda: any(a.endswith(robot.keys.alive(robot.name)) for a in server.alive))


def test_corrections_apply_by_version_and_a_gap_fetches_the_plan(server: ScriptedServer) -> None:
    updates: List[PlanDocument] = []
    with Robot("r9", server.endpoint, on_plan=updates.append) as robot:
        _connected(server, robot)
        _until(lambda: robot.fetches >= 1)  # it asked for its plan on joining; there was none
        assert robot.plan is None and robot.path == []

        v1 = _plan("p-7", 1, [0, 1, 2, 3, 4, 5])
        server.publish_plan(v1)
        assert robot.wait_for_plan("p-7", 1, timeout=10).path == [(float(x), 0.0) for x in range(6)]

        # v1 -> v2 applies in place.
        server.publish_correction(_correction("p-7", 1, 2, 3, [2.2, 2.8]))
        v2 = robot.wait_for_plan("p-7", 2, timeout=10)
        assert [w.x for w in v2.waypoints] == [0, 1, 2.2, 2.8, 3, 4, 5]
        fetches_before = robot.fetches

        # v2 -> v3 is lost; the server now serves v3. v3 -> v4 arrives: a gap, so the robot fetches v3 and
        # applies v4 on it.
        v3 = Correction.from_json(_correction("p-7", 2, 0, 1, [0.5])).apply(v2)
        server.served = v3.to_json()
        server.publish_correction(_correction("p-7", 3, 5, 7, [9.0]))
        v4 = robot.wait_for_plan("p-7", 4, timeout=10)
        assert [w.x for w in v4.waypoints] == [0.5, 1, 2.2, 2.8, 3, 9.0]
        assert robot.fetches == fetches_before + 1
        assert [c.version for c in robot.corrections_applied] == [2, 4]

        # A stale correction and an older plan version change nothing.
        server.publish_correction(_correction("p-7", 1, 0, 6, []))
        server.publish_plan(_plan("p-7", 2, [7, 7]))
        # A new plan replaces it, whatever its version.
        server.publish_plan(_plan("p-8", 1, [4, 3]))
        assert robot.wait_for_plan("p-8", 1, timeout=10).path == [(4.0, 0.0), (3.0, 0.0)]
        assert robot.corrections_applied == []
        assert robot.errors == []
        assert [u.version for u in updates] == [1, 2, 4, 1]


def test_a_robot_that_joins_late_finds_its_plan_by_query(server: ScriptedServer) -> None:
    server.served = _plan("p-5", 3, [1, 2, 3])
    with Robot("r9", server.endpoint) as robot:
        doc = robot.wait_for_plan("p-5", 3, timeout=15)
        assert doc.path == [(1.0, 0.0), (2.0, 0.0), (3.0, 0.0)]
        assert server.queries >= 1


def test_malformed_messages_are_reported_and_the_robot_keeps_going(server: ScriptedServer) -> None:
    with Robot("r9", server.endpoint) as robot:
        _connected(server, robot)
        server.session.put(server.keys.plan("r9"), b"{not json")
        server.publish_plan(_plan("p-1", 1, [0, 1]))
        robot.wait_for_plan("p-1", 1, timeout=10)
        assert len(robot.errors) == 1 and robot.errors[0].startswith("plan:")

