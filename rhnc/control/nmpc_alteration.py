"""The heading bounds of a readily apparent alteration (COLREG Rules 8(b), 16, 17(b)) for the NMPC.

Once the own ship gives way (or acts as a stand-on ship), :class:`rhnc.control.nmpc_colregs.CollisionDomains`
records the alteration in its :class:`rhnc.control.nmpc_colregs.DomainReport` (``alteration_floor``
to starboard, ``alteration_ceiling`` to port: time it began, heading then, heading to
reach), and :func:`heading_bounds` turns it into bounds of the predicted headings: a ramp
the ship can follow from the measured state, so that the alteration is made and seen.
"""

from __future__ import annotations

import math

import numpy as np

from orchestrator.geometry import wrap_float

#: the heading floor of a readily apparent alteration rises at this rate [deg/s] from the
#: heading the ship had when the alteration began, after this delay [s]: the KCS model
#: turns 10 deg in 51 s on 10/35 of its yaw moment and 180 deg in 207 s on all of it
ALTERATION_RATE_DEG_S = 0.3
ALTERATION_DELAY_S = 20.0
#: a ship behind that ramp is asked to catch up as a first-order yaw response towards this
#: rate [deg/s] with this time constant [s]: the KCS model's yaw inertia over its yaw damping
#: is about 13 s, and its full yaw moment holds about 0.7 deg/s, so the bound asks for some
#: 40 % of the moment and stays reachable from any measured state, while it still demands
#: progress from the first step of every plan
CATCH_UP_RATE_DEG_S = 0.3
YAW_TIME_CONSTANT_S = 13.0
#: share of the yaw moment with which the prediction model's own turn from the measured state
#: caps the bounds (``heading_bounds``' ``reach``): what the plan is never asked to beat
REACH_MOMENT_SHARE = 0.5
#: numerical slack of that cap below the measured heading [deg]
HEADING_TOLERANCE_DEG = 0.1
#: heading error [deg] (yaw rate counted as its value over ``YAW_TIME_CONSTANT_S``) at which
#: the fallback's steering (:func:`alteration_steering`) applies the full yaw moment
STEERING_BAND_DEG = 10.0


def heading_bounds(report, time_s: float, heading_rad: float, yaw_rate_rps: float,
                   times_s: np.ndarray, reach: tuple[np.ndarray, np.ndarray] | None = None,
                   ) -> tuple[np.ndarray | None, np.ndarray | None]:
    """Lower and upper heading bounds [rad] at the absolute ``times_s`` [s] (None: unbounded).

    ``report`` is the solve's :class:`rhnc.control.nmpc_colregs.DomainReport` (its
    ``alteration_floor`` and ``alteration_ceiling``).

    The bound of a readily apparent alteration rises (falls) at ``ALTERATION_RATE_DEG_S``
    from the heading the ship had when the alteration began, after
    ``ALTERATION_DELAY_S``, to the alteration's heading.  The ramp is fixed in time, so
    re-solving every interval does not push it ahead of the ship.  Not to make the problem
    infeasible from a ship lagging behind it, it is capped by what the ship can reach from
    the measured state (``heading_rad`` at ``time_s``): the measured heading less what a yaw
    rate the other way carries it on over the delay (and ``HEADING_TOLERANCE_DEG``), plus a
    first-order yaw response towards ``CATCH_UP_RATE_DEG_S`` from the yaw rate the ship already
    has towards the alteration.  Taken from rest at every solve, that response asked a ship
    turning at 0.15 deg/s for no more than it did: it held that rate, half the ramp's, and an
    alteration of 35 deg took 4 min.  No larger allowance: the controller applies only the first
    step of each plan, and a first step allowed to sag below the measured heading would
    postpone the alteration at every solve and never reach it.  Headings are brought to within half a turn of ``heading_rad``.

    ``reach``: the headings [rad] at ``times_s`` of the prediction model itself turning from the
    measured state to starboard and to port with ``REACH_MOMENT_SHARE`` of its yaw moment
    (:meth:`rhnc.control.nmpc_bounds.StepBounds._heading_reach`).  The bounds never ask for more
    than those: the first-order response above is the KCS's at speed, and a ship swinging the
    other way at 12 m/s took 40-100 s to reverse under the full moment, far behind the ramp and
    its cap (every solve of those steps failed, and the controller fell back).
    """
    if report.alteration_floor is None and report.alteration_ceiling is None:
        return None, None  # no alteration: nothing to compute (most steps)
    times_s = np.asarray(times_s, dtype=float)
    tolerance = math.radians(HEADING_TOLERANCE_DEG)
    ahead_s = np.maximum(times_s - time_s, 0.0)
    catch_up = math.radians(CATCH_UP_RATE_DEG_S)
    lag = YAW_TIME_CONSTANT_S * (1.0 - np.exp(-ahead_s / YAW_TIME_CONSTANT_S))

    def reachable(toward_rps: float) -> np.ndarray:
        # heading gained by a first-order yaw response from the rate the ship has towards the
        # alteration (none if it swings the other way: the start allows for that) to the catch-up rate
        start_rate = min(max(toward_rps, 0.0), catch_up)
        return catch_up * ahead_s - (catch_up - start_rate) * lag

    def near(angle: float) -> float:
        return angle - 2.0 * math.pi * round((angle - heading_rad) / (2.0 * math.pi))

    def near_all(angles: np.ndarray) -> np.ndarray:
        angles = np.asarray(angles, dtype=float)
        return angles - 2.0 * math.pi * np.round((angles[0] - heading_rad) / (2.0 * math.pi))

    def ramp(alteration) -> tuple[np.ndarray, float]:
        began_s, heading_then, goal = alteration
        rise = np.radians(ALTERATION_RATE_DEG_S) * np.maximum(times_s - began_s - ALTERATION_DELAY_S, 0.0)
        return rise, near(goal) - near(heading_then)

    lower = upper = None
    if report.alteration_floor is not None:
        rise, size = ramp(report.alteration_floor)
        goal = near(report.alteration_floor[2])
        start = heading_rad - tolerance - max(0.0, -yaw_rate_rps) * ALTERATION_DELAY_S
        lower = np.minimum.reduce([np.full_like(times_s, goal), goal - size + rise, start + reachable(yaw_rate_rps)])
        if reach is not None:
            lower = np.minimum(lower, near_all(reach[0]) - tolerance)
    if report.alteration_ceiling is not None:
        rise, size = ramp(report.alteration_ceiling)
        goal = near(report.alteration_ceiling[2])
        start = heading_rad + tolerance + max(0.0, yaw_rate_rps) * ALTERATION_DELAY_S
        upper = np.maximum.reduce([np.full_like(times_s, goal), goal - size - rise, start - reachable(-yaw_rate_rps)])
        if reach is not None:
            upper = np.maximum(upper, near_all(reach[1]) + tolerance)
    return lower, upper


def alteration_steering(report, tau_r_max: float):
    """The yaw moment of a fallback that opens the range or keeps making the held alteration, or
    None (neither).

    When a solve fails before the controller has any plan to fall back on, holding the
    course with no yaw moment keeps the ship standing on towards the targets it is giving
    way to, step after step while the solves fail.  In immediate danger (a target inside its
    clearance and closing: ``report``'s ``escape_heading``) the fallback steers straight away
    from that target, where the range opens fastest (Rules 2(b), 17(b)); with an alteration
    held (``alteration_floor`` to starboard, else ``alteration_ceiling`` to port), to the
    alteration's heading.  ``steer(heading_rad, yaw_rate_rps) -> tau_r`` is a
    proportional-derivative law on the heading error with the yaw rate weighted by the
    model's yaw time constant (``YAW_TIME_CONSTANT_S``), full moment from
    ``STEERING_BAND_DEG`` of error.
    """
    escape = report.escape_heading
    alteration = report.alteration_floor if report.alteration_floor is not None else report.alteration_ceiling
    if escape is None and alteration is None:
        return None
    goal = float(escape if escape is not None else alteration[2])
    band = math.radians(STEERING_BAND_DEG)

    def steer(heading_rad: float, yaw_rate_rps: float) -> float:
        error = wrap_float(goal - heading_rad)
        return tau_r_max * min(max((error - YAW_TIME_CONSTANT_S * yaw_rate_rps) / band, -1.0), 1.0)

    return steer
