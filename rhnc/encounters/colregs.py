"""Encounter classification under the rules of the road (COLREG Rules 13-15 and 17).

The controller and the ``colregs`` analysis classify each target from the same geometry,
so the side the NMPC is pushed to and the verdict it is judged by cannot disagree.

Geometry (x north, y east, SI; courses clockwise from north):

* relative bearing ``beta`` of the target seen from the own ship: the bearing from own
  ship to target minus the own course, wrapped to (-180, 180] deg; positive to starboard;
* aspect ``alpha`` of the own ship seen from the target: the bearing from target to own
  ship minus the target's course, wrapped the same way.

Classes (own ship's view), checked in this order:

``static``
    The obstacle does not move (speed below ``STATIC_SPEED_MPS``).
``none``
    No risk of collision: the ships are opening (TCPA <= 0) or the predicted CPA is beyond
    ``cpa_limit_m``, or the TCPA beyond ``tcpa_limit_s``.
``overtaking`` (Rule 13, own ship gives way)
    The own ship comes up on the target from more than 22.5 deg abaft its beam:
    ``|alpha| > 112.5 deg``.
``overtaken`` (Rule 13 for the target; Rule 17 for us: stand on)
    The target comes up from more than 22.5 deg abaft our beam: ``|beta| > 112.5 deg``.
``head_on`` (Rule 14, both alter to starboard and pass port to port)
    The target is nearly ahead, ``|beta| <= HEAD_ON_BEARING_DEG``, on a nearly reciprocal
    course, ``|course difference - 180| <= HEAD_ON_COURSE_DEG``.
``crossing_give_way`` (Rule 15: the target is on our starboard side; we keep out of its way
    and avoid crossing ahead of it, Rule 16)
``crossing_stand_on`` (Rule 15 for the target; Rule 17 for us)

The rules' own words and the tolerances we read them with:

* Rule 13(b): a vessel is overtaking "when coming up with another vessel from a direction
  more than 22.5 degrees abaft her beam": the aspect ``|alpha|`` (or, for a ship coming up on
  us, the bearing ``|beta|``) strictly more than 90 + 22.5 = ``ABAFT_BEAM_DEG`` deg.
  Checked before head-on and crossing (Rule 13(a): "notwithstanding anything contained
  in the Rules of Part B, Sections I and II").
* Rule 14(a): "meeting on reciprocal or nearly reciprocal courses", 14(b): seeing the
  other "ahead or nearly ahead".  Nearly reciprocal: the courses differ from 180 deg by at
  most ``HEAD_ON_COURSE_DEG`` = 15 deg; nearly ahead: ``|beta| <= HEAD_ON_BEARING_DEG`` = 10 deg
  (a mast-head light pair is seen in line within about 6 deg; radar plotting practice
  allows more).
* Rule 15: any other crossing with risk of collision; the target on our starboard side
  (``beta > 0``) is the one we give way to.

The thresholds are module constants, not options, so the analysis and the controller
always agree.  A class decided within ``BORDERLINE_DEG`` of one of these boundaries (the
angle that decided it lies that close to its threshold) is a borderline class: another
observer, with another sensor or another reading of "nearly", may well classify it the
other way.  :attr:`Encounter.borderline` names the boundary; the ``colregs`` analysis
reports such targets as borderline.

Hysteresis: a class is decided when the risk of collision first appears and is kept for
the whole encounter (COLREG roles do not change as the geometry evolves during the
manoeuvre, e.g. a give-way ship turning to starboard would otherwise turn a crossing into
a head-on).  The encounter ends, and the class is released, when the ships have passed
(TCPA <= 0) and the range exceeds ``release_range_m``.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence

import numpy as np

from orchestrator.geometry import NM, wrap_deg

STATIC_SPEED_MPS = 0.1
HEAD_ON_BEARING_DEG = 10.0
HEAD_ON_COURSE_DEG = 15.0
ABAFT_BEAM_DEG = 112.5
#: a class decided within this many degrees of a boundary is borderline
BORDERLINE_DEG = 2.5
#: Rule 17(b): a stand-on ship may act once the CPA predicted at the present velocities lies
#: inside the required separation and is at most this far ahead [s] ...
STAND_ON_ACTION_TCPA_S = 600.0
#: ... or the range has fallen below this many times the required separation
STAND_ON_ACTION_RANGE_FACTOR = 2.0

#: a readily apparent alteration (Rules 8(b), 16): this many degrees of course [deg] ...
APPARENT_ALTERATION_DEG = 35.0
#: ... made in this time [s] (20 s before the rudder bites, then 0.3 deg/s: the KCS model
#: on 10/35 of its yaw moment); the course is taken to change at the turn's midpoint
APPARENT_ALTERATION_TURN_S = 20.0 + 35.0 / 0.3
#: the time a ship keeps in hand before the last moment such an alteration still opens
#: the CPA to the separation [s]: the turn is slower in a seaway and the ship must see the
#: need first (two 60 s navigation or three 20 s control intervals)
ACTION_BUFFER_S = 180.0

ENCOUNTER_CLASSES = ("static", "none", "head_on", "crossing_give_way", "crossing_stand_on",
                     "overtaking", "overtaken")

#: The own ship's role per class: "give_way" (Rules 14-16: act early, to starboard),
#: "stand_on" (Rule 17: keep course and speed until the other's action is not enough),
#: "avoid" (a static obstacle), "none".
ROLE = {"static": "avoid", "none": "none", "head_on": "give_way", "crossing_give_way": "give_way",
        "crossing_stand_on": "stand_on", "overtaking": "give_way", "overtaken": "stand_on"}


def bearing_deg(from_x, from_y, to_x, to_y):
    """True bearing [deg in [0, 360)] from one point to another (x north, y east)."""
    return np.mod(np.degrees(np.arctan2(np.asarray(to_y) - from_y, np.asarray(to_x) - from_x)), 360.0)


def cpa_tcpa(own_xy, own_velocity, target_xy, target_velocity) -> tuple[float, float]:
    """Closest approach of two constant-velocity motions (SI).

    Returns
    -------
    cpa_m : float
        Range at the closest approach [m] (the current range if they are opening).
    tcpa_s : float
        Time to the closest approach [s]; <= 0 when the range is already opening,
        ``inf`` when the relative velocity is zero.
    """
    r = np.subtract(target_xy, own_xy).astype(float)
    w = np.subtract(target_velocity, own_velocity).astype(float)
    w2 = float(w @ w)
    if w2 < 1e-12:
        return float(np.hypot(*r)), math.inf
    tcpa = -float(r @ w) / w2
    closest = r + w * max(tcpa, 0.0)
    return float(np.hypot(*closest)), tcpa


@dataclasses.dataclass(frozen=True)
class Encounter:
    """The classified geometry of one target at one instant (own ship's view)."""

    encounter_class: str
    relative_bearing_deg: float
    aspect_deg: float
    range_m: float
    cpa_m: float
    tcpa_s: float
    borderline: str = ""

    @property
    def role(self) -> str:
        return ROLE[self.encounter_class]


def classify(own_xy: Sequence[float], own_course_rad: float, own_speed_mps: float,
             target_xy: Sequence[float], target_velocity_mps: Sequence[float],
             cpa_limit_m: float = 2.0 * NM, tcpa_limit_s: float = 30.0 * 60.0) -> Encounter:
    """Classify one target (rules in the module docstring).

    Parameters
    ----------
    own_xy : (x, y) [m]; own_course_rad : course over ground [rad]; own_speed_mps [m/s]
    target_xy : (x, y) [m]; target_velocity_mps : (vx, vy) [m/s]
    cpa_limit_m : float
        A predicted CPA beyond this is no risk of collision [m].
    tcpa_limit_s : float
        A CPA further ahead in time than this is no risk yet [s].
    """
    own_velocity = own_speed_mps * np.array([math.cos(own_course_rad), math.sin(own_course_rad)])
    target_velocity = np.asarray(target_velocity_mps, dtype=float)
    target_speed = float(np.hypot(*target_velocity))
    own_course_deg = math.degrees(own_course_rad)
    range_m = float(np.hypot(target_xy[0] - own_xy[0], target_xy[1] - own_xy[1]))
    beta = float(wrap_deg(bearing_deg(own_xy[0], own_xy[1], target_xy[0], target_xy[1]) - own_course_deg))
    cpa, tcpa = cpa_tcpa(own_xy, own_velocity, target_xy, target_velocity)
    if target_speed < STATIC_SPEED_MPS:
        return Encounter("static", beta, 0.0, range_m, cpa, tcpa)
    target_course_deg = math.degrees(math.atan2(target_velocity[1], target_velocity[0]))
    alpha = float(wrap_deg(bearing_deg(target_xy[0], target_xy[1], own_xy[0], own_xy[1]) - target_course_deg))
    course_difference = abs(float(wrap_deg(target_course_deg - own_course_deg - 180.0)))
    if not (0.0 < tcpa <= tcpa_limit_s) or cpa > cpa_limit_m:
        name = "none"
    elif abs(alpha) > ABAFT_BEAM_DEG:
        name = "overtaking"
    elif abs(beta) > ABAFT_BEAM_DEG:
        name = "overtaken"
    elif abs(beta) <= HEAD_ON_BEARING_DEG and course_difference <= HEAD_ON_COURSE_DEG:
        name = "head_on"
    elif beta > 0.0:
        name = "crossing_give_way"
    else:
        name = "crossing_stand_on"
    borderline = "" if name == "none" else _borderline(name, alpha, beta, course_difference)
    return Encounter(name, beta, alpha, range_m, cpa, tcpa, borderline)


def _borderline(name: str, alpha: float, beta: float, course_difference: float) -> str:
    """The boundary a class was decided within ``BORDERLINE_DEG`` of ("" if none)."""
    near = []
    if abs(abs(alpha) - ABAFT_BEAM_DEG) <= BORDERLINE_DEG:
        near.append(f"overtaking: own ship {abs(alpha):.1f} deg from the target's bow (22.5 deg abaft the beam is "
                    f"{ABAFT_BEAM_DEG:g})")
    if name != "overtaking" and abs(abs(beta) - ABAFT_BEAM_DEG) <= BORDERLINE_DEG:
        near.append(f"overtaken: target {abs(beta):.1f} deg from our bow (22.5 deg abaft the beam is "
                    f"{ABAFT_BEAM_DEG:g})")
    if name in ("head_on", "crossing_give_way", "crossing_stand_on"):
        ahead = abs(beta) <= HEAD_ON_BEARING_DEG + BORDERLINE_DEG
        reciprocal = course_difference <= HEAD_ON_COURSE_DEG + BORDERLINE_DEG
        if ahead and reciprocal and (abs(abs(beta) - HEAD_ON_BEARING_DEG) <= BORDERLINE_DEG
                                     or abs(course_difference - HEAD_ON_COURSE_DEG) <= BORDERLINE_DEG):
            near.append(f"head-on: bearing {abs(beta):.1f} deg (nearly ahead: <= {HEAD_ON_BEARING_DEG:g}), courses "
                        f"{course_difference:.1f} deg from reciprocal (nearly: <= {HEAD_ON_COURSE_DEG:g})")
    return "; ".join(near)


def latest_alteration_s(own_xy, own_velocity, target_xy, target_velocity, separation_m: float,
                        side: float = 1.0, alteration_deg: float = APPARENT_ALTERATION_DEG,
                        turn_s: float = APPARENT_ALTERATION_TURN_S, step_s: float = 10.0,
                        lookback_s: float = 0.0) -> float:
    """How long the own ship can wait before a readily apparent alteration still opens the CPA
    to ``separation_m`` [s] (collision risk by time, not by range).

    The own ship holds its velocity for the wait, then alters ``alteration_deg`` to ``side``
    (+1 starboard, -1 port) over ``turn_s`` (the course taken to change at the turn's
    midpoint) and holds the new course; the target keeps its velocity.  Returns the longest
    such wait (a multiple of ``step_s``) after which the CPA is at least the separation:
    ``inf`` when the ships are opening or pass clear anyway, ``-inf`` when even an alteration
    begun now is not enough (a larger one, or a change of speed, is needed: act now).

    With ``lookback_s`` > 0, when no alteration begun now is enough, the same approach is
    followed back that far (both ships on their present velocities) and the last moment
    that was still enough is returned as a negative wait (how long ago it ran out); ``-inf``
    only when no moment within the lookback was.  A time that has run out then stays run
    out: along a steady approach the last moment is one instant, and the wait counts down
    through zero to negative values instead of jumping back to ``-inf``.

    Parameters
    ----------
    own_xy, own_velocity, target_xy, target_velocity : (2,) [m, m/s]
    separation_m : float
        R + R_i plus any margin [m].
    """
    own_xy = np.asarray(own_xy, dtype=float)
    own_velocity = np.asarray(own_velocity, dtype=float)
    target_xy = np.asarray(target_xy, dtype=float)
    target_velocity = np.asarray(target_velocity, dtype=float)
    cpa, tcpa = cpa_tcpa(own_xy, own_velocity, target_xy, target_velocity)
    if cpa >= separation_m or not 0.0 < tcpa < math.inf:
        return math.inf
    angle = side * math.radians(alteration_deg)
    c, s = math.cos(angle), math.sin(angle)
    altered = np.array([c * own_velocity[0] - s * own_velocity[1], s * own_velocity[0] + c * own_velocity[1]])
    back = int(max(lookback_s, 0.0) // step_s)
    waits = step_s * np.arange(-back, int(math.ceil(tcpa / step_s)) + 1)
    switch = waits + 0.5 * turn_s
    relative = (target_xy - own_xy)[None, :] + np.outer(switch, target_velocity - own_velocity)
    w = target_velocity - altered
    w2 = float(w @ w)
    if w2 < 1e-12:
        closest = np.hypot(relative[:, 0], relative[:, 1])
    else:
        ahead = np.maximum(-(relative @ w) / w2, 0.0)
        closest = np.hypot(relative[:, 0] + ahead * w[0], relative[:, 1] + ahead * w[1])
    # the range during the wait and the turn matters too: before the switch it is the straight approach
    straight_min = np.where(switch >= tcpa, cpa, np.inf)
    closest = np.minimum(closest, straight_min)
    enough = closest >= separation_m
    short = np.nonzero(~enough[back:])[0]
    if short.size == 0:
        return float(waits[-1])
    if short[0] > 0:
        return float(waits[back + short[0] - 1])
    past = np.nonzero(enough[:back])[0]  # not enough now: when did it last suffice?
    return float(waits[past[-1]]) if past.size else -math.inf


def stand_on_latest_s(encounter_class: str, relative_bearing_deg: float, own_xy, own_velocity, target_xy,
                      target_velocity, separation_m: float, risk_tcpa_s: float = 30.0 * 60.0) -> float:
    """:func:`latest_alteration_s` for a stand-on ship: to starboard for a crossing ship on
    our port side (Rule 17(c)), away from the other ship when it overtakes us [s].

    Looked back to where the CPA was ``risk_tcpa_s`` ahead (the onset of risk at the
    latest): negative when the last moment for the alteration has passed since, so that
    :func:`stand_on_must_act` keeps "act" once that time has run out."""
    side = 1.0 if encounter_class == "crossing_stand_on" or relative_bearing_deg < 0.0 else -1.0
    tcpa = cpa_tcpa(own_xy, own_velocity, target_xy, target_velocity)[1]
    lookback = max(0.0, risk_tcpa_s - tcpa) if math.isfinite(tcpa) else 0.0
    return latest_alteration_s(own_xy, own_velocity, target_xy, target_velocity, separation_m, side,
                               lookback_s=lookback)


def stand_on_must_act(cpa_m: float, tcpa_s: float, range_m: float, separation_m: float,
                      action_tcpa_s: float = STAND_ON_ACTION_TCPA_S,
                      action_range_factor: float = STAND_ON_ACTION_RANGE_FACTOR,
                      latest_s: float = math.inf) -> bool:
    """Rule 17(b): the give-way vessel's action is clearly not enough, so the stand-on ship acts.

    Read as: the closest approach predicted with both ships at their present velocities
    (the stand-on ship keeping its course and speed) lies inside ``separation_m`` and
    either it is at most ``action_tcpa_s`` ahead, or the ships are already within
    ``action_range_factor * separation_m`` (a ship closing slowly, e.g. overtaking from
    astern, whose TCPA stays long while it is close), or a readily apparent alteration
    would open the CPA to the separation only if begun within ``ACTION_BUFFER_S`` from now,
    or that moment has passed (``latest_s`` <= ``ACTION_BUFFER_S``, negative once passed, from
    :func:`stand_on_latest_s`: a fast ship, whose TCPA is still long while the time to act
    runs out; once run out, "act" holds: the decision is monotone along the approach).  When
    no such alteration would ever have done, ``-inf``, the other criteria decide: a ship
    crossing from port on a course near ours is not helped by a turn to starboard, and
    acting early would only break Rule 17(a).  The controller decides with this
    function when to stop standing on, and the ``colregs`` analysis judges with it whether
    a stand-on manoeuvre came too early: one definition for both.

    Parameters
    ----------
    cpa_m, tcpa_s : float
        Predicted closest approach [m] and the time to it [s] (<= 0: opening).
    range_m : float
        Present range [m].
    separation_m : float
        The separation to keep, R + R_i [m].
    latest_s : float
        :func:`stand_on_latest_s` [s] (default: not considered).
    """
    if not (cpa_m < separation_m and tcpa_s > 0.0):
        return False
    # -inf: no 35 deg alteration opened the CPA at any moment of this approach; acting now is
    # then no better than acting later with a larger one, so the other criteria decide
    running_out = -math.inf < latest_s <= ACTION_BUFFER_S
    return tcpa_s <= action_tcpa_s or range_m <= action_range_factor * separation_m or running_out


class EncounterTracker:
    """Classes per target with hysteresis: decided at the onset of risk, kept until passed.

    Targets are identified by their row in the ``obstacles`` array (x, y, vx, vy, radius),
    as the traffic participant publishes them.

    Parameters
    ----------
    cpa_limit_m, tcpa_limit_s : float
        Risk of collision thresholds passed to :func:`classify`.
    release_range_m : float
        After the CPA, the class is released once the range exceeds this [m].
    """

    def __init__(self, cpa_limit_m: float = 2.0 * NM, tcpa_limit_s: float = 30.0 * 60.0,
                 release_range_m: float = 4.0 * NM) -> None:
        self.cpa_limit_m = float(cpa_limit_m)
        self.tcpa_limit_s = float(tcpa_limit_s)
        self.release_range_m = float(release_range_m)
        self._locked: dict[int, str] = {}
        self._borderline: dict[int, str] = {}

    def update(self, own_xy: Sequence[float], own_course_rad: float, own_speed_mps: float,
               obstacles: np.ndarray) -> list[Encounter]:
        """Classify every row of ``obstacles``, keeping locked classes; one Encounter per row."""
        rows = np.zeros((0, 5)) if obstacles is None else np.atleast_2d(np.asarray(obstacles, dtype=float))
        result = []
        for index, row in enumerate(rows):
            now = classify(own_xy, own_course_rad, own_speed_mps, row[:2], row[2:4],
                           self.cpa_limit_m, self.tcpa_limit_s)
            locked = self._locked.get(index)
            if locked is not None:
                if now.tcpa_s <= 0.0 and now.range_m > self.release_range_m:
                    del self._locked[index]
                    self._borderline.pop(index, None)
                else:  # the class and its borderline note as decided at the onset
                    now = dataclasses.replace(now, encounter_class=locked, borderline=self._borderline[index])
            elif now.encounter_class not in ("none", "static"):
                self._locked[index] = now.encounter_class
                self._borderline[index] = now.borderline
            result.append(now)
        return result

    @property
    def locked(self) -> dict[int, str]:
        """Classes currently held, by obstacle row."""
        return dict(self._locked)
