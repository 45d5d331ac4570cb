"""Passages on a chart: a track that crosses land is flagged, bad passage input stops with one line (exit 2)."""

import json
import re
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest

from orchestrator.cli import main
from orchestrator.geometry import NM
from rhnc.chart.chart import load_chart
from rhnc.cosim.chart_outputs import clearance_analysis

PASSAGES = Path(__file__).resolve().parents[2] / "scenarios" / "passages"


def gibraltar_copy(tmp_path, replace=()):
    """The strait scenario in ``tmp_path`` with its files named absolutely, ``replace`` applied."""
    text = (PASSAGES / "gibraltar_strait.toml").read_text()
    text = text.replace('"weather/', f'"{PASSAGES}/weather/').replace('"gibraltar_strait.chart.toml"',
                                                                      f'"{PASSAGES}/gibraltar_strait.chart.toml"')
    for old, new in replace:
        assert old in text
        text = text.replace(old, new)
    path = tmp_path / "passage.toml"
    path.write_text(text)
    return path


def ship(name="ship"):
    return SimpleNamespace(name=name, output_names=("x", "y", "psi", "u"))


def test_a_track_across_land_is_flagged_with_where_and_when(tmp_path):
    chart = load_chart(PASSAGES / "gibraltar_strait.chart.toml")
    # a straight line from the strait's east entrance to its west one through Morocco
    start = chart.projection.to_local(36.0, -5.2)
    end = chart.projection.to_local(35.75, -6.0)
    frame = pd.DataFrame({"time_s": [0.0, 3600.0], "ship.x": [start[0], end[0]], "ship.y": [start[1], end[1]]})
    cosim = SimpleNamespace(participants=[ship(), SimpleNamespace(name="nav", output_names=(), chart=chart)])
    scenario = SimpleNamespace(directory=PASSAGES)
    result = clearance_analysis(frame, scenario, cosim, tmp_path)
    assert result["crossed"] and not result["kept"]
    assert result["closest"]["kind"] == "land"
    assert 35.75 < result["closest"]["lat_deg"] < 36.0 and 0.0 < result["closest"]["time_s"] < 3600.0
    track = np.loadtxt(tmp_path / "track_geographic.csv", delimiter=",", skiprows=1)
    np.testing.assert_allclose(track[:, 3:], [[36.0, -5.2], [35.75, -6.0]], atol=1e-7)


def test_the_shipped_strait_route_keeps_clear_of_the_drawn_zone_and_land():
    chart = load_chart(PASSAGES / "gibraltar_strait.chart.toml")
    assert {area.kind for area in chart.areas} == {"land", "no_go"}
    assert chart.clearance_m == pytest.approx(1.0 * NM)
    start = chart.projection.to_local(36.08, -4.95)
    assert chart.distances_m([start[0]], [start[1]])[0] > chart.clearance_m


def test_a_start_on_land_stops_the_run_naming_the_key(tmp_path, capsys):
    path = gibraltar_copy(tmp_path, [("start_deg = [36.08, -4.95]\ngoal_deg",
                                      "start_nm = [12.0, 50.0]  # Morocco, near Ceuta\ngoal_deg")])
    code = main(["run", str(path), "--results", str(tmp_path / "results"), "--no-progress"])
    err = capsys.readouterr().err
    assert code == 2
    assert re.search(r"participants.nav.options.start_nm: \(22224, 92600\) m lies on land or in a no-go area", err)
    assert not (tmp_path / "results").exists()


def test_a_start_on_land_in_latitude_and_longitude_is_refused_naming_that_key(tmp_path, capsys):
    path = gibraltar_copy(tmp_path, [("start_deg = [36.08, -4.95]\ngoal_deg",
                                      "start_deg = [35.85, -5.35]  # Morocco, near Ceuta\ngoal_deg")])
    code = main(["run", str(path), "--results", str(tmp_path / "results"), "--no-progress"])
    err = capsys.readouterr().err
    assert code == 2 and len(err.strip().splitlines()) == 1
    assert re.search(r"participants.nav.options.start_deg: \(\d+, \d+\) m lies on land or in a no-go area", err)
    assert not (tmp_path / "results").exists()


def test_a_no_go_file_that_is_not_polygons_stops_the_run(tmp_path, capsys):
    (tmp_path / "lanes.geojson").write_text(json.dumps(
        {"type": "Feature", "properties": {"name": "lane"},
         "geometry": {"type": "LineString", "coordinates": [[-5.6, 35.95], [-5.4, 35.95]]}}))
    (tmp_path / "strait.chart.toml").write_text('origin_deg = [35.65, -6.45]\nclearance_nm = 1.0\n'
                                                'no_go = ["lanes.geojson"]\n')
    path = gibraltar_copy(tmp_path, [(f'chart = "{PASSAGES}/gibraltar_strait.chart.toml"',
                                      f'chart = "{tmp_path}/strait.chart.toml"')])
    code = main(["run", str(path), "--results", str(tmp_path / "results"), "--no-progress"])
    err = capsys.readouterr().err
    assert code == 2
    assert "lanes.geojson: feature 0 (lane): expected a Polygon or MultiPolygon geometry, got LineString" in err
    assert len(err.strip().splitlines()) == 1
    assert not (tmp_path / "results").exists()


def test_a_weather_file_missing_a_variable_stops_the_run(tmp_path, capsys):
    import netCDF4
    import shutil

    shutil.copy(PASSAGES / "weather" / "gibraltar_strait_era5.nc", tmp_path / "era5.nc")
    with netCDF4.Dataset(tmp_path / "era5.nc", "a") as ds:
        ds.renameVariable("swh", "dropped")
    path = gibraltar_copy(tmp_path, [(f'file = "{PASSAGES}/weather/gibraltar_strait_era5.nc"',
                                      f'file = "{tmp_path}/era5.nc"')])
    code = main(["run", str(path), "--results", str(tmp_path / "results"), "--no-progress"])
    err = capsys.readouterr().err
    assert code == 2
    assert re.search(r"passage.toml: metocean: .*era5.nc: no variable for hs \(looked for swh", err)
    assert not (tmp_path / "results").exists()
