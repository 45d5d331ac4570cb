"""KCS plant FMU: validation, trajectory against an independent solve_ivp integration of the
model's equations (docs/method.md), input saturation, and FMU state round trips."""

from __future__ import annotations

import tomllib

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException
from fmpy.validation import validate_fmu
from scipy.integrate import solve_ivp

from orchestrator.fmu_build import MODELS_DIR

KNOT = 1852.0 / 3600.0
G = 9.81
STATES = ["x", "y", "psi", "u", "v", "r"]


def parameters(name: str = "default") -> dict[str, float]:
    with open(MODELS_DIR / "KCS" / "parameter_sets.toml", "rb") as f:
        values = tomllib.load(f)[name]
    values.pop("description")
    return values


def reference_rhs(p, tau_u, tau_r, env):
    """The 3-DOF equations with the model readme's wind and wave loads, written independently of the C."""
    m11, m22, m33 = p["m11"], p["m22"], p["m33"]
    d11, d22, d33, d23, d32 = p["d11"], p["d22"], p["d33"], p["d23"], p["d32"]
    vc = np.array([env["current_north"], env["current_east"]])
    beta, wind = env["wind_direction"], env["wind_speed"]
    wind_velocity = -wind * np.array([np.cos(beta), np.sin(beta)])  # air moves towards

    def rhs(t, s):
        x, y, psi, u, v, r = s
        rot = np.array([[np.cos(psi), -np.sin(psi)], [np.sin(psi), np.cos(psi)]])
        ground = rot @ np.array([u, v]) + vc
        apparent = rot.T @ (wind_velocity - ground)  # air relative to ship, body frame
        gamma = np.arctan2(-apparent[1], -apparent[0])  # angle off the bow it comes from
        q = 0.5 * p["rho_air"] * apparent @ apparent
        gw = beta - psi
        qw = 0.5 * p["rho_water"] * G * env["hs"] ** 2
        w_u = -q * p["wind_cx"] * p["wind_area_frontal"] * np.cos(gamma) \
            - qw * p["wave_cx"] * p["beam"] * np.cos(gw)
        w_v = -q * p["wind_cy"] * p["wind_area_lateral"] * np.sin(gamma) \
            - qw * p["wave_cy"] * p["lpp"] * np.sin(gw)
        w_r = -q * p["wind_cn"] * p["wind_area_lateral"] * p["lpp"] * np.sin(2 * gamma) \
            - qw * p["wave_cn"] * p["lpp"] ** 2 * np.sin(2 * gw)
        return [
            ground[0], ground[1], r,
            (m22 * v * r - d11 * u + tau_u + w_u) / m11,
            (-m11 * u * r - d22 * v - d23 * r + w_v) / m22,
            ((m11 - m22) * u * v - d32 * v - d33 * r + tau_r + w_r) / m33,
        ]

    return rhs


def schedule(p):
    """Stepped (tau_u, tau_r) over a 2-hour manoeuvre: (start time s, tau_u N, tau_r N m).
    One segment asks for more than the bounds to exercise the saturation."""
    cruise = p["d11"] * 18 * KNOT
    return [
        (0.0, cruise, 0.0),
        (600.0, cruise, 0.3 * p["tau_r_max"]),
        (1500.0, 1.3 * cruise, -0.6 * p["tau_r_max"]),
        (2400.0, 0.8 * cruise, 0.0),
        (3600.0, 3.0 * p["tau_u_max"], 2.0 * p["tau_r_max"]),
        (4200.0, cruise, -0.2 * p["tau_r_max"]),
        (5400.0, cruise, 0.0),
    ]


def reference_trajectory(p, env, times, x0):
    steps = schedule(p)
    out = np.empty((len(times), 6))
    state = np.array(x0, dtype=float)
    out[0] = state
    for k in range(len(times) - 1):
        t0, t1 = times[k], times[k + 1]
        tau_u, tau_r = [s[1:] for s in steps if s[0] <= t0][-1]
        tau_u = np.clip(tau_u, -p["tau_u_max"], p["tau_u_max"])
        tau_r = np.clip(tau_r, -p["tau_r_max"], p["tau_r_max"])
        sol = solve_ivp(reference_rhs(p, tau_u, tau_r, env), (t0, t1), state, method="DOP853",
                        rtol=1e-10, atol=1e-9)
        state = sol.y[:, -1]
        out[k + 1] = state
    return out


def fmu_trajectory(slave, p, env, times, x0, h_int):
    start = dict(zip(["x0", "y0", "psi0", "u0", "v0", "r0"], x0))
    slave.initialize({**start, "h_int": h_int, **env})
    steps = schedule(p)
    out = [slave.get(*STATES)]
    for k in range(len(times) - 1):
        tau_u, tau_r = [s[1:] for s in steps if s[0] <= times[k]][-1]
        slave.set({"tau_u": tau_u, "tau_r": tau_r})
        slave.fmu.doStep(times[k], times[k + 1] - times[k])
        out.append(slave.get(*STATES))
    return np.array(out)


def assert_trajectories_close(fmu, ref, rtol=1e-6):
    """Relative to each signal's range; heading compared through its wrapped difference."""
    ref = ref.copy()
    heading_error = np.angle(np.exp(1j * (fmu[:, 2] - ref[:, 2])))
    assert np.max(np.abs(heading_error)) <= rtol * np.pi
    for k in (0, 1, 3, 4, 5):
        scale = np.max(np.abs(ref[:, k]))
        np.testing.assert_allclose(fmu[:, k], ref[:, k], rtol=0, atol=rtol * scale,
                                   err_msg=STATES[k])


def test_validates(fmus):
    assert validate_fmu(str(fmus["KCS"])) == []


CALM_WITH_CURRENT = dict(current_north=0.4, current_east=-0.3, wind_speed=0.0,
                         wind_direction=0.0, hs=0.0)
WIND_AND_WAVES = dict(current_north=0.2, current_east=0.5, wind_speed=13.0,
                      wind_direction=np.radians(60.0), hs=2.5)


@pytest.mark.parametrize("env", [CALM_WITH_CURRENT, WIND_AND_WAVES], ids=["current", "weather"])
def test_matches_independent_integration_over_two_hours(fmus, open_slave, env):
    # RK4's global error is O(h^4): at h_int = 0.25 s against the fastest pole (-0.11 1/s)
    # it is ~1e-8 relative, well inside the 1e-6 asked for.
    p = parameters()
    times = np.arange(0.0, 7200.0 + 1e-9, 30.0)
    x0 = [100.0, -200.0, np.radians(30.0), 18 * KNOT, 0.0, 0.0]
    ref = reference_trajectory(p, env, times, x0)
    fmu = fmu_trajectory(open_slave(fmus["KCS"]), p, env, times, x0, h_int=0.25)
    assert_trajectories_close(fmu, ref)
    # the manoeuvre really turned and moved the ship, and the heading output stays wrapped
    assert np.ptp(np.unwrap(ref[:, 2])) > np.pi
    assert np.all(np.abs(fmu[:, 2]) <= np.pi)


def test_outputs_over_ground_include_the_current(fmus, open_slave):
    slave = open_slave(fmus["KCS"])
    slave.initialize({"u0": 5.0, "psi0": np.pi / 2, **CALM_WITH_CURRENT})
    sog, cog = slave.get("sog", "cog")
    ground = np.array([0.4, 5.0 - 0.3])
    assert sog == pytest.approx(np.hypot(*ground), rel=1e-12)
    assert cog == pytest.approx(np.arctan2(ground[1], ground[0]), rel=1e-12)


def test_saturates_inputs_at_the_bounds(fmus, open_slave):
    p = parameters()
    finals = []
    for factor in (1.0, 5.0):
        slave = open_slave(fmus["KCS"])
        slave.initialize()
        slave.set({"tau_u": factor * p["tau_u_max"], "tau_r": -factor * p["tau_r_max"]})
        slave.fmu.doStep(0.0, 300.0)
        finals.append(slave.get(*STATES))
    assert finals[0] == finals[1]
    assert finals[0][3] > 0 and finals[0][5] < 0


@pytest.mark.parametrize("value", [float("nan"), float("inf"), -float("inf")])
def test_refuses_a_non_finite_input_naming_it(fmus, open_slave, value):
    """The FMU's own check (fmi2SetReal), called directly: no master in front of it."""
    slave = open_slave(fmus["KCS"])
    slave.initialize({"u0": 9.0})
    before = slave.get(*STATES)
    with pytest.raises(FMICallException):
        slave.fmu.setReal([slave.vr["tau_u"]], [value])
    assert f"fmi2SetReal: tau_u (value reference {slave.vr['tau_u']}) = " in slave.errors()
    assert "is not finite" in slave.errors()
    slave.fmu.doStep(0.0, 10.0)  # the refused value was not stored: the step stays finite
    assert np.all(np.isfinite(slave.get(*STATES))) and slave.get(*STATES) != before


def test_state_round_trip_reproduces_the_continuation_exactly(fmus, open_slave):
    p = parameters()
    slave = open_slave(fmus["KCS"])
    slave.initialize({"u0": 9.0, **WIND_AND_WAVES})
    slave.set({"tau_u": p["d11"] * 9.0, "tau_r": 0.4 * p["tau_r_max"]})
    slave.fmu.doStep(0.0, 600.0)
    state = slave.fmu.getFMUstate()
    serialized = slave.fmu.serializeFMUstate(state)

    def continuation(t0):
        out = []
        for k in range(5):
            slave.set({"tau_r": (-1) ** k * 0.5 * p["tau_r_max"]})
            slave.fmu.doStep(t0 + 100.0 * k, 100.0)
            out.append(slave.get(*STATES))
        return out

    first = continuation(600.0)
    slave.set({"tau_r": 0.4 * p["tau_r_max"]})
    slave.fmu.setFMUstate(state)
    assert continuation(600.0) == first
    restored = slave.fmu.deSerializeFMUstate(serialized)
    slave.fmu.setFMUstate(restored)
    assert continuation(600.0) == first
    slave.fmu.freeFMUstate(state)
    slave.fmu.freeFMUstate(restored)


def test_refuses_a_mismatched_communication_point(fmus, open_slave):
    slave = open_slave(fmus["KCS"])
    slave.initialize()
    slave.fmu.doStep(0.0, 10.0)
    with pytest.raises(FMICallException):
        slave.fmu.doStep(20.0, 10.0)
    assert "currentCommunicationPoint 20 does not match the FMU's time 10" in slave.errors()


def test_refuses_fixed_parameter_after_initialisation_naming_it(fmus, open_slave):
    slave = open_slave(fmus["KCS"])
    slave.initialize()
    with pytest.raises(FMICallException):
        slave.set({"m11": 1.0})
    assert "fixed parameter m11 (value reference" in slave.errors()
    with pytest.raises(FMICallException):
        slave.set({"h_int": 0.0})  # inside the declared range [0, inf), refused by the model
    assert "h_int (value reference 43) = 0 must be positive" in slave.errors()
    with pytest.raises(FMICallException):
        slave.set({"h_int": -1.0})  # outside the declared range, refused by the shared layer
    assert "fmi2SetReal: h_int (value reference 43) = -1 is outside its range [0, inf]" in slave.errors()


def sway_yaw_poles(p, u0):
    """Poles of the sway-yaw pair linearised about straight motion at surge speed u0."""
    a = np.array([
        [-p["d22"] / p["m22"], (-p["m11"] * u0 - p["d23"]) / p["m22"]],
        [((p["m11"] - p["m22"]) * u0 - p["d32"]) / p["m33"], -p["d33"] / p["m33"]],
    ])
    return np.linalg.eigvals(a)


def test_paper_table2_set_is_unstable_at_cruise_speed():
    """Table 2 is stable only below u0 = 0.25 m/s; the unstable pole is about
    +17.7 1/s at u0 = 9 m/s (+18.2 1/s at exactly 18 kn = 9.26 m/s)."""
    p = parameters("paper_table2")
    assert max(sway_yaw_poles(p, 9.0).real) == pytest.approx(17.7, abs=0.05)
    assert max(sway_yaw_poles(p, 18 * KNOT).real) == pytest.approx(18.2, abs=0.05)
    assert max(sway_yaw_poles(p, 0.24).real) < 0 < max(sway_yaw_poles(p, 0.26).real)


def test_default_set_is_course_stable_at_18_knots():
    assert max(sway_yaw_poles(parameters(), 18 * KNOT).real) < 0


@pytest.mark.parametrize("byte, what", [(0, "magic"), (4, "size")])
def test_a_serialized_state_with_a_wrong_magic_or_size_is_refused(fmus, open_slave, byte, what):
    """The state's first two words (a magic number, the size of the state) tell a state of this FMU's
    build; either one wrong is refused, whatever the other says."""
    slave = open_slave(fmus["KCS"])
    slave.initialize({"u0": 9.0})
    state = slave.fmu.getFMUstate()
    serialized = bytearray(slave.fmu.serializeFMUstate(state))
    restored = slave.fmu.deSerializeFMUstate(bytes(serialized))  # the untouched one is taken
    slave.fmu.freeFMUstate(restored)
    serialized[byte] ^= 0x01
    with pytest.raises(FMICallException):
        slave.fmu.deSerializeFMUstate(bytes(serialized))
    assert "fmi2DeSerializeFMUstate: the FMU state does not belong to this FMU" in slave.errors(), what
    with pytest.raises(FMICallException):  # and one of another length
        slave.fmu.deSerializeFMUstate(bytes(serialized[:-1]))
    assert f"fmi2DeSerializeFMUstate: {len(serialized) - 1} bytes given, {len(serialized)} expected" in slave.errors()
    slave.fmu.freeFMUstate(state)


def test_the_last_successful_time_and_the_terminated_flag_are_reported(fmus, open_slave):
    from fmpy.fmi2 import fmi2LastSuccessfulTime, fmi2Terminated

    slave = open_slave(fmus["KCS"])
    slave.initialize({"u0": 9.0})
    slave.fmu.doStep(0.0, 10.0)
    slave.fmu.doStep(10.0, 5.0)
    assert slave.fmu.getRealStatus(fmi2LastSuccessfulTime) == 15.0
    assert slave.fmu.getBooleanStatus(fmi2Terminated) is False
    with pytest.raises(FMICallException):
        slave.fmu.getRealStatus(fmi2Terminated)  # not a real status
    assert "only fmi2LastSuccessfulTime is available" in slave.errors()


def test_debug_logging_without_categories_is_accepted_and_an_unknown_one_refused(fmus, open_slave):
    from fmpy.fmi2 import fmi2True

    slave = open_slave(fmus["KCS"])
    slave.fmu.fmi2SetDebugLogging(slave.fmu.component, fmi2True, 0, None)  # no categories: a NULL array
    slave.fmu.setDebugLogging(True, ["logAll"])
    with pytest.raises(FMICallException):
        slave.fmu.setDebugLogging(True, ["logEverything"])
    assert 'unknown log category "logEverything"' in slave.errors()


def test_a_get_or_set_of_an_unknown_value_reference_is_refused_naming_it(fmus, open_slave):
    slave = open_slave(fmus["KCS"])
    slave.initialize()
    with pytest.raises(FMICallException):
        slave.fmu.getReal([9999])
    assert "fmi2GetReal: unknown value reference 9999" in slave.errors()
    with pytest.raises(FMICallException):
        slave.fmu.setReal([9999], [1.0])
    assert "fmi2SetReal: unknown value reference 9999" in slave.errors()


def test_freeing_a_state_through_a_null_pointer_is_refused_naming_it(fmus, open_slave):
    slave = open_slave(fmus["KCS"])
    slave.initialize()
    with pytest.raises(FMICallException):
        slave.fmu.fmi2FreeFMUstate(slave.fmu.component, None)
    assert "fmi2FreeFMUstate: invalid argument FMUstate = NULL" in slave.errors()
