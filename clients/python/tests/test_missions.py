"""Missions against the real shiftd: a two-robot mission on a small uploaded site followed over its events until
planned, shown, assigned; a second one cancelled with its plans; bad requests refused naming the field; the
site's coverage raster as JSON and PNG. Without a daemon: the mission documents and their SSE decoding."""

from __future__ import annotations

import struct
import time
from typing import Iterator, List

import pytest

from shift_client import (
    Client,
    MissionCoverage,
    MissionEvents,
    MissionPlanView,
    MissionRequest,
    MissionRobot,
    MissionView,
    OccupancyGrid,
    ShiftError,
)
from shift_client.events import decode_mission_messages, iter_sse
from shift_client.types import PlanInfo, PlanOptions

from conftest import Daemon

SITE = "py-mission"
W, H, RES = 80, 50, 0.1


@pytest.fixture(scope="module")
def api(daemon: Daemon) -> Iterator[Client]:
    with Client(daemon.url) as c:
        summary = c.upload_grid(SITE, room_with_block())
        assert (summary.width, summary.height) == (W, H)
        yield c


def room_with_block() -> OccupancyGrid:
    """8 m × 5 m at 0.1 m: a one-cell wall ring and a 1 m × 1 m block in the middle."""
    cells = []
    for r in range(H):
        for c in range(W):
            wall = r in (0, H - 1) or c in (0, W - 1)
            block = 35 <= c < 45 and 20 <= r < 30
            cells.append(100 if wall or block else 0)
    return OccupancyGrid(resolution=RES, origin=(0.0, 0.0), width=W, height=H, cells=cells)


def fleet(*names: str) -> List[MissionRobot]:
    """Robots with docks in opposite corners."""
    docks = [(1.0, 1.0), (7.0, 4.0), (1.0, 4.0), (7.0, 1.0)]
    return [MissionRobot(n, docks[i], radius=0.15, tool_width=0.3) for i, n in enumerate(names)]


def until_planned(events: MissionEvents, timeout: float = 120.0) -> List[MissionView]:
    """The views of the stream up to the first that is no longer queued or planning."""
    seen: List[MissionView] = []
    deadline = time.monotonic() + timeout
    for view in events:
        seen.append(view)
        if view.status not in ("queued", "planning") or time.monotonic() > deadline:
            break
    return seen


def png_size(png: bytes) -> tuple:
    """(width, height) of a PNG from its IHDR chunk."""
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and png[12:16] == b"IHDR", png[:16]
    return struct.unpack(">II", png[16:24])


def test_a_two_robot_mission_is_planned_over_its_events_shown_and_assigned(api: Client) -> None:
    accepted = api.create_mission(MissionRequest(SITE, fleet("pm1", "pm2"), options=PlanOptions(seed=3)))
    assert accepted.status == "queued" and accepted.mission_id.startswith("m-")
    with api.mission_events(accepted.mission_id) as events:
        seen = until_planned(events)
    assert seen and seen[0].status in ("queued", "planning", "ready")
    ready = seen[-1]
    assert ready.status == "ready", ready
    assert all(v.mission_id == accepted.mission_id and v.site == SITE for v in seen)
    progress = [v.progress for v in seen]
    assert progress == sorted(progress) and all(0.0 <= p <= 1.0 for p in progress)
    assert [p.robot for p in ready.plans] == ["pm1", "pm2"]
    assert ready.coverage.planned_pct is not None and ready.coverage.planned_pct >= 95.0, ready.coverage
    assert ready.coverage.seam_pct is not None and ready.coverage.measured_pct == 0.0
    assert ready.eta_s is not None and ready.eta_s > 0.0
    free_m2 = (78 * 48 - 100) * RES * RES
    area = sum(p.area_m2 or 0.0 for p in ready.plans)
    assert 0.7 * free_m2 < area <= free_m2 * 1.01, (area, free_m2)

    # Each part is an ordinary plan naming its mission.
    for p in ready.plans:
        info = api.get_plan(p.plan_id)
        assert (info.status, info.version, info.mission) == ("ready", 1, accepted.mission_id)
        assert info.metrics is not None and p.planned_duration_s == pytest.approx(info.metrics.duration_s)
        assert p.version == 1 and p.driven_fraction == 0.0

    shown = api.get_mission(accepted.mission_id)
    assert (shown.status, shown.plans, shown.coverage) == ("ready", ready.plans, ready.coverage)
    assert not shown.is_settled

    active = api.assign_mission(accepted.mission_id)
    assert active.status == "active"
    for p in active.plans:
        info = api.get_plan(p.plan_id)
        assert (info.status, info.robot) == ("active", p.robot)
    # A stream opened now starts with the current view (and stays open while the mission is active).
    with api.mission_events(accepted.mission_id) as events:
        first = next(iter(events))
    assert (first.mission_id, first.status) == (accepted.mission_id, "active")

    # Replanning the remainder of a planned mission is accepted at once.
    replanned = api.replan_mission(accepted.mission_id)
    assert replanned.mission_id == accepted.mission_id and replanned.status != "failed"


def test_a_cancelled_mission_cancels_its_plans(api: Client) -> None:
    accepted = api.create_mission(MissionRequest(SITE, fleet("pc1", "pc2")))
    cancelled = api.cancel_mission(accepted.mission_id)
    assert (cancelled.mission_id, cancelled.status) == (accepted.mission_id, "cancelled")
    assert cancelled.is_settled and len(cancelled.plans) == 2
    assert all(p.status == "cancelled" for p in cancelled.plans), cancelled.plans
    for p in cancelled.plans:
        assert api.get_plan(p.plan_id).status == "cancelled"
    # A settled mission's stream is its view alone.
    with api.mission_events(accepted.mission_id) as events:
        only = list(events)
    assert [v.status for v in only] == ["cancelled"]
    for call in (
        lambda: api.cancel_mission(accepted.mission_id),
        lambda: api.assign_mission(accepted.mission_id),
        lambda: api.replan_mission(accepted.mission_id),
        lambda: api.join_mission(accepted.mission_id, MissionRobot("pc3", (7.0, 4.0), 0.15, 0.3)),
    ):
        with pytest.raises(ShiftError) as e:
            call()
        assert e.value.status == 409, e.value


def test_bad_missions_are_refused_naming_the_field(api: Client) -> None:
    twice = fleet("pb1", "pb2")
    twice[1] = MissionRobot("pb1", (7.0, 4.0), 0.15, 0.3)
    with pytest.raises(ShiftError) as e:
        api.create_mission(MissionRequest(SITE, twice))
    assert (e.value.status, e.value.code) == (400, "invalid_request")
    assert "robots[1].id" in e.value.message, e.value.message
    with pytest.raises(ShiftError) as e:
        api.create_mission(MissionRequest(SITE, []))
    assert e.value.status == 400 and "robots" in e.value.message
    with pytest.raises(ShiftError) as e:
        api.create_mission(MissionRequest(SITE, [MissionRobot("pb1", (1.0, 1.0), 0.15, -0.3)]))
    assert e.value.status == 400 and "robots[0]" in e.value.message and "tool_width" in e.value.message
    with pytest.raises(ShiftError) as e:
        api.create_mission(MissionRequest("nowhere", fleet("pb1")))
    assert e.value.status == 404
    for call in (lambda: api.get_mission("m-999999"), lambda: api.mission_events("m-999999")):
        with pytest.raises(ShiftError) as e:
            call()
        assert (e.value.status, e.value.code) == (404, "not_found")


def test_the_site_coverage_raster_as_json_and_png(api: Client) -> None:
    grid = api.site_coverage(SITE)
    assert (grid.width, grid.height, grid.resolution, grid.origin) == (W, H, pytest.approx(RES), (0.0, 0.0))
    assert len(grid.cells) == W * H and set(grid.cells) <= {-1, 0, 100}
    # No robot drove here: the free cells are 0, walls and the block -1.
    assert grid.cells.count(0) == api.get_site(SITE).free_cells
    assert grid.cell(0, 0) == -1 and grid.cell(40, 25) == -1 and grid.cell(10, 10) == 0
    assert grid.cell(W, 0) is None

    png = api.site_coverage_png(SITE)
    assert png_size(png) == (W, H)
    with pytest.raises(ShiftError) as e:
        api.site_coverage("nowhere")
    assert e.value.status == 404
    with pytest.raises(ShiftError) as e:
        api.site_coverage_png("nowhere")
    assert e.value.status == 404


def test_mission_documents_and_events_decode_without_a_daemon() -> None:
    raw = {
        "mission_id": "m-1",
        "site": "s",
        "status": "planning",
        "progress": 0.5,
        "plans": [
            {"robot": "r1", "plan_id": "p-1", "status": "ready", "version": 1, "planned_duration_s": 12.5,
             "area_m2": 3.0, "driven_fraction": 0.0, "a_newer_field": 1},
            {"robot": "r2", "plan_id": "p-2", "status": "planning", "version": 0, "driven_fraction": 0.0},
        ],
        "coverage": {"measured_pct": 0.0, "planned_pct": 99.0},
        "created_ms": 1,
        "updated_ms": 2,
        "another": {"nested": True},
    }
    view = MissionView.from_json(raw)
    assert view.plans[0] == MissionPlanView("r1", "p-1", "ready", 1, 0.0, 12.5, 3.0)
    assert view.plans[1].planned_duration_s is None and view.plans[1].area_m2 is None
    assert view.coverage == MissionCoverage(measured_pct=0.0, planned_pct=99.0, seam_pct=None)
    assert (view.eta_s, view.error, view.warnings, view.is_settled) == (None, None, [], False)
    assert PlanInfo.from_json({"plan_id": "p-1", "site": "s", "status": "ready", "progress": 1.0, "version": 1,
                               "mission": "m-1"}).mission == "m-1"

    request = MissionRequest("s", [MissionRobot("r1", (1, 2), 0.25, 0.5)], objective="length")
    wire = request.to_json()
    assert wire == {
        "site": "s",
        "robots": [{"id": "r1", "start": [1.0, 2.0], "radius": 0.25, "tool_width": 0.5, "v_min": 0.1, "v_max": 1.0,
                    "a_max": 0.5}],
        "objective": "length",
    }
    assert MissionRequest.from_json(wire) == MissionRequest("s", [MissionRobot("r1", (1.0, 2.0), 0.25, 0.5)],
                                                            objective="length")

    import json

    text = f": keep-alive\n\nevent: mission\ndata: {json.dumps(raw)}\n\nevent: other\ndata: 1\n\n"
    views = list(decode_mission_messages(iter_sse(text.split("\n"))))
    assert [v.mission_id for v in views] == ["m-1"]
