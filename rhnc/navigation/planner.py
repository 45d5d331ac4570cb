"""Local path planning by fixed-step descent of the superposed field (Algorithm 1).

From the start point the planner takes N_L steps of length ``alpha = v_s delta`` along
the negative normalised gradient of U (or of G alone in the collision-avoidance state),
``p(k+1) = p(k) - alpha grad(p) / |grad(p)|``, giving N_L + 1 points.  The gradient is
``np.gradient`` of the field at the grid nodes, interpolated bilinearly to the point
(:meth:`rhnc.navigation.fields.SuperpositionField.gradient_at`), so the path is not snapped to the
grid.

Four guards the paper does not spell out (and a fifth on request, ``final_approach``: the
goal within the horizon is approached in a straight line):

* **Goal.**  When the goal is within one step, the step ends on the goal and the
  remaining points stay there (the reference then stops: zero speed), instead of
  oscillating about it.
* **Flat field.**  Where ``|grad| < flat_gradient_per_m`` (default 1e-9 per metre, i.e.
  U changing by less than 1e-6 over a kilometre, against ~1e-4 per metre for the
  guidance term at k3 = 16 on a 100 nm map), the step goes along the direct bearing to
  the goal.
* **Local minimum.**  Fixed-step descent into a local minimum of U (in front of a
  high-cost patch placed symmetrically on the line, say) would turn back and forth
  there for ever.  A step that turns by more than 120 degrees from the previous one
  (no ship turns so in one interval) marks the path as trapped; that step and the
  rest of this plan descend G alone, which has no minimum but the goal.  The next
  planning instant starts afresh.
* **Map border.**  The path never leaves the map.  A start outside it is moved to the
  nearest point on the border.  A step that would cross the border is projected onto
  it: the outward component of the step direction is removed and the step keeps its
  length along the border (sliding rather than stopping); in a corner, where nothing is
  left, the step goes along the bearing to the goal, itself projected.  A final clip
  guards rounding.
"""

from __future__ import annotations

import dataclasses
import logging
from collections.abc import Sequence

import numpy as np

from rhnc.navigation.fields import SuperpositionField

log = logging.getLogger(__name__)


@dataclasses.dataclass(frozen=True)
class PlannedPath:
    """Result of one planning instant.

    Attributes
    ----------
    points : ndarray (N_L + 1, 2)
        Path points (x north, y east) [m]; row 0 is the start.
    reached_goal : bool
        The path ends on the goal.
    flat_steps : int
        Steps that fell back to the direct bearing (flat gradient).
    border_steps : int
        Steps projected onto the map border.
    trapped_at : int or None
        Index of the step at which a local minimum of U was detected (the rest of the
        path descends G alone), or None.
    """

    points: np.ndarray
    reached_goal: bool
    flat_steps: int
    border_steps: int
    trapped_at: int | None = None


def _project_direction(position: np.ndarray, direction: np.ndarray, step: float,
                       extent: tuple[float, float, float, float]) -> np.ndarray:
    """Remove the components of ``direction`` that would carry a step out of the map."""
    lows = (extent[0], extent[2])
    highs = (extent[1], extent[3])
    projected = direction.copy()
    for axis in range(2):
        target = position[axis] + step * projected[axis]
        if target < lows[axis] or target > highs[axis]:
            projected[axis] = 0.0
    return projected


def plan_local_path(field: SuperpositionField, start: Sequence[float], step_length: float,
                    horizon_steps: int, avoidance: bool = False,
                    flat_gradient_per_m: float = 1e-9, reversal_cosine: float = -0.5,
                    final_approach: bool = False) -> PlannedPath:
    """Plan N_L steps down the field (Algorithm 1).

    Parameters
    ----------
    field : SuperpositionField
        Already updated for this start point and speed.
    start : (float, float)
        Start point (x north, y east) [m].
    step_length : float
        alpha = v_s delta [m].
    horizon_steps : int
        N_L.
    avoidance : bool
        Collision-avoidance state (ET = 1): descend G alone.
    flat_gradient_per_m : float
        Gradient magnitude [1/m] below which the direct bearing to the goal is used.
    reversal_cosine : float
        A step whose direction has a cosine below this with the previous step's marks a
        local minimum (default -0.5: a turn of more than 120 degrees).
    final_approach : bool
        When the goal lies within the horizon (``horizon_steps * step_length``) of the
        start, the path runs straight to it (near the goal the bearing that the energy
        fields assume swings, and the descent would run along the map edge).

    Returns
    -------
    PlannedPath
    """
    if horizon_steps < 1:
        raise ValueError("horizon_steps must be at least 1")
    if not step_length > 0:
        raise ValueError("step_length must be positive")
    extent = field.extent
    low = np.array([extent[0], extent[2]])
    high = np.array([extent[1], extent[3]])
    goal = np.clip(np.array(field.goal, dtype=float), low, high)
    position = np.array(start, dtype=float)
    if np.any(position < low) or np.any(position > high):
        log.warning("planning start (%.0f, %.0f) m lies outside the map; moved onto its border",
                    position[0], position[1])
        position = np.clip(position, low, high)
    points = np.empty((horizon_steps + 1, 2))
    points[0] = position
    to_goal = float(np.hypot(*(goal - position)))
    if final_approach and to_goal <= horizon_steps * step_length:
        along = np.minimum(step_length * np.arange(horizon_steps + 1), to_goal)
        direction = (goal - position) / to_goal if to_goal > 0 else np.zeros(2)
        points = position + along[:, None] * direction
        points[along >= to_goal] = goal
        return PlannedPath(points=points, reached_goal=True, flat_steps=0, border_steps=0)
    flat_steps = border_steps = 0
    reached = False
    trapped_at = None
    previous = None
    for k in range(horizon_steps):
        to_goal = goal - position
        distance = float(np.hypot(*to_goal))
        if reached or distance <= step_length:
            position = goal.copy()
            reached = True
            points[k + 1] = position
            continue
        unit_to_goal = to_goal / distance
        guidance_only = avoidance or trapped_at is not None
        direction, flat, border = _step_direction(field, position, unit_to_goal, guidance_only,
                                                  flat_gradient_per_m, step_length, extent)
        if previous is not None and not guidance_only and float(direction @ previous) < reversal_cosine:
            trapped_at = k
            log.info("local minimum of U at (%.0f, %.0f) m, step %d: descending G alone", *position, k)
            direction, flat, border = _step_direction(field, position, unit_to_goal, True,
                                                      flat_gradient_per_m, step_length, extent)
        flat_steps += flat
        border_steps += border
        position = np.clip(position + step_length * direction, low, high)
        points[k + 1] = position
        previous = direction
    return PlannedPath(points=points, reached_goal=reached, flat_steps=flat_steps, border_steps=border_steps,
                       trapped_at=trapped_at)


def _step_direction(field: SuperpositionField, position: np.ndarray, unit_to_goal: np.ndarray,
                    guidance_only: bool, flat_gradient_per_m: float, step_length: float,
                    extent: tuple[float, float, float, float]) -> tuple[np.ndarray, bool, bool]:
    """Unit step direction at ``position``: down the gradient (or to the goal where flat),
    projected onto the map border.  Returns (direction, was flat, was projected)."""
    gx, gy = field.gradient_at(position[0], position[1], guidance_only)
    magnitude = float(np.hypot(gx, gy))
    flat = magnitude < flat_gradient_per_m
    direction = unit_to_goal if flat else -np.array([gx, gy]) / magnitude
    projected = _project_direction(position, direction, step_length, extent)
    border = not np.array_equal(projected, direction)
    if border:
        norm = float(np.hypot(*projected))
        if norm < 1e-9:
            projected = _project_direction(position, unit_to_goal, step_length, extent)
            norm = float(np.hypot(*projected))
        direction = projected / norm if norm >= 1e-9 else np.zeros(2)
    return direction, flat, border
