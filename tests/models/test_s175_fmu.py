"""S175, the third-party test ship: fmpy validates it, and its vendor-unit outputs follow an
independent integration (solve_ivp) of its equations with the coefficients of derive.py, in the
force mode (the default, unchanged since before the actuator interface: a golden run of that
FMU) and with actuator_mode = 1 (steering gear at its rate, shaft, propeller, a rudder that
stalls); the data sheet ships/S175.toml gives the FMU's thrust."""

from __future__ import annotations

from pathlib import Path

import math

import numpy as np
import pandas as pd
import pytest
from fmpy.validation import validate_fmu
from scipy.integrate import solve_ivp
from script_module import module_of_file

KNOT = 1852.0 / 3600.0
DEG = np.pi / 180.0
A, E2 = 6378137.0, 6.69437999014e-3
DERIVE = Path(__file__).resolve().parents[2] / "models" / "S175" / "derive.py"
GOLDEN = Path(__file__).resolve().parents[1] / "data" / "s175_force_mode_golden.csv"
SERVICE_RPM = 83.57268   # holds 18 kn against the hull's resistance (derive.py)


def coefficients():
    return module_of_file(DERIVE, "s175_derive").derive()


def derive_module():
    return module_of_file(DERIVE, "s175_derive")


def test_validates(fmus):
    assert validate_fmu(str(fmus["S175"])) == []


def actuator_forces(u, v, r, delta, n):
    """Propeller and rudder [X, Y, N] (N, N, N m) of the readme (Son and Nomoto's form, the
    stall of the readme), written again; data from derive.py."""
    a = derive_module()
    big_u = math.hypot(u, v)
    vp, rp = v / big_u, r * 175.0 / big_u
    u_p = u * ((1 - a.W_P) + 1.09 * (vp - 0.526 * rp) ** 2)
    thrust = 1025.0 * a.D_P ** 2 * (a.K_T[0] * (n * a.D_P) ** 2 + a.K_T[1] * n * a.D_P * u_p)
    u_r = a.EPSILON * math.sqrt(max(u_p ** 2 + 8 * a.KAPPA * thrust / (math.pi * 1025.0 * a.D_P ** 2), 0.0))
    v_r = big_u * (0.088 * vp - 0.156 * rp - 0.275 * rp ** 3 + 1.96 * rp ** 2 * vp)
    alpha = delta + math.atan2(v_r, u_r)
    stall = math.radians(a.STALL_DEG)
    if abs(alpha) <= stall:
        shape = math.sin(alpha)
    else:
        drop = min((abs(alpha) - stall) / math.radians(5.0), 1.0)
        shape = math.copysign(math.sin(stall) * (1 - (1 - a.POST_STALL) * drop), alpha)
    normal = 0.5 * 1025.0 * a.A_R * (u_r ** 2 + v_r ** 2) * a.lift_slope() * shape
    return ((1 - a.T_P) * thrust - 0.71 * normal * math.sin(delta), -(1 + a.A_H) * normal * math.cos(delta),
            -(a.X_R + a.A_H * a.X_H) * 175.0 * normal * math.cos(delta))


def reference_rhs(c, inputs, actuators=False):
    """The S175's equations, written again from its readme (SI; lat/lon in rad); with
    ``actuators`` the state carries the rudder angle and the shaft speed [1/s] too."""
    tau_u = min(inputs.get("propeller_thrust", 0.0), 800.0) * 1e3
    tau_r = inputs.get("rudder_moment", 0.0) * 1e3
    tau_v = 0.0
    rudder_order = np.clip(inputs.get("rudder_order", 0.0), -35.0, 35.0) * DEG
    shaft_order = np.clip(inputs.get("shaft_speed_order", 0.0), 0.0, 107.0) / 60.0
    set_, drift = inputs["current_set"] * DEG, inputs["current_drift"] * KNOT
    wind_from, wind = inputs["wind_from"] * DEG, inputs["wind_speed_true"] * KNOT
    hs = inputs["wave_height"]

    def rhs(_t, s):
        nonlocal tau_u, tau_v, tau_r
        lat, _lon, _n, _e, psi, u, v, r = s[:8]
        if actuators:
            tau_u, tau_v, tau_r = actuator_forces(u, v, r, s[8], s[9])
        vn = u * np.cos(psi) - v * np.sin(psi) + drift * np.cos(set_)
        ve = u * np.sin(psi) + v * np.cos(psi) + drift * np.sin(set_)
        rel_n, rel_e = vn + wind * np.cos(wind_from), ve + wind * np.sin(wind_from)
        u_rw = np.cos(psi) * rel_n + np.sin(psi) * rel_e
        v_rw = -np.sin(psi) * rel_n + np.cos(psi) * rel_e
        g, q = np.arctan2(v_rw, u_rw), 0.5 * 1.225 * (u_rw ** 2 + v_rw ** 2)
        gw, qw = wind_from - psi, 0.5 * 1025.0 * 9.81 * hs ** 2
        w = (-q * 0.7 * 640 * np.cos(g) - qw * 0.1 * 25.4 * np.cos(gw),
             -q * 0.85 * 3000 * np.sin(g) - qw * 0.03 * 175 * np.sin(gw),
             -q * 0.1 * 3000 * 175 * np.sin(2 * g) - qw * 0.005 * 175 ** 2 * np.sin(2 * gw))
        k = 1 - E2 * np.sin(lat) ** 2
        derivative = [vn / (A * (1 - E2) / k ** 1.5), ve / (A / np.sqrt(k) * np.cos(lat)), vn, ve, r,
                      (c["m22"] * v * r - c["x_uu"] * u * abs(u) + tau_u + w[0]) / c["m11"],
                      (-c["m11"] * u * r - c["d22"] * v - c["d23"] * r + w[1] + tau_v) / c["m22"],
                      ((c["m11"] - c["m22"]) * u * v - c["d32"] * v - c["d33"] * r + tau_r + w[2]) / c["m33"]]
        if actuators:
            n = s[9]
            derivative += [np.clip(rudder_order - s[8], -2.32 * DEG, 2.32 * DEG),
                           (shaft_order - n) / (5.65 / n if n > 0.3 else 18.83)]
        return derivative
    return rhs


def test_follows_an_independent_integration_in_its_own_units(fmus, open_slave):
    c = coefficients()
    ship = open_slave(fmus["S175"])
    ship.initialize({"start_lat": 52.0, "start_lon": 3.5, "start_heading": 300.0, "start_stw": 16.0,
                     "internal_step": 0.1})
    inputs = {"propeller_thrust": 900.0, "rudder_moment": -9.0e4, "current_set": 135.0, "current_drift": 1.5,
              "wind_speed_true": 30.0, "wind_from": 200.0, "wave_height": 2.5}
    ship.set(inputs)
    state = [52.0 * DEG, 3.5 * DEG, 0.0, 0.0, 300.0 * DEG, 16.0 * KNOT, 0.0, 0.0]
    solution = solve_ivp(reference_rhs(c, inputs), (0.0, 600.0), state, rtol=1e-11, atol=1e-12,
                         t_eval=np.arange(60.0, 601.0, 60.0))
    for k, t in enumerate(solution.t):
        ship.fmu.doStep(t - 60.0, 60.0)
        lat, lon, north, east, heading, stw, sway, rot = ship.get(
            "lat", "lon", "north_km", "east_km", "heading", "stw", "sway_speed", "rot")
        s = solution.y[:, k]
        np.testing.assert_allclose([lat, lon], np.degrees(s[:2]), rtol=0, atol=1e-8)
        np.testing.assert_allclose([north, east], s[2:4] / 1e3, rtol=0, atol=1e-4)   # 0.1 m
        assert abs((heading - np.degrees(s[4])) % 360.0) < 1e-4 or abs((heading - np.degrees(s[4])) % 360.0 - 360) < 1e-4
        np.testing.assert_allclose([stw, sway], s[5:7] / KNOT, rtol=0, atol=1e-5)
        np.testing.assert_allclose(rot, np.degrees(s[7]) * 60.0, rtol=0, atol=1e-4)
        assert 0.0 <= heading < 360.0
    assert rot < -30.0 and np.hypot(north, east) > 0.5   # it sailed, turning hard to port


def test_the_force_mode_is_the_fmu_it_was_before_the_actuator_interface(fmus, open_slave):
    """The golden run was made with main's FMU before actuator_mode existed; the default mode
    must give it again, and the actuator orders must not reach the ship in it."""
    golden = pd.read_csv(GOLDEN, comment="#")
    names = [n for n in golden.columns if n != "time_s"]
    for orders in ({}, {"rudder_order": 30.0, "shaft_speed_order": 100.0}):
        ship = open_slave(fmus["S175"])
        ship.initialize({"start_lat": 52.0, "start_lon": 3.5, "start_heading": 300.0, "start_stw": 16.0})
        ship.set({"propeller_thrust": 900.0, "rudder_moment": -9.0e4, "current_set": 135.0, "current_drift": 1.5,
                  "wind_speed_true": 30.0, "wind_from": 200.0, "wave_height": 2.5, **orders})
        rows, t = [], 0.0
        while t < 600.0:
            if t == 300.0:
                ship.set({"propeller_thrust": 300.0, "rudder_moment": 2.0e5})
            ship.fmu.doStep(t, 10.0)
            t += 10.0
            if t % 30.0 == 0.0:
                rows.append(ship.get(*names))
        np.testing.assert_allclose(np.array(rows), golden[names].to_numpy(), rtol=1e-12, atol=0)
        assert ship.get("rudder_position", "shaft_speed", "shaft_thrust") == [0.0, 0.0, 300.0]


def test_the_actuator_mode_follows_an_independent_integration(fmus, open_slave):
    """Rudder 20 deg to port (below the stall), shaft from 83.6 to 100 rpm, in current, wind and
    waves: the steering gear, the shaft lag, the propeller and the rudder of the readme."""
    c = coefficients()
    ship = open_slave(fmus["S175"])
    ship.initialize({"actuator_mode": 1.0, "start_lat": 35.0, "start_lon": 140.0, "start_heading": 45.0,
                     "start_stw": 18.0, "start_shaft_speed": SERVICE_RPM, "internal_step": 0.05})
    inputs = {"rudder_order": -20.0, "shaft_speed_order": 100.0, "current_set": 135.0, "current_drift": 1.0,
              "wind_speed_true": 25.0, "wind_from": 200.0, "wave_height": 2.0}
    ship.set(inputs)
    state = [35.0 * DEG, 140.0 * DEG, 0.0, 0.0, 45.0 * DEG, 18.0 * KNOT, 0.0, 0.0, 0.0, SERVICE_RPM / 60.0]
    solution = solve_ivp(reference_rhs(c, inputs, actuators=True), (0.0, 600.0), state, method="LSODA",
                         rtol=1e-10, atol=1e-10, t_eval=np.arange(30.0, 601.0, 30.0), max_step=0.5)
    for k, t in enumerate(solution.t):
        ship.fmu.doStep(t - 30.0, 30.0)
        north, east, stw, sway, rot, rudder, shaft = ship.get(
            "north_km", "east_km", "stw", "sway_speed", "rot", "rudder_position", "shaft_speed")
        s = solution.y[:, k]
        np.testing.assert_allclose([north, east], s[2:4] / 1e3, rtol=0, atol=2e-4)      # 0.2 m
        np.testing.assert_allclose([stw, sway], s[5:7] / KNOT, rtol=0, atol=1e-4)
        np.testing.assert_allclose([rot, rudder, shaft], [np.degrees(s[7]) * 60.0, np.degrees(s[8]), 60.0 * s[9]],
                                   rtol=0, atol=1e-3)
    assert rudder == pytest.approx(-20.0) and shaft == pytest.approx(100.0, abs=0.01) and rot < -20.0


def start_turn(fmus, open_slave, rudder_order: float):
    ship = open_slave(fmus["S175"])
    ship.initialize({"actuator_mode": 1.0, "start_stw": 18.0, "start_shaft_speed": SERVICE_RPM,
                     "internal_step": 0.05})
    ship.set({"rudder_order": rudder_order, "shaft_speed_order": SERVICE_RPM})
    return ship


def test_the_steering_gear_holds_its_range_and_rate(fmus, open_slave):
    """An order of 50 deg: the rudder moves at 2.32 deg/s at most and stops at 35 deg; reversed
    to -50 deg it swings back at exactly that rate until it nears -35 deg."""
    ship = start_turn(fmus, open_slave, 50.0)
    angles, t = [0.0], 0.0
    for order in (50.0, -50.0):
        ship.set({"rudder_order": order})
        for _ in range(60):
            ship.fmu.doStep(t, 0.5)
            t += 0.5
            angles.append(ship.get("rudder_position")[0])
    rate = np.diff(angles) / 0.5
    assert np.max(np.abs(rate)) <= 2.32 + 1e-9
    assert max(angles) <= 35.0 and angles[60] == pytest.approx(35.0, abs=0.01)
    np.testing.assert_allclose(rate[60:110], -2.32, rtol=0, atol=1e-9)   # 25 s of the swing back


def test_the_rudder_stalls_beyond_30_degrees(fmus, open_slave):
    """Hard over from straight motion: once the rudder passes its 30 deg stall, more angle gives
    less normal force, so 20 s after the order 35 deg has turned the ship less than 30 deg
    (without the stall the larger angle turns it faster: sin 35 > sin 30)."""
    rates = {}
    for order in (30.0, 35.0):
        ship = start_turn(fmus, open_slave, order)
        for k in range(20):
            ship.fmu.doStep(k * 1.0, 1.0)
        rates[order] = ship.get("rot")[0]
        assert ship.get("rudder_position")[0] == pytest.approx(order, abs=0.01)
    assert 0.0 < rates[35.0] < 0.99 * rates[30.0]


def test_the_data_sheet_gives_the_fmus_thrust_and_trim_revolutions():
    """ships/S175.toml through the allocation's force model: in straight motion its thrust is
    the FMU's (the same K_T(J) and wake), and the revolutions it asks for the hull's resistance
    at 18 kn are those the scenarios start with."""
    from rhnc.control.allocation import ForceModel, coefficients_from_ship

    model = ForceModel(coefficients_from_ship("S175", "test"))
    a = derive_module()
    u = 18.0 * KNOT
    for rpm in (40.0, SERVICE_RPM, 107.0):
        assert model.thrust(rpm / 60.0, u) == pytest.approx(a.thrust(rpm / 60.0, u), rel=1e-12)
    assert 60.0 * model.rps_for(coefficients()["x_uu"] * u * u, u) == pytest.approx(SERVICE_RPM, abs=1e-4)


def test_fmu_thrust_at_the_trim_revolutions(fmus, open_slave):
    ship = open_slave(fmus["S175"])
    ship.initialize({"actuator_mode": 1.0, "start_stw": 18.0, "start_shaft_speed": SERVICE_RPM})
    ship.set({"shaft_speed_order": SERVICE_RPM})
    ship.fmu.doStep(0.0, 1.0)
    thrust_kn, stw = ship.get("shaft_thrust", "stw")
    assert thrust_kn * 1e3 == pytest.approx(derive_module().thrust(SERVICE_RPM / 60.0, stw * KNOT), rel=1e-9)
    assert (1 - 0.175) * thrust_kn == pytest.approx(coefficients()["x_uu"] * (18.0 * KNOT) ** 2 / 1e3, rel=1e-3)


@pytest.mark.parametrize("name, value, message", [
    ("actuator_mode", 0.5, "actuator_mode = 0.5 must be 0"),
    ("start_lat", 89.0, "start_lat = 89 deg is outside"),
])
def test_bad_parameters_are_refused_at_initialization_naming_them(refused_at_initialization, name, value, message):
    refused_at_initialization("S175", name, value, message)
