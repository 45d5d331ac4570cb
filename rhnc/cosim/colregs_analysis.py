"""Judging a sailed encounter by the rules of the road (COLREG Rules 8 and 13-17).

Works on the recorded tracks alone (no co-simulation needed), so constructed time series
test every verdict.  Per target it reports

* the encounter class and the own ship's role, decided at the onset of risk of collision
  by :class:`rhnc.encounters.colregs.EncounterTracker` (the class the controller also uses), fed
  with the own ship's course and speed over ground; ``borderline`` names the boundary when
  the class was decided within :data:`rhnc.encounters.colregs.BORDERLINE_DEG` of it ("" if not),
  and the run's ``borderline`` lists those targets;
* the closest point of approach: range and time, refined along the straight chords
  between samples (both ships moving linearly over a sample interval);
* the passing side: where the target lies from the own ship's course over ground at the
  CPA (``port``: a port-to-port passing), and, in a crossing, whether the own ship
  crossed ahead of or astern of the target (on crossing the target's course line; at the CPA if
  the tracks never cross);
* the first manoeuvre after the onset: the first time the course over ground departs from
  the course at the onset by ``manoeuvre_threshold_deg`` or more and stays beyond it for
  ``manoeuvre_hold_s`` (a sustained alteration, not yaw in a seaway), or the speed over ground
  falls below ``1 - manoeuvre_speed_reduction`` of the speed at the onset and stays below it as
  long, whichever comes first (``manoeuvre_kind``: ``course`` or ``speed``), and the side of
  the first change of course;
* a verdict per rule, ``"pass"``, ``"fail"`` or ``"not applicable"``, with the reason.

Manoeuvres are read from the course over ground (COG, from the sampled positions), not from
the heading: in a cross wind a ship holding its course sails with a drift angle of several
degrees, and a controller that trims its heading for it has not altered course.  Another
ship sees the COG (radar, AIS).  The largest difference heading - COG between onset and CPA
is reported as ``max_drift_angle_deg`` when the heading is given.

A target that starts inside R + R_i (the situation begins inside the domain: no
controller can then keep R + R_i) is reported apart, ``started_inside``, with its own
criterion: the range must open at once, its closest approach coming within
``inside_open_within_s`` (60 s) of the start (``range_opened_in_time``; the time is
``range_opening_s``); whether it ever fell below its value at the start is
``range_kept_from_start``.  Its rule verdicts judge the separation by that criterion;
``separation_kept`` still says, truthfully, that R + R_i was not kept.

The verdicts and their thresholds (:class:`JudgementSettings`): :mod:`rhnc.encounters.colregs_judgement`.
"""

from __future__ import annotations

import math

import numpy as np

from orchestrator.geometry import NM
from rhnc.encounters.colregs import (STAND_ON_ACTION_RANGE_FACTOR, EncounterTracker, cpa_tcpa, stand_on_latest_s,
                                    stand_on_must_act, wrap_deg)
from rhnc.encounters.colregs_judgement import (FAIL, GIVE_WAY_CLASSES, NOT_APPLICABLE, PASS, RULES, STAND_ON_CLASSES,
                                               JudgementSettings, closest_approach, first_manoeuvre, judge_target)

__all__ = ["PASS", "FAIL", "NOT_APPLICABLE", "RULES", "JudgementSettings", "closest_approach", "first_manoeuvre",
           "ground_velocity", "judge_target", "judge_encounters", "colregs_analysis"]


def ground_velocity(t, x, y) -> tuple[np.ndarray, np.ndarray]:
    """Velocity over ground (north, east) [m/s] at each sample, from the positions."""
    t = np.asarray(t, dtype=float)
    if t.size < 2:
        return np.zeros_like(t), np.zeros_like(t)
    return np.gradient(np.asarray(x, float), t), np.gradient(np.asarray(y, float), t)


def judge_encounters(t, x, y, heading_rad, obstacles: np.ndarray, own_radius_m: float = 0.0,
                     settings: JudgementSettings | None = None) -> dict:
    """The ``colregs`` analysis of a run from its sampled tracks.

    Parameters
    ----------
    t, x, y, heading_rad : (n,) arrays
        Times [s], own positions [m] and heading [rad] (or None).  Every judgement uses
        the course over ground from the positions; the heading only gives each target's
        ``max_drift_angle_deg`` (heading - COG, largest between onset and CPA).
    obstacles : (n, m, 5) array
        Every obstacle at each sample: x, y, vx, vy, radius [m, m/s].
    own_radius_m : float
        Own hazard radius R [m].

    Returns
    -------
    dict
        ``targets`` (one dict per obstacle row), ``verdict`` (overall), ``side_correct``
        (every target with a COLREG side passed on it, or None), and counts.
    """
    settings = settings or JudgementSettings()
    t = np.asarray(t, dtype=float)
    own_xy = np.column_stack([x, y]).astype(float)
    heading = None if heading_rad is None else np.asarray(heading_rad, dtype=float)
    obstacles = np.asarray(obstacles, dtype=float).reshape(t.size, -1, 5)
    vx, vy = ground_velocity(t, x, y)
    speed = np.hypot(vx, vy)
    course = np.arctan2(vy, vx)
    tracker = EncounterTracker(settings.risk_cpa_nm * NM, settings.risk_tcpa_min * 60.0,
                               release_range_m=math.inf)
    classes: dict[int, tuple[str, int]] = {}
    borderline: dict[int, str] = {}
    for k in range(t.size):
        encounters = tracker.update(own_xy[k], course[k], speed[k], obstacles[k])
        for i, encounter in enumerate(encounters):
            if i not in classes and encounter.encounter_class not in ("none",):
                classes[i] = (encounter.encounter_class, k)
                borderline[i] = encounter.borderline
    must_act = {j: time for j, (other, k) in classes.items() if other in STAND_ON_CLASSES
                and (time := _stand_on_action_time(t, own_xy, np.column_stack([vx, vy]), obstacles[:, j], other, k,
                                                   own_radius_m, settings)) is not None}
    targets = []
    for i in range(obstacles.shape[1]):
        name, onset = classes.get(i, ("none", None))
        required = own_radius_m + float(np.max(obstacles[:, i, 4]))
        # the times the own ship had to act for another target: as its give-way vessel, or
        # as a stand-on vessel whose time to stand on had run out (Rule 17(b))
        give_way_onsets = tuple(float(t[k]) for j, (other, k) in classes.items()
                                if j != i and other in GIVE_WAY_CLASSES)
        give_way_onsets += tuple(must_act[j] for j in must_act if j != i)
        judged = judge_target(t, own_xy, course, speed, obstacles[:, i], name, onset, required, settings,
                              give_way_onsets, must_act.get(i))
        judged["max_drift_angle_deg"] = None
        if heading is not None and onset is not None:
            window = (t >= t[onset]) & (t <= judged["time_of_cpa_s"])
            drift = wrap_deg(np.degrees(heading[window] - course[window]))
            judged["max_drift_angle_deg"] = float(np.max(np.abs(drift))) if drift.size else 0.0
        judged["borderline"] = borderline.get(i, "")
        targets.append({"obstacle": i, **judged})
    verdicts = [target["verdict"] for target in targets if target["verdict"] != NOT_APPLICABLE]
    sides = [target["side_correct"] for target in targets if target["side_correct"] is not None]
    outside = [target["separation_kept"] for target in targets if not target["started_inside"]]
    inside = [target["range_kept_from_start"] for target in targets if target["started_inside"]]
    opened = [target["range_opened_in_time"] for target in targets if target["started_inside"]]
    margins = [target["cpa_nm"] - target["required_nm"] for target in targets if not target["started_inside"]]
    return {
        "separation_kept": bool(all(outside)),
        "separation_margin_nm": min(margins) if margins else None,
        "started_inside": [target["obstacle"] for target in targets if target["started_inside"]],
        "started_inside_range_kept": bool(all(inside)) if inside else None,
        "started_inside_opened": bool(all(opened)) if opened else None,
        "borderline": [target["obstacle"] for target in targets if target["borderline"]],
        "targets": targets,
        "verdict": NOT_APPLICABLE if not verdicts else (PASS if all(v == PASS for v in verdicts) else FAIL),
        "side_correct": None if not sides else bool(all(sides)),
        "targets_failed": sum(1 for v in verdicts if v == FAIL),
        "rules_failed": sorted({rule for target in targets for rule in RULES if target[rule] == FAIL}),
    }


def _stand_on_action_time(t, own_xy, own_velocity, target: np.ndarray, encounter_class: str, onset: int,
                          own_radius_m: float, settings: JudgementSettings) -> float | None:
    """The first time [s] after the onset at which a stand-on ship must act for this target
    (:func:`rhnc.encounters.colregs.stand_on_must_act`, as the controller decides it), None if never."""
    required = own_radius_m + float(np.max(target[:, 4]))
    for k in range(onset, t.size):
        cpa, tcpa = cpa_tcpa(own_xy[k], own_velocity[k], target[k, :2], target[k, 2:4])
        if not (cpa < required and tcpa > 0.0):
            continue
        offset = target[k, :2] - own_xy[k]
        bearing = float(wrap_deg(math.degrees(math.atan2(offset[1], offset[0])
                                              - math.atan2(own_velocity[k, 1], own_velocity[k, 0]))))
        latest = stand_on_latest_s(encounter_class, bearing, own_xy[k], own_velocity[k], target[k, :2],
                                   target[k, 2:4], required)
        if stand_on_must_act(cpa, tcpa, float(np.hypot(*offset)), required, settings.stand_on_wait_min * 60.0,
                             settings.stand_on_range_factor, latest):
            return float(t[k])
    return None


def colregs_analysis(frame, scenario, cosim, out_dir, manoeuvre_threshold_deg: float = 5.0,
                     manoeuvre_hold_s: float = 120.0, apparent_course_change_deg: float = 30.0,
                     apparent_speed_reduction: float = 0.5, early_before_cpa_min: float = 5.0,
                     stand_on_wait_min: float = 10.0, risk_cpa_nm: float = 2.0, risk_tcpa_min: float = 30.0,
                     stand_on_range_factor: float = STAND_ON_ACTION_RANGE_FACTOR,
                     at_once_within_s: float = 60.0, manoeuvre_speed_reduction: float = 0.1) -> dict:
    """The ``colregs`` analysis of a run: :func:`judge_encounters` on its recorded tracks.

    The obstacles are the true ones (the array feeding an ``obstacles`` input, or the truth behind a
    tracker feeding it: :func:`rhnc.cosim.obstacle_ports.true_obstacles_column`); the
    own radius R is the controller's.  The keyword options are :class:`JudgementSettings`
    (``[outputs.options.colregs]``).
    """
    from orchestrator.analyses import array_output
    from rhnc.cosim.plant import own_radius_m, plant_name

    settings = JudgementSettings(manoeuvre_threshold_deg, manoeuvre_hold_s, apparent_course_change_deg,
                                 apparent_speed_reduction, early_before_cpa_min, stand_on_wait_min,
                                 risk_cpa_nm, risk_tcpa_min, stand_on_range_factor,
                                 at_once_within_s=at_once_within_s,
                                 manoeuvre_speed_reduction=manoeuvre_speed_reduction)
    plant = plant_name(cosim)
    from rhnc.cosim.obstacle_ports import true_obstacles_column

    true_obstacles = true_obstacles_column(scenario, cosim)  # judged on the true tracks, not a tracker's
    if true_obstacles is None:
        return {"targets": [], "verdict": NOT_APPLICABLE, "side_correct": None, "targets_failed": 0,
                "rules_failed": [], "separation_kept": True, "separation_margin_nm": None, "started_inside": [],
                "started_inside_range_kept": None, "started_inside_opened": None, "borderline": []}
    return judge_encounters(frame["time_s"].to_numpy(), frame[f"{plant}.x"].to_numpy(),
                            frame[f"{plant}.y"].to_numpy(), frame[f"{plant}.psi"].to_numpy(),
                            array_output(frame, true_obstacles), own_radius_m(cosim), settings)


def _check_options(options) -> None:
    """Refuse bad ``[outputs.options.colregs]`` values before a run (ValueError names the key)."""
    JudgementSettings(**dict(options))


colregs_analysis.check_options = _check_options
