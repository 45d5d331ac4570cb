"""The MMG equations of models/KCSMMG/readme.md written again in Python, independently of the
C, for the FMU tests (solve_ivp against the FMU)."""

from __future__ import annotations

import math
import tomllib

import numpy as np

from orchestrator.fmu_build import MODELS_DIR

G = 9.81
STATES = ["x", "y", "psi", "u", "v", "r", "rudder_angle", "propeller_rps"]


def mmg_parameters(name: str = "default") -> dict[str, float]:
    with open(MODELS_DIR / "KCSMMG" / "parameter_sets.toml", "rb") as f:
        values = tomllib.load(f)[name]
    values.pop("description")
    return values


def _clip(value, low, high):
    return min(max(value, low), high)


def forces(p, u, v, r, delta, n):
    """Hull, propeller and rudder forces [N, N, N m about midship] and thrust, torque."""
    rho, L, d, D = p["rho_water"], p["lpp"], p["draught"], p["prop_diameter"]
    U = math.hypot(u, v)
    if U > 1e-9:
        vp, rp = v / U, r * L / U
    else:
        vp = rp = 0.0
    q = 0.5 * rho * L * d * U * U
    XH = q * (-p["r0_prime"] + p["x_vv"] * vp**2 + p["x_vr"] * vp * rp + p["x_rr"] * rp**2 + p["x_vvvv"] * vp**4)
    YH = q * (p["y_v"] * vp + p["y_r"] * rp + p["y_vvv"] * vp**3 + p["y_vvr"] * vp**2 * rp
              + p["y_vrr"] * vp * rp**2 + p["y_rrr"] * rp**3)
    NH = q * L * (p["n_v"] * vp + p["n_r"] * rp + p["n_vvv"] * vp**3 + p["n_vvr"] * vp**2 * rp
                  + p["n_vrr"] * vp * rp**2 + p["n_rrr"] * rp**3)
    beta = math.atan2(-v, u) if U > 1e-9 else 0.0
    beta_p = beta - p["x_p"] * rp
    c2 = p["wake_c2_plus"] if beta_p > 0 else p["wake_c2_minus"]
    one_minus_w = (1 - p["w_p0"]) * (1 + (1 - math.exp(-p["wake_c1"] * abs(beta_p))) * (c2 - 1))
    ua = u * one_minus_w
    nd = n * D
    thrust = rho * D**2 * (p["k_t0"] * nd**2 + p["k_t1"] * nd * ua + p["k_t2"] * ua**2)
    torque = rho * D**3 * (p["k_q0"] * nd**2 + p["k_q1"] * nd * ua + p["k_q2"] * ua**2)
    XP = (1 - p["t_p"]) * thrust
    slip = math.sqrt(ua**2 + max(0.0, 8 * thrust / (math.pi * rho * D**2)))
    eta, kappa = p["rudder_eta"], p["kappa"]
    uR = p["epsilon"] * math.sqrt(eta * (ua + kappa * (slip - ua)) ** 2 + (1 - eta) * ua**2)
    beta_r = beta - p["l_r"] * rp
    gamma = p["gamma_r_plus"] if beta_r >= 0 else p["gamma_r_minus"]
    vR = U * gamma * beta_r
    alpha = delta - math.atan2(vR, uR)
    FN = 0.5 * rho * p["rudder_area"] * (uR**2 + vR**2) * p["f_alpha"] * math.sin(alpha)
    XR = -(1 - p["t_r"]) * FN * math.sin(delta)
    YR = -(1 + p["a_h"]) * FN * math.cos(delta)
    NR = -(p["x_r"] * L + p["a_h"] * p["x_h"] * L) * FN * math.cos(delta)
    return XH + XP + XR, YH + YR, NH + NR, thrust, torque


def loads(p, psi, u, v, env):
    """Wind and wave loads as models/KCS/readme.md (same formulas as the 3-DOF plant)."""
    cn, ce = env["current_north"], env["current_east"]
    beta, wind = env["wind_direction"], env["wind_speed"]
    c, s = math.cos(psi), math.sin(psi)
    rel_n = u * c - v * s + cn + wind * math.cos(beta)
    rel_e = u * s + v * c + ce + wind * math.sin(beta)
    u_rw, v_rw = c * rel_n + s * rel_e, -s * rel_n + c * rel_e
    gamma = math.atan2(v_rw, u_rw)
    qa = 0.5 * p["rho_air"] * (u_rw**2 + v_rw**2)
    gw = beta - psi
    qw = 0.5 * p["rho_water"] * G * env["hs"] ** 2
    wu = -qa * p["wind_cx"] * p["wind_area_frontal"] * math.cos(gamma) - qw * p["wave_cx"] * p["beam"] * math.cos(gw)
    wv = -qa * p["wind_cy"] * p["wind_area_lateral"] * math.sin(gamma) - qw * p["wave_cy"] * p["lpp"] * math.sin(gw)
    wr = (-qa * p["wind_cn"] * p["wind_area_lateral"] * p["lpp"] * math.sin(2 * gamma)
          - qw * p["wave_cn"] * p["lpp"] ** 2 * math.sin(2 * gw))
    return wu, wv, wr


def make_rhs(p, rudder_command, rps_command, env):
    """solve_ivp right-hand side for constant commands (rad, 1/s) and weather."""
    m = p["rho_water"] * p["displacement"]
    xg = p["x_g"]
    izz = m * p["k_zz"] ** 2 + xg**2 * m + p["j_z"]
    d_cmd = _clip(rudder_command, -p["rudder_max"], p["rudder_max"])
    n_cmd = _clip(rps_command, 0.0, p["propeller_rps_max"])

    def rhs(t, s):
        x, y, psi, u, v, r, delta, n = s
        X, Y, N, _, _ = forces(p, u, v, r, delta, n)
        wu, wv, wr = loads(p, psi, u, v, env)
        X, Y, N = X + wu, Y + wv, N + wr
        udot = (X + (m + p["m_y"]) * v * r + xg * m * r * r) / (m + p["m_x"])
        a = np.array([[m + p["m_y"], xg * m], [xg * m, izz]])
        b = np.array([Y - (m + p["m_x"]) * u * r, N - xg * m * u * r])
        vdot, rdot = np.linalg.solve(a, b)
        ddot = _clip((d_cmd - delta) / p["rudder_time_constant"], -p["rudder_rate_max"], p["rudder_rate_max"])
        ndot = _clip((n_cmd - n) / p["propeller_time_constant"], -p["propeller_rate_max"], p["propeller_rate_max"])
        return [u * math.cos(psi) - v * math.sin(psi) + env["current_north"],
                u * math.sin(psi) + v * math.cos(psi) + env["current_east"],
                r, udot, vdot, rdot, ddot, ndot]

    return rhs


def equilibrium_rps(p, speed_m_s: float) -> float:
    """Propeller revolutions [1/s] that hold ``speed_m_s`` in calm straight motion."""
    low, high = 0.0, p["propeller_rps_max"]
    for _ in range(80):
        mid = 0.5 * (low + high)
        X = forces(p, speed_m_s, 0.0, 0.0, 0.0, mid)[0]
        low, high = (mid, high) if X < 0 else (low, mid)
    return 0.5 * (low + high)
