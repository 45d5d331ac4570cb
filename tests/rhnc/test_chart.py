"""Charts: the local projection, land and no-go polygons with a clearance, clearance along a track's chords."""

import json

import numpy as np
import pytest

from orchestrator.errors import ScenarioError
from orchestrator.geometry import NM
from rhnc.chart.chart import load_chart
from rhnc.chart.clearance import track_clearance
from rhnc.chart.projection import LocalProjection, wrap_longitude_deg

ORIGIN = (51.0, 1.5)


def square(lat0, lon0, lat1, lon1):
    return {"type": "Polygon", "coordinates": [[[lon0, lat0], [lon1, lat0], [lon1, lat1], [lon0, lat1], [lon0, lat0]]]}


def write_chart(tmp_path, areas, clearance_nm=1.0, extra=""):
    (tmp_path / "islands.geojson").write_text(json.dumps(
        {"type": "FeatureCollection",
         "features": [{"type": "Feature", "properties": {"name": name}, "geometry": geometry}
                      for name, geometry in areas]}))
    chart = tmp_path / "passage.chart.toml"
    chart.write_text(f'origin_deg = [{ORIGIN[0]}, {ORIGIN[1]}]\nclearance_nm = {clearance_nm}\n'
                     f'no_go = ["islands.geojson"]\n{extra}')
    return chart


def test_projection_keeps_distances_from_the_origin_and_returns():
    projection = LocalProjection(*ORIGIN)
    north, east = projection.to_local(ORIGIN[0] + 1.0, ORIGIN[1])
    assert east == pytest.approx(0.0, abs=1e-6)
    assert north == pytest.approx(111_257.0, rel=1e-3)  # one degree of latitude at 51.5 N on WGS84
    lat, lon = projection.to_geographic(*projection.to_local(50.2, 2.9))
    assert (lat, lon) == pytest.approx((50.2, 2.9), abs=1e-9)


def test_longitudes_from_0_to_360_are_the_same_places():
    projection = LocalProjection(36.0, -5.5)
    assert np.allclose(projection.to_local(36.1, 354.4), projection.to_local(36.1, -5.6), atol=1e-6, rtol=0)
    assert projection.to_local(36.1, -5.6)[1] == pytest.approx(-9005.0, abs=1.0)  # 0.1 deg west at 36.1 N
    assert wrap_longitude_deg(359.0) == pytest.approx(-1.0)


def test_a_leg_across_an_island_is_not_clear_though_both_ends_are(tmp_path):
    chart = load_chart(write_chart(tmp_path, [("island", square(51.0, 1.5, 51.02, 1.52))]))
    projection = chart.projection
    a = np.column_stack(projection.to_local(51.01, 1.3))  # ~7 nm west of the island
    b = np.column_stack(projection.to_local(51.01, 1.7))  # ~7 nm east of it
    assert chart.distances_m(a[:, 0], a[:, 1])[0] > 5 * NM
    assert chart.distances_m(b[:, 0], b[:, 1])[0] > 5 * NM
    assert not chart.legs_clear(a, b)[0]
    assert chart.leg_distances_m(a, b)[0] == 0.0
    north_of_it = np.column_stack(projection.to_local(51.05, 1.3)), np.column_stack(projection.to_local(51.05, 1.7))
    assert chart.legs_clear(*north_of_it)[0]  # 1.8 nm north of the island, clearance 1 nm


def test_a_leg_inside_the_clearance_is_not_clear(tmp_path):
    chart = load_chart(write_chart(tmp_path, [("island", square(51.0, 1.5, 51.02, 1.52))], clearance_nm=2.0))
    projection = chart.projection
    a = np.column_stack(projection.to_local(51.05, 1.3))
    b = np.column_stack(projection.to_local(51.05, 1.7))
    distance = chart.leg_distances_m(a, b)[0] / NM
    assert 1.5 < distance < 2.0
    assert not chart.legs_clear(a, b)[0]


def test_clearance_along_chords_finds_where_and_when(tmp_path):
    chart = load_chart(write_chart(tmp_path, [("island", square(51.0, 1.5, 51.02, 1.52))], clearance_nm=0.5))
    projection = chart.projection
    north, east = projection.to_local(np.array([51.01, 51.01]), np.array([1.3, 1.7]))
    result = track_clearance(chart, [0.0, 1000.0], north, east)
    assert result["crossed"] and not result["kept"]
    assert result["min_clearance_nm"] == 0.0
    closest = result["closest"]
    assert closest["area"] == "island"
    assert closest["lon_deg"] == pytest.approx(1.5, abs=1e-3)  # enters the island on its west side
    assert closest["lat_deg"] == pytest.approx(51.01, abs=1e-3)
    expected_time = 1000.0 * (0 - east[0]) / (east[1] - east[0])  # the island's west edge is the origin's meridian
    assert closest["time_s"] == pytest.approx(expected_time, rel=2e-3)


def test_clearance_of_a_track_that_keeps_away(tmp_path):
    chart = load_chart(write_chart(tmp_path, [("island", square(51.0, 1.5, 51.02, 1.52))], clearance_nm=1.0))
    north, east = chart.projection.to_local(np.array([51.05, 51.05, 51.05]), np.array([1.3, 1.5, 1.7]))
    result = track_clearance(chart, [0.0, 500.0, 1000.0], north, east)
    assert result["kept"] and not result["crossed"]
    assert result["min_clearance_nm"] == pytest.approx((51.05 - 51.02) * 60.0, rel=0.01)
    assert result["per_area"]["island"] == pytest.approx(result["min_clearance_nm"])


def test_a_geojson_that_is_not_polygons_is_refused_naming_file_and_feature(tmp_path):
    line = {"type": "LineString", "coordinates": [[1.0, 51.0], [1.1, 51.1]]}
    with pytest.raises(ScenarioError, match=r"islands.geojson: feature 1 \(lane\): expected a Polygon or "
                                            r"MultiPolygon geometry, got LineString"):
        load_chart(write_chart(tmp_path, [("island", square(51.0, 1.5, 51.02, 1.52)), ("lane", line)]))


@pytest.mark.parametrize("text, match", [
    ('origin_deg = [51.0]\nclearance_nm = 1.0\n', "origin_deg: expected"),
    ('origin_deg = [51.0, 1.0]\nclearance_nm = -1.0\n', "clearance_nm: expected a non-negative"),
    ('origin_deg = [51.0, 1.0]\nclearance_nm = 1.0\nno_go = ["missing.geojson"]\n', r"no_go\[0\]: GeoJSON file not found"),
    ('origin_deg = [51.0, 1.0]\nclearance_nm = 1.0\ncoast = "x"\n', "unknown key 'coast'"),
])
def test_bad_chart_files_name_the_key(tmp_path, text, match):
    path = tmp_path / "bad.chart.toml"
    path.write_text(text)
    with pytest.raises(ScenarioError, match=f"bad.chart.toml: {match}"):
        load_chart(path)


def test_a_leg_from_inside_the_clearance_may_lead_out_but_not_closer(tmp_path):
    chart = load_chart(write_chart(tmp_path, [("island", square(51.0, 1.5, 51.02, 1.52))], clearance_nm=2.0))
    projection = chart.projection
    inside = np.column_stack(projection.to_local(51.03, 1.51))  # 0.6 nm north of the island
    away = np.column_stack(projection.to_local(51.08, 1.51))
    along = np.column_stack(projection.to_local(51.025, 1.6))  # passes 0.3 nm off it
    assert chart.legs_clear(inside, away)[0]
    assert not chart.legs_clear(inside, along)[0]


@pytest.mark.slow  # imports global-land-mask: 0.9 GB unpacked, about 10 s
def test_the_shipped_coastline_is_the_land_mask_cell_for_cell():
    import shapely
    from global_land_mask import globe
    from pathlib import Path

    path = Path(__file__).resolve().parents[2] / "scenarios" / "passages" / "gibraltar_strait.land.geojson"
    document = json.loads(path.read_text())
    south, west, north, east = document["properties"]["bounds_deg"]
    land = shapely.union_all([shapely.geometry.shape(f["geometry"]) for f in document["features"]])
    rng = np.random.default_rng(7)
    # cell centres, so that a point is never on a cell edge
    lat = (np.floor(rng.uniform(south, north, 3000) * 120) + 0.5) / 120
    lon = (np.floor(rng.uniform(west, east, 3000) * 120) + 0.5) / 120
    inside = shapely.contains_xy(land, lon, lat)
    np.testing.assert_array_equal(inside, globe.is_land(lat, lon))
    assert 0.2 < inside.mean() < 0.8  # both land and sea are sampled
