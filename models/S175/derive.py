"""Derive the S175 plant's coefficients from its particulars (run: python models/S175/derive.py).

Same method as the KCS set (models/KCS/readme.md): linear manoeuvring derivatives from the
regressions of Clarke, Gedling and Hine (1983), dimensionalised at the 18 kn service speed,
resistance from the ITTC-57 friction line with a form factor, rudder force after Fujii. The
printed values are those in models/S175/model.c.
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


if __name__ == "__main__":
    for key, value in derive().items():
        print(f"{key:10s} {value:.6e}")
