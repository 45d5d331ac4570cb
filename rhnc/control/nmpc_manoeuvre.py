"""How far a readily apparent manoeuvre keeps the own ship from the traffic, with the time it takes.

A manoeuvre is chosen among a few candidates (a turn to a side the rules allow, at the present
speed or slowed, or a reduction of speed alone) by the least clearance it keeps from every
target over the risk window.  Scored as if the ship took its new course and speed at once, a
reduction of speed looked far better than it is: a ship of 20 000 t slows from 18 to 8 kn in
about 4 min, while a ship overtaking it at 28 kn closes 1.3 nm in that time.  Here the own ship
holds its course and speed for a response delay, then turns towards the new course at a steady
rate and slows (or gathers way) at the rate its engine and hull give, while every target keeps
its velocity.  The candidates' ranking, not their absolute figures, is what counts: the NMPC then
flies the chosen one with its own model.

Beside it, the simpler measures the choice of a free side still uses: :func:`side_clearance_m`
(the new course and speed taken at once) and :func:`closing_on_the_port_side` (a ship that may
become one crossing from port, for which no turn to port is weighed); and how far a turn to port
back to the route may go (:func:`port_return_course`).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from orchestrator.geometry import wrap_angle
from rhnc.encounters.colregs import APPARENT_ALTERATION_DEG, APPARENT_ALTERATION_TURN_S, classify

#: the response delay of :data:`rhnc.encounters.colregs.APPARENT_ALTERATION_TURN_S` [s]
RESPONSE_DELAY_S = 20.0


@dataclasses.dataclass(frozen=True)
class ManoeuvreResponse:
    """How fast the own ship takes up a new course and speed.

    Attributes
    ----------
    delay_s : float
        Course and speed held before the manoeuvre shows [s].
    turn_rate_rps : float
        Steady rate of turn [rad/s] (default: a readily apparent alteration in
        ``APPARENT_ALTERATION_TURN_S``, as the rules' timing assumes).
    deceleration_mps2 : float
        Loss of speed per second while slowing [m/s^2] (the NMPC gives its ship's figure:
        full astern force and the hull's drag, at the share its speed bound ramps with).
    acceleration_mps2 : float
        Gain of speed per second while speeding up [m/s^2] (the NMPC gives its ship's figure:
        full ahead force less the hull's drag at the top speed, at the share its reference
        speed ramps up with).
    top_speed_mps : float or None
        The fastest the ship may go [m/s] (the NMPC's speed bound); None: no speeding up weighed.
    step_s : float
        Time between the samples of the approach [s].
    horizon_s : float
        How far ahead the approach is followed [s]: the risk window.
    """

    delay_s: float = RESPONSE_DELAY_S
    turn_rate_rps: float = math.radians(APPARENT_ALTERATION_DEG) / (APPARENT_ALTERATION_TURN_S - RESPONSE_DELAY_S)
    deceleration_mps2: float = 0.02
    acceleration_mps2: float = 0.005
    top_speed_mps: float | None = None
    step_s: float = 5.0
    horizon_s: float = 1800.0


def own_track(own_xy, speed_mps: float, heading_rad: float, course_rad: float, goal_speed_mps: float,
              response: ManoeuvreResponse) -> tuple[np.ndarray, np.ndarray]:
    """Sample times [s] and own positions [m] ((n, 2)) while the manoeuvre is taken up."""
    times = np.arange(0.0, response.horizon_s + 0.5 * response.step_s, response.step_s)
    acting = np.maximum(times - response.delay_s, 0.0)
    turn = float(wrap_angle(course_rad - heading_rad))
    headings = heading_rad + np.sign(turn) * np.minimum(response.turn_rate_rps * acting, abs(turn))
    if goal_speed_mps > speed_mps:
        speeds = np.minimum(speed_mps + response.acceleration_mps2 * acting, goal_speed_mps)
    else:
        speeds = np.maximum(speed_mps - response.deceleration_mps2 * acting, goal_speed_mps)
    # positions by the trapezoidal rule over each step
    velocity = speeds[:, None] * np.column_stack([np.cos(headings), np.sin(headings)])
    steps = 0.5 * (velocity[1:] + velocity[:-1]) * np.diff(times)[:, None]
    positions = np.asarray(own_xy, dtype=float) + np.vstack([np.zeros(2), np.cumsum(steps, axis=0)])
    return times, positions


def response_clearance_m(own_xy, speed_mps: float, heading_rad: float, course_rad: float, goal_speed_mps: float,
                         traffic, response: ManoeuvreResponse, beyond: bool = False) -> float:
    """The least clearance [m] the own ship keeps from ``traffic`` ((position, velocity,
    clearance) per target, each keeping its velocity) while it turns from ``heading_rad`` to
    ``course_rad`` and slows or speeds up to ``goal_speed_mps`` as ``response`` says: the smallest range
    less the target's clearance over the samples; ``inf`` without targets.

    With ``beyond``, also after the samples, each ship holding its last velocity for ever: the
    whole encounter, for a manoeuvre that may only put the closest approach off past the risk
    window (speeding up ahead of a ship that is faster still)."""
    times, positions = own_track(own_xy, speed_mps, heading_rad, course_rad, goal_speed_mps, response)
    last_velocity = (positions[-1] - positions[-2]) / (times[-1] - times[-2])
    least = math.inf
    for position, velocity, clearance in traffic:
        velocity = np.asarray(velocity, dtype=float)
        target = np.asarray(position, dtype=float) + np.outer(times, velocity)
        least = min(least, float(np.min(np.hypot(*(target - positions).T))) - clearance)
        if beyond:
            relative, closing = target[-1] - positions[-1], velocity - last_velocity
            w2 = float(closing @ closing)
            when = 0.0 if w2 < 1e-12 else max(-float(relative @ closing) / w2, 0.0)
            least = min(least, float(np.hypot(*(relative + closing * when))) - clearance)
    return least


def side_clearance_m(own_xy, own_speed_mps: float, course_rad: float, traffic, horizon_s: float = 1800.0) -> float:
    """The least clearance [m] the own ship keeps from a set of targets on a new course: the
    smallest CPA less the target's clearance, the own ship sailing ``course_rad`` at its speed
    from ``own_xy`` and every target keeping its velocity, over ``horizon_s`` (the risk
    window); ``inf`` without targets.  Compares the two sides of an alteration the rules
    leave free (Rule 13).

    Parameters
    ----------
    own_xy : (2,) [m]; own_speed_mps [m/s]; course_rad [rad]
    traffic : iterable of (position (2,) [m], velocity (2,) [m/s], clearance [m])
    horizon_s : float
        A CPA further ahead counts at its range at this time [s].
    """
    velocity = own_speed_mps * np.array([math.cos(course_rad), math.sin(course_rad)])
    least = math.inf
    for position, target_velocity, clearance in traffic:
        relative = np.asarray(position, dtype=float) - np.asarray(own_xy, dtype=float)
        closing = np.asarray(target_velocity, dtype=float) - velocity
        w2 = float(closing @ closing)
        when = 0.0 if w2 < 1e-12 else min(max(-float(relative @ closing) / w2, 0.0), horizon_s)
        least = min(least, float(np.hypot(*(relative + closing * when))) - clearance)
    return least


def closing_on_the_port_side(own_xy, own_speed_mps: float, heading_rad: float, traffic) -> bool:
    """Whether a ship of ``traffic`` ((position, velocity, clearance) per target) on our port
    side, forward of 22.5 deg abaft the beam (relative bearing -112.5 to 0 deg from
    ``heading_rad``), is closing on us."""
    own_velocity = own_speed_mps * np.array([math.cos(heading_rad), math.sin(heading_rad)])
    for position, velocity, _ in traffic:
        relative = np.asarray(position, dtype=float) - np.asarray(own_xy, dtype=float)
        bearing = math.degrees(wrap_angle(math.atan2(relative[1], relative[0]) - heading_rad))
        if -112.5 < bearing < 0.0 and float(relative @ (np.asarray(velocity, dtype=float) - own_velocity)) < 0.0:
            return True
    return False


#: the courses a turn back to port is weighed at, this far apart [deg]
RETURN_STEP_DEG = 5.0


def port_return_limit(own_xy, own_speed_mps: float, course_rad: float, reference_course_rad: float, targets,
                      cpa_limit_m: float, tcpa_limit_s: float) -> float | None:
    """How far [rad, a course within half a turn of ``course_rad``] a turn to port from
    ``course_rad`` back towards ``reference_course_rad`` may go without making a ship of
    ``targets`` ((position, velocity) each, none of them in a risk of collision with us yet) one
    crossing from port: a ship we would then stand on for, with a turn to port under way at the
    onset of risk, which Rule 17(c) rules out.  None when the whole turn is free, or the
    reference is not to port of the course.

    The courses are weighed every ``RETURN_STEP_DEG`` from ``course_rad`` to the reference,
    each held at the present speed and classified as :func:`rhnc.encounters.colregs.classify`
    (what the tracker locks at the onset of risk) does; the limit is the last before the first
    that makes a ship crossing from port, less one more step: while turning, the course runs
    a little past the bound.

    A ship that had given way to one target turned back to its route as soon as that target was
    past; the turn put a ship 5-6 nm on the port beam, no risk until then, on a CPA of 0.8-1.8 nm,
    and the risk arose in the middle of a turn to port for a ship on the port side.
    """
    turn = float(wrap_angle(reference_course_rad - course_rad))
    if turn >= 0.0:
        return None
    step = math.radians(RETURN_STEP_DEG)
    courses = [course_rad - k * step for k in range(1, int(-turn / step) + 1)] + [course_rad + turn]
    allowed = [course_rad, course_rad]  # the last two courses that made none
    for course in courses:
        for position, velocity in targets:
            encounter = classify(own_xy, course, own_speed_mps, position, velocity, cpa_limit_m, tcpa_limit_s)
            if encounter.encounter_class == "crossing_stand_on":
                return allowed[0]
        allowed = [allowed[1], course]
    return None
