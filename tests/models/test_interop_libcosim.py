"""Interoperability: the FMUs run in a second importer, OSP's libcosim, as they do in fmpy.

libcosim (the Open Simulation Platform's C++ co-simulation library, through libcosimpy)
loads, initialises and steps our KCS plant with its own FMI 2.0 implementation; the
trajectory must equal fmpy's stepped the same way.  Times in libcosim are nanoseconds.
"""

import numpy as np
import pytest
from fmpy import simulate_fmu

libcosimpy = pytest.importorskip("libcosimpy")
from libcosimpy.CosimExecution import CosimExecution  # noqa: E402
from libcosimpy.CosimLogging import CosimLogLevel, log_output_level  # noqa: E402
from libcosimpy.CosimManipulator import CosimManipulator  # noqa: E402
from libcosimpy.CosimObserver import CosimObserver  # noqa: E402
from libcosimpy.CosimSlave import CosimLocalSlave  # noqa: E402

NANO = 1_000_000_000
STEP_S = 2.0
STOP_S = 600.0
INITIAL = {"u0": 9.26, "psi0": 0.3}
INPUTS = {"tau_u": 7.7e5, "tau_r": 1.0e8, "current_north": 0.2, "current_east": -0.1,
          "wind_speed": 12.0, "wind_direction": 0.8, "hs": 2.5}
OUTPUTS = ("x", "y", "psi", "u", "v", "r")


def libcosim_run(fmu_path, vr):
    log_output_level(CosimLogLevel.WARNING)
    execution = CosimExecution.from_step_size(int(STEP_S * NANO))
    slave = execution.add_local_slave(CosimLocalSlave(fmu_path=str(fmu_path), instance_name="ship"))
    for name, value in INITIAL.items():
        assert execution.real_initial_value(slave, vr[name], value)
    manipulator = CosimManipulator.create_override()
    assert execution.add_manipulator(manipulator)
    observer = CosimObserver.create_last_value()
    assert execution.add_observer(observer)
    # inputs held constant from the start, as fmpy's start values below
    for name, value in INPUTS.items():
        assert execution.real_initial_value(slave, vr[name], value)
    assert execution.simulate_until(int(STOP_S * NANO))
    return observer.last_real_values(slave, [vr[name] for name in OUTPUTS])


def test_kcs_in_libcosim_matches_fmpy(fmus):
    from fmpy import read_model_description

    fmu = fmus["KCS"]
    vr = {v.name: v.valueReference for v in read_model_description(str(fmu)).modelVariables}
    theirs = libcosim_run(fmu, vr)
    ours = simulate_fmu(str(fmu), start_time=0.0, stop_time=STOP_S, output_interval=STEP_S,
                        start_values={**INITIAL, **INPUTS}, output=list(OUTPUTS))
    np.testing.assert_allclose(theirs, [ours[name][-1] for name in OUTPUTS], rtol=1e-9, atol=1e-9)
    assert np.hypot(theirs[0], theirs[1]) > 500.0 and abs(theirs[2] - 0.3) > 0.5  # it sailed and turned


def test_metocean_in_libcosim_returns_the_planners_values(fmus, tmp_path):
    from fmpy import read_model_description

    from orchestrator.geometry import NM
    from rhnc.weather.weather_generators import paper_default

    field = paper_default(resolution_nm=5.0)
    grid = field.write_fmu_grid(tmp_path / "weather.grid")
    fmu = fmus["MetOcean"]
    vr = {v.name: v.valueReference for v in read_model_description(str(fmu)).modelVariables}
    log_output_level(CosimLogLevel.WARNING)
    execution = CosimExecution.from_step_size(int(60 * NANO))
    env = execution.add_local_slave(CosimLocalSlave(fmu_path=str(fmu), instance_name="env"))
    assert execution.string_initial_value(env, vr["grid_file"], str(grid))
    point = (37.3 * NM, 61.8 * NM)
    assert execution.real_initial_value(env, vr["x"], point[0])
    assert execution.real_initial_value(env, vr["y"], point[1])
    observer = CosimObserver.create_last_value()
    assert execution.add_observer(observer)
    assert execution.simulate_until(int(120 * NANO))
    names = ("wind_speed", "wind_direction", "hs", "current_north", "current_east")
    theirs = observer.last_real_values(env, [vr[name] for name in names])
    expected = field.sample(*point)
    np.testing.assert_allclose(theirs, [float(expected[name]) for name in names], rtol=1e-12, atol=1e-12)


def test_metocean_in_libcosim_follows_the_moving_storm_in_time(fmus, tmp_path):
    from fmpy import read_model_description

    from orchestrator.geometry import NM
    from rhnc.weather.weather_generators import moving_storm

    field = moving_storm(resolution_nm=5.0, duration_h=3.0)
    grid = field.write_fmu_grid(tmp_path / "storm.grid")
    fmu = fmus["MetOcean"]
    vr = {v.name: v.valueReference for v in read_model_description(str(fmu)).modelVariables}
    names = ("wind_speed", "hs", "wind_north", "wind_east")
    point = (41.3 * NM, 52.8 * NM)
    for stop_s in (1800, 5400, 4 * 3600):  # between steps, between other steps, after the last
        log_output_level(CosimLogLevel.WARNING)
        execution = CosimExecution.from_step_size(int(60 * NANO))
        env = execution.add_local_slave(CosimLocalSlave(fmu_path=str(fmu), instance_name="env"))
        assert execution.string_initial_value(env, vr["grid_file"], str(grid))
        assert execution.real_initial_value(env, vr["x"], point[0])
        assert execution.real_initial_value(env, vr["y"], point[1])
        observer = CosimObserver.create_last_value()
        assert execution.add_observer(observer)
        assert execution.simulate_until(int(stop_s * NANO))
        theirs = observer.last_real_values(env, [vr[name] for name in names])
        expected = field.sample(*point, t_s=float(stop_s))
        np.testing.assert_allclose(theirs, [float(expected[name]) for name in names], rtol=1e-12, atol=1e-12)
        # not the first step's value: the wind has turned as the storm moved
        assert abs(theirs[3] - float(field.sample(*point, t_s=0.0)["wind_east"])) > 1.0
