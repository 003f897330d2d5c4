"""The wire rules the client shares with proto, without a daemon: key expressions, the correction rule, SSE
parsing, the PointCloud2 CDR layout, error bodies."""

from __future__ import annotations

import pickle
import struct
from datetime import datetime, timezone

import pytest

from shift_client import (
    Correction,
    CorrectionError,
    CorrectionEvent,
    KeySpace,
    OccupancyGrid,
    PlanDocument,
    PlanRequest,
    ProgressEvent,
    RegionReadyEvent,
    RobotSpec,
    ShiftError,
    StatusEvent,
    UnknownEvent,
    VersionGap,
    Waypoint,
)
from shift_client.cdr import encode_point_cloud2_xyz, split_stamp
from shift_client.errors import parse_retry_after
from shift_client.events import decode_messages, iter_sse
from shift_client.keys import InvalidName
from shift_client.types import AttributeBlob, PlanOptions


def test_keys_follow_design_5_4_like_proto() -> None:
    ks = KeySpace()
    assert ks.odom("r1") == "shift/default/robots/r1/odom"
    assert ks.cloud("r1") == "shift/default/robots/r1/cloud"
    assert ks.scan("r1") == "shift/default/robots/r1/scan"
    assert ks.plan("r1") == "shift/default/robots/r1/plan"
    assert ks.plan_path("r1") == "shift/default/robots/r1/plan_path"
    assert ks.corrections("r1") == "shift/default/robots/r1/corrections"
    assert ks.alive("r1") == "shift/default/robots/r1/alive"
    assert ks.plan_status("p-42") == "shift/default/plans/p-42/status"
    assert KeySpace("acme/shift", "north").odom("bot_7") == "acme/shift/north/robots/bot_7/odom"
    assert ks.odom("robot-1_b") == "shift/default/robots/robot-1_b/odom"


@pytest.mark.parametrize(
    "bad", ["", "a/b", "r*", "r$1", "r#", "r?", "r 1", "@r", "tab\t", ".", "..", "r.1", "é", "x" * 65]
)
def test_invalid_robot_names_are_refused(bad: str) -> None:
    with pytest.raises(InvalidName) as e:
        KeySpace().odom(bad)
    assert e.value.what == "robot name"
    with pytest.raises(InvalidName):
        KeySpace().plan_status(bad)


@pytest.mark.parametrize("prefix", ["", "/shift", "shift/", "a//b", "sh*ft"])
def test_invalid_prefixes_are_refused(prefix: str) -> None:
    with pytest.raises(InvalidName) as e:
        KeySpace(prefix, "f")
    assert e.value.what == "prefix"


def test_invalid_name_message_matches_proto() -> None:
    with pytest.raises(InvalidName) as e:
        KeySpace().odom("a/b")
    assert str(e.value) == "invalid robot name `a/b`: may hold only letters, digits, '-' and '_'"


def _wp(x: float, t: float) -> Waypoint:
    return Waypoint(x=x, y=0.0, z=0.0, v=0.5, t=t, kind="cover", region=1)


def _doc(n: int) -> PlanDocument:
    return PlanDocument("p-1", 1, "map", [_wp(float(i), 2.0 * i) for i in range(n)], [], None)


def _corr(base: int, frm: int, to: int, new: list, dt: float = 0.0, plan: str = "p-1") -> Correction:
    return Correction(plan, "r1", base, base + 1, frm, to, new, "obstacle", 10, dt_after_s=dt)


def test_correction_replaces_the_range_and_shifts_later_times() -> None:
    out = _corr(1, 2, 3, [_wp(1.5, 3.0), _wp(2.5, 5.5)], dt=1.5).apply(_doc(5))
    assert out.version == 2
    assert [w.x for w in out.waypoints] == [0.0, 1.0, 1.5, 2.5, 3.0, 4.0]
    assert out.waypoints[4].t == 6.0 + 1.5
    assert out.waypoints[1].t == 2.0


def test_correction_refuses_gaps_ranges_versions_and_other_plans() -> None:
    d = _doc(3)
    with pytest.raises(VersionGap) as gap:
        _corr(2, 0, 1, []).apply(d)
    assert (gap.value.base, gap.value.have) == (2, 1)
    with pytest.raises(CorrectionError, match="range"):
        _corr(1, 2, 4, []).apply(d)
    bad = Correction("p-1", "r1", 1, 5, 0, 0, [], "obstacle", 1)
    with pytest.raises(CorrectionError, match="does not follow"):
        bad.apply(d)
    with pytest.raises(CorrectionError, match="plan p-2"):
        _corr(1, 0, 0, [], plan="p-2").apply(d)


def test_correction_chain_applies_in_order_and_a_stale_copy_refuses_the_next() -> None:
    doc = _doc(12)
    for k, (frm, span, n) in enumerate([(3, 2, 4), (0, 0, 1), (10, 5, 0), (7, 1, 2)]):
        to = min(frm + span, len(doc.waypoints))
        new = [_wp(100.0 + k + 0.1 * i, 0.0) for i in range(n)]
        c = _corr(doc.version, frm, to, new, dt=0.5)
        nxt = c.apply(doc)
        assert len(nxt.waypoints) == len(doc.waypoints) - (to - frm) + n
        assert nxt.waypoints[:frm] == doc.waypoints[:frm]
        assert nxt.waypoints[frm : frm + n] == new
        with pytest.raises(VersionGap):
            c.apply(nxt)
        doc = nxt
    assert doc.version == 5


def test_correction_parses_the_wire_form() -> None:
    c = Correction.from_json(
        {
            "plan_id": "p-3", "robot": "r1", "base_version": 4, "version": 5, "from": 7, "to": 9,
            "waypoints": [{"x": 1, "y": 2, "z": 0, "v": 0.3, "t": 4.5, "kind": "transit"}],
            "reason": "skipped", "dt_after_s": 0.25, "skipped": [[1, 2], [3, 4]], "compute_us": 812,
        }
    )
    assert (c.from_, c.to, c.base_version, c.version) == (7, 9, 4, 5)
    assert c.waypoints[0].region is None and c.waypoints[0].kind == "transit"
    assert c.skipped == [(1.0, 2.0), (3.0, 4.0)]


def test_sse_stream_parses_into_typed_events() -> None:
    status = (
        '{"type":"status","plan_id":"p-1","site":"demo","status":"planning","progress":0.25,"version":0,'
        '"regions_ready":1,"created_ms":1,"updated_ms":2,"corrections":0}'
    )
    lines = [
        ": keep-alive",
        "event: status",
        f"data: {status}",
        "",
        "event: progress",
        'data:{"type":"progress","plan_id":"p-1","progress":0.5}',
        "",
        "event: region-ready",
        'data: {"type":"region-ready","plan_id":"p-1",',
        'data: "region":{"region":3,"polygon":[[0,0],[1,0],[1,1]],"path":[[0.5,0.5],[0.6,0.5]]}}',
        "",
        "event: correction",
        'data: {"type":"correction","plan_id":"p-1","robot":"r1","base_version":1,"version":2,"from":0,'
        '"to":1,"waypoints":[],"reason":"obstacle","compute_us":5}',
        "",
        "event: weather",
        'data: {"type":"weather","rain":true}',
        "",
        "event: progress",
        'data: {"type":"progress","plan_id":"p-1","progress":0.9}',
    ]
    events = list(decode_messages(iter_sse(lines)))
    assert len(events) == 5, "the unterminated last message is not dispatched"
    assert isinstance(events[0], StatusEvent) and events[0].plan.status == "planning"
    assert not events[0].plan.is_final
    assert events[1] == ProgressEvent("p-1", 0.5)
    assert isinstance(events[2], RegionReadyEvent) and events[2].region == 3
    assert events[2].path == [(0.5, 0.5), (0.6, 0.5)]
    assert isinstance(events[3], CorrectionEvent) and events[3].correction.version == 2
    assert events[4] == UnknownEvent("weather", {"type": "weather", "rain": True})


def test_point_cloud2_layout_is_plain_cdr_with_aligned_fields() -> None:
    got = encode_point_cloud2_xyz([(1.0, -2.0, 0.5)], "map", 3.25)
    expected = b"\x00\x01\x00\x00"
    expected += struct.pack("<iI", 3, 250_000_000)
    expected += struct.pack("<I", 4) + b"map\x00"
    expected += struct.pack("<III", 1, 1, 3)  # height, width, 3 fields
    for i, name in enumerate(b"xyz"):
        # name (u32 length 2, "n\0", 2 bytes padding), offset u32, datatype u8 + 3 padding, count u32
        expected += struct.pack("<I", 2) + bytes([name, 0]) + b"\x00\x00"
        expected += struct.pack("<I", 4 * i) + b"\x07\x00\x00\x00" + struct.pack("<I", 1)
    expected += b"\x00\x00\x00\x00"  # is_bigendian false + padding
    expected += struct.pack("<III", 12, 12, 12)  # point_step, row_step, data length
    expected += struct.pack("<fff", 1.0, -2.0, 0.5) + b"\x01"  # is_dense
    assert got == expected
    assert encode_point_cloud2_xyz([(float("nan"), 0, 0)])[-1] == 0
    assert split_stamp(-1.5) == (-2, 500_000_000)


def test_error_bodies_become_one_exception() -> None:
    e = ShiftError.from_response(404, b'{"error": {"code": "not_found", "message": "unknown plan \\"p-9\\""}}')
    assert (e.status, e.code, e.message) == (404, "not_found", 'unknown plan "p-9"')
    plain = ShiftError.from_response(502, b"Bad Gateway\n")
    assert (plain.status, plain.code, plain.message) == (502, "http_502", "Bad Gateway")


def test_requests_serialise_to_the_api_shape() -> None:
    req = PlanRequest(
        site="demo",
        start=(0.5, 0.5),
        robot=RobotSpec(0.15, 0.3, v_max=0.8),
        attribute=[AttributeBlob(1.0, 1.0, 0.5, 0.9)],
        region=[(0, 0), (4, 0), (4, 4)],
        options=PlanOptions(decomposition="bcd", seed=7),
    )
    assert req.to_json() == {
        "site": "demo",
        "start": [0.5, 0.5],
        "robot": {"radius": 0.15, "tool_width": 0.3, "v_min": 0.1, "v_max": 0.8, "a_max": 0.5},
        "attribute": {"blobs": [{"x": 1.0, "y": 1.0, "sigma": 0.5, "amplitude": 0.9}]},
        "region": [[0.0, 0.0], [4.0, 0.0], [4.0, 4.0]],
        "options": {"decomposition": "bcd", "seed": 7},
    }
    with pytest.raises(ValueError, match="cells"):
        OccupancyGrid(0.05, (0.0, 0.0), 3, 2, [0] * 5)


def test_plan_documents_round_trip() -> None:
    doc = PlanDocument.from_json(
        {
            "plan_id": "p-1", "version": 3, "frame": "map",
            "waypoints": [{"x": 1.0, "y": 2.0, "z": 0.0, "v": 0.4, "t": 12.5, "kind": "cover", "region": 2}],
            "regions": [{"id": 2, "polygon": [[0, 0], [3, 0], [3, 3], [0, 3]]}],
            "metrics": {"coverage_pct": 99.6, "overlap_pct": 3.1, "length_m": 201.0, "turns": 80,
                        "collisions": 0, "duration_s": 640.0, "compute_ms": 42.0},
        }
    )
    assert doc.waypoints[0] == Waypoint(1.0, 2.0, 0.0, 0.4, 12.5, "cover", 2)
    assert doc.regions[0].polygon[2] == (3.0, 3.0)
    assert doc.metrics is not None and doc.metrics.turns == 80 and doc.metrics.dwell_cv is None
    assert PlanDocument.from_json(doc.to_json()) == doc


def test_retry_after_reads_seconds_and_http_dates() -> None:
    now = datetime(2026, 12, 3, 12, 0, 0, tzinfo=timezone.utc)
    assert parse_retry_after("5") == 5.0
    assert parse_retry_after(" 0 ") == 0.0
    assert parse_retry_after("Thu, 03 Dec 2026 12:00:30 GMT", now) == 30.0
    assert parse_retry_after("Thu, 03 Dec 2026 11:00:00 GMT", now) == 0.0, "a date gone by waits nothing"
    assert parse_retry_after("soon") is None
    assert parse_retry_after("-3") is None
    assert parse_retry_after(None) is None
    e = ShiftError.from_response(429, b'{"error": {"code": "queue_full", "message": "full"}}', {"retry-after": "7"})
    assert (e.code, e.retry_after_s) == ("queue_full", 7.0)
    assert pickle.loads(pickle.dumps(e)).retry_after_s == 7.0
