"""Derive the S175 plant's coefficients from its particulars (run: python models/S175/derive.py).

Same method as the KCS set (models/KCS/readme.md): linear manoeuvring derivatives from the
regressions of Clarke, Gedling and Hine (1983), dimensionalised at the 18 kn service speed,
resistance from the ITTC-57 friction line with a form factor, rudder force after Fujii. The
printed values are those in models/S175/model.c.

The actuators (``actuator_mode = 1``, readme.md): propeller, rudder and shaft of Son and Nomoto
(1981) for the S-175 (D, K_T(J), w_P, t_P, A_R and its aspect ratio, epsilon, kappa, a_H, x'_H,
x'_R, the shaft's time constant), with our estimates for the steering gear, the stall and the
largest revolutions.  ``actuators()`` prints what the data sheet (ships/S175.toml) and
``identify`` take from them: the revolutions holding 18 kn, the largest revolutions (those
whose thrust drives the hull at the 23 kn the force interface's ``max_thrust`` was set for),
the net thrust at them and the rudder's yaw moment at its stall angle, both at 18 kn.
"""

import math

from orchestrator.geometry import KNOT

RHO = 1025.0
NU = 1.19e-6          # m^2/s, sea water at 15 C

L, B, T, CB = 175.0, 25.4, 8.5, 0.572      # m, m, m, -: the ITTC S-175 container ship
U = 18.0 * KNOT                             # m/s, dimensionalisation speed


def derive() -> dict[str, float]:
    volume = L * B * T * CB
    m = RHO * volume
    f = math.pi * (T / L) ** 2
    bt, bl, tl = B / T, B / L, T / L
    yvdot = -f * (1 + 0.16 * CB * bt - 5.1 * bl ** 2)
    nrdot = -f * (1 / 12 + 0.017 * CB * bt - 0.33 * bl)
    yv = -f * (1 + 0.40 * CB * bt)
    yr = -f * (-0.5 + 2.2 * bl - 0.080 * bt)
    nv = -f * (0.5 + 2.4 * tl)
    nr = -f * (0.25 + 0.039 * bt - 0.56 * bl)
    q = 0.5 * RHO
    m11 = 1.06 * m                          # 6 % surge added mass
    m22 = m - yvdot * q * L ** 3
    m33 = m * (0.25 * L) ** 2 - nrdot * q * L ** 5
    d22 = -yv * q * L ** 2 * U
    d33 = -nr * q * L ** 4 * U
    d23 = (m - m11) * U - yr * q * L ** 3 * U
    d32 = (m11 - m22) * U - nv * q * L ** 3 * U
    wetted = 1.7 * L * T + volume / T       # m^2, Mumford
    cf = 0.075 / (math.log10(U * L / NU) - 2) ** 2
    ct = 1.12 * cf + 0.15e-3 + 0.2e-3       # form factor 1.12, C_W, C_A
    x_uu = q * wetted * ct                  # N/(m/s)^2: R = x_uu u |u|
    area_rudder = L * T / 50.0
    aspect = 1.6
    cn = 6.13 * aspect / (aspect + 2.25) * math.sin(math.radians(35.0))
    tau_r_max = q * U ** 2 * area_rudder * cn * 0.5 * L
    return {"volume": volume, "m": m, "m11": m11, "m22": m22, "m33": m33, "x_uu": x_uu,
            "d22": d22, "d33": d33, "d23": d23, "d32": d32, "R18": x_uu * U ** 2,
            "R22": x_uu * (22 * KNOT) ** 2, "tau_r_max": tau_r_max, "clarke_C": yv * nr - nv * (yr - m / (q * L ** 3))}


#: Propeller, rudder and shaft, Son and Nomoto (1981) for the S-175
D_P, K_T = 6.533, (0.527, -0.455)          # m; K_T(J) = k0 + k1 J
W_P, T_P = 0.184, 0.175                     # wake and thrust deduction fractions
A_R, ASPECT = 33.0376, 1.8219               # m^2 movable rudder area; its aspect ratio
EPSILON, KAPPA = 0.921, 0.631               # rudder inflow: u_R^2 = eps^2 (u_P^2 + 8 kappa T / (pi rho D^2))
A_H, X_H, X_R = 0.237, -0.48, -0.5          # hull-rudder interaction; x'_H, x'_R (of Lpp)
SHAFT_TIME_S_RPS = 5.65                     # s x 1/s: the shaft's time constant is 5.65 / n above 0.3 1/s
#: Ours (not published with the set): the steering gear, the stall, the largest revolutions
RUDDER_MAX_DEG, RUDDER_RATE_DEG_S = 35.0, 2.32
STALL_DEG, POST_STALL = 30.0, 0.6
TOP_SPEED_KN = 23.0


def lift_slope() -> float:
    """Fujii's normal-force slope of a rudder of this aspect ratio [1/rad]."""
    return 6.13 * ASPECT / (ASPECT + 2.25)


def thrust(n: float, u: float) -> float:
    """Propeller thrust [N] at n [1/s] in straight motion at u [m/s]."""
    ua, nd = u * (1 - W_P), n * D_P
    return RHO * D_P ** 2 * (K_T[0] * nd * nd + K_T[1] * nd * ua)


def rudder_inflow(n: float, u: float) -> float:
    """Rudder inflow speed [m/s] in straight motion (Son and Nomoto's form)."""
    ua = u * (1 - W_P)
    return EPSILON * math.sqrt(max(ua * ua + 8 * KAPPA * thrust(n, u) / (math.pi * RHO * D_P ** 2), 0.0))


def revolutions_for(force: float, u: float) -> float:
    """Revolutions [1/s] whose net thrust (1 - t_P) T is ``force`` [N] at u [m/s] (bisection)."""
    low, high = 0.0, 10.0
    for _ in range(100):
        n = 0.5 * (low + high)
        low, high = (n, high) if (1 - T_P) * thrust(n, u) < force else (low, n)
    return n


def actuators() -> dict[str, float]:
    c = derive()
    u = 18.0 * KNOT
    n_service = revolutions_for(c["x_uu"] * u * u, u)
    top = TOP_SPEED_KN * KNOT
    n_max = round(60 * revolutions_for(c["x_uu"] * top * top, top)) / 60   # whole rpm
    stall = math.radians(STALL_DEG)
    lever = -(X_R + A_H * X_H) * L
    moment = lever * 0.5 * RHO * A_R * rudder_inflow(n_service, u) ** 2 * lift_slope() * math.sin(stall) * math.cos(stall)
    return {"rpm_service": 60 * n_service, "rpm_max": 60 * n_max, "lift_slope": lift_slope(), "rudder_lever_m": lever,
            "shaft_time_constant_service_s": SHAFT_TIME_S_RPS / n_service,
            "shaft_rate_max_rpm_s": 60 * n_max ** 2 / (4 * SHAFT_TIME_S_RPS),
            "net_thrust_max_18kn_N": (1 - T_P) * thrust(n_max, u), "rudder_moment_stall_18kn_Nm": moment}


if __name__ == "__main__":
    for key, value in {**derive(), **actuators()}.items():
        print(f"{key:30s} {value:.6e}")
