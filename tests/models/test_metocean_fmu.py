"""MetOcean FMU: MOGRID1 and MOGRID2 reading, exact node values, bilinear and time interpolation, errors."""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException
from fmpy.validation import validate_fmu

FIELDS = ["wind_north", "wind_east", "hs", "current_north", "current_east"]
OUTPUTS = ["wind_speed", "wind_direction", *FIELDS]


def write_grid(path: Path, x0, dx, y0, dy, fields: dict[str, np.ndarray]) -> Path:
    """Minimal MOGRID1 writer (spec'd format, written independently of rhnc/weather/metocean.py)."""
    nx, ny = fields["hs"].shape
    with path.open("wb") as f:
        f.write(b"MOGRID1\n")
        f.write(struct.pack("<ii", nx, ny))
        f.write(struct.pack("<dddd", x0, dx, y0, dy))
        for name in FIELDS:
            f.write(np.ascontiguousarray(fields[name], dtype="<f8").tobytes())  # [i * ny + j]
    return path


@pytest.fixture
def grid(tmp_path):
    nx, ny = 4, 3
    rng = np.random.default_rng(7)
    fields = {name: rng.uniform(-10, 10, (nx, ny)) for name in FIELDS}
    fields["hs"] = np.abs(fields["hs"])
    geometry = dict(x0=-1000.0, dx=500.0, y0=2000.0, dy=250.0)
    path = write_grid(tmp_path / "grid.mogrid", **geometry, fields=fields)
    return path, geometry, fields


def expected(fields, name, wn=None, we=None):
    if name == "wind_speed":
        return np.hypot(wn, we)
    if name == "wind_direction":
        return np.arctan2(-we, -wn)
    return fields[name]


def test_validates(fmus):
    assert validate_fmu(str(fmus["MetOcean"])) == []


def test_exact_values_at_nodes(fmus, open_slave, grid):
    path, g, fields = grid
    slave = open_slave(fmus["MetOcean"])
    slave.initialize({"grid_file": str(path)})
    for i in range(4):
        for j in range(3):
            slave.set({"x": g["x0"] + i * g["dx"], "y": g["y0"] + j * g["dy"]})
            values = dict(zip(OUTPUTS, slave.get(*OUTPUTS)))
            node = {n: fields[n][i, j] for n in FIELDS}
            for name in FIELDS:
                assert values[name] == node[name]
            assert values["wind_speed"] == pytest.approx(np.hypot(node["wind_north"],
                                                                  node["wind_east"]), rel=1e-15)
            assert values["wind_direction"] == pytest.approx(
                np.arctan2(-node["wind_east"], -node["wind_north"]), rel=1e-15)


def test_bilinear_between_nodes_and_direction_convention(fmus, open_slave, grid):
    path, g, fields = grid
    slave = open_slave(fmus["MetOcean"])
    slave.initialize({"grid_file": str(path)})
    # midpoint of the cell (1, 1)-(2, 2): mean of its four corners
    slave.set({"x": g["x0"] + 1.5 * g["dx"], "y": g["y0"] + 1.5 * g["dy"]})
    slave.fmu.doStep(0.0, 10.0)
    for name, value in zip(FIELDS, slave.get(*FIELDS)):
        assert value == pytest.approx(np.mean(fields[name][1:3, 1:3]), rel=1e-13)
    # a quarter into cell (0, 1) along x, three quarters along y
    tx, ty = 0.25, 0.75
    slave.set({"x": g["x0"] + tx * g["dx"], "y": g["y0"] + (1 + ty) * g["dy"]})
    for name, value in zip(FIELDS, slave.get(*FIELDS)):
        f = fields[name]
        want = ((1 - tx) * ((1 - ty) * f[0, 1] + ty * f[0, 2])
                + tx * ((1 - ty) * f[1, 1] + ty * f[1, 2]))
        assert value == pytest.approx(want, rel=1e-13)


def test_wind_from_the_north_blowing_south(fmus, open_slave, tmp_path):
    shape = (2, 2)
    fields = {n: np.zeros(shape) for n in FIELDS}
    fields["wind_north"][:] = -12.0  # air moves south: it comes from the north
    path = write_grid(tmp_path / "north.mogrid", 0.0, 1.0, 0.0, 1.0, fields)
    slave = open_slave(fmus["MetOcean"])
    slave.initialize({"grid_file": str(path), "x": 0.5, "y": 0.5})
    speed, direction = slave.get("wind_speed", "wind_direction")
    assert speed == 12.0 and direction == 0.0


def test_point_outside_the_grid_is_an_error_naming_it(fmus, open_slave, grid):
    path, g, _ = grid
    slave = open_slave(fmus["MetOcean"])
    slave.initialize({"grid_file": str(path)})
    slave.set({"x": 600.0, "y": 2100.0})  # north of the last node at x = 500 m
    with pytest.raises(FMICallException):
        slave.fmu.doStep(0.0, 10.0)
    message = slave.errors()
    assert "x = 600.000 m, y = 2100.000 m is outside the grid" in message
    assert "x -1000.000..500.000 m, y 2000.000..2500.000 m" in message


def test_output_read_outside_the_grid_is_an_error(fmus, open_slave, grid):
    path, g, _ = grid
    slave = open_slave(fmus["MetOcean"])
    slave.initialize({"grid_file": str(path)})
    slave.set({"x": 0.0, "y": 1999.0})
    with pytest.raises(FMICallException):
        slave.get("hs")
    assert "reading an output: point x = 0.000 m, y = 1999.000 m is outside" in slave.errors()


def test_missing_grid_file_fails_initialisation_naming_it(fmus, open_slave, tmp_path):
    missing = tmp_path / "nowhere.mogrid"
    slave = open_slave(fmus["MetOcean"])
    with pytest.raises(FMICallException):
        slave.initialize({"grid_file": str(missing)})
    assert f'grid_file "{missing}" cannot be opened' in slave.errors()


def test_corrupt_grid_file_fails_initialisation_naming_it(fmus, open_slave, grid, tmp_path):
    path, _, _ = grid
    truncated = tmp_path / "truncated.mogrid"
    truncated.write_bytes(path.read_bytes()[:-8])
    slave = open_slave(fmus["MetOcean"])
    with pytest.raises(FMICallException):
        slave.initialize({"grid_file": str(truncated)})
    assert f'grid_file "{truncated}" is truncated' in slave.errors()


# -- MOGRID2: the time axis --------------------------------------------------------------
def write_grid2(path: Path, x0, dx, y0, dy, times, fields: dict[str, np.ndarray]) -> Path:
    """Minimal MOGRID2 writer (written independently of rhnc/weather/metocean.py): fields (nt, nx, ny)."""
    nt, nx, ny = fields["hs"].shape
    with path.open("wb") as f:
        f.write(b"MOGRID2\n")
        f.write(struct.pack("<iii", nx, ny, nt))
        f.write(struct.pack("<dddd", x0, dx, y0, dy))
        f.write(np.asarray(times, dtype="<f8").tobytes())
        for k in range(nt):
            for name in FIELDS:
                f.write(np.ascontiguousarray(fields[name][k], dtype="<f8").tobytes())
    return path


@pytest.fixture
def timed_grid(tmp_path):
    rng = np.random.default_rng(3)
    times = [0.0, 600.0, 1500.0]
    fields = {name: rng.uniform(-10, 10, (3, 4, 3)) for name in FIELDS}
    path = write_grid2(tmp_path / "timed.mogrid", 0.0, 100.0, 0.0, 50.0, times, fields)
    return path, times, fields


def test_time_steps_exact_linear_between_and_held_outside(fmus, open_slave, timed_grid):
    path, times, fields = timed_grid
    slave = open_slave(fmus["MetOcean"])
    slave.initialize({"grid_file": str(path), "x": 200.0, "y": 50.0}, start_time=-300.0)  # node (2, 1)
    node = {name: fields[name][:, 2, 1] for name in FIELDS}
    t, h = -300.0, 150.0
    while t < 2000.0:
        slave.fmu.doStep(t, h)
        t += h
        values = dict(zip(FIELDS, slave.get(*FIELDS)))
        held = min(max(t, times[0]), times[-1])
        for name in FIELDS:
            want = np.interp(held, times, node[name])
            if held in times:  # exactly the stored value at a time step
                assert values[name] == node[name][times.index(held)], (name, t)
            else:
                assert values[name] == pytest.approx(want, rel=1e-13, abs=1e-13), (name, t)


def test_fmu_and_sample_agree_along_a_sailed_track_in_a_moving_storm(fmus, open_slave, tmp_path):
    """The planner's sample and the FMU give the same weather at the places and times sailed."""
    from orchestrator.geometry import KNOT, NM
    from rhnc.weather.weather_generators import moving_storm

    field = moving_storm(resolution_nm=2.0, duration_h=6.0)
    assert field.is_time_varying
    grid = field.write_fmu_grid(tmp_path / "storm.grid")
    slave = open_slave(fmus["MetOcean"])
    slave.initialize({"grid_file": str(grid)}, start_time=-700.0)  # before the first step: held
    speed = 18.0 * KNOT
    t, h, compared, changing = -700.0, 700.0, 0, []
    while t + h <= 7.5 * 3600.0:  # beyond the last step (6 h): held
        end = t + h
        along = speed * max(end, 0.0)
        x, y = along / np.sqrt(2), along / np.sqrt(2) + 1.5 * NM * (1 - np.cos(end / 3000.0))  # weaving
        slave.set({"x": x, "y": y})
        slave.fmu.doStep(t, h)
        t = end
        got = dict(zip(OUTPUTS, slave.get(*OUTPUTS)))
        want = field.sample(x, y, t_s=t)
        for name in FIELDS + ["wind_speed"]:
            assert got[name] == pytest.approx(float(want[name]), rel=1e-12, abs=1e-12), (name, t)
        assert np.mod(got["wind_direction"], 2 * np.pi) == pytest.approx(float(want["wind_direction"]), abs=1e-12)
        # the weather at this place an hour later differs: time matters along this track
        changing.append(abs(float(field.sample(x, y, t_s=t + 3600.0)["hs"] - want["hs"])))
        compared += 1
    assert compared >= 35 and max(changing) > 0.3


def test_times_out_of_order_fail_initialisation_naming_the_file(fmus, open_slave, timed_grid, tmp_path):
    _, _, fields = timed_grid
    bad = write_grid2(tmp_path / "bad.mogrid", 0.0, 100.0, 0.0, 50.0, [0.0, 600.0, 600.0], fields)
    slave = open_slave(fmus["MetOcean"])
    with pytest.raises(FMICallException):
        slave.initialize({"grid_file": str(bad)})
    assert f'grid_file "{bad}": time 2 (600 s) is not finite or not after the one before' in slave.errors()


def test_default_grid_in_resources_runs_the_default_experiment(fmus):
    """With no grid_file the FMU reads the paper's weather from its resources (5 nm grid)."""
    from fmpy import simulate_fmu

    from orchestrator.geometry import NM
    from rhnc.weather.weather_generators import paper_default

    point = (40.0 * NM, 55.0 * NM)
    result = simulate_fmu(str(fmus["MetOcean"]), stop_time=60.0, output_interval=60.0,
                          start_values={"x": point[0], "y": point[1]}, output=["hs", "wind_speed"])
    expected = paper_default(resolution_nm=5.0).sample(*point)
    assert result["hs"][-1] == pytest.approx(float(expected["hs"]), rel=1e-12)
    assert result["wind_speed"][-1] == pytest.approx(float(expected["wind_speed"]), rel=1e-12)


def test_shipped_default_grid_is_the_generators_output():
    """models/MetOcean/resources/default.grid is not stale: the generator writes the same bytes."""
    import tempfile
    from pathlib import Path

    from orchestrator.fmu_build import MODELS_DIR
    from rhnc.weather.weather_generators import paper_default

    with tempfile.TemporaryDirectory() as tmp:
        fresh = paper_default(resolution_nm=5.0).write_fmu_grid(Path(tmp) / "g")
        assert fresh.read_bytes() == (MODELS_DIR / "MetOcean" / "resources" / "default.grid").read_bytes()


def test_a_relative_grid_name_is_taken_in_the_resources_folder(fmus, open_slave):
    slave = open_slave(fmus["MetOcean"])
    with pytest.raises(FMICallException):
        slave.initialize({"grid_file": "no_such.grid"})
    assert "resources/no_such.grid\" cannot be opened" in slave.errors()


@pytest.mark.parametrize("folder", ["unzip*A:[b] é", "unzip%2a%5c"])
def test_resources_are_found_in_a_folder_whose_name_the_uri_percent_encodes(fmus, slave_class, tmp_path, folder):
    """The resource location is a file URI, escaped in upper case hex by FMPy (``*`` as %2A, ``é`` as
    %C3%A9), and a name may hold a '%' itself: the FMU decodes every escape, back to the folder's own name."""
    _reads_the_default_grid(slave_class(fmus["MetOcean"], tmp_path / folder))
    missing = slave_class(fmus["MetOcean"], tmp_path / f"{folder}-2")
    try:
        with pytest.raises(FMICallException):
            missing.initialize({"grid_file": "no_such.grid"})
        assert f"{tmp_path / (folder + '-2')}/resources/no_such.grid\" cannot be opened" in missing.errors()
    finally:
        missing.close()


@pytest.mark.parametrize("prefix", ["file://", "file://localhost", "file:"])
def test_every_local_form_of_the_resource_uri_with_lower_case_escapes_is_read(fmus, slave_class, tmp_path, monkeypatch,
                                                                              prefix):
    """Another master may write ``file:/p`` or ``file://localhost/p`` and escape in lower case hex."""
    import pathlib

    def lower_case_uri(path):
        return prefix + "".join(c if c.isalnum() or c in "/._-" else "".join(f"%{b:02x}" for b in c.encode())
                                for c in str(path))

    monkeypatch.setattr(pathlib.Path, "as_uri", lower_case_uri)
    slave = slave_class(fmus["MetOcean"], tmp_path / "unzip*?:[e] é")  # %2a %3f %3a %5b %5d %20 %c3%a9
    monkeypatch.undo()
    _reads_the_default_grid(slave)


def _reads_the_default_grid(slave) -> None:
    """The FMU, unpacked where its resources' URI needs decoding, reads its shipped grid there:
    the wave height at a point is the generator's; the slave is closed afterwards."""
    from orchestrator.geometry import NM
    from rhnc.weather.weather_generators import paper_default

    try:
        point = (40.0 * NM, 55.0 * NM)
        slave.initialize({"grid_file": "default.grid", "x": point[0], "y": point[1]})
        assert slave.get("hs")[0] == pytest.approx(float(paper_default(resolution_nm=5.0).sample(*point)["hs"]),
                                                   rel=1e-12)
    finally:
        slave.close()
