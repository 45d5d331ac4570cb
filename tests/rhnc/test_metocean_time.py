"""Time-varying met-ocean fields: interpolation in time, snapshots, NetCDF and FMU-grid files."""

import struct

import numpy as np
import pytest
import xarray as xr

from orchestrator.errors import ScenarioError
from rhnc.navigation.fields import resample_weather
from rhnc.weather.metocean import FIELDS, MetOceanField
from rhnc.weather.metocean_sources import from_netcdf, from_scenario_table
from rhnc.weather.weather_generators import paper_default

TIMES_S = np.array([0.0, 3600.0, 9000.0])  # uneven steps on purpose


@pytest.fixture
def moving():
    """3 time steps on a 3 x 4 grid; every field differs per node and per step."""
    rng = np.random.default_rng(11)
    fields = {name: rng.uniform(-10.0, 10.0, (3, 3, 4)) for name in FIELDS}
    return MetOceanField(np.array([0.0, 500.0, 1000.0]), np.array([0.0, 100.0, 200.0, 300.0]), fields,
                         times_s=TIMES_S)


def test_static_field_behaves_as_without_time():
    field = paper_default(resolution_nm=10.0)
    assert not field.is_time_varying and field.hs.shape == (11, 11)
    x, y = np.array([1000.0, 50_000.0]), np.array([7000.0, 90_000.0])
    for name, value in field.sample(x, y).items():
        np.testing.assert_array_equal(field.sample(x, y, t_s=1e6)[name], value)
    assert field.snapshot(500.0) is field


def test_exact_at_time_steps_and_nodes(moving):
    for k, t in enumerate(TIMES_S):
        sampled = moving.sample(500.0, 200.0, t_s=t)
        for name in FIELDS:
            assert sampled[name] == moving._fields[name][k, 1, 2]


def test_linear_between_time_steps_and_held_outside(moving):
    x, y = 250.0, 130.0  # inside cell (0, 1): half-way along x, 0.3 along y, bilinear at each step
    at = [{name: 0.5 * (0.7 * g[k, 0, 1] + 0.3 * g[k, 0, 2]) + 0.5 * (0.7 * g[k, 1, 1] + 0.3 * g[k, 1, 2])
           for name, g in moving._fields.items()} for k in range(3)]
    for fraction in (0.1, 0.5, 0.8):
        t = TIMES_S[1] + fraction * (TIMES_S[2] - TIMES_S[1])
        sampled = moving.sample(x, y, t_s=t)
        for name in FIELDS:
            assert sampled[name] == pytest.approx((1 - fraction) * at[1][name] + fraction * at[2][name], rel=1e-12)
    for name in FIELDS:
        assert moving.sample(x, y, t_s=-100.0)[name] == pytest.approx(at[0][name], rel=1e-12)
        assert moving.sample(x, y, t_s=1e6)[name] == pytest.approx(at[2][name], rel=1e-12)


def test_times_per_point_broadcast_with_positions(moving):
    x = np.array([0.0, 300.0, 1000.0])
    y = np.array([300.0, 50.0, 0.0])
    t = np.array([0.0, 2000.0, 9000.0])
    together = moving.sample(x, y, t_s=t)
    for n in range(3):
        alone = moving.sample(x[n], y[n], t_s=t[n])
        for name in FIELDS:
            assert together[name][n] == pytest.approx(alone[name], rel=1e-14)


def test_time_varying_field_needs_a_time(moving):
    with pytest.raises(ValueError, match=r"varies in time \(3 steps\): sample it at a time t_s"):
        moving.sample(0.0, 0.0)


def test_snapshot_is_the_field_at_that_time(moving):
    snapshot = moving.snapshot(5000.0)
    assert not snapshot.is_time_varying
    x, y = np.meshgrid([0.0, 333.0, 1000.0], [0.0, 123.0, 300.0], indexing="ij")
    expected = moving.sample(x, y, t_s=5000.0)
    for name in FIELDS:
        np.testing.assert_allclose(snapshot.sample(x, y)[name], expected[name], rtol=1e-12, atol=1e-12)


def test_planning_weather_is_taken_at_the_time(moving):
    # 100 m planning nodes: every 5th along x and every one along y is a met-ocean node
    for k, t in enumerate(TIMES_S):
        weather = resample_weather(moving, resolution_nm=100.0 / 1852.0, t_s=t)
        np.testing.assert_allclose(weather.hs[::5, :], moving._fields["hs"][k], rtol=1e-12)
    halfway = resample_weather(moving, resolution_nm=100.0 / 1852.0, t_s=1800.0)
    np.testing.assert_allclose(halfway.hs[::5, :], moving._fields["hs"][:2].mean(axis=0), rtol=1e-12)


def test_times_must_increase():
    fields = {name: np.zeros((2, 2, 2)) for name in FIELDS}
    with pytest.raises(ValueError, match="strictly increasing"):
        MetOceanField([0.0, 1.0], [0.0, 1.0], fields, times_s=[10.0, 10.0])
    with pytest.raises(ValueError, match=r"has shape \(2, 2, 2\), grid is \(3, 2, 2\)"):
        MetOceanField([0.0, 1.0], [0.0, 1.0], fields, times_s=[0.0, 1.0, 2.0])


def test_netcdf_round_trip_keeps_every_time_step(moving, tmp_path):
    moving.start_time = "2023-03-01T06:00:00"
    path = moving.to_netcdf(tmp_path / "moving.nc")
    with xr.open_dataset(path) as ds:
        assert ds["swh"].dims == ("time", "northing", "easting")
        assert str(ds["time"].values[1]).startswith("2023-03-01T07:00:00")
    again = from_netcdf(path)
    np.testing.assert_array_equal(again.times_s, TIMES_S)
    for name in FIELDS:
        np.testing.assert_array_equal(getattr(again, name), getattr(moving, name))
    # a later departure shifts the clock: the file's first step is then 2 h before t = 0
    later = from_netcdf(path, start_time="2023-03-01T08:00:00")
    np.testing.assert_array_equal(later.times_s, TIMES_S - 7200.0)
    single = from_netcdf(path, time_index=2)
    np.testing.assert_array_equal(single.hs, moving._fields["hs"][2])


def test_netcdf_written_directly_is_the_xarray_dataset(moving, tmp_path):
    """The file every run writes (through netCDF4) holds what ``to_dataset`` describes, attributes too."""
    from rhnc.weather.metocean_netcdf import to_dataset

    for field in (moving, paper_default(resolution_nm=20.0)):
        path = field.to_netcdf(tmp_path / f"direct{field.is_time_varying}.nc")
        with xr.open_dataset(path) as written:
            expected = to_dataset(field)
            assert written.identical(expected)
            for name in written.variables:
                assert written[name].attrs == expected[name].attrs, name


def test_file_options_are_checked(moving, tmp_path):
    moving.to_netcdf(tmp_path / "w.nc")
    where = "s.toml: metocean"
    with pytest.raises(ScenarioError, match=r"s.toml: metocean: time_index 3 is not one of the file's 3 time steps"):
        from_scenario_table({"file": "w.nc", "time_index": 3}, tmp_path, where)
    with pytest.raises(ScenarioError, match=r"s.toml: metocean: start_time 'noon' is not an ISO 8601 date"):
        from_scenario_table({"file": "w.nc", "start_time": "noon"}, tmp_path, where)
    with pytest.raises(ScenarioError, match=r"s.toml: metocean.start_time: expected a string, got 2023"):
        from_scenario_table({"file": "w.nc", "start_time": 2023}, tmp_path, where)
    with pytest.raises(ScenarioError, match=r"s.toml: metocean.time_index: expected an integer, got '1'"):
        from_scenario_table({"file": "w.nc", "time_index": "1"}, tmp_path, where)
    with pytest.raises(ScenarioError, match=r"s.toml: metocean: unknown key 'start'"):
        from_scenario_table({"file": "w.nc", "start": "noon"}, tmp_path, where)


def test_time_without_cf_units_is_refused(tmp_path):
    shape = (2, 2, 2)
    ds = xr.Dataset({name: (("time", "northing", "easting"), np.ones(shape)) for name in ("u10", "v10", "swh")},
                    coords={"northing": [0.0, 1.0], "easting": [0.0, 1.0], "time": [0, 6]})
    ds.to_netcdf(tmp_path / "bare.nc")
    with pytest.raises(ValueError, match=r"bare.nc: the 'time' coordinate is not a CF time"):
        from_netcdf(tmp_path / "bare.nc")


def test_fmu_grid_file_carries_the_times(moving, tmp_path):
    data = moving.write_fmu_grid(tmp_path / "g.grid").read_bytes()
    assert data[:8] == b"MOGRID2\n"
    assert struct.unpack("<iii", data[8:20]) == (3, 4, 3)
    assert struct.unpack("<3d", data[52:76]) == tuple(TIMES_S)
    body = np.frombuffer(data[76:], dtype="<f8").reshape(3, len(FIELDS), 3, 4)
    np.testing.assert_array_equal(body[2, FIELDS.index("hs")], moving._fields["hs"][2])
