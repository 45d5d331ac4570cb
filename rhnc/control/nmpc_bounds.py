"""The bounds of one NMPC step's decision variables (:class:`StepBounds`, a part of
:class:`rhnc.control.nmpc.NMPCController`).

The fixed bounds (inputs within their limits, u >= 0, collision slacks >= 0) and the speed
bound with the initial state; the inputs the actuators can reach from the last applied input;
the headings the rules allow (no alteration to port, a readily apparent alteration's floor
or ceiling, the model's own swing); the ramp of a readily apparent reduction of speed; and
the speed asked for while speeding up is held (a reference, not a bound).  What each bound
is for: the module docstring of :mod:`rhnc.control.nmpc`.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np

from rhnc.control.nmpc_actions import PORT_ALLOWANCE_DEG
from rhnc.control.nmpc_alteration import HEADING_TOLERANCE_DEG, REACH_MOMENT_SHARE
from rhnc.control.nmpc_colregs import DomainReport
from rhnc.control.nmpc_settings import NMPCSettings
from rhnc.ship.ship_model import ShipParameters

#: deceleration [m/s²] assumed when a ship measured above the speed bound slows down
SLOW_DOWN_MPS2 = 0.02
#: share of the deceleration full astern force and the hull's drag give at the speed to reach
#: that a reduction of speed asks of the plan (the rest is margin for wind and waves)
SLOWING_SHARE = 0.7
#: share of the acceleration full ahead force less the hull's drag at the top speed give that
#: speeding up asks of the plan and assumes in choosing it (the rest is margin for a turn made
#: with it, wind and waves)
SPEEDING_SHARE = 0.5


class StepBounds:
    """The bound-building steps of the NMPC controller, on the controller's own problem and settings."""

    settings: NMPCSettings
    params: ShipParameters
    problem: Any
    input_scale: np.ndarray
    state_scale: np.ndarray
    speed_scale: float
    speeding_mps2: float
    _bound_templates: tuple[np.ndarray, np.ndarray, np.ndarray] | None
    _rollout: Callable[..., np.ndarray]
    _to_scaled: Callable[[np.ndarray, np.ndarray], np.ndarray]

    def _heading_reach(self, state: np.ndarray, previous_tau: np.ndarray, disturbance) -> tuple[np.ndarray, np.ndarray]:
        """Headings [rad] over the horizon of the prediction model turning from ``state`` to
        starboard and to port with ``REACH_MOMENT_SHARE`` of its yaw moment (reached at the input
        rate limit, if any, from the last applied moment), the surge force held."""
        s = self.settings
        goal = REACH_MOMENT_SHARE * self.params.tau_max[1]
        k = np.arange(1, s.horizon_steps + 1)
        headings = []
        for sign in (1.0, -1.0):
            yaw = np.full(s.horizon_steps, sign * goal)
            if s.tau_rate_max is not None:  # interval j may differ from the last input by j + 1 steps
                start = float(np.clip(previous_tau[1], -self.params.tau_max[1], self.params.tau_max[1]))
                yaw = sign * np.minimum(sign * start + s.tau_rate_max[1] * s.control_interval_s * k, goal)
            inputs = np.column_stack([np.full(s.horizon_steps, previous_tau[0]), yaw])
            headings.append(self._rollout(state, inputs, disturbance)[1:, 2])
        return headings[0], headings[1]

    def _speed_asked(self, report: DomainReport, state: np.ndarray, time_s: float) -> np.ndarray | None:
        """The speed [m/s] each node after the first is asked for at ``time_s`` [s] while speeding up
        is held: up at ``speeding_mps2`` from the speed and time it began at
        (``report.speed_up_since``), or from the measured speed where that asks for more, to the
        speed asked for (within the speed bound), or None.

        From the measured speed alone, the ramp never asked the ship to make up speed it lost:
        a stand-on ship turning 35 deg and speeding up shed 18 -> 16.4 kn in the turn, each
        step's ramp starting lower, and gathered way only once the turn was done, 160 s after
        the decision (a ship overtaking us at 29 kn then passed 0.91 nm off, where the choice had
        counted on the ramp)."""
        goal = report.speed_up_goal_mps
        if goal is None:
            return None
        s = self.settings
        ahead = np.arange(1, s.horizon_steps + 1) * s.control_interval_s
        ramp = state[3] + self.speeding_mps2 * ahead
        if report.speed_up_since is not None:
            since_s, from_mps = report.speed_up_since
            ramp = np.maximum(ramp, from_mps + self.speeding_mps2 * (time_s - since_s + ahead))
        return np.minimum(ramp, max(min(goal, s.max_speed_mps), 0.0))

    def _track_asked(self, ref_scaled: np.ndarray, state: np.ndarray) -> None:
        """While speeding up is held: the reference positions (in place, scaled, from the solve's
        origin at the ship) along the reference's course from the ship at the reference speed,
        the speed asked for, instead of the route's, which the ship's turn has left.

        A route's positions advance at the route's speed along the route: with the ship turned
        35 deg off it, the position error is least at the route's speed times cos 35 deg (18 ->
        14.7 kn), and a plan asked to speed up shed speed in the turn instead (18 -> 16.6 kn,
        the surge force astern for a step), where the choice of the action had counted on it
        gathering way."""
        s = self.settings
        scale = self.state_scale
        speeds = np.concatenate([[math.hypot(state[3], state[4])],
                                 np.hypot(ref_scaled[3, 1:], ref_scaled[4, 1:]) * scale[3]])
        courses = ref_scaled[2, 1:] * scale[2] + np.arctan2(ref_scaled[4, 1:], ref_scaled[3, 1:])
        runs = 0.5 * (speeds[:-1] + speeds[1:]) * s.control_interval_s
        ref_scaled[0, 1:] = np.cumsum(runs * np.cos(courses)) / scale[0]
        ref_scaled[1, 1:] = np.cumsum(runs * np.sin(courses)) / scale[1]

    def _rate_and_heading_bounds(self, lbx, ubx, state, ref_scaled, w_prev, report, floor, ceiling,
                                 starboard_reach=None) -> None:
        """Narrow the bounds (in place) to the inputs the actuators can reach and the headings the
        rules allow (``starboard_reach``: :meth:`_heading_reach`'s turn to starboard)."""
        s = self.settings
        N = s.horizon_steps
        if s.tau_rate_max is not None:   # what the actuators can reach from the last applied input
            reach = (np.arange(1, N + 1)[:, None] * s.control_interval_s * np.asarray(s.tau_rate_max)
                     / self.input_scale)
            index = self.problem.w_index
            lbx[index] = np.maximum(lbx[index], w_prev - reach)
            ubx[index] = np.minimum(ubx[index], w_prev + reach)
        heading_index = self.problem.z_index[1:, 2]
        if report.no_port_turn:  # Rules 14, 15, 17(c): no alteration to port
            allowance = math.radians(PORT_ALLOWANCE_DEG)
            lbx[heading_index] = np.minimum(ref_scaled[2, 1:] - allowance, state[2])
            if starboard_reach is not None:
                # a ship already swinging to port carries on for a while whatever the rudder does:
                # the bound dips below the measured heading only as far as the model itself, turning
                # to starboard, swings on, and comes back with it (at the measured heading a ship
                # that had turned to port for a target inside its domain found no feasible plan when
                # a ship crossing from starboard ruled out port turns, and fell back; a fixed margin
                # below the measured heading moved down with every step and let a ship returning
                # to its track carry on to port past a ship meeting it)
                lbx[heading_index] = np.minimum(lbx[heading_index], starboard_reach - math.radians(HEADING_TOLERANCE_DEG))
        if report.speed_goal_mps is not None:  # a readily apparent reduction of speed (Rule 8(e), 17(b))
            goal = report.speed_goal_mps
            slowing = SLOWING_SHARE * (self.params.tau_max[0] + self.params.equilibrium_tau(goal)[0]) / self.params.m11
            ramp = state[3] - slowing * np.arange(1, N + 1) * s.control_interval_s
            speed_index = self.problem.z_index[1:, 3]
            ubx[speed_index] = np.minimum(ubx[speed_index], np.maximum(goal, ramp) / self.speed_scale)
        if floor is not None:
            lbx[heading_index] = np.maximum(lbx[heading_index], floor)
        if ceiling is not None:
            ubx[heading_index] = np.minimum(ubx[heading_index], ceiling)

    def _bounds(self, state: np.ndarray, origin: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Bounds of the decision variables for a solve from ``state``: the fixed ones (inputs,
        u >= 0, slacks >= 0) copied from templates built once, then the speed bound and the
        initial state."""
        s = self.settings
        problem = self.problem
        if self._bound_templates is None:
            lbx = np.full(problem.size, -np.inf)
            ubx = np.full(problem.size, np.inf)
            lbx[problem.w_index.ravel()] = -1.0
            if s.tau_u_min_N is not None:   # a propeller turning ahead only: no astern thrust to plan with
                lbx[problem.w_index[:, 0]] = max(-1.0, s.tau_u_min_N / self.input_scale[0])
            ubx[problem.w_index.ravel()] = 1.0
            lbx[problem.z_index[1:, 3]] = 0.0  # u >= 0: no sailing backwards
            lbx[problem.sigma_index] = 0.0  # collision slacks
            self._bound_templates = (lbx, ubx, np.arange(1, s.horizon_steps + 1))
        lbx_template, ubx_template, k = self._bound_templates
        lbx, ubx = lbx_template.copy(), ubx_template.copy()
        # u <= max speed; a ship measured faster may take its deceleration limit to get there
        u_max = np.maximum(s.max_speed_mps, state[3] - SLOW_DOWN_MPS2 * k * s.control_interval_s)
        ubx[problem.z_index[1:, 3]] = u_max / self.speed_scale
        z0 = self._to_scaled(state, origin)
        lbx[problem.z_index[0]] = z0
        ubx[problem.z_index[0]] = z0
        return lbx, ubx
