"""The REST client against the real shiftd: sites and maps, plans, events, speed profile, cancel, errors, auth."""

from __future__ import annotations

from pathlib import Path
from typing import Iterator, List

import pytest

from shift_client import (
    Client,
    OccupancyGrid,
    PlanRequest,
    ProgressEvent,
    RegionReadyEvent,
    RobotSpec,
    ShiftError,
    StatusEvent,
)

from conftest import Daemon

DEMO = PlanRequest(site="demo", start=(0.5, 0.5), robot=RobotSpec(radius=0.15, tool_width=0.3))


@pytest.fixture()
def api(daemon: Daemon) -> Iterator[Client]:
    with Client(daemon.url) as c:
        yield c


def room_grid(w: int, h: int, res: float) -> OccupancyGrid:
    """A ``w × h`` grid of ``res`` m cells, free inside a one-cell wall ring."""
    cells = [100 if r in (0, h - 1) or c in (0, w - 1) else 0 for r in range(h) for c in range(w)]
    return OccupancyGrid(resolution=res, origin=(0.0, 0.0), width=w, height=h, cells=cells)


def test_health_readiness_metrics_and_the_demo_site(api: Client) -> None:
    assert api.healthy() and api.ready()
    site = api.get_site("demo")
    assert site.site == "demo" and site.resolution == pytest.approx(0.05)
    assert site.width > 0 and site.height > 0 and 0 < site.free_cells < site.width * site.height
    assert "shift_" in api.metrics_text()


def test_uploads_a_json_grid_and_a_map_server_map(api: Client, tmp_path: Path) -> None:
    grid = api.upload_grid("py-grid", room_grid(80, 60, 0.05))
    assert (grid.site, grid.width, grid.height) == ("py-grid", 80, 60)
    assert grid.free_cells == 78 * 58
    assert api.get_site("py-grid") == grid

    # A 40 × 30 PGM: white (free) inside a black (occupied) border, a 4 × 4 black block in the middle.
    w, h = 40, 30
    pixels = bytearray()
    for r in range(h):
        for c in range(w):
            wall = r in (0, h - 1) or c in (0, w - 1) or (13 <= r < 17 and 18 <= c < 22)
            pixels.append(0 if wall else 254)
    (tmp_path / "room.pgm").write_bytes(f"P5\n{w} {h}\n255\n".encode() + bytes(pixels))
    (tmp_path / "room.yaml").write_text(
        "image: room.pgm  # beside this file\nresolution: 0.1\norigin: [-1.0, -2.0, 0.0]\nnegate: 0\n"
        "occupied_thresh: 0.65\nfree_thresh: 0.196\n"
    )
    ros = api.upload_map_file("py-ros", tmp_path / "room.yaml")
    assert (ros.width, ros.height, ros.resolution, ros.origin) == (40, 30, pytest.approx(0.1), (-1.0, -2.0))
    assert ros.free_cells == 38 * 28 - 16


def test_api_errors_carry_status_code_and_message(api: Client) -> None:
    with pytest.raises(ShiftError) as e:
        api.get_plan("p-does-not-exist")
    assert (e.value.status, e.value.code) == (404, "not_found")
    assert "p-does-not-exist" in e.value.message
    with pytest.raises(ShiftError) as e:
        api.get_site("nowhere")
    assert e.value.status == 404
    with pytest.raises(ShiftError) as e:
        api.create_plan(PlanRequest(site="nowhere", start=(0.5, 0.5), robot=RobotSpec(0.15, 0.3)))
    assert e.value.status == 404
    with pytest.raises(ShiftError) as e:
        api.create_plan(PlanRequest(site="demo", start=(0.5, 0.5), robot=RobotSpec(radius=-1.0, tool_width=0.3)))
    assert e.value.status == 400
    with pytest.raises(ShiftError) as e:
        api.plan_events("p-does-not-exist")
    assert e.value.status == 404
    with pytest.raises(ShiftError) as e:
        api.get_robot("nobody-here")
    assert e.value.status == 404


def test_plans_on_the_demo_site_streaming_its_events(api: Client) -> None:
    # With one worker, the plan under test waits behind another: its stream starts while it is queued.
    ahead = api.create_plan(DEMO)
    accepted = api.create_plan(DEMO)
    assert accepted.status == "queued" and accepted.plan_id != ahead.plan_id
    events: List[object] = []
    with api.plan_events(accepted.plan_id) as stream:
        for event in stream:
            events.append(event)
            if isinstance(event, StatusEvent) and event.plan.is_final:
                break
    first, last = events[0], events[-1]
    assert isinstance(first, StatusEvent) and first.plan.status in ("queued", "planning")
    assert isinstance(last, StatusEvent) and last.plan.status == "ready", last
    statuses = [e.plan.status for e in events if isinstance(e, StatusEvent)]
    assert "planning" in statuses
    progress = [e.progress for e in events if isinstance(e, ProgressEvent)]
    assert progress and progress == sorted(progress) and all(0.0 <= p <= 1.0 for p in progress)
    regions = [e for e in events if isinstance(e, RegionReadyEvent)]
    assert regions and all(len(r.path) >= 2 and len(r.polygon) >= 3 for r in regions)

    info = api.wait_for_plan(accepted.plan_id)
    assert info.status == "ready" and info.version == 1 and info.progress == pytest.approx(1.0)
    assert info.metrics is not None and info.metrics.coverage_pct > 90.0 and info.metrics.collisions == 0
    doc = api.get_path(accepted.plan_id)
    assert (doc.plan_id, doc.version, doc.frame) == (accepted.plan_id, 1, "map")
    assert len(doc.waypoints) > 10 and {w.kind for w in doc.waypoints} <= {"cover", "transit"}
    assert {r.region for r in regions} == {r.id for r in doc.regions}
    assert doc.metrics == info.metrics

    profile = api.get_speed_profile(accepted.plan_id)
    assert (profile.plan_id, profile.version) == (accepted.plan_id, 1)
    assert len(profile.samples) == len(doc.waypoints)
    assert [s.v for s in profile.samples] == [w.v for w in doc.waypoints]
    assert [s.t for s in profile.samples] == [w.t for w in doc.waypoints]
    arcs = [s.s for s in profile.samples]
    assert arcs[0] == 0.0 and arcs == sorted(arcs)
    assert arcs[-1] == pytest.approx(doc.metrics.length_m, rel=0.02)
    assert all(0.1 - 1e-9 <= w.v <= 1.0 + 1e-9 for w in doc.waypoints)
    assert api.wait_for_plan(ahead.plan_id).status == "ready"


def test_cancel_a_queued_plan(api: Client) -> None:
    ahead = api.create_plan(DEMO)
    queued = api.create_plan(DEMO)
    cancelled = api.cancel_plan(queued.plan_id)
    assert (cancelled.plan_id, cancelled.status) == (queued.plan_id, "cancelled")
    assert api.get_plan(queued.plan_id).status == "cancelled"
    # A cancelled plan's stream is its status alone.
    with api.plan_events(queued.plan_id) as stream:
        only = list(stream)
    assert len(only) == 1 and isinstance(only[0], StatusEvent) and only[0].plan.status == "cancelled"
    for call in (lambda: api.get_path(queued.plan_id), lambda: api.assign_plan(queued.plan_id, "r1")):
        with pytest.raises(ShiftError) as e:
            call()
        assert e.value.status == 409
    # Frees the worker for the other tests; a plan that already finished answers 409.
    try:
        assert api.cancel_plan(ahead.plan_id).status == "cancelled"
    except ShiftError as e:
        assert e.status == 409 and api.get_plan(ahead.plan_id).status == "ready"


def test_mutating_routes_need_the_bearer_token(token_daemon: Daemon) -> None:
    with Client(token_daemon.url) as anonymous:
        assert anonymous.get_site("demo").site == "demo", "reads are open"
        with pytest.raises(ShiftError) as e:
            anonymous.create_plan(DEMO)
        assert (e.value.status, e.value.code) == (401, "unauthorized")
    with Client(token_daemon.url, token="wrong") as wrong:
        with pytest.raises(ShiftError) as e:
            wrong.upload_grid("x", room_grid(10, 10, 0.1))
        assert (e.value.status, e.value.code) == (403, "forbidden")
    with Client(token_daemon.url, token=token_daemon.token) as authorised:
        accepted = authorised.create_plan(DEMO)
        assert authorised.wait_for_plan(accepted.plan_id).status == "ready"


def test_a_full_queue_says_when_to_come_back_and_create_plan_can_wait(busy_daemon: Daemon) -> None:
    with Client(busy_daemon.url) as api:
        accepted: List[str] = []
        refused = None
        for _ in range(200):
            try:
                accepted.append(api.create_plan(DEMO).plan_id)
            except ShiftError as e:
                refused = e
                break
        assert refused is not None, f"{len(accepted)} plans accepted, none refused"
        assert (refused.status, refused.code, refused.retry_after_s) == (429, "queue_full", 1.0)
        # Waiting as the daemon asks, the same request gets in once the worker frees a place.
        late = api.create_plan(DEMO, busy_wait_s=120.0)
        for plan_id in accepted + [late.plan_id]:
            assert api.wait_for_plan(plan_id).status == "ready"
        # Without a wait the 429 is raised at once.
        with pytest.raises(ShiftError) as e:
            for _ in range(200):
                api.create_plan(DEMO)
        assert e.value.status == 429
