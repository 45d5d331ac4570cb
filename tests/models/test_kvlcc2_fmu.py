"""KVLCC2, the second third-party test ship: fmpy validates it; its vendor-unit outputs follow
an independent integration of its readme's equations (the MMG forces of mmg_reference.py with
the KVLCC2 coefficients, the governed shaft and the sphere written again here); its rudder
stalls; its force interface and parameter checks do what the readme says."""

from __future__ import annotations

import math

import numpy as np
import pytest
from fmpy.validation import validate_fmu
from scipy.integrate import solve_ivp

from mmg_reference import forces

KNOT = 1852.0 / 3600.0
DEG = math.pi / 180.0
R_EARTH = 6371008.8

#: The readme's coefficients in mmg_reference's names (Yasukawa and Yoshimura 2015, KVLCC2).
P = dict(rho_water=1025.0, lpp=320.0, draught=20.8, prop_diameter=9.86, r0_prime=7.658504e-3,
         x_vv=-0.040, x_vr=0.002, x_rr=0.011, x_vvvv=0.771, y_v=-0.315, y_r=0.083, y_vvv=-1.607, y_vvr=0.379,
         y_vrr=-0.391, y_rrr=0.008, n_v=-0.137, n_r=-0.049, n_vvv=-0.030, n_vvr=-0.294, n_vrr=0.055,
         n_rrr=-0.013, x_p=-0.48, w_p0=0.40, t_p=0.220, wake_c1=2.0, wake_c2_plus=1.6, wake_c2_minus=1.1,
         k_t0=0.2931, k_t1=-0.2753, k_t2=-0.1385, k_q0=0.0327, k_q1=-0.0250, k_q2=-0.0075, rudder_area=112.5,
         f_alpha=2.747, rudder_eta=9.86 / 15.8, epsilon=1.09, kappa=0.50, t_r=0.387, a_h=0.312, x_h=-0.464,
         x_r=-0.5, gamma_r_plus=0.640, gamma_r_minus=0.395, l_r=-0.710)


def reference_rhs(rudder_deg: float, rpm: float):
    """Calm water and air, rudder order below the stall (|alpha| < 27 deg), governed shaft, sphere."""
    m = 1025.0 * 312600.0
    q = 0.5 * 1025.0 * 320.0 * 20.8
    m11, m22, m23 = m + 0.022 * q * 320.0, m + 0.223 * q * 320.0, 11.2 * m
    m33 = m * 80.0 ** 2 + 11.2 ** 2 * m + 0.011 * q * 320.0 ** 3
    delta_order, n_order = rudder_deg * DEG, rpm / 60.0

    def rhs(_t, s):
        lat, _lon, psi, u, v, r, delta, n, n_ref, z = s
        X, Y, N, _thrust, torque = forces(P, u, v, r, delta, n)
        gamma, qa = math.atan2(v, u), 0.5 * 1.225 * (u * u + v * v)     # the air the ship moves through
        X -= qa * 0.8 * 1200.0 * math.cos(gamma)
        Y -= qa * 0.9 * 4800.0 * math.sin(gamma)
        N -= qa * 0.08 * 4800.0 * 320.0 * math.sin(2 * gamma)
        vdot, rdot = np.linalg.solve([[m22, m23], [m23, m33]], [Y - m11 * u * r, N - m23 * u * r])
        error = n_ref - n
        q_engine = min(max(5e6 * error + z, 0.0), 4.2e6)
        vn, ve = u * math.cos(psi) - v * math.sin(psi), u * math.sin(psi) + v * math.cos(psi)
        return [vn / R_EARTH, ve / (R_EARTH * math.cos(lat)), r, (X + m22 * v * r + m23 * r * r) / m11, vdot, rdot,
                min(max(delta_order - delta, -2.34 * DEG), 2.34 * DEG),
                (q_engine - torque) / (2 * math.pi * 1.2e6),
                min(max(0.5 * (n_order - n_ref), -1 / 60.0), 1 / 60.0),
                2e6 * error if 0.0 < 5e6 * error + z < 4.2e6 else 0.0]
    return rhs


def test_validates(fmus):
    assert validate_fmu(str(fmus["KVLCC2"])) == []


def test_follows_an_independent_integration_in_its_own_units(fmus, open_slave):
    ship = open_slave(fmus["KVLCC2"])
    start = {"InitialLatitude": 26.0, "InitialLongitude": 52.0, "InitialHeading": 120.0, "InitialSpeed": 15.0,
             "InitialShaftSpeed": 70.0, "IntegrationStep": 0.05}
    ship.initialize(start)
    ship.set({"RudderOrder": 15.0, "ShaftSpeedOrder": 76.0})
    u0, n0 = 15.0 * KNOT, 70.0 / 60.0
    torque0 = forces(P, u0, 0.0, 0.0, 0.0, n0)[4]
    state = [26.0 * DEG, 52.0 * DEG, 120.0 * DEG, u0, 0.0, 0.0, 0.0, n0, n0, torque0]
    solution = solve_ivp(reference_rhs(15.0, 76.0), (0.0, 600.0), state, method="LSODA", rtol=1e-10, atol=1e-10,
                         t_eval=np.arange(30.0, 601.0, 30.0), max_step=0.5)
    for k, t in enumerate(solution.t):
        ship.fmu.doStep(t - 30.0, 30.0)
        lat, lon, heading, surge, sway, rate, rudder, shaft = ship.get(
            "Latitude", "Longitude", "Heading", "SurgeSpeed", "SwaySpeed", "YawRate", "RudderAngle", "ShaftSpeed")
        s = solution.y[:, k]
        np.testing.assert_allclose([lat, lon], np.degrees(s[:2]), rtol=0, atol=2e-6)      # 0.2 m
        assert abs((heading - np.degrees(s[2]) + 180.0) % 360.0 - 180.0) < 1e-3
        np.testing.assert_allclose([surge, sway], s[3:5] / KNOT, rtol=0, atol=1e-4)
        np.testing.assert_allclose([rate, rudder, shaft], [np.degrees(s[5]), np.degrees(s[6]), 60 * s[7]],
                                   rtol=0, atol=1e-4)
    assert rudder == pytest.approx(15.0) and shaft == pytest.approx(76.0, abs=0.05) and rate > 0.1


def test_the_rudder_stalls(fmus, open_slave):
    """Hard over from straight motion: while the rudder sweeps to 35 deg at 2.34 deg/s the ship
    has hardly started to turn (the effective angle is the rudder angle), and the yaw
    acceleration falls once the rudder passes its 27 deg stall instead of growing to 35 deg."""
    ship = open_slave(fmus["KVLCC2"])
    ship.initialize({"InitialSpeed": 15.5, "InitialShaftSpeed": 71.0, "IntegrationStep": 0.05})
    ship.set({"RudderOrder": 35.0, "ShaftSpeedOrder": 71.0})
    samples = []
    for k in range(20):
        ship.fmu.doStep(k * 1.0, 1.0)
        samples.append(ship.get("RudderAngle", "YawRate"))
    rudder, rate = np.array(samples).T
    acceleration = np.diff(rate)
    angle = 0.5 * (rudder[1:] + rudder[:-1])
    at_stall = acceleration[np.argmin(abs(angle - 26.0))]
    hard_over = acceleration[np.argmin(abs(angle - 34.0))]
    assert rudder[-1] == pytest.approx(35.0, abs=0.1) and hard_over < 0.9 * at_stall


def test_the_force_interface_holds_the_speed_its_demand_balances_and_saturates(fmus, open_slave):
    speed = 15.5 * KNOT    # hull resistance and the air drag of the superstructure (the readme's R'_0, C_X)
    resistance_mn = (0.5 * 1025.0 * 320.0 * 20.8 * 7.658504e-3 + 0.5 * 1.225 * 0.8 * 1200.0) * speed ** 2 / 1e6
    ship = open_slave(fmus["KVLCC2"])
    ship.initialize({"ForceMode": 1.0, "InitialSpeed": 15.5})
    ship.set({"SurgeForceDemand": resistance_mn, "YawMomentDemand": 0.0})
    for k in range(30):
        ship.fmu.doStep(k * 20.0, 20.0)
    surge, rate, rudder, shaft = ship.get("SurgeSpeed", "YawRate", "RudderAngle", "ShaftSpeed")
    assert surge == pytest.approx(15.5, abs=0.01) and rate == 0.0 and rudder == 0.0 and shaft == 0.0
    turned = []
    for demand in (587.0, 5870.0):             # the second is saturated at MaxYawMoment = 587 MN m
        ship = open_slave(fmus["KVLCC2"])
        ship.initialize({"ForceMode": 1.0, "InitialSpeed": 15.5})
        ship.set({"SurgeForceDemand": resistance_mn, "YawMomentDemand": demand})
        ship.fmu.doStep(0.0, 60.0)
        turned.append(ship.get("YawRate")[0])
    assert turned[0] > 0.05 and turned[1] == pytest.approx(turned[0], rel=1e-12)


@pytest.mark.parametrize("name, value, message", [
    ("ForceMode", 0.5, "ForceMode = 0.5 must be 0"),
    ("InitialShaftSpeed", 95.0, "InitialShaftSpeed = 95 rpm is outside"),
    ("InitialLatitude", 89.0, "InitialLatitude = 89 deg is outside"),
])
def test_bad_parameters_are_refused_at_initialization_naming_them(refused_at_initialization, name, value, message):
    refused_at_initialization("KVLCC2", name, value, message)
