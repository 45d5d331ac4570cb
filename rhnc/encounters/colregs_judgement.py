"""Judging one target of a sailed encounter by the rules of the road (COLREG Rules 8 and 13-17).

:func:`judge_target` takes the own ship's track (positions, course and speed over ground),
one target's track, the encounter class decided at the onset of risk of collision and the
separation R + R_i, and reports the closest approach, the passing side, the first
manoeuvre and a verdict per rule; :mod:`rhnc.cosim.colregs_analysis` runs it for every target
of a run.

The verdicts (thresholds are :class:`JudgementSettings`):

Rule 8 (action to avoid collision), applicable to a give-way vessel and to any vessel that
manoeuvred: the alteration is large enough to be readily apparent (a change of course of at
least ``apparent_course_change_deg``, or a speed reduction of at least
``apparent_speed_reduction`` of the speed at onset, measured from the onset of risk to the
CPA or, for a manoeuvre shown before the CPA, to ``alteration_completion_s`` after it was
shown, whichever is later: an alteration that opens the range while it is still turning
passes its CPA before it is complete, and is judged by what it became, not by the part of it
that came before the CPA), made at least
``early_before_cpa_min`` before the CPA, and the ships pass at a safe distance (the
separation R + R_i is kept).
Rule 13 (overtaking): the overtaking vessel keeps out of the way: separation kept.
Rule 14 (head-on): no alteration to port, and a port-to-port passing.
Rule 15 (crossing, give-way): the own ship does not cross ahead of the target and keeps
the separation.
Rule 16 (action by the give-way vessel): an early alteration (as in Rule 8) and the
separation kept ("keep well clear").
Rule 17 (stand-on): keep course and speed; a manoeuvre is allowed only once the give-way
vessel's action is clearly not enough, read as :func:`rhnc.encounters.colregs.stand_on_must_act` (the
controller's rule): at the start of the manoeuvre, the CPA predicted with the own ship still
on the course and speed it stood on with is below the separation, and less than
``stand_on_wait_min`` ahead or the range below ``stand_on_range_factor`` separations; or the
own ship is at that time giving way to another target (with several targets a stand-on ship
may have to act for a third one); and in a crossing, no alteration to port for a vessel on
the own port side (Rule 17(c)).

The target ships in our scenarios do not manoeuvre, so a stand-on own ship is eventually
required to act (Rule 17(b)); the verdict checks that it waited long enough and turned
the right way.  The overall verdict is ``"pass"`` when every applicable rule passes.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from orchestrator.geometry import NM
from rhnc.encounters.colregs import (ROLE, STAND_ON_ACTION_RANGE_FACTOR, cpa_tcpa, stand_on_latest_s, stand_on_must_act,
                                    wrap_deg)
from rhnc.encounters.encounter import segment_min_distance

PASS, FAIL, NOT_APPLICABLE = "pass", "fail", "not applicable"
RULES = ("rule_8", "rule_13", "rule_14", "rule_15", "rule_16", "rule_17")
GIVE_WAY_CLASSES = ("head_on", "crossing_give_way", "overtaking")
STAND_ON_CLASSES = ("crossing_stand_on", "overtaken")


@dataclasses.dataclass(frozen=True)
class JudgementSettings:
    """Thresholds of the verdicts (units in the names)."""

    manoeuvre_threshold_deg: float = 5.0
    manoeuvre_hold_s: float = 120.0
    apparent_course_change_deg: float = 30.0
    apparent_speed_reduction: float = 0.5
    early_before_cpa_min: float = 5.0
    stand_on_wait_min: float = 10.0
    risk_cpa_nm: float = 2.0
    risk_tcpa_min: float = 30.0
    stand_on_range_factor: float = STAND_ON_ACTION_RANGE_FACTOR
    inside_open_within_s: float = 60.0
    #: the time [s] from a manoeuvre shown (``manoeuvre_threshold_deg``) to a readily apparent
    #: alteration complete: 30 deg more at the 0.3 deg/s of a loaded merchant ship's steady turn
    #: is 100 s, with 20 s for the rudder and the yaw to build up
    alteration_completion_s: float = 120.0
    #: "early ... if the circumstances of the case admit": an alteration begun within this
    #: time [s] of the moment the ship was first called on to act (three control intervals)
    at_once_within_s: float = 60.0
    #: a reduction of the speed over ground by this fraction of the speed at the onset, held
    #: ``manoeuvre_hold_s``, shows a manoeuvre as ``manoeuvre_threshold_deg`` of course does
    #: (Rule 8(b): "any alteration of course and/or speed"; 8(e): slacken her speed)
    manoeuvre_speed_reduction: float = 0.1

    def __post_init__(self) -> None:
        for field in dataclasses.fields(self):
            value = getattr(self, field.name)
            if not (isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
                    and value >= 0):
                raise ValueError(f"{field.name} must be a number >= 0, got {value!r}")


def closest_approach(t, own_xy: np.ndarray, target_xy: np.ndarray) -> tuple[float, float, float]:
    """Range [m], time [s] and the fractional sample index of the closest approach.

    The minimum over the samples is refined along the chords joining them.
    """
    t = np.asarray(t, dtype=float)
    at_samples = np.hypot(*(own_xy - target_xy).T)
    if t.size < 2:
        return float(at_samples[0]), float(t[0]), 0.0
    between, fraction = segment_min_distance(own_xy[:-1], own_xy[1:], target_xy[:-1], target_xy[1:])
    k = int(np.argmin(between))
    if at_samples.min() <= between[k]:
        k_sample = int(np.argmin(at_samples))
        return float(at_samples[k_sample]), float(t[k_sample]), float(k_sample)
    return float(between[k]), float(t[k] + fraction[k] * (t[k + 1] - t[k])), k + float(fraction[k])


def first_manoeuvre(t, heading_rad, start_index: int, end_time_s: float,
                    settings: JudgementSettings) -> tuple[float | None, str | None]:
    """Time [s] and side of the first sustained change of course after ``start_index``.

    ``heading_rad`` is the course (over ground, as :func:`rhnc.cosim.colregs_analysis.judge_encounters` passes it) at
    each sample [rad].  It must depart from its value at ``start_index`` by at least the threshold and
    stay beyond it (on the same side) for ``manoeuvre_hold_s``; only changes that begin
    before ``end_time_s`` count.  The change is the accumulated (unwrapped) one, so the side
    of a turn through more than 180 deg stays the side it began on.
    """
    t = np.asarray(t, dtype=float)
    unwrapped = np.unwrap(np.asarray(heading_rad, dtype=float))
    # the accumulated change, not wrapped: a turn to starboard that passes 180 deg is still
    # a turn to starboard (wrapped, it read as a turn to port from there on)
    change = np.degrees(unwrapped - unwrapped[start_index])
    threshold = settings.manoeuvre_threshold_deg
    for k in range(start_index, t.size):
        if t[k] > end_time_s:
            break
        if abs(change[k]) < threshold:
            continue
        sign = np.sign(change[k])
        window = (t >= t[k]) & (t <= t[k] + settings.manoeuvre_hold_s)
        held = np.all(sign * change[window] >= threshold)
        if held and t[-1] >= t[k] + settings.manoeuvre_hold_s:
            return float(t[k]), "starboard" if sign > 0 else "port"
    return None, None


def first_speed_reduction(t, speed_mps, start_index: int, end_time_s: float, settings: JudgementSettings) -> float | None:
    """Time [s] of the first sustained reduction of speed after ``start_index``: the speed over
    ground below ``1 - manoeuvre_speed_reduction`` of its value at ``start_index`` and staying
    below it for ``manoeuvre_hold_s`` (not the surge of a seaway); only reductions that begin
    before ``end_time_s`` count.  None without one."""
    t = np.asarray(t, dtype=float)
    speed = np.asarray(speed_mps, dtype=float)
    limit = (1.0 - settings.manoeuvre_speed_reduction) * speed[start_index]
    if settings.manoeuvre_speed_reduction <= 0.0 or speed[start_index] <= 0.0:
        return None
    for k in np.nonzero(speed[start_index:] < limit)[0] + start_index:
        if t[k] > end_time_s:
            break
        window = (t >= t[k]) & (t <= t[k] + settings.manoeuvre_hold_s)
        if np.all(speed[window] < limit) and t[-1] >= t[k] + settings.manoeuvre_hold_s:
            return float(t[k])
    return None


def crossed_ahead(own_xy: np.ndarray, target: np.ndarray, start: int, cpa_index: float) -> bool | None:
    """Whether the own ship crossed ahead of a moving target's bow (None: static target).

    Judged where the own ship crosses the target's course line (the first sign change of
    its lateral offset from the line after ``start``); without a crossing, by its position
    along the target's course at the CPA.
    """
    velocity = target[:, 2:4]
    speed = np.hypot(*velocity.T)
    if np.all(speed < 0.1):
        return None
    unit = velocity / np.maximum(speed, 1e-9)[:, None]
    relative = own_xy - target[:, :2]
    lateral = unit[:, 0] * relative[:, 1] - unit[:, 1] * relative[:, 0]
    along = np.sum(unit * relative, axis=1)
    sign = np.sign(lateral[start:])
    changes = np.nonzero(sign[:-1] * sign[1:] < 0)[0]
    if changes.size:
        k = start + int(changes[0])
        return bool(along[k] + along[k + 1] > 0.0)
    k = min(int(round(cpa_index)), len(along) - 1)
    return bool(along[k] > 0.0)


def judge_target(t, own_xy, course_rad, speed_mps, target: np.ndarray, encounter_class: str,
                 onset_index: int | None, required_m: float, settings: JudgementSettings,
                 give_way_onsets_s: tuple[float, ...] = (), stand_on_action_s: float | None = None) -> dict:
    """Everything the ``colregs`` analysis reports for one target (see :mod:`rhnc.cosim.colregs_analysis`).

    Parameters
    ----------
    t : (n,) [s]; own_xy : (n, 2) [m]; course_rad : (n,) course over ground [rad];
    speed_mps : (n,) speed over ground [m/s]
    target : (n, 5)
        The target at each sample: x, y, vx, vy, radius [m, m/s].
    encounter_class : str
        The class locked at the onset of risk ("none" when risk never arose).
    onset_index : int or None
        The sample of the onset of risk.
    required_m : float
        R + R_i [m].
    give_way_onsets_s : tuple of float
        Onsets [s] of the encounters with *other* targets in which the own ship gives way,
        and the times at which it had to act, as a stand-on ship, for another target.
        A stand-on manoeuvre made once one of those had begun answers that obligation, so
        Rule 17's "wait until the give-way vessel's action is not enough" does not apply
        to it (Rule 17(c) still does).
    stand_on_action_s : float, optional
        A stand-on target: when Rule 17(b) first let the own ship act for it [s] (the
        moment it was called on to act; for a give-way ship that is the onset).
    """
    t = np.asarray(t, dtype=float)
    cpa_m, cpa_time, cpa_index = closest_approach(t, own_xy, target[:, :2])
    initial_range_m = float(np.hypot(*(target[0, :2] - own_xy[0])))
    started_inside = bool(initial_range_m < required_m)
    k = min(int(round(cpa_index)), t.size - 1)
    offset = target[k, :2] - own_xy[k]
    bearing = float(wrap_deg(math.degrees(math.atan2(offset[1], offset[0]) - course_rad[k])))
    result: dict = {
        "encounter_class": encounter_class,
        "role": ROLE[encounter_class],
        "onset_s": None if onset_index is None else float(t[onset_index]),
        "cpa_nm": cpa_m / NM,
        "required_nm": required_m / NM,
        "separation_kept": bool(cpa_m >= required_m - 1e-6),
        "initial_range_nm": initial_range_m / NM,
        "started_inside": started_inside,
        "range_kept_from_start": bool(cpa_m >= initial_range_m - 1e-6) if started_inside else None,
        "range_opening_s": float(cpa_time - t[0]) if started_inside else None,
        "range_opened_in_time": bool(cpa_time - t[0] <= settings.inside_open_within_s) if started_inside else None,
        "time_of_cpa_s": cpa_time,
        "passing_side": "starboard" if bearing > 0 else "port",
        "relative_bearing_at_cpa_deg": bearing,
        "crossed": None,
        "manoeuvre_time_s": None,
        "manoeuvre_side": None,
        "manoeuvre_start_s": None,
        "called_to_act_s": (stand_on_action_s if encounter_class in STAND_ON_CLASSES else
                            None if onset_index is None else float(t[onset_index])),
        "early_by": None,
        "predicted_time_of_cpa_s": None,
        "max_course_change_deg": 0.0,
        "max_speed_reduction": 0.0,
    }
    if onset_index is None:
        result.update({rule: NOT_APPLICABLE for rule in RULES})
        result.update({"reasons": {}, "side_correct": None, "verdict": NOT_APPLICABLE})
        return result
    if encounter_class.startswith("crossing"):
        ahead = crossed_ahead(own_xy, target, onset_index, cpa_index)
        result["crossed"] = None if ahead is None else ("ahead" if ahead else "astern")
    result.update(_first_manoeuvre_fields(t, own_xy, course_rad, speed_mps, target, onset_index, cpa_time,
                                          settings))
    result.update(_manoeuvre_size(t, course_rad, speed_mps, onset_index, cpa_time, result["manoeuvre_time_s"],
                                  settings))
    verdicts, reasons = _verdicts(result, encounter_class, t, own_xy, course_rad, onset_index, target, settings,
                                  give_way_onsets_s)
    result.update(verdicts)
    result["reasons"] = reasons
    result["side_correct"] = _side_correct(result, encounter_class)
    applicable = [v for v in verdicts.values() if v != NOT_APPLICABLE]
    result["verdict"] = NOT_APPLICABLE if not applicable else (PASS if all(v == PASS for v in applicable) else FAIL)
    return result


def _manoeuvre_size(t, course_rad, speed_mps, onset_index: int, cpa_time: float, manoeuvre_time: float | None,
                    settings: JudgementSettings) -> dict:
    """The largest change of course [deg] and reduction of speed (a fraction of the speed at the
    onset) from the onset to the CPA or, for a manoeuvre shown before the CPA, to
    ``alteration_completion_s`` after it was shown, whichever is later."""
    until = cpa_time if manoeuvre_time is None else max(cpa_time, manoeuvre_time + settings.alteration_completion_s)
    before = (t >= t[onset_index]) & (t <= until)
    unwrapped = np.unwrap(course_rad)
    change = np.degrees(unwrapped[before] - unwrapped[onset_index])
    size = {"max_course_change_deg": float(np.max(np.abs(change))) if change.size else 0.0, "max_speed_reduction": 0.0}
    speed0 = float(speed_mps[onset_index])
    if speed0 > 0 and np.any(before):
        size["max_speed_reduction"] = float(max(0.0, 1.0 - np.min(speed_mps[before]) / speed0))
    return size


def _first_manoeuvre_fields(t, own_xy, course_rad, speed_mps, target: np.ndarray, onset_index: int,
                            cpa_time: float, settings: JudgementSettings) -> dict:
    """The first manoeuvre's time (5 deg of course, or a tenth of the speed, shown), its kind
    (``course`` or ``speed``), the side of the first change of course, when the manoeuvre began,
    and the CPA predicted then.

    A reduction of speed alone is a manoeuvre (Rules 8(b), 8(e)): read from the course alone, a
    ship that gave way to three ships crossing from starboard by slowing from 18 to 8 kn 1 min
    after the onset got "no alteration before the CPA" for all three."""
    course_time, side = first_manoeuvre(t, course_rad, onset_index, cpa_time, settings)
    speed_time = first_speed_reduction(t, speed_mps, onset_index, cpa_time, settings)
    by_speed = speed_time is not None and (course_time is None or speed_time < course_time)
    manoeuvre_time = speed_time if by_speed else course_time
    fields = {"manoeuvre_time_s": manoeuvre_time, "manoeuvre_side": side,
              "manoeuvre_kind": None if manoeuvre_time is None else ("speed" if by_speed else "course")}
    if manoeuvre_time is not None:
        k_before = (_last_full_speed_sample(t, speed_mps, onset_index, int(np.searchsorted(t, manoeuvre_time)),
                                            settings) if by_speed
                    else _last_steady_sample(t, course_rad, onset_index, int(np.searchsorted(t, manoeuvre_time)),
                                             settings))
        _, tcpa = _prediction_at(t, own_xy, target, k_before)
        fields["manoeuvre_start_s"] = float(t[k_before])
        fields["predicted_time_of_cpa_s"] = float(t[k_before] + tcpa) if 0.0 < tcpa < math.inf else None
    return fields


def _prediction_at(t, own_xy, target: np.ndarray, k: int) -> tuple[float, float]:
    """The CPA [m] and TCPA [s] predicted at sample ``k`` with both ships' velocities there."""
    own_velocity = np.gradient(own_xy, t, axis=0)[k]
    return cpa_tcpa(own_xy[k], own_velocity, target[k, :2], target[k, 2:4])


def _last_full_speed_sample(t, speed_mps, onset_index: int, index: int, settings: JudgementSettings) -> int:
    """The last sample before ``index`` whose speed is within half the manoeuvre's reduction of
    the speed at the onset (where the reduction began); the onset if none."""
    speed = np.asarray(speed_mps[onset_index:index + 1], dtype=float)
    full = np.nonzero(speed >= (1.0 - 0.5 * settings.manoeuvre_speed_reduction) * speed[0])[0]
    return onset_index + int(full[-1]) if full.size else onset_index


def _side_correct(result: dict, encounter_class: str) -> bool | None:
    """The COLREG side: port to port head-on, astern of a crossing ship we give way to; None
    for a target that started inside R + R_i (immediate danger: Rule 2(b))."""
    if result["started_inside"]:
        return None
    if encounter_class == "head_on":
        return result["passing_side"] == "port"
    if encounter_class == "crossing_give_way":
        return result["crossed"] != "ahead"
    if encounter_class == "crossing_stand_on":
        return result["manoeuvre_side"] != "port"
    return None


def predicted_time_of_cpa(t, own_xy, course_rad, target: np.ndarray, onset_index: int, manoeuvre_time_s: float,
                          settings: JudgementSettings) -> float | None:
    """When the CPA would have come had both ships kept the velocities they had as the
    manoeuvre began (the last steady sample before it) [s]; None when the ships were not
    closing then (or kept their distance).

    Rules 8 and 16 measure "early" against the later of this CPA and the sailed one
    (:func:`early_by`): the manoeuvre itself moves the sailed CPA (an overtaking ship that
    turns away meets its CPA as it turns).
    """
    k_before = _last_steady_sample(t, course_rad, onset_index, int(np.searchsorted(t, manoeuvre_time_s)), settings)
    _, tcpa = _prediction_at(t, own_xy, target, k_before)
    return float(t[k_before] + tcpa) if 0.0 < tcpa < math.inf else None


def _last_steady_sample(t, course_rad, onset_index: int, index: int, settings: JudgementSettings) -> int:
    """The last sample before ``index`` whose course is within half the manoeuvre threshold of
    the course at the onset (where the manoeuvre began); the onset if none.  The change is
    accumulated, as in :func:`first_manoeuvre` (a full round turn is not steady)."""
    unwrapped = np.unwrap(np.asarray(course_rad[onset_index:index + 1], dtype=float))
    change = np.abs(np.degrees(unwrapped - unwrapped[0]))
    steady = np.nonzero(change < 0.5 * settings.manoeuvre_threshold_deg)[0]
    return onset_index + int(steady[-1]) if steady.size else onset_index


def _verdicts(result, encounter_class, t, own_xy, course_rad, onset_index, target, settings,
              give_way_onsets_s=()) -> tuple[dict, dict]:
    verdicts = {rule: NOT_APPLICABLE for rule in RULES}
    reasons: dict[str, str] = {}

    def judge(rule: str, failures: list[str]) -> None:
        verdicts[rule] = FAIL if failures else PASS
        if failures:
            reasons[rule] = "; ".join(failures)

    separation = _separation_failures(result, settings)
    manoeuvred = result["manoeuvre_time_s"] is not None
    timing, result["early_by"] = _timing_failures(result, settings)
    give_way = encounter_class in GIVE_WAY_CLASSES
    # a stand-on ship's manoeuvre made while it gives way to another target is that
    # encounter's action (judged there, Rule 8 included), not one taken for this target
    for_another = manoeuvred and any(onset <= result["manoeuvre_time_s"] for onset in give_way_onsets_s)
    # a target that started inside R + R_i is immediate danger from the start: the sides of
    # Rules 14, 15 and 17(c) yield to opening the range at once (Rule 2(b), as the controller
    # lets them), and its own criterion, the range opening, is what is judged; so for Rules 8
    # and 16, whose size and timing hold "if the circumstances of the case admit" (8(a), (b))
    # and "so far as possible" (16): the range must open within inside_open_within_s, less
    # time than a readily apparent alteration takes (colregs.APPARENT_ALTERATION_TURN_S, 137 s)
    immediate = result["started_inside"]
    if immediate:
        timing = []
    if give_way or (manoeuvred and encounter_class != "static"
                    and not (encounter_class in STAND_ON_CLASSES and for_another)):
        large = (result["max_course_change_deg"] >= settings.apparent_course_change_deg
                 or result["max_speed_reduction"] >= settings.apparent_speed_reduction or immediate)
        size = [] if large else [f"alteration {result['max_course_change_deg']:.0f} deg, speed "
                                 f"-{100 * result['max_speed_reduction']:.0f} %: not readily apparent"]
        judge("rule_8", size + timing + separation)
    if encounter_class == "overtaking":
        judge("rule_13", separation)
    if encounter_class == "head_on":
        side = [] if result["passing_side"] == "port" or immediate else ["passed starboard to starboard"]
        turn = ["altered to port"] if result["manoeuvre_side"] == "port" and not immediate else []
        judge("rule_14", turn + side + (separation if immediate else []))
    if encounter_class == "crossing_give_way":
        ahead = result["crossed"] == "ahead" and not immediate
        judge("rule_15", (["crossed ahead of the target"] if ahead else []) + separation)
    if give_way:
        judge("rule_16", timing + separation)
    if encounter_class in STAND_ON_CLASSES:
        failures = []
        if manoeuvred:
            failures += _stand_on_failures(result, encounter_class, t, own_xy, course_rad, onset_index, target,
                                           settings, give_way_onsets_s)
            if encounter_class == "crossing_stand_on" and result["manoeuvre_side"] == "port" and not immediate:
                failures.append("altered to port for a vessel on the port side (Rule 17(c))")
        judge("rule_17", failures + separation)
    return verdicts, reasons


def _separation_failures(result, settings) -> list[str]:
    """Why the separation was not kept (empty when it was): the CPA against the required
    distance, or for a target started inside it, the range not opening in time."""
    if result["started_inside"]:  # no controller can keep R + R_i: the range must open at once
        kept = result["range_opened_in_time"]
        separation = [] if kept else [f"started {result['initial_range_nm']:.2f} nm off, inside the required "
                                      f"{result['required_nm']:.2f} nm, and closed to {result['cpa_nm']:.2f} nm "
                                      f"{result['range_opening_s']:.0f} s after the start (> "
                                      f"{settings.inside_open_within_s:g} s)"]
    else:
        kept = result["separation_kept"]
        separation = [] if kept else [f"CPA {result['cpa_nm']:.2f} nm < required {result['required_nm']:.2f} nm"]
    return separation


def early_by(result, settings) -> str | None:
    """The reading by which the first alteration was early (Rules 8(a), 16), None if by none.

    The rules ask for action "in ample time" and "early", "if the circumstances of the case
    admit" (8(a)), "so far as possible" (16).  The alteration is timed from when the turn
    began (``manoeuvre_start_s``: the last sample of a steady course before it; it shows as
    ``manoeuvre_threshold_deg`` of course only a minute or more later), and it is early when
    it began at least ``early_before_cpa_min`` before the closest approach it avoided:

    * ``"sailed CPA"``: the CPA of the sailed tracks;
    * ``"predicted CPA"``: the CPA predicted at the velocities as it began (the turn moves
      the sailed CPA forward, an overtaking ship's and an overtaken one's most: turning
      away from a ship closing slowly from astern meets the CPA as the turn is made);
    * ``"at once"``: or, where the circumstances admitted nothing earlier, it began within
      ``at_once_within_s`` of the moment the ship was first called on to act
      (``called_to_act_s``: the onset of risk for a give-way ship, which may come with the
      CPA closer than that, e.g. a target at risk from the start; for a stand-on ship the
      moment Rule 17(b) let it act, before which Rule 17(a) had it keep its course).
    """
    start = result.get("manoeuvre_start_s")
    if start is None:
        return None
    early_s = settings.early_before_cpa_min * 60.0
    predicted = result.get("predicted_time_of_cpa_s")
    called = result.get("called_to_act_s")
    if result["time_of_cpa_s"] - start >= early_s:
        return "sailed CPA"
    if predicted is not None and predicted - start >= early_s:
        return "predicted CPA"
    if called is not None and start - called <= settings.at_once_within_s:
        return "at once"
    return None


def _timing_failures(result, settings) -> tuple[list[str], str | None]:
    """Why the alteration was not early (empty when it was: :func:`early_by`) and the reading
    by which it was."""
    if result["manoeuvre_time_s"] is None:
        return ["no alteration before the CPA"], None
    reading = early_by(result, settings)
    if reading is not None:
        return [], reading
    start = result["manoeuvre_start_s"]
    predicted = result["predicted_time_of_cpa_s"]
    then = "" if predicted is None else f", {(predicted - start) / 60:.1f} min before the CPA predicted then"
    called = result.get("called_to_act_s")
    late = "" if called is None else f", {start - called:.0f} s after it was called on to act"
    return [f"alteration began {(result['time_of_cpa_s'] - start) / 60:.1f} min before the CPA "
            f"(< {settings.early_before_cpa_min:g} min{then}{late})"], None


def _stand_on_failures(result, encounter_class, t, own_xy, course_rad, onset_index, target, settings,
                       give_way_onsets_s) -> list[str]:
    """A stand-on ship's alteration judged with the velocity it stood on with before it began:
    made while the give-way vessel's action could still suffice (and not while giving way to another)."""
    # judge the decision with the velocity the ship stood on with before it began
    k_before = int(np.searchsorted(t, result["manoeuvre_start_s"]))
    cpa, tcpa = _prediction_at(t, own_xy, target, k_before)
    range_m = float(np.hypot(*(target[k_before, :2] - own_xy[k_before])))
    giving_way = any(onset <= result["manoeuvre_time_s"] for onset in give_way_onsets_s)
    offset = target[k_before, :2] - own_xy[k_before]
    bearing = float(wrap_deg(math.degrees(math.atan2(offset[1], offset[0]) - course_rad[k_before])))
    latest = stand_on_latest_s(encounter_class, bearing, own_xy[k_before],
                               np.gradient(own_xy, t, axis=0)[k_before], target[k_before, :2],
                               target[k_before, 2:4], result["required_nm"] * NM)
    if not giving_way and not stand_on_must_act(cpa, tcpa, range_m, result["required_nm"] * NM,
                                                settings.stand_on_wait_min * 60.0,
                                                settings.stand_on_range_factor, latest):
        action = "reduced speed" if result.get("manoeuvre_kind") == "speed" else "altered course"
        return [f"{action} with predicted CPA {cpa / NM:.2f} nm in {tcpa / 60:.1f} min at "
                f"{range_m / NM:.2f} nm: the give-way vessel's action could still suffice"]
    return []
