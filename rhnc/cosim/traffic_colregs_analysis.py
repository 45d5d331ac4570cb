"""The ``traffic_colregs`` analysis: every target judged by the rules of the road from its own bridge.

With targets that act themselves (``behaviour = "rules"``, or several autonomous ships),
the own ship's ``colregs`` analysis says whether *it* kept the rules; this one runs the same
judgement (:func:`rhnc.cosim.colregs_analysis.judge_encounters`) with each target as the
own ship and the own ship (hazard radius: the target's R_i) and the other targets as its
obstacles.  Per pair of own ship and target it reports a **mutual turn into each other**:
both ships manoeuvred after the onset of risk and at least one of them altered to the
side the rules forbid it (``side_correct`` false: a turn to port in a head-on, crossing
ahead as give-way ship, a turn to port as stand-on ship in a crossing).
"""

from __future__ import annotations

import numpy as np

from orchestrator.analyses import array_output
from orchestrator.errors import ToolchainError
from rhnc.cosim.colregs_analysis import judge_encounters, ground_velocity
from rhnc.cosim.obstacle_ports import true_obstacles_column
from rhnc.cosim.plant import own_radius_m, plant_name


def judge_traffic(t, own_x, own_y, targets: np.ndarray, own_radius: float = 0.0) -> dict:
    """Each target's own judgement and the mutual turns (module docstring).

    Parameters
    ----------
    t, own_x, own_y : (n,) arrays
        Times [s] and the own ship's positions [m].
    targets : (n, m, 5) array
        True targets: x, y, vx, vy, radius [m, m/s].
    own_radius : float
        The own ship's hazard radius R [m].
    """
    t = np.asarray(t, dtype=float)
    targets = np.asarray(targets, dtype=float).reshape(t.size, -1, 5)
    vx, vy = ground_velocity(t, own_x, own_y)
    own_rows = np.stack([own_x, own_y, vx, vy, np.zeros_like(vx)], axis=1)
    own_view = judge_encounters(t, own_x, own_y, None, targets, own_radius)
    result = []
    mutual = 0
    for i in range(targets.shape[1]):
        ship = own_rows.copy()
        ship[:, 4] = targets[:, i, 4] + own_radius
        others = np.concatenate([ship[:, None, :], np.delete(targets, i, axis=1)], axis=1)
        others[:, 1:, 4] = np.maximum(others[:, 1:, 4], targets[:, i, 4][:, None])
        view = judge_encounters(t, targets[:, i, 0], targets[:, i, 1], None, others, 0.0)
        against_own = view["targets"][0]
        own_entry = own_view["targets"][i]
        both_turned = against_own["manoeuvre_time_s"] is not None and own_entry["manoeuvre_time_s"] is not None
        wrong_side = against_own["side_correct"] is False or own_entry["side_correct"] is False
        turned_into = bool(both_turned and wrong_side)
        mutual += turned_into
        result.append({"target": i, "verdict": view["verdict"], "side_correct": view["side_correct"],
                       "separation_kept": view["separation_kept"], "rules_failed": view["rules_failed"],
                       "class_against_own_ship": against_own["encounter_class"],
                       "manoeuvre_side": against_own["manoeuvre_side"], "own_manoeuvre_side":
                       own_entry["manoeuvre_side"], "mutual_turn_into_each_other": turned_into})
    sides = [entry["side_correct"] for entry in result if entry["side_correct"] is not None]
    return {"targets": result, "mutual_turns_into_each_other": mutual,
            "targets_side_correct": None if not sides else bool(all(sides)),
            "targets_separation_kept": bool(all(entry["separation_kept"] for entry in result)),
            "targets_failed": sum(1 for entry in result if entry["verdict"] == "fail")}


def traffic_colregs_analysis(frame, scenario, cosim, out_dir) -> dict:
    """``judge_traffic`` on a run's recorded own ship and true targets."""
    column = true_obstacles_column(scenario, cosim)
    if column is None:
        raise ToolchainError("the traffic_colregs analysis needs targets feeding an 'obstacles' input")
    targets_column = column.split(".")[0] + ".targets"
    if not any(c.startswith(targets_column + "[") for c in frame.columns):
        raise ToolchainError(f"no recorded '{targets_column}' (the traffic participant's targets)")
    plant = plant_name(cosim)
    return judge_traffic(frame["time_s"].to_numpy(), frame[f"{plant}.x"].to_numpy(), frame[f"{plant}.y"].to_numpy(),
                         array_output(frame, targets_column), own_radius_m(cosim))
