"""Estimation errors of a target tracker against the true tracks: RMS errors, coverage, track breaks.

Works on recorded arrays alone.  At every sample each true target keeps the confirmed
track row it was matched to while that row stays valid and within ``gate_m``; a target
without one is matched to the nearest valid row within the gate that no other target
keeps (so two ships passing close to each other do not swap tracks in the figures when
the tracker kept them apart).  Over the matched samples the position and velocity errors
give RMS and maximum figures.  A *track break* is a matched target that loses its match,
or whose match moves to another row (a new track for the same ship), after it was first
tracked.
"""

from __future__ import annotations

import numpy as np

from orchestrator.geometry import NM


def tracking_errors(t, truth, estimates, valid, gate_m: float = 0.5 * NM) -> dict:
    """Per-target and overall estimation figures.

    Parameters
    ----------
    t : (k,) array
        Sample times [s].
    truth : (k, n, >=4) array
        True targets: x, y [m], vx, vy [m/s], ...
    estimates : (k, m, >=4) array
        Published track rows (NaN where a row did not exist yet).
    valid : (k, m) array
        1 where the row held a confirmed track.
    gate_m : float
        Largest distance at which a track counts as the target's [m].
    """
    t = np.asarray(t, dtype=float)
    truth = np.asarray(truth, dtype=float)
    estimates = np.asarray(estimates, dtype=float).reshape(t.size, -1, truth.shape[-1] if truth.ndim == 3 else 5)
    valid = np.nan_to_num(np.asarray(valid, dtype=float).reshape(t.size, -1)) > 0.5
    n = truth.shape[1]
    rows_of = np.full((n, t.size), -1)
    position_errors = np.full((n, t.size), np.nan)
    velocity_errors = np.full((n, t.size), np.nan)
    previous = np.full(n, -1)
    for k in range(t.size):
        current, distance = _match_sample(truth[k], estimates[k], valid[k, :estimates.shape[1]], previous, gate_m)
        for i in range(n):
            j = int(current[i])
            if j >= 0:
                rows_of[i, k] = j
                position_errors[i, k] = distance[(i, j)]
                velocity_errors[i, k] = float(np.hypot(*(estimates[k, j, 2:4] - truth[k, i, 2:4])))
        previous = current
    targets = [_target_figures(i, t, rows_of[i], position_errors[i], velocity_errors[i]) for i in range(n)]
    tracked = [entry for entry in targets if entry["position_rms_m"] is not None]

    def largest(key: str) -> float | None:
        return max((float(entry[key]) for entry in tracked), default=None)

    return {
        "targets": targets,
        "targets_never_tracked": sum(1 for entry in targets if entry["position_rms_m"] is None),
        "position_rms_max_m": largest("position_rms_m"),
        "position_error_max_m": largest("position_max_m"),
        "velocity_rms_max_mps": largest("velocity_rms_mps"),
        "track_breaks": sum(e["track_breaks"] for e in targets),
        "coverage_min": min((float(entry["coverage"]) for entry in tracked), default=None),
    }


def _match_sample(truth, estimates, valid, previous, gate_m: float):
    """Rows matched to the targets at one sample, and the distances [m] of every target-row pair.

    A target keeps its previous row while that row is valid and within the gate; the others,
    nearest first, take the nearest valid row within the gate that no other target holds.
    """
    n = truth.shape[0]
    available = set(np.nonzero(valid)[0].tolist())
    distance = {(i, j): float(np.hypot(*(estimates[j, :2] - truth[i, :2]))) for i in range(n) for j in available}
    current = np.full(n, -1)
    for i in range(n):  # a target keeps its track while it can
        j = int(previous[i])
        if j in available and distance[(i, j)] <= gate_m:
            current[i] = j
    available -= set(current[current >= 0].tolist())
    for i in np.argsort([min((distance[(i, j)] for j in available), default=np.inf) for i in range(n)]):
        if current[i] >= 0 or not available:
            continue
        j = min(available, key=lambda row: distance[(int(i), row)])
        if distance[(int(i), j)] <= gate_m:
            current[i] = j
            available.discard(j)
    return current, distance


def _target_figures(i: int, t, rows, position_error, velocity_error) -> dict:
    """Coverage, RMS and largest errors and track breaks of target ``i`` (None where never tracked)."""
    matched = rows >= 0
    entry = {"target": i, "first_tracked_s": float(t[matched][0]) if matched.any() else None,
             "coverage": None, "position_rms_m": None, "position_max_m": None, "velocity_rms_mps": None,
             "track_breaks": 0}
    if matched.any():
        first = int(np.argmax(matched))
        after = rows[first:]
        entry["coverage"] = float(np.mean(after >= 0))
        entry["position_rms_m"] = float(np.sqrt(np.nanmean(position_error ** 2)))
        entry["position_max_m"] = float(np.nanmax(position_error))
        entry["velocity_rms_mps"] = float(np.sqrt(np.nanmean(velocity_error ** 2)))
        changes = (after[1:] != after[:-1]) & (after[:-1] >= 0)
        entry["track_breaks"] = int(np.sum(changes))
    return entry
