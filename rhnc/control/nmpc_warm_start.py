"""Warm start and fallback of the NMPC: the previous plan, shifted, and a guess clear of domains.

The previous solution, shifted by the time since it was computed and extended by rolling
the model forward with its last input, is both the next solve's initial guess and the plan
applied when a solve fails or is stopped at its time limit (the "shifted previous plan").
Without a previous plan the guess is the reference itself, and the fallback holds the last
surge force with zero yaw moment.

A solve stopped at its iteration budget leaves an unfinished iterate (not applied: it may
break the constraints).  It is carried over as the next solve's warm start, shifted the same
way, so that successive budgeted steps continue one solve instead of restarting it from
the fallback's plan: a problem that needs 100-150 iterations converges on the second step
instead of failing step after step while the fallback holds the course.
"""

from __future__ import annotations

import math

import numpy as np


class PlanMemory:
    """The last applied plan (SI states (N+1, 6) and inputs (N, 2)) and when it was made.

    Parameters
    ----------
    horizon_steps : int
        N.
    control_interval_s : float
        delta [s].
    rollout : callable
        ``rollout(state (6,), inputs (n, 2)[, disturbance]) -> states (n+1, 6)`` [SI] with the
        prediction model (no disturbance when it is left out).

    Attributes
    ----------
    clearance_relaxed : bool
        The last step found no plan that keeps every clearance (its plan needed the
        collision slacks, or both attempts failed): the next step solves the relaxed
        problem first (see :class:`rhnc.control.nmpc.NMPCController`).
    """

    def __init__(self, horizon_steps: int, control_interval_s: float, rollout) -> None:
        self.horizon_steps = horizon_steps
        self.control_interval_s = control_interval_s
        self.rollout = rollout
        self.states: np.ndarray | None = None
        self.inputs: np.ndarray | None = None
        self.time_s: float | None = None
        self.lam_x: np.ndarray | None = None
        self.lam_g: np.ndarray | None = None
        self.clearance_relaxed = False
        #: an unfinished iterate (time, states, inputs, lam_x, lam_g) newer than the plan, or None
        self.iterate: tuple | None = None

    def reset(self) -> None:
        self.states = self.inputs = self.time_s = self.lam_x = self.lam_g = None
        self.clearance_relaxed = False
        self.iterate = None

    def store(self, time_s: float, states: np.ndarray, inputs: np.ndarray, lam_x: np.ndarray | None = None,
              lam_g: np.ndarray | None = None) -> None:
        """Keep a plan (and the multipliers of the solve that made it, None for a fallback plan).

        It replaces any unfinished iterate kept before it."""
        self.time_s, self.states, self.inputs = float(time_s), np.array(states), np.array(inputs)
        self.lam_x = None if lam_x is None else np.array(lam_x)
        self.lam_g = None if lam_g is None else np.array(lam_g)
        self.iterate = None

    def keep_iterate(self, time_s: float, states: np.ndarray, inputs: np.ndarray, lam_x: np.ndarray | None,
                     lam_g: np.ndarray | None) -> None:
        """Keep a solve's unfinished iterate as the next warm start (never applied, never the fallback).

        Ignored when any of its numbers is not finite; the plan kept by :meth:`store` stays
        the fallback."""
        arrays = [a for a in (states, inputs, lam_x, lam_g) if a is not None]
        if not all(np.all(np.isfinite(a)) for a in arrays):
            self.iterate = None
            return
        self.iterate = (float(time_s), np.array(states), np.array(inputs),
                        None if lam_x is None else np.array(lam_x), None if lam_g is None else np.array(lam_g))

    def shifted_multipliers(self, time_s: float) -> tuple[np.ndarray, np.ndarray] | None:
        """The last solve's multipliers (bounds, constraints) advanced to ``time_s``, or None.

        Both vectors are N stage blocks of equal length (the bounds' vector then the last
        state's): each block takes the one ``shift`` stages later, the blocks past the end
        repeat the last one, the way :meth:`shifted` treats the plan.
        """
        shift = self._shift(time_s)
        if shift is None or self.lam_x is None or self.lam_g is None:
            return None
        return _shift_multipliers(self.lam_x, self.lam_g, self.horizon_steps, shift)

    def dual_guess(self, time_s: float) -> dict:
        """``lam_x0``, ``lam_g0`` of the warm start (:meth:`guess`), shifted, for a solver that
        starts from them ({} if none)."""
        iterate_shift = self._iterate_shift(time_s)
        if iterate_shift is not None:
            _, _, _, lam_x, lam_g = self.iterate
            shifted = (None if lam_x is None or lam_g is None
                       else _shift_multipliers(lam_x, lam_g, self.horizon_steps, iterate_shift))
        else:
            shifted = self.shifted_multipliers(time_s)
        if shifted is None or not (np.all(np.isfinite(shifted[0])) and np.all(np.isfinite(shifted[1]))):
            return {}
        return {"lam_x0": shifted[0], "lam_g0": shifted[1]}

    def _shift(self, time_s: float) -> int | None:
        if self.states is None or self.time_s is None:
            return None
        return self._steps_since(self.time_s, time_s)

    def _steps_since(self, then_s: float, time_s: float) -> int | None:
        shift = int(round((time_s - then_s) / self.control_interval_s))
        return shift if 0 <= shift <= self.horizon_steps else None

    def _iterate_shift(self, time_s: float) -> int | None:
        return None if self.iterate is None else self._steps_since(self.iterate[0], time_s)

    def shifted(self, time_s: float) -> tuple[np.ndarray, np.ndarray] | None:
        """The previous plan advanced to ``time_s``: (states (N+1, 6), inputs (N, 2)) [SI], or None."""
        shift = self._shift(time_s)
        if shift is None or self.states is None or self.inputs is None:
            return None
        return self._advanced(self.states, self.inputs, shift)

    def guess(self, time_s: float) -> tuple[np.ndarray, np.ndarray] | None:
        """The next solve's warm start advanced to ``time_s``: the unfinished iterate of the last
        solve when one is kept (:meth:`keep_iterate`), else the previous plan (:meth:`shifted`)."""
        shift = self._iterate_shift(time_s)
        if shift is None:
            return self.shifted(time_s)
        return self._advanced(self.iterate[1], self.iterate[2], shift)

    def _advanced(self, states: np.ndarray, inputs: np.ndarray, shift: int) -> tuple[np.ndarray, np.ndarray]:
        """A plan made ``shift`` intervals ago, shifted and extended by its last input."""
        N = self.horizon_steps
        inputs = np.vstack([inputs[shift:], np.repeat(inputs[-1:], shift, axis=0)])
        kept = states[shift:]
        tail = self.rollout(kept[-1], inputs[N - shift:]) if shift > 0 else kept[-1:]
        states = np.vstack([kept, tail[1:]]) if shift > 0 else kept
        return states, inputs

    def fallback_inputs(self, time_s: float, previous_tau: np.ndarray, tau_max: np.ndarray) -> np.ndarray:
        """Inputs (N, 2) of the fallback: the shifted plan, else hold the surge force, no yaw moment."""
        shift = self._shift(time_s)
        N = self.horizon_steps
        if shift is not None and shift < N:
            inputs = np.vstack([self.inputs[shift:], np.repeat(self.inputs[-1:], shift, axis=0)])
        else:
            hold = np.array([float(np.asarray(previous_tau)[0]), 0.0])
            inputs = np.repeat(hold[None, :], N, axis=0)
        return np.clip(inputs, -tau_max, tau_max)

    def fallback_plan(self, time_s: float, state: np.ndarray, previous_tau: np.ndarray, tau_max: np.ndarray,
                      disturbance: np.ndarray, steer=None) -> tuple[np.ndarray, np.ndarray]:
        """The plan applied when a solve fails: (states (N+1, 6), inputs (N, 2)) [SI], kept as the next one.

        The inputs of :meth:`fallback_inputs`, rolled out from the measured ``state`` with the
        ``disturbance`` estimate; with no previous plan left and a ``steer(heading_rad,
        yaw_rate_rps) -> tau_r`` given (a held alteration:
        :func:`rhnc.control.nmpc_alteration.alteration_steering`), the last surge force with
        that yaw moment, interval by interval along the prediction.  When the prediction is
        not finite, the states hold the measured one and the memory is cleared (no warm
        start from it).
        """
        shift = self._shift(time_s)
        try:
            with np.errstate(all="ignore"):
                if steer is not None and (shift is None or shift >= self.horizon_steps):
                    states, inputs = self._steered(state, previous_tau, tau_max, disturbance, steer)
                else:
                    inputs = self.fallback_inputs(time_s, previous_tau, tau_max)
                    states = self.rollout(state, inputs, disturbance)
        except RuntimeError:
            inputs = self.fallback_inputs(time_s, previous_tau, tau_max)
            states = np.full((len(inputs) + 1, 6), np.nan)
        # keep the shifted plan (not the failed iterate) as the next warm start / fallback
        if np.all(np.isfinite(states)):
            self.store(time_s, states, inputs)
        else:
            self.reset()
            states = np.vstack([state, np.repeat(state[None, :], len(inputs), axis=0)])
        return states, inputs


    def _steered(self, state, previous_tau, tau_max, disturbance, steer) -> tuple[np.ndarray, np.ndarray]:
        """The last surge force and the yaw moment ``steer`` asks for at each interval's start."""
        states = [np.asarray(state, dtype=float)]
        inputs = np.empty((self.horizon_steps, 2))
        for k in range(self.horizon_steps):
            inputs[k] = np.clip([float(np.asarray(previous_tau)[0]), steer(states[-1][2], states[-1][5])],
                                -tau_max, tau_max)
            states.append(self.rollout(states[-1], inputs[k:k + 1], disturbance)[-1])
        return np.array(states), inputs


def _shift_multipliers(lam_x: np.ndarray, lam_g: np.ndarray, horizon_steps: int,
                       shift: int) -> tuple[np.ndarray, np.ndarray]:
    N = horizon_steps
    stride_g = len(lam_g) // N
    stride_x = (len(lam_x) - 6) // N
    return (np.r_[_shift_blocks(lam_x[:N * stride_x], stride_x, shift), lam_x[N * stride_x:]],
            _shift_blocks(lam_g, stride_g, shift))


def _shift_blocks(values: np.ndarray, stride: int, shift: int) -> np.ndarray:
    blocks = values.reshape(-1, stride)
    kept = blocks[shift:]
    return np.vstack([kept, np.repeat(blocks[-1:], len(blocks) - len(kept), axis=0)]).ravel()


def push_guess_clear(z_guess: np.ndarray, slots: np.ndarray, ref_scaled: np.ndarray, control_interval_s: float) -> None:
    """Move guessed positions that lie inside an active domain sideways out of it (in place).

    ``z_guess`` holds the scaled states (N+1, 6); ``slots`` the obstacle parameters of
    :mod:`rhnc.control.nmpc_problem`.  The shift is perpendicular to the reference course, to the
    side of the domain's centre the node already lies on, and to starboard when it lies
    (nearly) on the centre line.  A straight reference through the middle of an obstacle
    is a symmetric problem whose "stop in front of it" plan is a stationary point;
    starting the solver from a detour picks a side, and the local solver keeps it.  A
    domain whose centre is moved to the target's starboard (head-on, crossing as the
    give-way ship) always pushes to starboard: that is the alteration Rules 14-16 ask for
    (port to port; astern of a ship crossing from starboard).
    """
    times = control_interval_s * np.arange(1, len(z_guess))
    nodes = z_guess[1:]  # a view: the nodes after the measured one, moved in place
    for i in np.flatnonzero(slots[9] > 0.5):
        cx, cy, vx, vy, ox, oy, rho, growth, inflation, _ = slots[:, i].tolist()
        give_way = ox * -vy + oy * vx > 1e-9 * rho * max(abs(vx) + abs(vy), 1e-12)
        # every node at once; a later slot sees the nodes the earlier ones moved
        r_push = 1.1 * (rho + growth * times) * math.sqrt(1.0 + inflation)
        dx = nodes[:, 0] - (cx + vx * times + ox)
        dy = nodes[:, 1] - (cy + vy * times + oy)
        inside = np.flatnonzero(dx * dx + dy * dy < r_push * r_push)
        if not inside.size:
            continue
        dx, dy, r_push = dx[inside], dy[inside], r_push[inside]
        course = ref_scaled[2, 1:][inside]
        along_x, along_y = np.cos(course), np.sin(course)
        starboard_x, starboard_y = -along_y, along_x
        along = dx * along_x + dy * along_y
        lateral = dx * starboard_x + dy * starboard_y
        side = np.where((lateral < -0.1 * rho) & (not give_way), -1.0, 1.0)
        new_lateral = side * np.sqrt(np.maximum(r_push * r_push - along * along, 0.0))
        nodes[inside, 0] += (new_lateral - lateral) * starboard_x
        nodes[inside, 1] += (new_lateral - lateral) * starboard_y
