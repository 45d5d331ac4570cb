"""KCSVendorB: the KCS dynamics behind kN / knot / degree names give KCS's trajectory once
the master maps the variables with a unit scale."""

from __future__ import annotations

import numpy as np
from fmpy.validation import validate_fmu

KNOT = 1852.0 / 3600.0
DEG = np.pi / 180.0

# KCS name -> (VendorB name, factor from SI to the vendor unit)
INPUTS = {
    "tau_u": ("thrust_kN", 1e-3), "tau_r": ("yaw_moment_kNm", 1e-3),
    "current_north": ("current_n_kn", 1 / KNOT), "current_east": ("current_e_kn", 1 / KNOT),
    "wind_speed": ("wind_speed_kn", 1 / KNOT), "wind_direction": ("wind_from_deg", 1 / DEG),
    "hs": ("sig_wave_height_m", 1.0),
}
OUTPUTS = {
    "x": ("north_m", 1.0), "y": ("east_m", 1.0), "psi": ("heading_deg", 1 / DEG),
    "u": ("surge_speed_kn", 1 / KNOT), "v": ("sway_speed_kn", 1 / KNOT),
    "r": ("yaw_rate_deg_s", 1 / DEG), "sog": ("sog_kn", 1 / KNOT), "cog": ("cog_deg", 1 / DEG),
}
INITIAL = {
    "x0": ("north0_m", 1.0), "y0": ("east0_m", 1.0), "psi0": ("heading0_deg", 1 / DEG),
    "u0": ("surge0_kn", 1 / KNOT), "v0": ("sway0_kn", 1 / KNOT), "r0": ("yaw_rate0_deg_s", 1 / DEG),
}


def mapped(values, table):
    return {table[k][0]: v * table[k][1] for k, v in values.items()}


def test_validates(fmus):
    assert validate_fmu(str(fmus["KCSVendorB"])) == []


def test_same_trajectory_as_kcs_after_unit_conversion(fmus, open_slave):
    kcs, vendor = open_slave(fmus["KCS"]), open_slave(fmus["KCSVendorB"])
    initial = {"x0": 50.0, "y0": 20.0, "psi0": 2.5, "u0": 9.0, "v0": 0.1, "r0": -0.001}
    kcs.initialize(initial)
    vendor.initialize(mapped(initial, INITIAL))
    names = list(OUTPUTS)
    trajectories = ([], [])
    t, h = 0.0, 20.0
    for k in range(180):
        inputs = {"tau_u": 8e5 + 2e5 * np.sin(k / 10), "tau_r": 2.5e8 * np.sign(np.sin(k / 15)),
                  "current_north": 0.3, "current_east": -0.2, "wind_speed": 14.0,
                  "wind_direction": -2.0 + 0.01 * k, "hs": 2.8}
        kcs.set(inputs)
        vendor.set(mapped(inputs, INPUTS))
        kcs.fmu.doStep(t, h)
        vendor.fmu.doStep(t, h)
        t += h
        trajectories[0].append(kcs.get(*names))
        trajectories[1].append([value / OUTPUTS[n][1] for n, value in
                                zip(names, vendor.get(*(OUTPUTS[n][0] for n in names)))])
    reference, converted = np.array(trajectories[0]), np.array(trajectories[1])
    assert np.ptp(reference[:, 0]) > 1000 and np.ptp(reference[:, 1]) > 1000  # it sailed
    for k, name in enumerate(names):
        if name in ("psi", "cog"):
            diff = np.angle(np.exp(1j * (converted[:, k] - reference[:, k])))
            np.testing.assert_allclose(diff, 0.0, atol=1e-12, err_msg=name)
        else:
            np.testing.assert_allclose(converted[:, k], reference[:, k], rtol=1e-12,
                                       atol=1e-12 * np.max(np.abs(reference[:, k])),
                                       err_msg=name)
