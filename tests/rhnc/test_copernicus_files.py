"""ERA5 single-level and CMEMS current files, written in exactly the services' layouts, read back."""

import netCDF4
import numpy as np
import pytest

from orchestrator.errors import ScenarioError
from orchestrator.geometry import local_north_east_m
from rhnc.weather.copernicus_layouts import write_cmems_currents, write_era5_single_levels
from rhnc.weather.metocean_sources import from_scenario_table

ORIGIN = (50.0, -1.0)  # a map across the Greenwich meridian: ERA5's 0-360 longitudes wrap inside it
TIMES = np.array(["2024-01-10T00", "2024-01-10T01", "2024-01-10T02"], dtype="datetime64[h]")


def era5(tmp_path, variables=("u10", "v10", "swh", "mwd")):
    lat = np.arange(49.0, 51.01, 0.25)
    lon = np.arange(-2.0, 2.01, 0.25)
    la, lo = np.meshgrid(lat, lon, indexing="ij")
    hour = np.arange(TIMES.size)[:, None, None]
    values = {"u10": 5.0 + 2.0 * lo + hour + 0 * la,  # towards east, growing eastward and by 1 m/s an hour
              "v10": -3.0 + 0 * lo + 0 * hour,
              "swh": 1.0 + 0.5 * (la - 49.0) + 0 * hour,
              "mwd": 270.0 + 0 * la + 0 * hour}
    path = write_era5_single_levels(tmp_path / "era5.nc", lat, lon, TIMES, **values)
    if set(variables) != set(values):
        with netCDF4.Dataset(path, "a") as ds:
            for name in set(values) - set(variables):
                ds.renameVariable(name, f"{name}_dropped")
    return path


def cmems(tmp_path):
    lat = np.arange(49.5, 50.51, 1 / 12)
    lon = np.arange(-1.5, 1.51, 1 / 12)
    la, lo = np.meshgrid(lat, lon, indexing="ij")
    times = np.array(["2024-01-09T23:30", "2024-01-10T01:30"], dtype="datetime64[m]")
    uo = np.stack([0.2 + 0 * la, 0.6 + 0 * la])  # 0.2 m/s east, then 0.6 two hours later
    vo = np.stack([0.1 * (lo + 1.5), 0.1 * (lo + 1.5)])
    uo[:, -1, -1] = np.nan  # land
    return write_cmems_currents(tmp_path / "cmems.nc", lat, lon, times, uo, vo, depths_m=(0.494025, 5.0, 10.0))


def test_the_files_have_the_services_layout(tmp_path):
    with netCDF4.Dataset(era5(tmp_path)) as ds:
        ds.set_auto_maskandscale(False)
        assert ds["u10"].dtype == np.int16 and hasattr(ds["u10"], "scale_factor") and hasattr(ds["u10"], "add_offset")
        assert ds["time"].units == "hours since 1900-01-01 00:00:00.0"
        assert np.all(np.diff(ds["latitude"][:]) < 0)
        assert ds["longitude"][:].min() >= 0.0 and ds["longitude"][:].max() > 350.0
    with netCDF4.Dataset(cmems(tmp_path)) as ds:
        assert ds["uo"].dimensions == ("time", "depth", "latitude", "longitude")
        assert ds["time"].units == "hours since 1950-01-01"


def test_era5_and_cmems_read_as_delivered(tmp_path):
    era5(tmp_path)
    cmems(tmp_path)
    field = from_scenario_table({"file": "era5.nc", "currents_file": "cmems.nc", "origin_deg": list(ORIGIN),
                                 "resolution_nm": 3.0}, tmp_path, "s.toml: metocean")
    np.testing.assert_array_equal(field.times_s, [0.0, 3600.0, 7200.0])
    assert field.start_time.startswith("2024-01-10T00:00")
    north, east = local_north_east_m(50.0, 0.5, *ORIGIN)  # east of Greenwich: stored at 0.5 deg in the file
    at = field.sample(north, east, t_s=3600.0)
    assert at["wind_east"] == pytest.approx(5.0 + 2.0 * 0.5 + 1.0, abs=0.01)  # unpacked and on the right side
    assert at["wind_north"] == pytest.approx(-3.0, abs=1e-3)
    assert field.sample(*local_north_east_m(50.5, 0.0, *ORIGIN), t_s=0.0)["hs"] == pytest.approx(1.75, abs=1e-3)
    west = field.sample(*local_north_east_m(50.0, -1.75, *ORIGIN), t_s=0.0)
    assert west["wind_east"] == pytest.approx(5.0 - 3.5, abs=0.01)  # stored at 358.25 deg
    # the current: 0.2 m/s at 23:30, 0.6 at 01:30, so 0.3 at 00:00 and 0.5 at 01:00
    assert field.sample(north, east, t_s=0.0)["current_east"] == pytest.approx(0.3, abs=1e-6)
    assert at["current_east"] == pytest.approx(0.5, abs=1e-6)
    assert at["current_north"] == pytest.approx(0.1 * 2.0, abs=1e-3)


def test_a_weather_file_missing_a_variable_names_it(tmp_path):
    era5(tmp_path, variables=("u10", "v10", "mwd"))
    with pytest.raises(ScenarioError, match=r"s.toml: metocean: .*era5.nc: no variable for hs \(looked for swh"):
        from_scenario_table({"file": "era5.nc", "origin_deg": list(ORIGIN)}, tmp_path, "s.toml: metocean")


def test_a_currents_file_missing_its_current_names_it(tmp_path):
    era5(tmp_path)
    path = cmems(tmp_path)
    with netCDF4.Dataset(path, "a") as ds:
        ds.renameVariable("vo", "v_dropped")
    with pytest.raises(ScenarioError, match=r"s.toml: metocean: .*cmems.nc: no variable for current_north"):
        from_scenario_table({"file": "era5.nc", "currents_file": "cmems.nc", "origin_deg": list(ORIGIN)},
                            tmp_path, "s.toml: metocean")
    with pytest.raises(ScenarioError, match=r"s.toml: metocean.currents_file: currents file not found: .*none.nc"):
        from_scenario_table({"file": "era5.nc", "currents_file": "none.nc"}, tmp_path, "s.toml: metocean")


def test_the_azimuthal_equidistant_plane_puts_weather_where_the_chart_does(tmp_path):
    from rhnc.chart.projection import LocalProjection

    era5(tmp_path)
    table = {"file": "era5.nc", "origin_deg": list(ORIGIN), "resolution_nm": 2.0}
    plane = from_scenario_table({**table, "projection": "aeqd"}, tmp_path, "s.toml: metocean")
    flat = from_scenario_table(table, tmp_path, "s.toml: metocean")
    north, east = LocalProjection(*ORIGIN).to_local(50.9, 1.6)  # far from the origin, inside the data
    expected = 5.0 + 2.0 * 1.6  # u10 at that longitude, at departure
    assert plane.sample(north, east, t_s=0.0)["wind_east"] == pytest.approx(expected, abs=0.01)
    assert abs(flat.sample(north, east, t_s=0.0)["wind_east"] - expected) > 0.03  # the other plane is off there
    with pytest.raises(ScenarioError, match=r"s.toml: metocean.projection: 'utm' is not valid \(valid: "
                                            r"equirectangular, aeqd\)"):
        from_scenario_table({**table, "projection": "utm"}, tmp_path, "s.toml: metocean")
