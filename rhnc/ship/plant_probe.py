"""A short sail of the plant that checks its mapped ports against the canonical frame.

A mapping can be consistent in units and still wrong in meaning: a rate of turn whose
sign is reversed, a heading counted anticlockwise from east (the mathematician's angle)
instead of clockwise from north, a heading in degrees read as radians through a
``scale``, a speed in knots read as m/s.  Each makes the NMPC steer with a wrong picture
and gives wrong results rather than an error.  They all break the kinematics that hold
in the canonical frame whatever the ship (x north, y east, psi clockwise from north, SI,
no current)::

    dx/dt = u cos psi - v sin psi,   dy/dt = u sin psi + v cos psi,   dpsi/dt = r

and the signs of the actuation: a positive yaw moment (or rudder to starboard, through
an allocation) turns the ship to starboard (r > 0), a positive surge force speeds it up.
:func:`probe_plant` sails three short runs from a heading of 30 deg (not a symmetry of
the compass, so a compass/maths mix-up shows) with the weather off and refuses the
mapping with one line naming the ports when any of these does not hold.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from orchestrator.errors import ScenarioError
from rhnc.ship.ship_model import STATE_NAMES

#: Probe heading [deg]: not 0, 45, 90 or 180, which some mix-ups map onto themselves.
PROBE_HEADING_DEG = 30.0
PROBE_DURATION_S = 90.0
PROBE_SAMPLE_S = 1.0
#: Largest relative error of the speed over ground predicted from u, v, psi [-]
VELOCITY_TOLERANCE = 0.10
#: Largest relative error of dpsi/dt = r [-]
YAW_RATE_TOLERANCE = 0.15
WEATHER_PORTS = ("current_north", "current_east", "wind_speed", "wind_direction", "hs")


def _sail(build: Callable, speed_mps: float, tau: tuple[float, float]) -> np.ndarray:
    """States (n, 6) of the plant sailed from the probe heading with ``tau`` held."""
    plant = build({"x_m": 0.0, "y_m": 0.0, "psi_rad": math.radians(PROBE_HEADING_DEG), "u_mps": speed_mps})
    weather = {port: 0.0 for port in WEATHER_PORTS if port in plant.input_names}
    rows: list[list[float]] = []
    try:
        outputs = plant.setup(0.0, weather)
        steps = int(round(PROBE_DURATION_S / PROBE_SAMPLE_S))
        for k in range(steps + 1):
            rows.append([outputs[port] for port in STATE_NAMES])
            if k < steps:
                outputs = plant.step(k * PROBE_SAMPLE_S, PROBE_SAMPLE_S,
                                     {"tau_u": tau[0], "tau_r": tau[1], **weather})
    finally:
        plant.terminate()
    states = np.array(rows, dtype=float)
    states[:, 2] = np.unwrap(states[:, 2])
    return states


def kinematic_check(states: np.ndarray, dt: float) -> dict[str, float]:
    """How the sampled states (n, 6) fit the canonical kinematics.

    Returns
    -------
    dict
        ``velocity_error``: RMS of the over-ground velocity from the positions minus the
        one from u, v, psi, divided by the RMS speed [-] (``velocity_error_sway_reversed``:
        the same with -v); ``yaw_rate_gain``: the least-squares
        k of dpsi/dt = k r [-] (nan when the ship hardly turned); ``sway_gain``: the least-
        squares b of the over-ground velocity = u e_psi + b v e_psi+90 [-] (nan when the sway
        is too small to tell); ``rms_speed_mps``.
    """
    x, y, psi, u, v, r = states.T
    xdot = (x[2:] - x[:-2]) / (2 * dt)
    ydot = (y[2:] - y[:-2]) / (2 * dt)
    psidot = (psi[2:] - psi[:-2]) / (2 * dt)
    psi, u, v, r = psi[1:-1], u[1:-1], v[1:-1], r[1:-1]
    measured = np.concatenate([xdot, ydot])
    along = np.concatenate([u * np.cos(psi), u * np.sin(psi)])
    across = np.concatenate([-v * np.sin(psi), v * np.cos(psi)])
    rms_speed = float(np.sqrt(np.mean(xdot ** 2 + ydot ** 2)))
    error = float(np.sqrt(np.mean((measured - along - across) ** 2) * 2) / max(rms_speed, 1e-9))
    flipped = float(np.sqrt(np.mean((measured - along + across) ** 2) * 2) / max(rms_speed, 1e-9))
    sway_gain = math.nan
    if np.sqrt(np.mean(v ** 2)) > 0.02 * max(rms_speed, 1e-9):
        design = np.column_stack([along, across])
        (_, sway_gain), *_ = np.linalg.lstsq(design, measured, rcond=None)
    yaw_rate_gain = math.nan
    if np.max(np.abs(r)) > 1e-4:   # 0.34 deg/min
        yaw_rate_gain = float(np.dot(psidot, r) / np.dot(r, r))
    return {"velocity_error": error, "velocity_error_sway_reversed": flipped,
            "yaw_rate_gain": yaw_rate_gain, "sway_gain": float(sway_gain),
            "rms_speed_mps": rms_speed}


def probe_plant(build: Callable, speed_mps: float, tau_u_max: float, tau_r_max: float, where: str) -> dict:
    """Sail the plant briefly and refuse a mapping that contradicts the canonical frame.

    Parameters
    ----------
    build : callable
        ``build(initial) -> participant`` (canonical ports, inputs ``tau_u``, ``tau_r``).
    speed_mps : float
        Speed the runs start at [m/s].
    tau_u_max, tau_r_max : float
        The ship's largest surge force [N] and yaw moment [N m]; the runs use half.
    where : str
        Scenario and participant, for the message.

    Returns
    -------
    dict
        What was measured (for the report).

    Raises
    ------
    ScenarioError
        One line naming the ports whose mapping contradicts the frame, and what was seen.
    """
    turning = _sail(build, speed_mps, (0.0, 0.5 * tau_r_max))
    coasting = _sail(build, speed_mps, (0.0, 0.0))
    pushing = _sail(build, speed_mps, (0.5 * tau_u_max, 0.0))
    frame = "canonical frame: x north, y east, psi clockwise from north in rad, u and v in m/s, r in rad/s"
    for name, states in (("turning", turning), ("coasting", coasting), ("pushing", pushing)):
        if not np.all(np.isfinite(states)):
            raise ScenarioError(f"{where}: the plant reports non-finite states when probed ({name}, 90 s from "
                                f"{speed_mps:.2f} m/s): check its mapping and start parameters")
    checks = {name: kinematic_check(states, PROBE_SAMPLE_S) for name, states in
              (("turning", turning), ("coasting", coasting))}
    sway_message = (f"{where}: mapping of v contradicts the {frame}: the sway speed has its sign reversed "
                    "(positive v is to starboard; the motion over ground fits -v)")
    for name, check in checks.items():
        if check["velocity_error"] > VELOCITY_TOLERANCE >= check["velocity_error_sway_reversed"]:
            raise ScenarioError(sway_message)
        if not check["velocity_error"] <= VELOCITY_TOLERANCE:
            raise ScenarioError(
                f"{where}: mapping of x, y, psi, u, v contradicts the {frame}: the ship's motion over ground "
                f"differs by {100 * check['velocity_error']:.0f} % from u, v along psi (probe {name} from "
                f"psi = {PROBE_HEADING_DEG:g} deg); look for a heading counted from east or anticlockwise, an "
                "angle or speed unit wrong by a scale, or x and y swapped")
    gain = checks["turning"]["yaw_rate_gain"]
    if math.isnan(gain):
        raise ScenarioError(f"{where}: the plant did not turn under a yaw moment of {0.5 * tau_r_max:g} N m in 90 s; "
                            "check the mapping of tau_r (or of the rudder command) and r")
    if not abs(gain - 1.0) <= YAW_RATE_TOLERANCE:
        raise ScenarioError(
            f"{where}: mapping of psi or r contradicts the {frame}: the heading changes at {gain:.3g} times "
            f"the reported yaw rate r (dpsi/dt = r expected); "
            + ("one of them has its sign reversed" if gain < 0 else "one of them has a wrong unit or scale"))
    sway = checks["turning"]["sway_gain"]
    if not math.isnan(sway) and sway < 0.0:
        raise ScenarioError(sway_message)
    if not turning[-1, 5] > 0.0:
        raise ScenarioError(f"{where}: a positive yaw moment turned the ship to port (r = {turning[-1, 5]:.3g} rad/s "
                            "after 90 s): the mapping of tau_r (or of the rudder command) has its sign reversed; "
                            "positive is a turn to starboard")
    if not pushing[-1, 3] > coasting[-1, 3]:
        raise ScenarioError(f"{where}: a positive surge force slowed the ship ({pushing[-1, 3]:.3g} m/s after 90 s "
                            f"against {coasting[-1, 3]:.3g} m/s without): the mapping of tau_u (or the propeller "
                            "command) has its sign reversed")
    return {"velocity_error": max(c["velocity_error"] for c in checks.values()), "yaw_rate_gain": gain,
            "sway_gain": sway, "yaw_rate_after_90s_rad_s": float(turning[-1, 5]),
            "speed_gain_after_90s_mps": float(pushing[-1, 3] - coasting[-1, 3])}
