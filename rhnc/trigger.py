"""Event trigger between the normal and the collision-avoidance state (Eq. 7, generalised).

Eq. 7 sets ET = 1 when an obstacle is within its warning range: eps1 for ships (moving
obstacles), eps2 for static ones.  The paper returns to the normal state when "both
coordinates exceed the obstacle", which only works for a north-east voyage; spec
section 4 asks for a generalisation.  Each obstacle has one of three states:

``clear``      farther than its warning range;
``triggered``  within range and not yet passed: ET = 1 while any obstacle is triggered;
``passed``     within range but behind the ship relative to the goal direction
               ((p_obs - p_ship) . (goal - p_ship) < 0) with the range opening
               (range rate > 0 from the relative velocity).

Transitions: clear -> triggered when the range drops to the warning range or below;
triggered -> passed when behind and opening; triggered or passed -> clear when the range
exceeds the warning range again; passed -> triggered when the obstacle is ahead again
and closing (the ship turned back towards it).  Hence ET returns to 0 when every
triggering obstacle is behind and opening, or out of range.

An obstacle counts as a ship when its speed over ground exceeds ``moving_speed`` (default
0.1 m/s).  Obstacles are identified by their row in the ``obstacles`` array
(docs/scenario-format.md); the row order must therefore be stable over a run.  Rows
that appear start ``clear``.

Every obstacle transition is logged (``logging``, INFO) and kept as a
:class:`TriggerTransition` in :attr:`EventTrigger.transitions`.
"""

from __future__ import annotations

import dataclasses
import logging
from collections.abc import Sequence

import numpy as np

log = logging.getLogger(__name__)

CLEAR, TRIGGERED, PASSED = "clear", "triggered", "passed"


@dataclasses.dataclass(frozen=True)
class TriggerTransition:
    """One change of an obstacle's state.

    Attributes
    ----------
    time : float
        [s].
    obstacle : int
        Row in the ``obstacles`` array.
    kind : str
        ``"ship"`` or ``"static"``.
    range_m : float
        Distance between the ship and the obstacle's centre [m].
    cause : str
        ``"within warning range"``, ``"passed: behind and opening"``,
        ``"beyond warning range"`` or ``"ahead and closing again"``.
    state : str
        The obstacle's new state.
    et : float
        ET after the update that made this transition.
    """

    time: float
    obstacle: int
    kind: str
    range_m: float
    cause: str
    state: str
    et: float

    def as_dict(self) -> dict:
        return dataclasses.asdict(self)


class EventTrigger:
    """ET of Eq. 7 with per-obstacle warning ranges and the generalised release.

    Parameters
    ----------
    ship_range_m : float
        eps1, warning range for moving obstacles [m].
    static_range_m : float
        eps2, warning range for static obstacles [m].
    moving_speed : float
        Speed [m/s] above which an obstacle is a ship.
    """

    def __init__(self, ship_range_m: float, static_range_m: float, moving_speed: float = 0.1) -> None:
        if not (ship_range_m > 0 and static_range_m > 0):
            raise ValueError("warning ranges must be positive")
        self.ship_range_m = float(ship_range_m)
        self.static_range_m = float(static_range_m)
        self.moving_speed = float(moving_speed)
        self.states: list[str] = []
        self.transitions: list[TriggerTransition] = []
        self.et = 0.0

    def update(self, time: float, position: Sequence[float], velocity: Sequence[float],
               goal: Sequence[float], obstacles: np.ndarray | None) -> float:
        """Update ET from the ship's state and the obstacles at ``time``.

        Parameters
        ----------
        time : float
            [s].
        position, velocity : (float, float)
            Ship position (x, y) [m] and velocity over ground (north, east) [m/s].
        goal : (float, float)
            Goal (x, y) [m]; defines "behind".
        obstacles : ndarray (n, 5) or None
            Columns x, y, vx, vy, radius [m, m/s] (radius unused here).

        Returns
        -------
        float
            ET: 1.0 collision-avoidance state, 0.0 normal.
        """
        obstacles = np.zeros((0, 5)) if obstacles is None else np.atleast_2d(np.asarray(obstacles, dtype=float))
        if obstacles.size == 0:
            obstacles = np.zeros((0, 5))
        n = obstacles.shape[0]
        if n > len(self.states):
            self.states.extend([CLEAR] * (n - len(self.states)))
        elif n < len(self.states):
            del self.states[n:]
        ship = np.asarray(position, dtype=float)
        ship_velocity = np.asarray(velocity, dtype=float)
        to_goal = np.asarray(goal, dtype=float) - ship
        pending = []
        for i in range(n):
            offset = obstacles[i, :2] - ship
            distance = float(np.hypot(*offset))
            moving = float(np.hypot(obstacles[i, 2], obstacles[i, 3])) > self.moving_speed
            warning = self.ship_range_m if moving else self.static_range_m
            range_rate = float(offset @ (obstacles[i, 2:4] - ship_velocity)) / max(distance, 1e-9)
            behind = float(offset @ to_goal) < 0.0
            state = self.states[i]
            new_state, cause = state, ""
            if distance > warning:
                if state != CLEAR:
                    new_state, cause = CLEAR, "beyond warning range"
            elif state == CLEAR:
                new_state, cause = TRIGGERED, "within warning range"
            elif state == TRIGGERED and behind and range_rate > 0.0:
                new_state, cause = PASSED, "passed: behind and opening"
            elif state == PASSED and not behind and range_rate < 0.0:
                new_state, cause = TRIGGERED, "ahead and closing again"
            if new_state != state:
                self.states[i] = new_state
                pending.append((i, "ship" if moving else "static", distance, cause, new_state))
        self.et = 1.0 if TRIGGERED in self.states else 0.0
        for i, kind, distance, cause, new_state in pending:
            record = TriggerTransition(time=float(time), obstacle=i, kind=kind, range_m=distance,
                                       cause=cause, state=new_state, et=self.et)
            self.transitions.append(record)
            log.info("t=%.0f s: obstacle %d (%s) at %.0f m: %s -> %s, ET=%.0f",
                     record.time, i, kind, distance, cause, new_state, self.et)
        return self.et
