"""Event trigger between the normal and the collision-avoidance state (Eq. 7, generalised).

Eq. 7 sets ET = 1 when an obstacle is within its warning range: eps1 for ships (moving
obstacles), eps2 for static ones.  The paper returns to the normal state when "both
coordinates exceed the obstacle", which only works for a north-east voyage.  Each
obstacle has one of three states:

``clear``      farther than its warning range;
``triggered``  within range and able to close: ET = 1 while any obstacle is triggered;
``passed``     its closest approach is over and the range is opening beyond its domain.

An obstacle "can still close" when, predicted at constant velocity, the range is
shrinking (TCPA > 0) for *either* of two own-ship velocities: the measured one, and the
same speed pointed at the goal (where the ship returns once the trigger lets go).  The
second guards against a release read off a transient: a ship that turns away from a
converging target opens the range for one check and would close it again on its way
back to the route.

Transitions:

* clear -> triggered when the range drops to the warning range or below (Eq. 7);
* triggered -> passed when the obstacle cannot close and the range exceeds its domain
  (its hazard radius, the ``radius`` column, plus ``own_radius_m``); being "behind"
  alone releases nothing;
* passed -> triggered ("closing again") as soon as it can close again while within the
  warning range, or its predicted CPA falls inside the warning range;
* triggered or passed -> clear when beyond the warning range and unable to close.

Hence a target that can still close is never released: a same-speed ship converging
from near abeam, whose range opens for one check while the own ship turns, is re-armed
at the next check instead of being forgotten.

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
        ``"within warning range"``, ``"passed: CPA past and opening beyond the domain"``,
        ``"beyond warning range"`` or ``"closing again"``.
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
    own_radius_m : float
        Own hazard radius R [m], added to each obstacle's radius to form its domain.
    """

    def __init__(self, ship_range_m: float, static_range_m: float, moving_speed: float = 0.1,
                 own_radius_m: float = 0.0) -> None:
        if not (ship_range_m > 0 and static_range_m > 0):
            raise ValueError("warning ranges must be positive")
        if not own_radius_m >= 0:
            raise ValueError("the own hazard radius must not be negative")
        self.own_radius_m = float(own_radius_m)
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
            Goal (x, y) [m]; the own ship's velocity pointed there is the second one an
            obstacle is checked against before it is released.
        obstacles : ndarray (n, 5) or None
            Columns x, y, vx, vy, radius [m, m/s]; radius + ``own_radius_m`` is the domain.

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
        speed = float(np.hypot(*ship_velocity))
        to_goal = np.asarray(goal, dtype=float) - ship
        goal_distance = float(np.hypot(*to_goal))
        homing_velocity = to_goal / goal_distance * speed if goal_distance > 0 else ship_velocity
        pending = []
        for i in range(n):
            offset = obstacles[i, :2] - ship
            distance = float(np.hypot(*offset))
            moving = float(np.hypot(obstacles[i, 2], obstacles[i, 3])) > self.moving_speed
            warning = self.ship_range_m if moving else self.static_range_m
            domain = float(obstacles[i, 4]) + self.own_radius_m
            closing, cpa_inside = False, False
            for own_velocity in (ship_velocity, homing_velocity):
                relative = obstacles[i, 2:4] - own_velocity
                closing_now, cpa_m = _closest_approach(offset, relative)
                closing = closing or closing_now
                cpa_inside = cpa_inside or (closing_now and cpa_m <= warning)
            state = self.states[i]
            new_state, cause = state, ""
            if state == CLEAR:
                if distance <= warning:
                    new_state, cause = TRIGGERED, "within warning range"
            elif distance > warning and not closing:
                new_state, cause = CLEAR, "beyond warning range"
            elif state == TRIGGERED and not closing and distance > domain:
                new_state, cause = PASSED, "passed: CPA past and opening beyond the domain"
            elif state == PASSED and ((closing and distance <= warning) or cpa_inside):
                new_state, cause = TRIGGERED, "closing again"
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


def _closest_approach(offset: np.ndarray, relative_velocity: np.ndarray) -> tuple[bool, float]:
    """(closing, CPA [m]) of an obstacle at ``offset`` moving at ``relative_velocity``.

    Closing means the CPA lies ahead in time (TCPA > 0); the CPA of an opening pair is the
    current range.
    """
    w2 = float(relative_velocity @ relative_velocity)
    if w2 < 1e-12:
        return False, float(np.hypot(*offset))
    tcpa = -float(offset @ relative_velocity) / w2
    if tcpa <= 0.0:
        return False, float(np.hypot(*offset))
    return True, float(np.hypot(*(offset + relative_velocity * tcpa)))
