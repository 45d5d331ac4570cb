"""KCSMMG plant FMU (KCS in MMG form, rudder and propeller inputs): fmpy validation, the
trajectory against an independent solve_ivp integration of the readme's equations, the
steering gear's limits, and the particulars check at build time."""

from __future__ import annotations

import math
import shutil

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException
from fmpy.validation import validate_fmu
from scipy.integrate import solve_ivp

from mmg_reference import STATES, equilibrium_rps, forces, make_rhs, mmg_parameters
from orchestrator import fmu_build
from orchestrator.errors import FmuError, ScenarioError
from orchestrator.fmu_participant import check_parameter_value

KNOT = 1852.0 / 3600.0


def test_fmu_passes_fmpy_validation(fmus):
    assert validate_fmu(str(fmus["KCSMMG"])) == []


@pytest.mark.parametrize("rudder_deg, weather", [
    (20.0, dict(current_north=0.3, current_east=-0.2, wind_direction=math.radians(60), wind_speed=12.0, hs=2.0)),
    (-35.0, dict(current_north=0.0, current_east=0.0, wind_direction=0.0, wind_speed=0.0, hs=0.0)),
])
def test_trajectory_matches_independent_integration(fmus, open_slave, rudder_deg, weather):
    """Rudder step from 18 kn with the engine held: 600 s of FMU against solve_ivp."""
    p = mmg_parameters()
    u0 = 18 * KNOT
    n0 = equilibrium_rps(p, u0)
    slave = open_slave(fmus["KCSMMG"])
    slave.initialize({"u0": u0, "propeller_rps0": n0, "psi0": 0.3})
    slave.set({"rudder_angle_cmd": math.radians(rudder_deg), "propeller_rps_cmd": n0, **weather})
    times = np.arange(0.0, 601.0, 5.0)
    fmu_states = [slave.get(*STATES)]
    for t in times[:-1]:
        slave.fmu.doStep(t, 5.0)
        fmu_states.append(slave.get(*STATES))
    rhs = make_rhs(p, math.radians(rudder_deg), n0, weather)
    reference = solve_ivp(rhs, (0.0, 600.0), [0, 0, 0.3, u0, 0, 0, 0, n0], t_eval=times,
                          rtol=1e-10, atol=1e-9, max_step=0.5)
    fmu_states = np.array(fmu_states)
    reference_states = reference.y.T.copy()
    reference_states[:, 2] = np.angle(np.exp(1j * reference_states[:, 2]))
    scale = np.array([1.0, 1.0, 1e-3, 1e-2, 1e-2, 1e-5, 1e-4, 1e-3])  # m, m, rad, m/s, ..., 1/s
    error = np.abs(fmu_states - reference_states)
    error[:, 2] = np.abs(np.angle(np.exp(1j * (fmu_states[:, 2] - reference_states[:, 2]))))
    assert np.all(error <= scale), f"largest error per state: {dict(zip(STATES, error.max(axis=0)))}"
    assert np.max(np.abs(fmu_states[:, 5])) > 0.005  # rad/s: it did turn


def test_rudder_moves_at_most_at_the_rate_limit_and_stops_at_35_degrees(fmus, open_slave):
    p = mmg_parameters()
    slave = open_slave(fmus["KCSMMG"])
    slave.initialize({"u0": 9.26, "propeller_rps0": 1.0})
    slave.set({"rudder_angle_cmd": math.radians(60.0), "propeller_rps_cmd": 9.0})
    slave.fmu.doStep(0.0, 5.0)
    rudder, rps = slave.get("rudder_angle", "propeller_rps")
    assert rudder == pytest.approx(5.0 * p["rudder_rate_max"], rel=1e-9)  # 2.32 deg/s
    assert rps == pytest.approx(1.0 + 5.0 * p["propeller_rate_max"], rel=1e-9)
    for k in range(1, 10):
        slave.fmu.doStep(5.0 * k, 5.0)
    rudder, rps = slave.get("rudder_angle", "propeller_rps")
    assert rudder == pytest.approx(math.radians(35.0), abs=1e-4)


def test_reported_thrust_and_power_follow_the_propeller_model(fmus, open_slave):
    p = mmg_parameters()
    n0 = equilibrium_rps(p, 9.26)
    slave = open_slave(fmus["KCSMMG"])
    slave.initialize({"u0": 9.26, "propeller_rps0": n0})
    thrust, power = slave.get("thrust", "delivered_power")
    _, _, _, thrust_ref, torque_ref = forces(p, 9.26, 0.0, 0.0, 0.0, n0)
    assert thrust == pytest.approx(thrust_ref, rel=1e-9)
    assert power == pytest.approx(2 * math.pi * n0 * torque_ref, rel=1e-9)
    assert 5e6 < power < 15e6  # W: a 3600 TEU ship at 18 kn


def test_build_refuses_a_parameter_set_whose_particulars_differ_from_the_ship(tmp_path):
    models = tmp_path / "models"
    shutil.copytree(fmu_build.MODELS_DIR, models)
    path = models / "KCSMMG" / "parameter_sets.toml"
    path.write_text(path.read_text().replace("wind_area_frontal = 1000.0", "wind_area_frontal = 2200.43"))
    with pytest.raises(FmuError, match=r"wind_area_frontal = 2200.43 differs from wind_area_frontal_m2 = 1000"):
        fmu_build.build_fmu("KCSMMG", tmp_path / "out", models)


def test_fmu_state_round_trip_repeats_a_step_exactly(fmus, open_slave):
    """Rudder and engine states are part of the FMU state: restoring it repeats a step bit for bit."""
    slave = open_slave(fmus["KCSMMG"])
    slave.initialize({"u0": 9.26, "propeller_rps0": 1.0})
    slave.set({"rudder_angle_cmd": 0.3, "propeller_rps_cmd": 1.4})
    slave.fmu.doStep(0.0, 10.0)
    state = slave.fmu.getFMUstate()
    restored = slave.fmu.deSerializeFMUstate(slave.fmu.serializeFMUstate(state))
    slave.fmu.doStep(10.0, 10.0)
    first = slave.get(*STATES)
    slave.fmu.setFMUstate(restored)
    slave.fmu.doStep(10.0, 10.0)
    assert slave.get(*STATES) == first
    assert 0.0 < first[6] < 0.3 and 1.0 < first[7] < 1.4  # actuators still moving at their rates
    slave.fmu.freeFMUstate(state)
    slave.fmu.freeFMUstate(restored)


def test_a_fraction_above_its_declared_maximum_is_refused_naming_it(fmus, open_slave):
    # the wake fraction and the thrust deduction are fractions of the inflow and the thrust:
    # both declare [0, 1], the only declared maxima, and the shared layer refuses either side
    slave = open_slave(fmus["KCSMMG"])
    slave.set({"t_p": 1.0, "w_p0": 0.0})  # the ends of the range are inside it
    with pytest.raises(FMICallException):
        slave.set({"t_p": 1.5})
    assert "fmi2SetReal: t_p (value reference 58) = 1.5 is outside its range [0, 1]" in slave.errors()
    with pytest.raises(FMICallException):
        slave.set({"w_p0": -0.1})
    assert "fmi2SetReal: w_p0 (value reference 57) = -0.1 is outside its range [0, 1]" in slave.errors()
    # and a scenario is refused before the FMU sees the value, naming the key
    variable = next(v for v in slave.description.modelVariables if v.name == "t_p")
    with pytest.raises(ScenarioError, match=r"^s.toml: participants.ship.parameters.t_p: 1.5 is outside the range "
                                            r"\[0, 1\] that KCSMMG.fmu declares for 't_p'$"):
        check_parameter_value(variable, 1.5, "s.toml: participants.ship.parameters.t_p", "KCSMMG.fmu")
