"""Trajectory-tracking NMPC with collision constraints (spec section 5, paper Eq. 20-23).

The optimal-control problem is built once as a CasADi ``nlpsol`` with parameters (reference,
previous input, terminal weight, obstacles) and re-solved every control interval with new
parameter values and a warm start from the shifted previous solution.

Scaling (so that the paper's Q = diag(0.1, 0.1, 10, 1, 1, 1), R = R1 = diag(0.01, 0.01)
keep a meaning at full scale): errors and inputs are made dimensionless the way naval
architects do with the "prime" system,

- positions in ship lengths ``L`` (``lpp`` of the parameter set, 230 m for the KCS),
- heading in radians, wrapped through ``2 (1 - cos e)`` (= e² near 0, no minimum at pi),
- surge and sway speed in m/s (``speed_scale_mps`` = 1 m/s, about 2 kn),
- yaw rate in units of (1 m/s) / L, i.e. as the difference of the bow's and the stern's
  transverse speeds in m/s,
- forces and moments in units of their bounds ``tau_max``.

So a cross-track error of one ship length costs as much (0.1) as a heading error of
0.1 rad, a speed error of 1 m/s costs 1 and a full-scale force step 0.01.  The speed unit
is deliberately not the service speed: with speeds in units of U, stopping dead costs 1
per step against 10 for a 60 deg course alteration, and the NMPC with the paper's Q then
stops in front of a 2 nm obstacle on its track instead of passing it (seen in trials).
The decision variables are the same scaled quantities, with positions measured from the
ship's position at the solve, which keeps the solver's numbers of order one.

Terminal weight P: the solution of the discrete algebraic Riccati equation of the scaled
model linearised about straight motion at the reference speed (python-control ``dare``,
Q and R as above), expressed in the reference's along-/cross-track frame and rotated to
the reference heading at the horizon's end; cached per reference speed (0.25 m/s bins).

Below ``MIN_TERMINAL_SPEED_MPS`` (a reference that stops at its destination) P is taken
at that speed: about zero speed the linearised model is not stabilisable.

Collision constraints (only while ET = 1): for every obstacle i and at every RK4 substep
of every interval (not only at the shooting nodes)

    |p - c_i(t)|² / (R + R_i)² >= 1 + (d_s / (2 (R + R_i)))²,

with c_i(t) the obstacle predicted at constant velocity and d_s the distance that own ship
and obstacle can close in one substep.  The right-hand side is the radius inflated so that
the straight chord between two admissible substep points cannot enter the circle
``R + R_i``.  Obstacle slots are fixed (``max_obstacles``); unused or switched-off slots
get an "active" parameter of 0, which turns their constraint into ``1 >= 0``.

When the problem with these hard constraints has no solution (an obstacle noticed too
late), the step is solved again with one slack per stage relaxing them at a heavy L1 + L2
cost (``collision_slack_weight``): the plan that violates the clearance least, reported in
the telemetry as ``collision_slack``.

Failures: when neither attempt reports success, the controller applies the previous plan
shifted by one interval (its next input and predicted states) and flags the step; when no
previous plan is left it holds the previous surge force with zero yaw moment.
"""

from __future__ import annotations

import dataclasses
import logging
import math
import time
from collections.abc import Sequence

import casadi as ca
import numpy as np

from orchestrator.interrupts import stop_requested
from rhnc.ship_model import ShipParameters, rk4_function

LOG = logging.getLogger(__name__)

KNOT = 1852.0 / 3600.0
#: Parameters per obstacle slot: cx, cy [L], vx, vy [L/s], (R + R_i) [L], inflation [-], active.
OBSTACLE_FIELDS = 7
#: collision slack (scaled clearance, |p - c|^2 / (R + R_i)^2 - 1) below which a plan counts as
#: keeping R + R_i: the solver's tolerance, about 0.05 % of the distance
SLACK_TOLERANCE = 1e-3
#: lowest speed [m/s] about which the terminal weight P is linearised
MIN_TERMINAL_SPEED_MPS = 1.0

SOLVERS = ("ipopt", "fatrop", "sqpmethod")


@dataclasses.dataclass(frozen=True)
class NMPCSettings:
    """Settings of the NMPC (one object instead of many arguments).

    Attributes
    ----------
    horizon_steps : int
        N_c, number of control intervals in the horizon.
    control_interval_s : float
        delta, length of one control interval [s]; the input is held over it.
    substeps : int
        RK4 steps per control interval, also the points where collisions are checked.
    solver : str
        ``"ipopt"``, ``"fatrop"`` or ``"sqpmethod"``.
    max_iterations : int
        Iteration limit of the NLP solver.
    max_obstacles : int
        Obstacle slots in the problem; the nearest ones are used when more are given.
    own_radius_m : float
        R, hazard radius of own ship [m].
    q, r, r_rate : tuple of float
        Diagonals of Q (6), R (2) and R1 (2) on the scaled quantities (module docstring).
    length_scale_m : float or None
        L for positions and yaw rate; None takes ``lpp`` of the parameter set (else 230 m).
    speed_scale_mps : float
        U for surge and sway speed [m/s].
    terminal_weight : bool
        Use the DARE terminal weight P (else P = Q).
    collision_slack_weight : float or None
        Soft collision constraints as the second attempt: one slack sigma_k >= 0 per stage
        relaxes that stage's clearance constraints, at the cost ``w (sigma_k + sigma_k^2)``.
        Each step first solves the hard problem (the slacks fixed at zero by their bounds,
        the same NLP); only when that fails (an obstacle noticed too late, a target that
        closes faster than the ship can turn) it re-solves with the slacks free and returns
        the plan that violates the clearance least, instead of a fallback that ignores the
        obstacle.  (The L1 term is an exact penalty: were the hard problem feasible, the
        soft one would give the same plan.)  None: no slacks and no second attempt.
    """

    horizon_steps: int = 15
    control_interval_s: float = 20.0
    substeps: int = 4
    solver: str = "fatrop"
    max_iterations: int = 200
    max_obstacles: int = 4
    own_radius_m: float = 0.0
    q: tuple[float, ...] = (0.1, 0.1, 10.0, 1.0, 1.0, 1.0)
    r: tuple[float, ...] = (0.01, 0.01)
    r_rate: tuple[float, ...] = (0.01, 0.01)
    length_scale_m: float | None = None
    speed_scale_mps: float = 1.0
    terminal_weight: bool = True
    collision_slack_weight: float | None = 1.0e4

    def __post_init__(self) -> None:
        if self.horizon_steps < 1:
            raise ValueError(f"horizon_steps must be >= 1, got {self.horizon_steps}")
        if self.control_interval_s <= 0.0:
            raise ValueError(f"control_interval_s must be > 0, got {self.control_interval_s}")
        if self.substeps < 1:
            raise ValueError(f"substeps must be >= 1, got {self.substeps}")
        if self.solver not in SOLVERS:
            raise ValueError(f"solver must be one of {', '.join(SOLVERS)}, got '{self.solver}'")
        if len(self.q) != 6 or len(self.r) != 2 or len(self.r_rate) != 2:
            raise ValueError("weights: q needs 6 values, r and r_rate 2 each")
        if min(self.q + self.r + self.r_rate) < 0.0:
            raise ValueError("weights must be >= 0")
        if self.collision_slack_weight is not None and not self.collision_slack_weight > 0.0:
            raise ValueError(f"collision_slack_weight must be > 0 or None, got {self.collision_slack_weight}")


@dataclasses.dataclass
class NMPCSolution:
    """Outcome of one control step.

    Attributes
    ----------
    tau : numpy.ndarray
        Applied input [tau_u N, tau_r N·m].
    states : numpy.ndarray
        (N+1, 6) predicted states in SI (absolute positions), row 0 the measured state.
    inputs : numpy.ndarray
        (N, 2) planned inputs in SI.
    solve_time_s : float
        Wall time of the NLP solver call [s].
    iterations : int
        Solver iterations.
    status : str
        Solver's return status.
    success : bool
        Solver reported success.
    fallback : bool
        The applied input came from the fallback, not from this solve.
    cost : float
        Optimal (or last) objective value (scaled, dimensionless).
    constraint_violation : float
        Largest violation of the NLP's constraints and bounds at the returned point (scaled).
    collision_slack : float
        Largest collision slack sigma of the plan (0: every clearance R + R_i is kept;
        > 0: the soft constraints had to give way, see ``collision_slack_weight``).
    """

    tau: np.ndarray
    states: np.ndarray
    inputs: np.ndarray
    solve_time_s: float
    iterations: int
    status: str
    success: bool
    fallback: bool
    cost: float
    constraint_violation: float
    collision_slack: float = 0.0


def wrap_angle(angle):
    """Wrap ``angle`` [rad] to (-pi, pi] (numpy)."""
    return np.pi - np.mod(np.pi - np.asarray(angle, dtype=float), 2.0 * np.pi)


def reference_inputs(reference: np.ndarray, dt: float, params: ShipParameters) -> np.ndarray:
    """Feed-forward inputs tau_d (N, 2) [SI] for reference states (N+1, 6) spaced ``dt`` [s].

    Inverse of the surge and yaw equations with v_d = 0 (the paper's Eq. 19 reference):
    ``tau_u = m11 udot + d11 u``, ``tau_r = m33 rdot + d33 r``, derivatives by forward
    differences, clipped to the bounds.
    """
    u = reference[:, 3]
    r = reference[:, 5]
    udot = np.diff(u) / dt
    rdot = np.diff(r) / dt
    tau_u = params.m11 * udot + params.d11 * u[:-1]
    tau_r = params.m33 * rdot + params.d33 * r[:-1]
    tau = np.column_stack([tau_u, tau_r])
    return np.clip(tau, -params.tau_max, params.tau_max)


class NMPCController:
    """Multiple-shooting NMPC of the 3-DOF ship, built once, re-solved every interval.

    Parameters
    ----------
    params : ShipParameters
        Prediction model (same set as the plant, without disturbances).
    settings : NMPCSettings
        Horizon, interval, solver, weights, scaling.
    """

    def __init__(self, params: ShipParameters, settings: NMPCSettings | None = None) -> None:
        self.params = params
        self.settings = settings or NMPCSettings()
        s = self.settings
        self.length_scale = float(s.length_scale_m or params.extras.get("lpp", 230.0))
        self.speed_scale = float(s.speed_scale_mps)
        L, U = self.length_scale, self.speed_scale
        #: SI value = scaled value * state_scale (positions relative to the solve's origin).
        self.state_scale = np.array([L, L, 1.0, U, U, U / L])
        self.input_scale = params.tau_max.copy()
        self._terminal_cache: dict[float, np.ndarray] = {}
        self._build()
        self._previous: NMPCSolution | None = None
        self._previous_time: float | None = None
        self.fallback_count = 0
        self.failure_count = 0

    # ------------------------------------------------------------------ problem build

    def _scaled_step(self) -> ca.Function:
        """F_s(z, w) -> (z_next, Z_sub): RK4 of the scaled model (translation invariant)."""
        s = self.settings
        F = rk4_function(self.params, s.control_interval_s, s.substeps, with_substeps=True)
        z = ca.SX.sym("z", 6)
        w = ca.SX.sym("w", 2)
        sx = ca.DM(self.state_scale)
        x_next, x_sub = F(z * sx, w * ca.DM(self.input_scale))
        z_sub = x_sub / ca.repmat(sx, 1, s.substeps)
        return ca.Function("F_scaled", [z, w], [x_next / sx, z_sub])

    def _build(self) -> None:
        s = self.settings
        N, S, M = s.horizon_steps, s.substeps, s.max_obstacles
        dt = s.control_interval_s
        h = dt / S
        Fs = self._scaled_step()
        self._F_scaled = Fs

        Z = [ca.SX.sym(f"z{k}", 6) for k in range(N + 1)]
        W = [ca.SX.sym(f"w{k}", 2) for k in range(N)]
        soft = s.collision_slack_weight is not None
        SIGMA = [ca.SX.sym(f"sigma{k}", 1 if soft else 0) for k in range(N)]
        ref = ca.SX.sym("ref", 6, N + 1)
        w_d = ca.SX.sym("w_d", 2, N)
        w_prev = ca.SX.sym("w_prev", 2)
        P = ca.SX.sym("P", 6, 6)
        obs = ca.SX.sym("obs", OBSTACLE_FIELDS, M)
        Q = ca.DM(s.q)
        R = ca.DM(s.r)
        R1 = ca.DM(s.r_rate)

        def stage_state_cost(z, zr):
            e = z - zr
            heading = 2.0 * (1.0 - ca.cos(e[2]))
            return (
                Q[0] * e[0] ** 2 + Q[1] * e[1] ** 2 + Q[2] * heading
                + Q[3] * e[3] ** 2 + Q[4] * e[4] ** 2 + Q[5] * e[5] ** 2
            )

        cost = 0
        g, lbg, ubg, equality = [], [], [], []
        for k in range(N):
            Z_next, Z_sub = Fs(Z[k], W[k])
            if k > 0:
                cost += stage_state_cost(Z[k], ref[:, k])
            dw = W[k] - w_d[:, k]
            cost += ca.sum1(R * dw**2)
            dw_rate = W[k] - (W[k - 1] if k > 0 else w_prev)
            cost += ca.sum1(R1 * dw_rate**2)
            relax = 0
            if soft:
                cost += s.collision_slack_weight * (SIGMA[k][0] + SIGMA[k][0] ** 2)
                relax = SIGMA[k][0]
            # dynamics of stage k first, then its path constraints (fatrop's structure)
            g.append(Z[k + 1] - Z_next)
            lbg += [0.0] * 6
            ubg += [0.0] * 6
            equality += [True] * 6
            for j in range(S):
                t_sub = k * dt + (j + 1) * h
                for i in range(M):
                    cx, cy, vx, vy, rsum, inflation, active = (obs[f, i] for f in range(OBSTACLE_FIELDS))
                    dx = Z_sub[0, j] - (cx + vx * t_sub)
                    dy = Z_sub[1, j] - (cy + vy * t_sub)
                    clearance = (dx**2 + dy**2) / rsum**2 - 1.0 - inflation
                    g.append(active * clearance + (1.0 - active) + relax)
                    lbg.append(0.0)
                    ubg.append(ca.inf)
                    equality.append(False)
        # terminal cost in the reference's along/cross-track frame
        eN = Z[N] - ref[:, N]
        c, sn = ca.cos(ref[2, N]), ca.sin(ref[2, N])
        e_path = ca.vertcat(
            c * eN[0] + sn * eN[1],
            -sn * eN[0] + c * eN[1],
            ca.atan2(ca.sin(eN[2]), ca.cos(eN[2])),
            eN[3],
            eN[4],
            eN[5],
        )
        cost += ca.mtimes([e_path.T, P, e_path])

        decision = []
        for k in range(N):
            decision += [Z[k], W[k], SIGMA[k]]
        decision.append(Z[N])
        n_sigma = 1 if soft else 0
        self._nx = 6 * (N + 1) + (2 + n_sigma) * N
        parameters = ca.vertcat(ca.vec(ref), ca.vec(w_d), w_prev, ca.vec(P), ca.vec(obs))
        nlp = {"x": ca.vertcat(*decision), "f": cost, "g": ca.vertcat(*g), "p": parameters}
        self._lbg = np.array(lbg, dtype=float)
        self._ubg = np.array(ubg, dtype=float)
        self._solver = ca.nlpsol("rhnc_nmpc", s.solver, nlp, self._solver_options(equality))
        # The second, relaxed attempt gets a solver of its own, built on first need: a solver
        # keeps state between calls (fatrop), and a failed hard attempt left in it spoils the
        # relaxed one started from the same guess (seen: 162 iterations and failure, against
        # 59 and success from a fresh solver).
        self._relaxed_solver = None
        self._relaxed_build = (nlp, self._solver_options(equality))
        # index helpers into the stacked decision vector (z_k then w_k per stage)
        stride = 8 + n_sigma
        self._z_index = np.array([[k * stride + i for i in range(6)] for k in range(N + 1)])
        self._w_index = np.array([[k * stride + 6 + i for i in range(2)] for k in range(N)])
        self._sigma_index = np.array([k * stride + 8 for k in range(N)]) if soft else np.zeros(0, dtype=int)

    def _solver_options(self, equality: Sequence[bool]) -> dict:
        s = self.settings
        common = {"expand": True, "print_time": False, "error_on_fail": False}
        if s.solver == "ipopt":
            return {
                **common,
                "ipopt": {
                    "print_level": 0,
                    "sb": "yes",
                    "max_iter": s.max_iterations,
                    "tol": 1e-6,
                    "mu_strategy": "adaptive",
                    "warm_start_init_point": "no",
                },
            }
        if s.solver == "fatrop":
            return {
                **common,
                "structure_detection": "auto",
                "equality": list(equality),
                "debug": False,
                "fatrop": {"print_level": 0, "max_iter": s.max_iterations, "tol": 1e-6, "mu_init": 1e-1},
            }
        return {
            **common,
            "qpsol": "qrqp",
            "qpsol_options": {"print_iter": False, "print_header": False, "print_info": False, "error_on_fail": False},
            "max_iter": s.max_iterations,
            "print_header": False,
            "print_iteration": False,
            "print_status": False,
            "convexify_strategy": "regularize",
            "tol_pr": 1e-6,
            "tol_du": 1e-6,
        }

    # ------------------------------------------------------------------ terminal weight

    def terminal_weight(self, speed_mps: float) -> np.ndarray:
        """DARE terminal weight P (6 x 6, scaled, path frame) about straight motion at ``speed_mps``."""
        s = self.settings
        if not s.terminal_weight:
            return np.diag(s.q)
        # Below ~1 m/s the linearised model loses stabilisability (the cross-track position
        # is reached only through sway, which is unactuated at u = 0) and the DARE has no
        # solution: a stopping or stopped reference takes P of slow straight motion.
        key = round(max(speed_mps, MIN_TERMINAL_SPEED_MPS) * 4.0) / 4.0
        if key not in self._terminal_cache:
            z0 = np.array([0.0, 0.0, 0.0, key / self.speed_scale, 0.0, 0.0])
            w0 = self.params.equilibrium_tau(key) / self.input_scale
            z = ca.SX.sym("z", 6)
            w = ca.SX.sym("w", 2)
            z_next = self._F_scaled(z, w)[0]
            jac = ca.Function("linearised_step", [z, w], [ca.jacobian(z_next, z), ca.jacobian(z_next, w)])
            A, B = (np.array(m) for m in jac(z0, w0))
            import control  # python-control: 1.5 s to import, needed only here

            P, _, _ = control.dare(A, B, np.diag(s.q), np.diag(s.r))
            self._terminal_cache[key] = 0.5 * (P + P.T)
        return self._terminal_cache[key]

    # ------------------------------------------------------------------ solving

    def reset(self) -> None:
        """Forget the previous plan (warm start and fallback)."""
        self._previous = None
        self._previous_time = None

    def _obstacle_parameters(self, obstacles: np.ndarray | None, origin: np.ndarray, speed: float, et: bool) -> np.ndarray:
        s = self.settings
        L = self.length_scale
        h = s.control_interval_s / s.substeps
        slots = np.zeros((OBSTACLE_FIELDS, s.max_obstacles))
        slots[4, :] = 1.0  # harmless radius for inactive slots
        if not et or obstacles is None or len(obstacles) == 0:
            return slots
        obstacles = np.atleast_2d(np.asarray(obstacles, dtype=float))
        distance = np.hypot(obstacles[:, 0] - origin[0], obstacles[:, 1] - origin[1]) - obstacles[:, 4]
        order = np.argsort(distance)
        if len(order) > s.max_obstacles:
            LOG.warning("%d obstacles given, NMPC uses the %d nearest", len(order), s.max_obstacles)
            order = order[: s.max_obstacles]
        for slot, i in enumerate(order):
            x, y, vx, vy, radius = obstacles[i]
            rsum = s.own_radius_m + radius
            if rsum <= 0.0:
                continue
            closing = speed + math.hypot(vx, vy)
            inflation = (closing * h / (2.0 * rsum)) ** 2
            slots[:, slot] = [(x - origin[0]) / L, (y - origin[1]) / L, vx / L, vy / L, rsum / L, inflation, 1.0]
        return slots

    def _initial_guess(self, time_s: float, state: np.ndarray, ref_scaled: np.ndarray, w_d: np.ndarray, origin: np.ndarray) -> np.ndarray:
        """Shifted previous solution (re-based on this origin) or the reference itself."""
        N = self.settings.horizon_steps
        guess = np.zeros(self._nx)
        prev = self._previous
        shift = None
        if prev is not None and self._previous_time is not None:
            shift = int(round((time_s - self._previous_time) / self.settings.control_interval_s))
        if prev is not None and shift is not None and 0 <= shift <= N:
            states = np.vstack([prev.states[shift:], np.repeat(prev.states[-1:], shift, axis=0)])
            inputs = np.vstack([prev.inputs[shift:], np.repeat(prev.inputs[-1:], shift, axis=0)]) if shift < N else np.repeat(prev.inputs[-1:], N, axis=0)
            if shift > 0:  # extend the tail by rolling the last state forward
                F = self._F_scaled
                for k in range(N + 1 - shift, N + 1):
                    z_prev = self._to_scaled(states[k - 1], states[k - 1])
                    z_next = np.array(F(z_prev, inputs[k - 1] / self.input_scale)[0]).ravel()
                    states[k] = self._from_scaled(z_next[None, :], states[k - 1])[0]
            z = (states - np.r_[origin, 0, 0, 0, 0]) / self.state_scale
            w = inputs / self.input_scale
        else:
            z = ref_scaled.T.copy()
            w = w_d.T.copy()
        z[0] = self._to_scaled(state, origin)
        guess[self._z_index.ravel()] = z.ravel()
        guess[self._w_index.ravel()] = np.clip(w, -1.0, 1.0).ravel()
        return guess

    def _push_guess_to_starboard(self, guess: np.ndarray, obs: np.ndarray, ref_scaled: np.ndarray) -> None:
        """Move initial-guess nodes that lie inside an active obstacle sideways out of it.

        The shift is perpendicular to the reference course, to the side the node already
        lies on, and to starboard when it lies (nearly) on the obstacle's centre line.  A
        straight reference through the middle of an obstacle is a symmetric problem whose
        "stop in front of it" plan is a stationary point; starting the solver from a
        detour picks the starboard pass that COLREG Rules 8 and 14 prefer.
        """
        dt = self.settings.control_interval_s
        for i in np.flatnonzero(obs[6] > 0.5):
            cx, cy, vx, vy, rsum, inflation, _ = obs[:, i]
            r_push = 1.1 * rsum * math.sqrt(1.0 + inflation)
            for k in range(1, self.settings.horizon_steps + 1):
                ix, iy = self._z_index[k, 0], self._z_index[k, 1]
                dx = guess[ix] - (cx + vx * k * dt)
                dy = guess[iy] - (cy + vy * k * dt)
                if dx * dx + dy * dy >= r_push * r_push:
                    continue
                course = ref_scaled[2, k]
                along_x, along_y = math.cos(course), math.sin(course)
                starboard_x, starboard_y = -along_y, along_x
                along = dx * along_x + dy * along_y
                lateral = dx * starboard_x + dy * starboard_y
                side = -1.0 if lateral < -0.1 * rsum else 1.0
                new_lateral = side * math.sqrt(max(r_push * r_push - along * along, 0.0))
                guess[ix] += (new_lateral - lateral) * starboard_x
                guess[iy] += (new_lateral - lateral) * starboard_y

    def _to_scaled(self, state: np.ndarray, origin: np.ndarray) -> np.ndarray:
        shifted = np.asarray(state, dtype=float) - np.r_[origin[:2], 0, 0, 0, 0]
        return shifted / self.state_scale

    def _from_scaled(self, z: np.ndarray, origin: np.ndarray) -> np.ndarray:
        return z * self.state_scale + np.r_[origin[:2], 0, 0, 0, 0]

    def solve(
        self,
        time_s: float,
        state: np.ndarray,
        reference: np.ndarray,
        obstacles: np.ndarray | None = None,
        et: bool = False,
        previous_tau: np.ndarray | None = None,
    ) -> NMPCSolution:
        """One control step.

        Parameters
        ----------
        time_s : float
            Current time [s].
        state : numpy.ndarray
            Measured state (6,) [SI].
        reference : numpy.ndarray
            Reference states (N+1, 6) [SI] at ``time_s + k * control_interval_s``.
        obstacles : numpy.ndarray, optional
            (n, 5) rows x, y [m], vx, vy [m/s], radius [m] at ``time_s``.
        et : bool
            Event trigger: collision constraints on.
        previous_tau : numpy.ndarray, optional
            Input applied over the last interval [SI] (default: the last solution's).

        Returns
        -------
        NMPCSolution
            Applied input, prediction and telemetry; on solver failure the fallback.
        """
        s = self.settings
        N = s.horizon_steps
        state = np.asarray(state, dtype=float)
        reference = np.asarray(reference, dtype=float)
        if reference.shape != (N + 1, 6):
            raise ValueError(f"reference must have shape ({N + 1}, 6), got {reference.shape}")
        origin = state[:2].copy()
        # same heading, nearest turn: the warm start must not begin a full circle away
        reference = reference.copy()
        reference[:, 2] -= 2.0 * np.pi * np.round((reference[0, 2] - state[2]) / (2.0 * np.pi))
        ref_scaled = ((reference - np.r_[origin, 0, 0, 0, 0]) / self.state_scale).T
        w_d = (reference_inputs(reference, s.control_interval_s, self.params) / self.input_scale).T
        if previous_tau is None:
            previous_tau = self._previous.tau if self._previous is not None else self.params.equilibrium_tau(state[3])
        w_prev = np.clip(np.asarray(previous_tau, dtype=float) / self.input_scale, -1.0, 1.0)
        speed_ref = float(np.mean(np.hypot(reference[:, 3], reference[:, 4])))
        P = self.terminal_weight(speed_ref)
        obs = self._obstacle_parameters(obstacles, origin, max(speed_ref, math.hypot(state[3], state[4])) * 1.25, et)
        p = np.concatenate([ref_scaled.ravel(order="F"), w_d.ravel(order="F"), w_prev, P.ravel(order="F"), obs.ravel(order="F")])

        lbx = np.full(self._nx, -np.inf)
        ubx = np.full(self._nx, np.inf)
        lbx[self._w_index.ravel()] = -1.0
        ubx[self._w_index.ravel()] = 1.0
        lbx[self._z_index[1:, 3]] = 0.0  # u >= 0: no sailing backwards
        lbx[self._sigma_index] = 0.0  # collision slacks
        z0 = self._to_scaled(state, origin)
        lbx[self._z_index[0]] = z0
        ubx[self._z_index[0]] = z0
        x0 = self._initial_guess(time_s, state, ref_scaled, w_d, origin)
        self._push_guess_to_starboard(x0, obs, ref_scaled)

        # First the hard problem (slacks fixed at zero: the paper's constraints); only when it
        # fails, the soft one (slacks free): the plan that violates the clearance least.
        elapsed, iterations = 0.0, 0
        for relaxed in ((False, True) if self._sigma_index.size else (False,)):
            if relaxed and stop_requested():  # Ctrl-C aborted the first attempt: no second one
                raise KeyboardInterrupt
            ubx[self._sigma_index] = np.inf if relaxed else 0.0
            start = time.perf_counter()
            solver = self._relaxed() if relaxed else self._solver
            result = solver(x0=x0, p=p, lbx=lbx, ubx=ubx, lbg=self._lbg, ubg=self._ubg)
            elapsed += time.perf_counter() - start
            stats = solver.stats()
            x_opt = np.array(result["x"]).ravel()
            iterations += int(stats.get("iter_count", -1))
            success = bool(stats.get("success", False)) and np.all(np.isfinite(x_opt))
            if success:
                break
        g_opt = np.array(result["g"]).ravel()
        violation = float(
            max(
                np.max(np.maximum(self._lbg - g_opt, 0.0), initial=0.0),
                np.max(np.maximum(g_opt - self._ubg, 0.0), initial=0.0),
                np.max(np.maximum(lbx - x_opt, 0.0), initial=0.0),
                np.max(np.maximum(x_opt - ubx, 0.0), initial=0.0),
            )
        )
        status = str(stats.get("return_status", "unknown"))
        if self.settings.solver == "fatrop":  # fatrop reports an integer code
            status = "Solve_Succeeded" if stats.get("success", False) else f"fatrop_return_code_{status}"
        cost = float(result["f"])
        slack = float(np.max(x_opt[self._sigma_index], initial=0.0))
        slack = slack if slack > SLACK_TOLERANCE else 0.0
        if success and slack > 0.0:
            LOG.warning("NMPC at t = %.1f s: collision clearance relaxed (slack %.3g): no plan keeps R + R_i",
                        time_s, slack)
        states = self._from_scaled(x_opt[self._z_index], origin)
        # the solver meets the bounds |w| <= 1 only to its tolerance: never apply more than tau_max
        inputs = np.clip(x_opt[self._w_index], -1.0, 1.0) * self.input_scale
        if success:
            solution = NMPCSolution(inputs[0].copy(), states, inputs, elapsed, iterations, status, True, False, cost,
                                    violation, slack)
            self._previous, self._previous_time = solution, time_s
            return solution
        self.failure_count += 1
        self.fallback_count += 1
        solution = self._fallback(time_s, state, previous_tau, elapsed, iterations, status, cost, violation)
        LOG.info("NMPC solve at t = %.1f s failed (%s); fallback applied", time_s, status)
        return solution

    def _relaxed(self):
        """The solver of the relaxed (soft-constraint) attempt, built on first use."""
        if self._relaxed_solver is None:
            nlp, options = self._relaxed_build
            self._relaxed_solver = ca.nlpsol("rhnc_nmpc_relaxed", self.settings.solver, nlp, options)
        return self._relaxed_solver

    def _fallback(self, time_s, state, previous_tau, elapsed, iterations, status, cost, violation) -> NMPCSolution:
        """Shifted previous plan, or hold the surge force with zero yaw moment."""
        s = self.settings
        N = s.horizon_steps
        prev = self._previous
        shift = None
        if prev is not None and self._previous_time is not None:
            shift = int(round((time_s - self._previous_time) / s.control_interval_s))
        if prev is not None and shift is not None and 0 <= shift < N:
            inputs = np.vstack([prev.inputs[shift:], np.repeat(prev.inputs[-1:], shift, axis=0)])
        else:
            hold = np.array([float(np.asarray(previous_tau)[0]), 0.0])
            inputs = np.repeat(hold[None, :], N, axis=0)
        inputs = np.clip(inputs, -self.params.tau_max, self.params.tau_max)
        states = self._rollout(state, inputs)
        # keep the shifted plan (not the failed iterate) as the next warm start / fallback
        self._previous = NMPCSolution(inputs[0].copy(), states, inputs, elapsed, iterations, status, False, True, cost, violation)
        self._previous_time = time_s
        return dataclasses.replace(self._previous)

    def _rollout(self, state: np.ndarray, inputs: np.ndarray) -> np.ndarray:
        origin = np.asarray(state[:2], dtype=float)
        z = self._to_scaled(state, origin)
        rows = [z]
        for w in inputs / self.input_scale:
            z = np.array(self._F_scaled(z, w)[0]).ravel()
            rows.append(z)
        return self._from_scaled(np.array(rows), origin)
