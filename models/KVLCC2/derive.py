"""Figures of the KVLCC2 plant derived from its published coefficients (run: python models/KVLCC2/derive.py).

The hull resistance R'_0 is the full-scale one (ITTC-57 friction, form factor 1.20, the
published wetted surface; the MMG set's 0.022 is the model's); the hull, propeller and rudder coefficients are those of model.c (the MMG standard set for
the KVLCC2, Yasukawa and Yoshimura 2015, full scale).  Printed: the mass terms, the shaft
speed that holds the service speed, its torque and power, and the force interface's limits
(MaxSurgeForce, MaxYawMoment) as a data sheet would give them: the net thrust at the largest
shaft speed and the rudder yaw moment at the stall angle, both at the service speed.
"""

import math

from orchestrator.geometry import KNOT  # m/s per knot

RHO = 1025.0
L, B, D_DRAUGHT, VOLUME, X_G = 320.0, 58.0, 20.8, 312600.0, 11.2   # m, m, m, m^3, m
D_P, A_R, H_R = 9.86, 112.5, 15.8                                  # m, m^2, m
MX, MY, JZ = 0.022, 0.223, 0.011
NU, WETTED = 1.19e-6, 27194.0             # m^2/s sea water at 15 C; m^2 wetted surface (published)
FORM_FACTOR, C_A = 1.20, 0.2e-3           # 1 + k of a full hull; correlation allowance
K_T = (0.2931, -0.2753, -0.1385)
K_Q = (0.0327, -0.0250, -0.0075)       # estimate (not published with the MMG set): see readme.md
W_P0, T_P = 0.40, 0.220
EPSILON, KAPPA, F_ALPHA, A_H, X_H, X_R = 1.09, 0.50, 2.747, 0.312, -0.464, -0.5
STALL_DEG = 27.0
SERVICE_KN, RPM_MAX = 15.5, 80.0


def thrust(n: float, u: float) -> float:
    ua, nd = u * (1 - W_P0), n * D_P
    return RHO * D_P ** 2 * (K_T[0] * nd ** 2 + K_T[1] * nd * ua + K_T[2] * ua ** 2)


def torque(n: float, u: float) -> float:
    ua, nd = u * (1 - W_P0), n * D_P
    return RHO * D_P ** 3 * (K_Q[0] * nd ** 2 + K_Q[1] * nd * ua + K_Q[2] * ua ** 2)


def resistance_coefficient(u: float) -> float:
    """R'_0 at full scale: ITTC-57 friction with a form factor, over 1/2 rho L d U^2."""
    cf = 0.075 / (math.log10(u * L / NU) - 2) ** 2
    return (FORM_FACTOR * cf + C_A) * WETTED / (L * D_DRAUGHT)


def derive() -> dict[str, float]:
    m = RHO * VOLUME
    q = 0.5 * RHO * L * D_DRAUGHT
    u = SERVICE_KN * KNOT
    r0 = resistance_coefficient(u)
    resistance = q * u ** 2 * r0
    low, high = 0.1, 5.0                      # shaft speed [1/s] holding the service speed
    for _ in range(80):
        n = 0.5 * (low + high)
        low, high = (n, high) if (1 - T_P) * thrust(n, u) < resistance else (low, n)
    n_max = RPM_MAX / 60.0
    ua = u * (1 - W_P0)
    t_max = thrust(n, u)
    slip = math.sqrt(ua ** 2 + 8 * t_max / (math.pi * RHO * D_P ** 2))
    eta = D_P / H_R
    u_r = EPSILON * math.sqrt(eta * (ua + KAPPA * (slip - ua)) ** 2 + (1 - eta) * ua ** 2)
    stall = math.radians(STALL_DEG)
    f_n = 0.5 * RHO * A_R * u_r ** 2 * F_ALPHA * math.sin(stall)
    lever = -(X_R + A_H * X_H) * L
    return {"m": m, "m_x": MX * q * L, "m_y": MY * q * L, "j_z": JZ * q * L ** 3,
            "i_zg": m * (0.25 * L) ** 2, "r0_prime": r0, "resistance_service_N": resistance,
            "rpm_service": 60 * n, "torque_service_Nm": torque(n, u),
            "power_service_kW": 2 * math.pi * n * torque(n, u) / 1e3,
            "torque_max_Nm": torque(n_max, u), "power_max_kW": 2 * math.pi * n_max * torque(n_max, u) / 1e3,
            "max_surge_force_MN": (1 - T_P) * thrust(n_max, u) / 1e6,
            "rudder_lever_m": lever, "rudder_in_slipstream": eta,
            "max_yaw_moment_MNm": lever * f_n * math.cos(stall) / 1e6}


if __name__ == "__main__":
    for key, value in derive().items():
        print(f"{key:22s} {value:.6e}")
