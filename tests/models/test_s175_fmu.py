"""S175, the third-party test ship: fmpy validates it, and its vendor-unit outputs follow an
independent integration (solve_ivp) of its equations with the coefficients of derive.py."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from fmpy.validation import validate_fmu
from scipy.integrate import solve_ivp
from script_module import module_of_file

KNOT = 1852.0 / 3600.0
DEG = np.pi / 180.0
A, E2 = 6378137.0, 6.69437999014e-3
DERIVE = Path(__file__).resolve().parents[2] / "models" / "S175" / "derive.py"


def coefficients():
    return module_of_file(DERIVE, "s175_derive").derive()


def test_validates(fmus):
    assert validate_fmu(str(fmus["S175"])) == []


def reference_rhs(c, inputs):
    """The S175's equations, written again from its readme (SI; lat/lon in rad)."""
    tau_u = min(inputs["propeller_thrust"], 800.0) * 1e3
    tau_r = inputs["rudder_moment"] * 1e3
    set_, drift = inputs["current_set"] * DEG, inputs["current_drift"] * KNOT
    wind_from, wind = inputs["wind_from"] * DEG, inputs["wind_speed_true"] * KNOT
    hs = inputs["wave_height"]

    def rhs(_t, s):
        lat, _lon, _n, _e, psi, u, v, r = s
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
        return [vn / (A * (1 - E2) / k ** 1.5), ve / (A / np.sqrt(k) * np.cos(lat)), vn, ve, r,
                (c["m22"] * v * r - c["x_uu"] * u * abs(u) + tau_u + w[0]) / c["m11"],
                (-c["m11"] * u * r - c["d22"] * v - c["d23"] * r + w[1]) / c["m22"],
                ((c["m11"] - c["m22"]) * u * v - c["d32"] * v - c["d33"] * r + tau_r + w[2]) / c["m33"]]
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
