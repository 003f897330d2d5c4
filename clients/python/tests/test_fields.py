"""Fields in WGS84 through the Python client against the real shiftd: a GeoJSON field with a hole, a plan from
a start in lon/lat, the path back as GeoJSON in [lon, lat], and a refusal naming the field."""

from __future__ import annotations

from typing import Iterator, List, Sequence, Tuple

import pytest

from shift_client import Client, PlanRequest, RobotSpec, ShiftError

from conftest import Daemon

LON0, LAT0 = 8.55, 47.37
M_PER_DEG_LAT, M_PER_DEG_LON = 111_180.0, 75_480.0


def ll(x: float, y: float) -> Tuple[float, float]:
    """(lon, lat) of the point x m east, y m north of the field's corner."""
    return (LON0 + x / M_PER_DEG_LON, LAT0 + y / M_PER_DEG_LAT)


def ring(pts: Sequence[Tuple[float, float]]) -> List[List[float]]:
    r = [list(ll(x, y)) for x, y in pts]
    return r + [r[0]]


def inside(p: Sequence[float], r: Sequence[Sequence[float]]) -> bool:
    """Even-odd point-in-ring test in degrees."""
    hit, n = False, len(r)
    for i in range(n):
        (xi, yi), (xj, yj) = r[i], r[i - 1]
        if (yi > p[1]) != (yj > p[1]) and p[0] < (xj - xi) * (p[1] - yi) / (yj - yi) + xi:
            hit = not hit
    return hit


OUTER = ring([(0, 0), (160, 0), (160, 100), (0, 100)])
POND = ring([(60, 40), (90, 40), (90, 65), (60, 65)])


@pytest.fixture()
def api(daemon: Daemon) -> Iterator[Client]:
    with Client(daemon.url) as c:
        yield c


def test_a_field_plans_from_lon_lat_and_comes_back_as_geojson(api: Client) -> None:
    site = api.upload_field("south", {"type": "Polygon", "coordinates": [OUTER, POND]}, tool_width=2.0)
    assert site.crs is not None and "etmerc" in site.crs
    assert site.origin_wgs84 is not None
    assert abs(site.origin_wgs84[0] - ll(80, 50)[0]) < 1e-6 and abs(site.origin_wgs84[1] - ll(80, 50)[1]) < 1e-6
    req = PlanRequest(site="south", start=None, start_wgs84=ll(4, 4), robot=RobotSpec(radius=0.9, tool_width=2.0))
    info = api.wait_for_plan(api.create_plan(req).plan_id, timeout=180)
    assert info.status == "ready", info
    assert info.metrics is not None and info.metrics.coverage_pct >= 99.0
    feature = api.get_path_geojson(info.plan_id)
    assert feature["type"] == "Feature" and feature["geometry"]["type"] == "LineString"
    line = feature["geometry"]["coordinates"]
    assert len(line) == len(feature["properties"]["v"]) == len(feature["properties"]["t"]) > 10
    for p in line:
        assert abs(p[0] - LON0) < 0.01 and abs(p[1] - LAT0) < 0.01, p  # [lon, lat] order
        assert inside(p, OUTER) and not inside(p, POND), p


def test_a_bad_field_is_refused_naming_where(api: Client) -> None:
    bow_tie = {"type": "Polygon", "coordinates": [ring([(0, 0), (50, 50), (50, 0), (0, 50)])]}
    with pytest.raises(ShiftError) as err:
        api.upload_field("bad", bow_tie)
    assert err.value.status == 400 and "field.coordinates" in str(err.value)
    with pytest.raises(ShiftError) as err:
        api.get_site("bad")
    assert err.value.status == 404
