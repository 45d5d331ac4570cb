"""Standard manoeuvre figures from a sailed trajectory: turning circle and zig-zag.

Definitions follow ITTC 7.5-04-02-01 and IMO MSC.137(76): advance and transfer at 90 deg
heading change, tactical diameter at 180 deg, overshoot angles of the zig-zag.  The
steering signal is the rudder angle of an actuator-level plant (``KCSMMG``) or, for a plant
that takes forces, the yaw moment tau_r standing in for it; only its sign changes matter.
"""

from __future__ import annotations

import numpy as np


def turning_circle(t, x, y, psi, execute_s: float, length_m: float) -> dict:
    """Turning-circle figures from a trajectory.

    Parameters
    ----------
    t, x, y, psi : array_like
        Time [s], north and east position [m], heading [rad] samples.
    execute_s : float
        Time the rudder (or yaw moment) is applied [s].
    length_m : float
        Ship length for the non-dimensional figures [m].

    Returns
    -------
    dict
        ``advance_m``, ``transfer_m``, ``tactical_diameter_m``, ``steady_diameter_m`` and
        the same divided by ``length_m`` (keys ending ``_L``); a figure the trajectory
        does not reach is ``None``.
    """
    t, x, y, psi = (np.asarray(a, dtype=float) for a in (t, x, y, psi))
    start = int(np.searchsorted(t, execute_s - 1e-9))
    psi0 = psi[start]
    change = np.abs(np.unwrap(psi[start:]) - np.unwrap(psi[start:])[0])
    dx, dy = x[start:] - x[start], y[start:] - y[start]
    along = dx * np.cos(psi0) + dy * np.sin(psi0)
    across = -dx * np.sin(psi0) + dy * np.cos(psi0)

    def at(angle, series):
        return _interp_at_crossing(change, series, np.radians(angle))

    out = {
        "advance_m": at(90, along),
        "transfer_m": at(90, np.abs(across)),
        "tactical_diameter_m": at(180, np.abs(across)),
        "steady_diameter_m": None,
    }
    steady = change >= np.radians(360)
    if np.count_nonzero(steady) > 8:
        cx, cy, radius = _fit_circle(x[start:][steady], y[start:][steady])
        out["steady_diameter_m"] = 2 * radius
    for key in list(out):
        out[key[:-2] + "_L"] = None if out[key] is None else out[key] / length_m
    return out


def zigzag(t, psi, steering, execute_s: float) -> dict:
    """Zig-zag figures: overshoot angles [deg] and the time to the first heading check.

    ``steering`` is the rudder angle command (or the yaw moment) at each sample.  The
    overshoot is the heading change beyond the value at which the steering was reversed,
    measured at the extreme heading that follows.
    """
    t, psi, steering = (np.asarray(a, dtype=float) for a in (t, psi, steering))
    start = int(np.searchsorted(t, execute_s - 1e-9))
    change = np.degrees(np.unwrap(psi[start:]) - np.unwrap(psi[start:])[0])
    moment = steering[start:]
    switches = np.nonzero(np.sign(moment[1:]) != np.sign(moment[:-1]))[0] + 1
    overshoots = []
    for n, index in enumerate(switches):
        end = switches[n + 1] if n + 1 < len(switches) else len(change)
        window = change[index:end]
        if window.size < 2 or end == len(change):
            break
        reversal = change[index]
        extreme = window.max() if reversal > 0 else window.min()
        overshoots.append(float(abs(extreme - reversal)))
    return {
        "first_overshoot_deg": overshoots[0] if overshoots else None,
        "second_overshoot_deg": overshoots[1] if len(overshoots) > 1 else None,
        "overshoots_deg": overshoots,
        "time_to_first_check_s": float(t[start:][switches[0]] - t[start]) if len(switches) else None,
    }


def _interp_at_crossing(change, series, angle):
    above = np.nonzero(change >= angle)[0]
    if above.size == 0:
        return None
    k = above[0]
    if k == 0:
        return float(series[0])
    f = (angle - change[k - 1]) / (change[k] - change[k - 1])
    return float(series[k - 1] + f * (series[k] - series[k - 1]))


def _fit_circle(x, y):
    """Least-squares circle (Kasa fit): centre and radius."""
    a = np.column_stack([x, y, np.ones_like(x)])
    b = x**2 + y**2
    (c0, c1, c2), *_ = np.linalg.lstsq(a, b, rcond=None)
    cx, cy = c0 / 2, c1 / 2
    return cx, cy, float(np.sqrt(c2 + cx**2 + cy**2))
