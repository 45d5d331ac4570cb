"""Could a single manoeuvre from the start have kept R + R_i from every target that started outside it?

The encounter suites judge "separation >= R + R_i for every target that starts outside it".
Some situations put two or three ships on collision courses 1-2 nm off at once, and the
controller loses the separation by a little.  Whether any ship could have kept it depends on
the geometry and on the ship, so this script asks the ship's own equations of motion (the
parameter set the run's controller predicted with, ``default`` when the summary does not say;
calm water, no disturbance), for every run that lost the separation to a target that started
outside, whether one manoeuvre begun at t = 0 keeps every target that started outside at
``range >= required_nm`` (R + R_i, from the run's summary).  The targets sail at their
recorded velocity at t = 0 in a straight line, as the suites' targets do unless their
waypoints turn; a target whose recorded velocity changes later in the run is flagged
("turned": the straight line, and the verdict, do not hold for it).  Targets that started
inside R + R_i are left out, as the suites leave them out of this criterion.

The manoeuvres, each held from t = 0 over a 30 min window sampled every second:

* a new heading every 10 deg relative to the initial one, to starboard and to port up to
  180 deg (0 deg: keep the heading), reached with the full yaw moment (a saturated PD law on
  the heading error, which gives the full moment until the ship must check its swing, then
  holds the heading);
* times four surge forces: full ahead, the force that holds the initial speed (the model's
  equilibrium), none, and full astern (Rule 8(e) names reversing; the model's bounds are
  symmetric, ``|tau_u| <= tau_u_max``).

The speed stays within the controller's speed bound ahead (24 kn unless the run set
``max_speed_kn``) and at zero astern: the linear hull model has no propeller, so under full
force it would run on to about 42 kn ahead, or astern, which no hull of this kind does; full
astern here is a crash stop that takes all way off.  After the window both ships are carried on
at their velocities at its end, so a manoeuvre that only postpones the closest approach does
not count as keeping the separation.

For each run the best manoeuvre is the one with the largest least clearance, min over time
and targets (started outside) of range - required; the run is "achievable" when that is at
least 0; the line also gives the best manoeuvre that does not speed up (surge force at most
the one holding the initial speed), since the speed bound is a setting of the controller.

Each manoeuvre's track is also judged for the sides, as the run's ``colregs`` analysis
judges a recorded track: :func:`rhnc.encounters.colregs_judgement.judge_target`, with the
encounter class the analysis recorded for each target (``analyses.colregs.targets[i]``) and
the onset of risk at t = 0, gives its ``side_correct``: a head-on ship passed port to port
(the side of the own course over ground it is on at the closest approach); a ship crossing
from starboard, that we give way to, not crossed ahead of (``crossed_ahead``: where the own
track crosses her course line, or by where the own ship is along it at the closest approach
when it never does); in a crossing from port, where we stand on, no first change of course
to port (Rule 17(c); keeping the heading keeps it).  Overtaking, being overtaken and targets
that started inside R + R_i have no side.  The tracks are judged to the run's end and on to
the latest closest approach, both ships straight after the window.  The line then gives the
best manoeuvre among those that keep every side, and the verdict: "achievable keeping every
side", "achievable only against a side rule" (some manoeuvre keeps the separation, none of
those keeps every side), or "not achievable by a single manoeuvre from the start"; the
totals count the lost targets (and runs) under each, per batch and over all batches.
This is a judgement by the ship's model with single manoeuvres, not a proof either
way.  There is deliberately no second leg: a sequence of manoeuvres (turn, then turn back,
or slow, then turn) can do better than any single one, so "not achievable" means "not by a
single manoeuvre from the start"; the headings are 10 deg apart, so a least clearance within
a few hundredths of a mile of 0 could go either way with a finer grid; the
model's yaw moment does not fall with speed (a real rudder loses its grip as the ship stops),
which flatters turns combined with stopping.  Reads the run folders of batch results
(``runs/*/summary.json``, ``timeseries.parquet``; the batch's ``summary.csv`` for the
situation) and prints one line per run, the totals per batch and over all batches:

    PYTHONPATH=. nice -n 10 python scripts/separation_feasibility.py results/suites_c4bf649/trafficgen55c_rhnc_colregs ...
"""

from __future__ import annotations

import argparse
import dataclasses
import json
from pathlib import Path

import numpy as np
import pandas as pd

from orchestrator.geometry import KNOT, NM, wrap_deg
from rhnc.cosim.colregs_analysis import ground_velocity
from rhnc.encounters.colregs_judgement import JudgementSettings, judge_target
from rhnc.ship.ship_model import ShipParameters, hull_forces, load_parameter_set, rk4_step

WINDOW_S = 1800.0
DT_S = 1.0
RK4_SUBSTEPS = 1
#: relative headings [deg]: every 10 deg to starboard (+) and port (-), 180 both ways
HEADING_OFFSETS_DEG = np.arange(-180.0, 181.0, 10.0)
SURGE_NAMES = ("full ahead", "speed held", "no thrust", "full astern")
#: the NMPC's default speed bound, the KCS's service speed (rhnc.control.nmpc_settings.SERVICE_SPEED_MPS)
SERVICE_SPEED_KN = 24.0
#: the heading-hold law: the full yaw moment while the heading error, less the yaw rate times
#: a lead, exceeds a band; inside it, proportional.  The lead checks the swing in time (the
#: full moment stops a KCS turning at 0.7 deg/s in about 9 s, 3 deg on); the band keeps the
#: law near bang-bang.  The linearised closed loop is stable from 0.5 to 26 kn (slowest pole
#: -0.03/s) though the linear KCS turns course-unstable as it speeds up
HEADING_BAND_DEG = 2.0
HEADING_LEAD_S = 10.0
#: time constant [s] with which the speed limiter holds a bound the surge force would pass
SPEED_LIMIT_TIME_S = 10.0
#: a target "turned" when its recorded velocity leaves its value at t = 0 by this much
TURN_DEG, TURN_KN = 2.0, 0.3
OWN_STATE = ["ship.x", "ship.y", "ship.psi", "ship.u", "ship.v", "ship.r"]
#: the sides are judged on the tracks carried on past the window, sampled this often [s] (as the
#: runs are recorded), until the run's end or the latest closest approach, at most this long after it
AFTER_WINDOW_DT_S = 20.0
AFTER_WINDOW_MAX_S = 6 * 3600.0
#: below this speed over ground [kn] the own ship's course is its heading (a ship stopped has no
#: course over ground: the positions' differences give the direction of a drift of millimetres)
STOPPED_KN = 0.5


@dataclasses.dataclass(frozen=True)
class Family:
    """The manoeuvres, one per column: a heading offset [rad] and a commanded surge force [N]."""

    heading_offset_rad: np.ndarray
    surge_force_N: np.ndarray
    labels: tuple[str, ...]


@dataclasses.dataclass(frozen=True)
class Targets:
    """The targets judged: position [m] and velocity [m/s] at t = 0, one row each, R + R_i [m],
    and the encounter class the run's ``colregs`` analysis gave each (none given: no side judged)."""

    xy: np.ndarray
    velocity: np.ndarray
    required_m: np.ndarray
    encounter_class: tuple[str, ...] = ()


def manoeuvre_family(params: ShipParameters, u0: float, offsets_deg: np.ndarray = HEADING_OFFSETS_DEG,
                     surge_names: tuple[str, ...] = SURGE_NAMES) -> Family:
    """Every heading offset with every surge force; ``u0`` [m/s] is the speed "speed held" keeps."""
    forces = {"full ahead": params.tau_u_max, "speed held": float(params.equilibrium_tau(u0)[0]),
              "no thrust": 0.0, "full astern": -params.tau_u_max}
    offsets, surges, labels = [], [], []
    for name in surge_names:
        for offset in offsets_deg:
            offsets.append(np.radians(offset))
            surges.append(forces[name])
            turn = "keep heading" if offset == 0 else f"turn {abs(offset):.0f} deg to {'starboard' if offset > 0 else 'port'}"
            labels.append(f"{turn}, {name}")
    return Family(np.array(offsets), np.array(surges), tuple(labels))


def _heading_hold_gains(params: ShipParameters) -> tuple[float, float]:
    """Proportional [N m/rad] and derivative [N m s/rad] gains of the heading-hold law: the
    full yaw moment at :data:`HEADING_BAND_DEG` of error, and :data:`HEADING_LEAD_S` of lead."""
    proportional = params.tau_r_max / np.radians(HEADING_BAND_DEG)
    return proportional, proportional * HEADING_LEAD_S


def _inputs(state: np.ndarray, psi_goal: np.ndarray, family: Family, params: ShipParameters,
            speed_bounds: tuple[float, float], gains: tuple[float, float]) -> np.ndarray:
    """Surge force and yaw moment (2, M) of every manoeuvre at ``state`` (6, M)."""
    _, u, v, r = state[2], state[3], state[4], state[5]
    yaw = np.clip(gains[0] * (psi_goal - state[2]) - gains[1] * r, -params.tau_r_max, params.tau_r_max)
    # the force that brings u to a bound in SPEED_LIMIT_TIME_S: far from it, no limit at all
    drag = -hull_forces(params, u, v, r)[0]
    upper = drag + params.m11 * (speed_bounds[1] - u) / SPEED_LIMIT_TIME_S
    lower = drag + params.m11 * (speed_bounds[0] - u) / SPEED_LIMIT_TIME_S
    surge = np.clip(np.clip(family.surge_force_N, lower, upper), -params.tau_u_max, params.tau_u_max)
    return np.vstack([surge, yaw])


@dataclasses.dataclass(frozen=True)
class Tracks:
    """The own ship under every manoeuvre: sample times (n,) [s], positions (n, M, 2) [m],
    headings (n, M) [rad] and the velocity over ground at the end of the window (M, 2) [m/s]."""

    times: np.ndarray
    positions: np.ndarray
    heading_rad: np.ndarray
    end_velocity: np.ndarray


def sail(own0: np.ndarray, family: Family, params: ShipParameters, speed_bounds: tuple[float, float],
         window_s: float = WINDOW_S, dt_s: float = DT_S) -> Tracks:
    """The own ship from ``own0`` (x, y, psi, u, v, r) under every manoeuvre of ``family``, its
    speed kept within ``speed_bounds`` [m/s], over the window."""
    state = np.repeat(np.asarray(own0, dtype=float)[:, None], len(family.labels), axis=1)
    psi_goal = state[2] + family.heading_offset_rad
    gains = _heading_hold_gains(params)
    times = np.arange(0.0, window_s + dt_s / 2, dt_s)
    positions = np.empty((times.size, state.shape[1], 2))
    heading = np.empty((times.size, state.shape[1]))
    for k in range(times.size):
        positions[k], heading[k] = state[:2].T, state[2]
        if k + 1 < times.size:
            tau = _inputs(state, psi_goal, family, params, speed_bounds, gains)
            state = rk4_step(state, tau, dt_s, RK4_SUBSTEPS, params)
    psi, u, v = state[2], state[3], state[4]
    velocity = np.column_stack([u * np.cos(psi) - v * np.sin(psi), u * np.sin(psi) + v * np.cos(psi)])
    return Tracks(times, positions, heading, velocity)


def least_clearance(tracks: Tracks, targets: Targets) -> np.ndarray:
    """Least range - required [m] over time and targets, per manoeuvre (M,).

    Between samples the relative motion is taken along the straight chord (as the analysis
    refines its CPA); after the window both ships sail on at their last velocities."""
    times, positions, end_velocity = tracks.times, tracks.positions, tracks.end_velocity
    target_xy = targets.xy[None, :, :] + times[:, None, None] * targets.velocity[None, :, :]   # (n, T, 2)
    relative = target_xy[:, None, :, :] - positions[:, :, None, :]                            # (n, M, T, 2)
    start, chord = relative[:-1], np.diff(relative, axis=0)
    along = np.clip(-np.sum(start * chord, axis=-1) / np.maximum(np.sum(chord * chord, axis=-1), 1e-12), 0.0, 1.0)
    ranges = np.linalg.norm(start + along[..., None] * chord, axis=-1)                        # (n-1, M, T)
    closest = ranges.min(axis=0)
    after = relative[-1]                                                                      # (M, T, 2)
    closing = targets.velocity[None, :, :] - end_velocity[:, None, :]
    t_cpa = np.clip(-np.sum(after * closing, axis=-1) / np.maximum(np.sum(closing * closing, axis=-1), 1e-12), 0.0, None)
    closest = np.minimum(closest, np.linalg.norm(after + t_cpa[..., None] * closing, axis=-1))
    return (closest - targets.required_m[None, :]).min(axis=1)


def closest_approach_after_window_s(tracks: Tracks, targets: Targets) -> float:
    """The latest closest approach [s] of any manoeuvre to any target once both sail on
    straight after the window (the window's end when every pair is opening by then)."""
    after = targets.xy[None, :, :] + tracks.times[-1] * targets.velocity[None, :, :] - tracks.positions[-1][:, None, :]
    closing = targets.velocity[None, :, :] - tracks.end_velocity[:, None, :]
    with np.errstate(all="ignore"):
        t_cpa = -np.sum(after * closing, axis=-1) / np.sum(closing * closing, axis=-1)
    t_cpa = t_cpa[np.isfinite(t_cpa)]
    return float(tracks.times[-1] + np.clip(t_cpa.max(initial=0.0), 0.0, AFTER_WINDOW_MAX_S))


def carried_on(tracks: Tracks, until_s: float) -> Tracks:
    """The tracks carried on past the window, both ships straight at their velocities at its end,
    sampled every :data:`AFTER_WINDOW_DT_S` to ``until_s`` [s] (at least one sample more)."""
    end = tracks.times[-1]
    later = end + AFTER_WINDOW_DT_S * np.arange(1, max(1, int(np.ceil((until_s - end) / AFTER_WINDOW_DT_S))) + 1)
    positions = tracks.positions[-1][None] + (later - end)[:, None, None] * tracks.end_velocity[None]
    return Tracks(np.concatenate([tracks.times, later]), np.concatenate([tracks.positions, positions]),
                  np.concatenate([tracks.heading_rad, np.repeat(tracks.heading_rad[-1:], later.size, axis=0)]),
                  tracks.end_velocity)


def judged_sides(tracks: Tracks, targets: Targets, settings: JudgementSettings | None = None) -> np.ndarray:
    """``side_correct`` (M, T) of every manoeuvre for every target, as the ``colregs`` analysis
    judges its recorded tracks (:func:`rhnc.encounters.colregs_judgement.judge_target`): True, False,
    or None where no side rule applies (its class, or a target that started inside R + R_i).

    The onset of risk is t = 0 (the manoeuvre is the action taken for the encounter; in the
    suites' runs that lost the separation the onsets are at t = 0 but one), each target sails the
    straight line, and the own ship's course is the course over ground from its positions
    (:func:`rhnc.cosim.colregs_analysis.ground_velocity`), its heading where it has stopped.
    ``tracks`` should run to the closest approaches (:func:`carried_on`).  A manoeuvre whose
    track is not finite (the model diverged) keeps no side (False).  ``settings``: the analysis's
    thresholds (its defaults, as the suites run it, when None)."""
    settings = settings or JudgementSettings()
    sides = np.full((tracks.positions.shape[1], len(targets.encounter_class)), None, dtype=object)
    target_tracks = [np.column_stack([xy + tracks.times[:, None] * velocity, np.tile(velocity, (tracks.times.size, 1)),
                                      np.zeros(tracks.times.size)]) for xy, velocity in zip(targets.xy, targets.velocity)]
    for m in range(sides.shape[0]):
        own_xy = tracks.positions[:, m]
        if not np.all(np.isfinite(own_xy)):
            sides[m] = False
            continue
        north, east = ground_velocity(tracks.times, own_xy[:, 0], own_xy[:, 1])
        speed = np.hypot(north, east)
        course = np.where(speed < STOPPED_KN * KNOT, tracks.heading_rad[:, m], np.arctan2(east, north))
        for i, (target, kind) in enumerate(zip(target_tracks, targets.encounter_class)):
            onset = None if kind == "none" else 0
            sides[m, i] = judge_target(tracks.times, own_xy, course, speed, target, kind, onset,
                                       float(targets.required_m[i]), settings)["side_correct"]
    return sides


def turned_at_s(times: np.ndarray, velocity: np.ndarray) -> float | None:
    """First time [s] the recorded velocity (n, 2) [m/s] leaves its value at t = 0 by
    :data:`TURN_DEG` or :data:`TURN_KN`; None if it never does."""
    heading = np.degrees(np.arctan2(velocity[:, 1], velocity[:, 0]))
    swing = np.abs(wrap_deg(heading - heading[0]))
    speed_change = np.abs(np.hypot(velocity[:, 0], velocity[:, 1]) - np.hypot(*velocity[0])) / KNOT
    moving = np.hypot(*velocity[0]) > 0.1 * KNOT
    changed = (speed_change > TURN_KN) | ((swing > TURN_DEG) & moving)
    return float(times[np.argmax(changed)]) if changed.any() else None


def _speed_bound_mps(summary: dict) -> float:
    overrides = summary.get("overrides") or {}
    return float(overrides.get("participants.ctrl.options.max_speed_kn", SERVICE_SPEED_KN)) * KNOT


def _parameter_set(summary: dict) -> str:
    check = ((summary.get("participants") or {}).get("ctrl") or {}).get("model_check") or {}
    return check.get("set") or "default"


ACHIEVABLE_KEEPING_SIDES = "achievable keeping every side"
ACHIEVABLE_AGAINST_SIDE = "achievable only against a side rule"
NOT_ACHIEVABLE = "not achievable by a single manoeuvre from the start"
VERDICTS = (ACHIEVABLE_KEEPING_SIDES, ACHIEVABLE_AGAINST_SIDE, NOT_ACHIEVABLE)


def _obstacle_columns(target: dict, fields: range) -> list[str]:
    """The time series' columns of a target's recorded x, y [m] (fields 0, 1) and vx, vy [m/s] (2, 3)."""
    return [f"traffic.obstacles[{target['obstacle']},{j}]" for j in fields]


def _targets_judged(series: pd.DataFrame, outside: list[dict]) -> Targets:
    """The targets that started outside, as the run recorded them at t = 0, with their class."""
    return Targets(np.array([series[_obstacle_columns(target, range(2))].iloc[0].to_numpy(float) for target in outside]),
                   np.array([series[_obstacle_columns(target, range(2, 4))].iloc[0].to_numpy(float)
                             for target in outside]),
                   np.array([target["required_nm"] * NM for target in outside]),
                   tuple(target.get("encounter_class") or "none" for target in outside))


def judge_run(run: Path, parameter_sets: dict[str, ShipParameters]) -> dict | None:
    """The verdict on one run folder, or None when it lost no target that started outside.

    ``best`` is the manoeuvre with the largest least clearance, ``best_keeping_sides`` the one
    among those that keep every side the ``colregs`` analysis judges (:func:`judged_sides`; None
    when none does), ``against_sides`` the targets (obstacle, class) whose side ``best`` breaks."""
    summary = json.loads((run / "summary.json").read_text())
    targets = ((summary.get("analyses") or {}).get("colregs") or {}).get("targets") or []
    outside = [target for target in targets if target.get("started_inside") is False]
    lost = [target for target in outside if target.get("separation_kept") is False]
    if not lost:
        return None
    name = _parameter_set(summary)
    if name not in parameter_sets:
        parameter_sets[name] = load_parameter_set(name)
    params = parameter_sets[name]
    series = pd.read_parquet(run / "timeseries.parquet")
    own0 = series[OWN_STATE].iloc[0].to_numpy(dtype=float)
    judged = _targets_judged(series, outside)
    times = series["time_s"].to_numpy(float)
    turned = {target["obstacle"]: at for target in outside
              if (at := turned_at_s(times, series[_obstacle_columns(target, range(2, 4))].to_numpy(float))) is not None}
    family = manoeuvre_family(params, own0[3])
    with np.errstate(all="ignore"):   # a set out of its range (paper_table2 at speed) diverges
        tracks = sail(own0, family, params, (0.0, _speed_bound_mps(summary)))
        clearance = least_clearance(tracks, judged)
        # judged as the analysis judged the run: to its end, and on to the last closest approach
        until_s = max(float(series["time_s"].iloc[-1]), closest_approach_after_window_s(tracks, judged))
        sides = judged_sides(carried_on(tracks, until_s), judged)
    diverged = ~np.isfinite(clearance)
    clearance[diverged] = -np.inf
    best = int(np.argmax(clearance))
    keeping = np.flatnonzero([all(side is not False for side in row) for row in sides])
    best_keeping = int(keeping[np.argmax(clearance[keeping])]) if keeping.size else None
    keeping_nm = -np.inf if best_keeping is None else float(clearance[best_keeping]) / NM
    outcome = (ACHIEVABLE_KEEPING_SIDES if keeping_nm >= 0.0 else
               ACHIEVABLE_AGAINST_SIDE if clearance[best] >= 0.0 else NOT_ACHIEVABLE)
    # the speed bound is the controller's, not the ship's design speed: say what is left without it
    no_faster = np.flatnonzero(family.surge_force_N <= params.equilibrium_tau(own0[3])[0])
    best_no_faster = int(no_faster[np.argmax(clearance[no_faster])])
    return {"run": run.name, "parameter_set": name,
            "lost": [(target["obstacle"], target.get("encounter_class", ""), target["cpa_nm"]) for target in lost],
            "turned": turned, "best": family.labels[best], "least_clearance_nm": float(clearance[best]) / NM,
            "achievable": bool(clearance[best] >= 0.0), "diverged": int(diverged.sum()), "best_no_faster": family.labels[best_no_faster],
            "least_clearance_no_faster_nm": float(clearance[best_no_faster]) / NM,
            "against_sides": [(target["obstacle"], kind) for target, kind, side in zip(outside, judged.encounter_class, sides[best])
                              if side is False],
            "best_keeping_sides": None if best_keeping is None else family.labels[best_keeping],
            "least_clearance_keeping_sides_nm": keeping_nm, "verdict": outcome}


def situations(folder: Path) -> dict[str, str]:
    """Run id -> ``param:situation`` from the batch's summary.csv (empty without one)."""
    table = folder / "summary.csv"
    if not table.exists():
        return {}
    frame = pd.read_csv(table)
    if "param:situation" not in frame or "run_id" not in frame:
        return {}
    return dict(zip(frame["run_id"].astype(str), frame["param:situation"].astype(str)))


def run_line(batch: str, verdict: dict, situation: str) -> str:
    """One run: the targets lost (with their CPA), the best manoeuvre (and the sides it breaks),
    the best that keeps every side, and the verdict."""
    lost = ", ".join(f"obstacle {index} {kind} CPA {cpa:.2f} nm" for index, kind, cpa in verdict["lost"])
    turned = "".join(f" [obstacle {index} turned at {at:.0f} s]" for index, at in verdict["turned"].items())
    against = ", ".join(f"obstacle {index} {kind}" for index, kind in verdict["against_sides"])
    against = f", against the side of {against}" if against else ""
    keeping = ("none keeps every side" if verdict["best_keeping_sides"] is None else
               f"{verdict['best_keeping_sides']}, {verdict['least_clearance_keeping_sides_nm']:+.3f} nm")
    outcome = verdict["verdict"]
    if verdict["diverged"]:
        outcome += f" ({verdict['diverged']} manoeuvres left out: the model diverged under them)"
    return (f"{batch} {verdict['run']} {situation}".rstrip() + f": lost {lost}; best: {verdict['best']}, "
            f"least clearance {verdict['least_clearance_nm']:+.3f} nm{against}; keeping every side: {keeping}: "
            f"{outcome}{turned} (without speeding up: {verdict['best_no_faster']}, "
            f"{verdict['least_clearance_no_faster_nm']:+.3f} nm)")


def totals_line(name: str, verdicts: list[dict]) -> str:
    """The lost targets (and runs) under each verdict."""
    counts = [[len(verdict["lost"]) for verdict in verdicts if verdict["verdict"] == outcome] for outcome in VERDICTS]
    return (f"{name}: {sum(map(sum, counts))} lost targets in {len(verdicts)} runs; "
            + "; ".join(f"{outcome}: {sum(lost)} ({len(lost)} runs)" for outcome, lost in zip(VERDICTS, counts)))


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folders", nargs="+", type=Path, help="batch result folders (with runs/*/summary.json)")
    args = parser.parse_args(argv)
    parameter_sets: dict[str, ShipParameters] = {}
    every: list[dict] = []
    for folder in args.folders:
        names = situations(folder)
        verdicts = [verdict for run in sorted(folder.glob("runs/*")) if (run / "summary.json").exists()
                    and (verdict := judge_run(run, parameter_sets)) is not None]
        for verdict in verdicts:
            print(run_line(folder.name, verdict, names.get(verdict["run"], "")))  # noqa: T201
        print(totals_line(folder.name, verdicts))  # noqa: T201
        every += verdicts
    if len(args.folders) > 1:
        print(totals_line(f"all {len(args.folders)} batches", every))  # noqa: T201
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
