"""Met-ocean data: the paper's generated field, NetCDF round trips, ERA5-style files, errors."""

from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from orchestrator.errors import ScenarioError
from orchestrator.geometry import NM
from rhnc.weather.metocean import MetOceanField, fetch_limited_hs
from rhnc.weather.metocean_sources import from_netcdf, from_scenario_table
from rhnc.weather.weather_generators import paper_default


def test_paper_default_field_is_plausible():
    field = paper_default()
    assert field.x.size == field.y.size == 101
    assert field.extent == (0.0, 100 * NM, 0.0, 100 * NM)
    # the spline passes through the control points at the lattice nodes
    assert field.wind_speed[50, 50] == pytest.approx(18.0)
    assert field.wind_speed[0, 0] == pytest.approx(8.0)
    np.testing.assert_allclose(field.wind_direction, np.radians(45.0))
    assert np.all(field.hs > 0) and np.all(field.hs <= 0.21 * field.wind_speed**2 / 9.81 + 1e-12)
    np.testing.assert_allclose(np.hypot(field.current_north, field.current_east), 0.5 * 1852 / 3600)


def test_fetch_limited_hs_by_hand():
    # U = 15 m/s, F = 100 km: 0.0016 * 15 * sqrt(1e5 / 9.81) = 2.4231 m (below PM's 4.82 m)
    assert fetch_limited_hs(15.0, 100e3) == pytest.approx(0.0016 * 15 * np.sqrt(1e5 / 9.81))
    # short wind over a long fetch is capped by the fully developed sea: 0.21 * 5^2 / 9.81
    assert fetch_limited_hs(5.0, 1e7) == pytest.approx(0.21 * 25 / 9.81)


def test_sample_is_bilinear_and_refuses_outside_points():
    x = np.array([0.0, 1000.0])
    y = np.array([0.0, 2000.0])
    values = {name: np.array([[0.0, 2.0], [4.0, 6.0]]) for name in
              ("wind_north", "wind_east", "hs", "current_north", "current_east")}
    field = MetOceanField(x, y, values)
    sample = field.sample(500.0, 1000.0)
    assert sample["hs"] == pytest.approx(3.0)
    assert field.sample(250.0, 0.0)["current_east"] == pytest.approx(1.0)
    with pytest.raises(ValueError, match=r"x=1001.0 m, y=0.0 m lies outside the met-ocean grid"):
        field.sample([0.0, 1001.0], [0.0, 0.0])


def test_netcdf_round_trip_keeps_cf_names(tmp_path):
    field = paper_default(resolution_nm=5.0)
    path = field.to_netcdf(tmp_path / "weather.nc")
    with xr.open_dataset(path) as ds:
        assert {"u10", "v10", "swh", "uo", "vo"} <= set(ds.data_vars)
        assert ds["swh"].attrs["standard_name"] == "sea_surface_wave_significant_height"
    again = from_netcdf(path)
    for name in ("wind_north", "wind_east", "hs", "current_north", "current_east"):
        np.testing.assert_array_equal(getattr(again, name), getattr(field, name))


def test_era5_style_latitude_longitude_file(tmp_path):
    lat = np.linspace(51.0, 50.0, 11)  # ERA5 stores latitude north to south
    lon = np.linspace(-5.0, -3.0, 21)
    shape = (2, lat.size, lon.size)
    u10 = np.broadcast_to(np.linspace(0, 10, lon.size), shape) * np.array([1.0, 2.0])[:, None, None]
    ds = xr.Dataset(
        {"u10": (("time", "latitude", "longitude"), u10),  # towards east, growing eastward, doubling in 1 h
         "v10": (("time", "latitude", "longitude"), np.zeros(shape)),
         "swh": (("time", "latitude", "longitude"), np.full(shape, 2.0))},
        coords={"latitude": lat, "longitude": lon,
                "time": ("time", [1067868, 1067869], {"units": "hours since 1900-01-01 00:00:00.0"})},
    )
    ds.to_netcdf(tmp_path / "era5.nc")
    everything = from_netcdf(tmp_path / "era5.nc")
    np.testing.assert_array_equal(everything.times_s, [0.0, 3600.0])  # every time step, since the first
    np.testing.assert_allclose(everything.wind_speed[1], 2 * everything.wind_speed[0])
    field = from_netcdf(tmp_path / "era5.nc", time_index=0)
    assert not field.is_time_varying
    assert field.x[0] == 0.0 and field.y[0] == 0.0
    assert field.x[-1] == pytest.approx(np.radians(1.0) * 6_371_000, rel=0.01)
    np.testing.assert_allclose(field.wind_direction[:, 1:], 1.5 * np.pi)  # from the west (calm at y = 0)
    assert field.wind_speed[0, -1] == pytest.approx(10.0, rel=0.05)
    np.testing.assert_allclose(field.hs, 2.0)
    np.testing.assert_allclose(field.current_north, 0.0)  # ERA5 has no current: zero


def test_missing_wave_variable_is_an_error(tmp_path):
    ds = xr.Dataset({"u10": (("northing", "easting"), np.zeros((2, 2)))},
                    coords={"northing": [0.0, 1.0], "easting": [0.0, 1.0]})
    ds.to_netcdf(tmp_path / "thin.nc")
    with pytest.raises(ValueError, match=r"thin.nc: no variable for wind_north \(looked for v10, northward_wind\)"):
        from_netcdf(tmp_path / "thin.nc")


def test_scenario_table_errors_name_the_key(tmp_path):
    where = "s.toml: metocean"
    with pytest.raises(ScenarioError, match=r"s.toml: metocean: give exactly one of 'generator' or 'file'"):
        from_scenario_table({}, tmp_path, where)
    with pytest.raises(ScenarioError, match=r"metocean.generator: unknown generator 'storm'"):
        from_scenario_table({"generator": "storm"}, tmp_path, where)
    with pytest.raises(ScenarioError, match=r"metocean: unknown key 'wind_kn'"):
        from_scenario_table({"generator": "paper_default", "wind_kn": 3}, tmp_path, where)
    with pytest.raises(ScenarioError, match=r"metocean.file: met-ocean file not found: .*none.nc"):
        from_scenario_table({"file": "none.nc"}, tmp_path, where)
    with pytest.raises(ScenarioError, match=r"metocean.wind_control_points_ms: expected a 2-D list of numbers"):
        from_scenario_table({"generator": "paper_default", "wind_control_points_ms": [1, 2]},
                                          tmp_path, where)
    with pytest.raises(ScenarioError, match=r"metocean: wind_control_points_ms needs a 2-D lattice"):
        from_scenario_table({"generator": "paper_default", "wind_control_points_ms": [[1, 2]]},
                                          tmp_path, where)


def test_scenario_table_reads_a_file_relative_to_the_scenario(tmp_path):
    paper_default(resolution_nm=10.0).to_netcdf(tmp_path / "w.nc")
    field = from_scenario_table({"file": "w.nc"}, Path(tmp_path), "s.toml: metocean")
    assert field.x.size == 11


def test_edges_held_beyond_the_map_in_whole_steps_the_map_itself_unchanged():
    field = paper_default(x_range_nm=(0.0, 10.0), y_range_nm=(0.0, 8.0), resolution_nm=0.5)
    held = field.with_edges_held(0.8 * NM)   # two steps of 0.5 nm cover 0.8 nm
    assert held.extent == pytest.approx((-1.0 * NM, 11.0 * NM, -1.0 * NM, 9.0 * NM))
    assert held.dx == pytest.approx(field.dx) and held.dy == pytest.approx(field.dy)
    inside = held.sample(field.x[:, None] + 0 * field.y[None, :], 0 * field.x[:, None] + field.y[None, :])
    np.testing.assert_array_equal(inside["hs"], field.hs)
    # beyond a side: that side's values; beyond a corner: the corner's
    beyond = held.sample(np.array([10.9, 4.0, 10.9]) * NM, np.array([3.0, -0.7, 8.6]) * NM)
    edge = field.sample(np.array([10.0, 4.0, 10.0]) * NM, np.array([3.0, 0.0, 8.0]) * NM)
    for name in ("wind_north", "wind_east", "hs", "current_north", "current_east"):
        np.testing.assert_allclose(beyond[name], edge[name], rtol=1e-12, atol=1e-12)
    assert field.with_edges_held(0.0) is field
    with pytest.raises(ValueError, match="non-negative distance, got -1"):
        field.with_edges_held(-1.0)


def test_edges_held_in_time_too():
    from rhnc.weather.weather_generators import moving_storm

    field = moving_storm(x_range_nm=(0.0, 20.0), y_range_nm=(0.0, 20.0), resolution_nm=1.0)
    held = field.with_edges_held(1.0 * NM)
    np.testing.assert_array_equal(held.times_s, field.times_s)
    for t in (field.times_s[0], 0.5 * (field.times_s[1] + field.times_s[2])):
        np.testing.assert_allclose(held.sample([21.0 * NM], [7.0 * NM], t)["wind_north"],
                                   field.sample([20.0 * NM], [7.0 * NM], t)["wind_north"], rtol=1e-12)


def test_a_scenario_table_may_hold_the_edges_and_a_bad_band_is_refused(tmp_path):
    table = {"generator": "paper_default", "x_range_nm": [0.0, 10.0], "y_range_nm": [0.0, 10.0], "resolution_nm": 1.0}
    held = from_scenario_table({**table, "hold_edges_nm": 1.5}, tmp_path, "s.toml: metocean")
    assert held.extent == pytest.approx((-2.0 * NM, 12.0 * NM, -2.0 * NM, 12.0 * NM))
    assert "edge values held 1.5 nm beyond" in held.source
    with pytest.raises(ScenarioError, match=r"^s.toml: metocean.hold_edges_nm: expected a distance of at least 0 nm, got -1$"):
        from_scenario_table({**table, "hold_edges_nm": -1.0}, tmp_path, "s.toml: metocean")
    with pytest.raises(ScenarioError, match=r"^s.toml: metocean.hold_edges_nm: expected a number, got 'far'$"):
        from_scenario_table({**table, "hold_edges_nm": "far"}, tmp_path, "s.toml: metocean")


def test_a_bad_edge_band_exits_2_from_the_cli_naming_the_key(tmp_path, capsys):
    from orchestrator.cli import main

    scenario = tmp_path / "held.toml"
    scenario.write_text('[simulation]\ndt_s = 1.0\nsteps = 2\n[metocean]\ngenerator = "paper_default"\n'
                        'hold_edges_nm = -0.5\n[participants.a]\ntype = "scripted_tau"\n')
    assert main(["run", str(scenario), "--results", str(tmp_path / "results")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "held.toml" in err[0] and "metocean.hold_edges_nm" in err[0]
    assert not (tmp_path / "results").exists() or not any((tmp_path / "results").iterdir())


def test_planners_read_the_data_extent_of_a_field_or_else_its_axes():
    from types import SimpleNamespace

    from rhnc.weather.metocean_grid import data_extent

    field = paper_default(x_range_nm=(0.0, 10.0), y_range_nm=(2.0, 8.0), resolution_nm=1.0)
    held = field.with_edges_held(1.5 * NM)
    assert data_extent(held) == pytest.approx((0.0, 10.0 * NM, 2.0 * NM, 8.0 * NM))
    assert data_extent(held) != pytest.approx(held.extent)
    axes_only = SimpleNamespace(x=np.array([1.0, 2.0, 3.0]), y=np.array([-4.0, 5.0]))   # no data_extent
    assert data_extent(axes_only) == (1.0, 3.0, -4.0, 5.0)
