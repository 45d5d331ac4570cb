"""Reference states from timed path points (Eq. 19).

With the path points p(k) = (x_d, y_d) timed ``delta`` apart::

    psi_d = atan2(ydot_d, xdot_d)
    u_d   = sqrt(xdot_d^2 + ydot_d^2)
    v_d   = 0
    r_d   = (xdot_d yddot_d - ydot_d xddot_d) / (xdot_d^2 + ydot_d^2)

Derivatives are finite differences on the timed path: first derivatives central in the
interior and one-sided (second order when there are three points or more) at the ends
(``np.gradient``); second derivatives the three-point second difference
``(p(k+1) - 2 p(k) + p(k-1)) / delta^2`` in the interior, copied from the neighbour at
the ends; r_d at the two end points is the neighbour's (constant-curvature
extrapolation).  On a circle of radius R sailed at speed v with an angle theta per step, this
gives r_d = (v/R)(1 + theta^2/12 + ...).

Degenerate cases stay finite:

* two points: constant velocity, r_d = 0;
* a straight path: r_d = 0 (to rounding);
* zero speed (the path has stopped at the goal, or u_d below ``still_speed``): the
  heading holds the previous one (or ``initial_heading``, or the next moving one when
  the path starts at rest), and r_d = 0.
"""

from __future__ import annotations

import numpy as np

#: Columns of the ``reference`` port (docs/scenario-format.md).
COLUMNS = ("t", "x", "y", "psi", "u", "v", "r")


def reference_states(points: np.ndarray, delta: float, start_time: float = 0.0,
                     initial_heading: float | None = None, still_speed: float = 1e-3) -> np.ndarray:
    """Turn path points timed ``delta`` apart into reference states (Eq. 19).

    Parameters
    ----------
    points : ndarray (N+1, 2)
        Path points (x north, y east) [m].
    delta : float
        Time between points [s].
    start_time : float
        Time of the first point [s].
    initial_heading : float, optional
        Heading [rad] to hold where the path is at rest before it ever moves.
    still_speed : float
        Speed [m/s] below which the ship counts as at rest.

    Returns
    -------
    ndarray (N+1, 7)
        Columns t [s], x [m], y [m], psi [rad], u [m/s], v [m/s], r [rad/s].
    """
    points = np.asarray(points, dtype=float)
    if points.ndim != 2 or points.shape[1] != 2 or points.shape[0] < 1:
        raise ValueError(f"path points must have shape (N+1, 2), got {points.shape}")
    if not delta > 0:
        raise ValueError("delta must be positive")
    n = points.shape[0]
    out = np.zeros((n, 7))
    out[:, 0] = start_time + delta * np.arange(n)
    out[:, 1:3] = points
    if n == 1:
        out[0, 3] = initial_heading if initial_heading is not None else 0.0
        return out

    velocity = np.gradient(points, delta, axis=0, edge_order=2 if n >= 3 else 1)
    acceleration = np.zeros_like(points)
    if n >= 3:
        acceleration[1:-1] = (points[2:] - 2.0 * points[1:-1] + points[:-2]) / delta ** 2
        acceleration[0] = acceleration[1]
        acceleration[-1] = acceleration[-2]
    speed_sq = velocity[:, 0] ** 2 + velocity[:, 1] ** 2
    speed = np.sqrt(speed_sq)
    moving = speed > still_speed

    heading = np.arctan2(velocity[:, 1], velocity[:, 0])
    if not np.all(moving):
        if np.any(moving):
            hold = heading[np.argmax(moving)] if initial_heading is None else initial_heading
        else:
            hold = initial_heading if initial_heading is not None else 0.0
        for k in range(n):
            if moving[k]:
                hold = heading[k]
            else:
                heading[k] = hold
    yaw_rate = np.zeros(n)
    yaw_rate[moving] = ((velocity[moving, 0] * acceleration[moving, 1]
                         - velocity[moving, 1] * acceleration[moving, 0]) / speed_sq[moving])
    if n >= 3:
        # The one-sided end velocities are less accurate than the central ones: hold the
        # neighbour's yaw rate at the ends (constant-curvature extrapolation).
        yaw_rate[0] = yaw_rate[1] if moving[0] else 0.0
        yaw_rate[-1] = yaw_rate[-2] if moving[-1] else 0.0
    out[:, 3] = heading
    out[:, 4] = np.where(moving, speed, 0.0)
    out[:, 6] = yaw_rate
    return out
