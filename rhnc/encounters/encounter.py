"""Safety and tracking figures of an encounter: separation, clearance, cross-track error.

Separation is measured at the sampled positions and, as a conservative check, along the
straight segments joining them (own ship and obstacle both moving linearly over a sample
interval), so a ship that crosses a circle between two samples is caught.
"""

from __future__ import annotations

import numpy as np

from orchestrator.geometry import NM


def segment_min_distance(p0, p1, q0, q1):
    """Minimum distance between two points moving linearly from p0 to p1 and q0 to q1.

    Arrays of shape (n, 2); returns (n,) distances and the fraction of the interval [0, 1]
    at which each minimum occurs.
    """
    d0 = np.asarray(p0, float) - np.asarray(q0, float)
    d1 = np.asarray(p1, float) - np.asarray(q1, float)
    dd = d1 - d0
    denominator = np.sum(dd * dd, axis=-1)
    s = np.divide(-np.sum(d0 * dd, axis=-1), denominator, out=np.zeros_like(denominator),
                  where=denominator > 1e-18)
    s = np.clip(s, 0.0, 1.0)
    closest = d0 + s[..., None] * dd
    return np.hypot(closest[..., 0], closest[..., 1]), s


def separations(t, x, y, obstacles: np.ndarray, own_radius_m: float = 0.0) -> list[dict]:
    """Per obstacle: minimum centre distance and clearance beyond R + R_i, and when.

    Parameters
    ----------
    t, x, y : (n,) arrays
        Times [s] and own-ship positions [m].
    obstacles : (n, m, 5) array
        Obstacles at each sample: x, y, vx, vy, radius [m, m/s].
    own_radius_m : float
        Own ship's hazard radius R [m].
    """
    t = np.asarray(t, float)
    own = np.column_stack([x, y])
    result = []
    for i in range(obstacles.shape[1]):
        centre = obstacles[:, i, :2]
        radius = obstacles[:, i, 4]
        at_samples = np.hypot(*(own - centre).T)
        between, fraction = segment_min_distance(own[:-1], own[1:], centre[:-1], centre[1:])
        k = int(np.argmin(at_samples))
        chord = float(between.min()) if between.size else float(at_samples[k])
        required = own_radius_m + float(radius.max())
        result.append({
            "obstacle": i,
            "min_distance_nm": float(at_samples[k]) / NM,
            "required_nm": required / NM,
            "min_clearance_nm": (float(at_samples[k]) - required) / NM,
            "time_of_min_s": float(t[k]),
            # straight chords between samples: a lower bound on the true distance when the
            # ship curves around the obstacle (the arc bulges away from it), exact for
            # straight motion; it catches a circle crossed between two samples
            "min_distance_between_samples_nm": min(chord, float(at_samples[k])) / NM,
        })
    return result


def cross_track_error(x, y, reference_x, reference_y, reference_psi):
    """Signed cross-track error [m] of the ship from the reference point and course.

    Positive when the ship is to starboard of the reference course.
    """
    dx = np.asarray(x) - np.asarray(reference_x)
    dy = np.asarray(y) - np.asarray(reference_y)
    return -dx * np.sin(reference_psi) + dy * np.cos(reference_psi)


def time_back_on_track(t, cross_track_m, after_s: float, tolerance_m: float):
    """First time after ``after_s`` from which |cross-track| stays within tolerance, or None."""
    t = np.asarray(t, float)
    outside = (np.abs(cross_track_m) > tolerance_m) & (t >= after_s)
    if not np.any(t >= after_s):
        return None
    if not np.any(outside):
        return float(t[t >= after_s][0])
    last_outside = np.nonzero(outside)[0][-1]
    return float(t[last_outside + 1]) if last_outside + 1 < t.size else None


def reference_at_times(reference: np.ndarray, times) -> np.ndarray:
    """The reference state at each sample's own time.

    ``reference`` is the recorded reference output, shape (samples, N + 1, 7) with columns
    t, x, y, psi, u, v, r: the trajectory last published (held between the publisher's
    steps).  Each sample's state is interpolated in its own trajectory at its time, so a
    reference planned every 4 min, or not republished at the last sample, still gives the
    point the ship should be at then.  Returns (samples, 6).
    """
    reference = np.asarray(reference, dtype=float)
    out = np.empty((reference.shape[0], 6))
    for k, (trajectory, t) in enumerate(zip(reference, np.asarray(times, dtype=float))):
        columns = trajectory[:, 1:].copy()
        columns[:, 2] = np.unwrap(columns[:, 2])
        out[k] = [np.interp(t, trajectory[:, 0], columns[:, j]) for j in range(6)]
    return out
