"""The NMPC's nonlinear program: scaled prediction model, cost, collision domains, layout.

The problem is built once as CasADi expressions with parameters (reference, feed-forward
and previous input, terminal weight, disturbance estimate, obstacle domains) and handed
to ``nlpsol`` by :class:`rhnc.control.nmpc.NMPCController`; everything that changes from one solve
to the next is a parameter, so the same compiled problem serves every step.

Prediction model: the 3-DOF ship of :mod:`rhnc.ship.ship_model` plus a disturbance vector
``d = [c_n, c_e, w_u, w_v, w_r]`` held constant over the horizon: a current (north, east
[m/s]) added to the position rates and body-frame forces (surge, sway [N], yaw moment
[N m]) added to the force balances.  With ``d = 0`` it is the paper's Eq. 16; the
disturbance observer (:mod:`rhnc.control.disturbance_observer`) supplies ``d`` when it is on.

Collision domain of obstacle slot i at prediction time t (fields of ``OBSTACLE_FIELDS``):

    |p - (c_i + v_i t + o_i)|² / (rho_i + g_i t)² >= 1 + inflation_i,

a circle around the obstacle's constant-velocity prediction ``c_i + v_i t``, its centre
moved by ``o_i`` (the COLREG offset: ahead of and to starboard of a target, see
:mod:`rhnc.control.nmpc_colregs`) and its radius ``rho_i`` growing by ``g_i`` per second (the
margin for prediction error, which grows with the prediction time).  ``inflation_i``
widens the circle so that the straight chord between two admissible substep points
cannot cut the circle either.  An inactive slot (``active = 0``) turns into ``1 >= 0``.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

import casadi as ca
import numpy as np

from rhnc.ship.ship_model import ShipParameters, casadi_derivatives, rk4_states

#: Parameters per obstacle slot: cx, cy [L], vx, vy [L/s], offset x, y [L], rho [L],
#: growth [L/s], inflation [-], active [0/1].
OBSTACLE_FIELDS = 10
#: Disturbance parameters: current north, east [m/s]; w_u, w_v [N]; w_r [N m].
DISTURBANCE_SIZE = 5


#: fatrop's initial barrier parameter.  The guess is the previous plan, shifted, so it starts
#: close to the solution: 1e-3 took 15 % fewer iterations than 1e-1 in the benchmark's
#: closed loops (one and three targets), to the same plans within the solver's tolerance.
FATROP_MU_INIT = 1e-3
#: fatrop stops at an "acceptable" point when its scaled KKT error (constraint violation,
#: dual infeasibility scaled by the multipliers' size, complementarity) stays below
#: ``FATROP_ACCEPTABLE_TOL`` for ``FATROP_ACCEPTABLE_ITER`` iterations in a row.  Near a
#: solution where a collision constraint is active its Hessian needs a large regularization
#: (the clearance's curvature times its multiplier outweighs the position weights), and the
#: dual infeasibility then crept down over 150-200 iterations from about 4e-5 on a plan that
#: was primal feasible to 1e-14 and no longer moved (cost constant to 12 digits).  The
#: controller takes such a point only when its own check of the constraint violation passes
#: (``ACCEPTABLE_VIOLATION``); on 762 replayed Imazu solves the accepted plans' first inputs
#: differed from the fully converged ones by at most 5e-5 of tau_max.
FATROP_ACCEPTABLE_TOL = 1e-4
FATROP_ACCEPTABLE_ITER = 5
#: largest constraint violation (scaled: 1e-6 ship lengths of dynamics residual, 1e-6 of the
#: clearance ratio) of a point the solver stopped at as acceptable, for the NMPC to use it;
#: the solvers' own tolerance
ACCEPTABLE_VIOLATION = 1e-6
#: solver plugins whose solver object carries state from one solve to the next: the NMPC
#: replaces the object after a solve that did not succeed or took more than
#: ``FRESH_SOLVER_AFTER_ITERATIONS`` iterations (:mod:`rhnc.control.solver_watchdog`, ``renew``).
#: Measured on the 3 914 solver calls of one Imazu suite run, replayed in order: one object
#: for all calls (as before) 8 iterations at the median, 73 385 in all, 177 failures; a new
#: object for every call 6, 59 512, 35; renewed after a failure or more than 10 iterations
#: 8, 61 508, 43; after more than 6: 6, 59 698, 41 (with 3.3 ms of solver CPU at the median
#: against 3.5 ms for a new object every call: a reused object is warm in the caches, and
#: building one costs about 0.7 ms).  In a run without encounters (Experiment 2) a new
#: object per solve cost 1 s of processor time over 481 solves and saved no iteration.
FRESH_SOLVER_PLUGINS = ("fatrop",)
FRESH_SOLVER_AFTER_ITERATIONS = 6


def renew_solver_after(outcome) -> bool:
    """Whether a solve's outcome (``success``, ``iterations``) calls for a new solver object."""
    return not outcome.success or outcome.iterations > FRESH_SOLVER_AFTER_ITERATIONS
#: IPOPT options of a warm-started solve (the guess and its multipliers near the solution)
WARM_START_IPOPT = {"warm_start_bound_push": 1e-6, "warm_start_mult_bound_push": 1e-6, "mu_init": 1e-4}


def disturbed_derivatives(params: ShipParameters) -> ca.Function:
    """``f(X[6], tau[2], d[5]) -> Xdot[6]``: the prediction model with a constant disturbance."""
    f = casadi_derivatives(params)
    state = ca.SX.sym("X", 6)
    tau = ca.SX.sym("tau", 2)
    d = ca.SX.sym("d", DISTURBANCE_SIZE)
    sway, yaw = params.sway_yaw_accelerations(d[3], d[4])
    extra = ca.vertcat(d[0], d[1], 0.0, d[2] / params.m11, sway, yaw)
    return ca.Function("ship_fd", [state, tau, d], [f(state, tau) + extra])


def disturbed_rk4(params: ShipParameters, dt_s: float, substeps: int) -> ca.Function:
    """``F(X, tau, d) -> (X_next, Xs)``: RK4 over ``dt_s`` [s]; ``Xs`` the substep ends (6 x substeps)."""
    f = disturbed_derivatives(params)
    state = ca.SX.sym("X", 6)
    tau = ca.SX.sym("tau", 2)
    d = ca.SX.sym("d", DISTURBANCE_SIZE)
    columns = rk4_states(f, state, dt_s / substeps, substeps, tau, d)
    return ca.Function("ship_Fd", [state, tau, d], [columns[-1], ca.horzcat(*columns)])


def scaled_step(params: ShipParameters, dt_s: float, substeps: int, state_scale: np.ndarray,
                input_scale: np.ndarray) -> ca.Function:
    """``F_s(z, w, d) -> (z_next, Z_sub)``: the RK4 step on scaled states and inputs (d in SI)."""
    F = disturbed_rk4(params, dt_s, substeps)
    z = ca.SX.sym("z", 6)
    w = ca.SX.sym("w", 2)
    d = ca.SX.sym("d", DISTURBANCE_SIZE)
    sx = ca.DM(state_scale)
    x_next, x_sub = F(z * sx, w * ca.DM(input_scale), d)
    return ca.Function("F_scaled", [z, w, d], [x_next / sx, x_sub / ca.repmat(sx, 1, substeps)])


class StepEvaluator:
    """``F_s(z, w, d) -> z_next`` (numpy) through CasADi's argument buffers.

    The NMPC evaluates its model step twice per control step (the shifted plan's new last
    state, the first interval from the measured state); a Python call of the CasADi
    function costs about 30 us in argument conversions, a buffered one about 2 us.
    """

    def __init__(self, step: ca.Function) -> None:
        self._arguments = [np.zeros(step.numel_in(i)) for i in range(step.n_in())]
        self._results = [np.zeros(step.numel_out(i)) for i in range(step.n_out())]
        self._buffer, self._evaluate = step.buffer()
        for i, array in enumerate(self._arguments):
            self._buffer.set_arg(i, array.data)  # type: ignore[call-arg]  # the size defaults at run time
        for i, array in enumerate(self._results):
            self._buffer.set_res(i, array.data)  # type: ignore[call-arg]

    def __call__(self, z: np.ndarray, w: np.ndarray, d: np.ndarray) -> np.ndarray:
        for array, value in zip(self._arguments, (z, w, d)):
            array[:] = value
        self._evaluate()
        return self._results[0].copy()


@dataclasses.dataclass
class NMPCProblem:
    """The built NLP and where things sit in its decision and parameter vectors.

    Attributes
    ----------
    nlp : dict
        CasADi NLP (``x``, ``f``, ``g``, ``p``).
    equality : list of bool
        Which rows of ``g`` are equalities (fatrop's structure detection needs it).
    lbg, ubg : numpy.ndarray
        Bounds of ``g``.
    z_index, w_index, sigma_index : numpy.ndarray
        Indices of the scaled states (N+1, 6), inputs (N, 2) and collision slacks (N or 0)
        in the decision vector.
    size : int
        Length of the decision vector.
    step : casadi.Function
        The scaled model step ``F_s(z, w, d)``.
    compact_nlp : dict or None
        The same NLP as an MX graph that maps one interval's function over the horizon
        (what :mod:`rhnc.control.nmpc_codegen` compiles).
    """

    nlp: dict
    equality: list
    lbg: np.ndarray
    ubg: np.ndarray
    z_index: np.ndarray
    w_index: np.ndarray
    sigma_index: np.ndarray
    size: int
    step: ca.Function
    compact_nlp: dict | None = None

    @staticmethod
    def parameters(ref_scaled: np.ndarray, w_d: np.ndarray, w_prev: np.ndarray, terminal: np.ndarray,
                   disturbance: np.ndarray, obstacles: np.ndarray) -> np.ndarray:
        """Stack the parameter vector in the order the problem declared it."""
        return np.concatenate([
            np.asarray(ref_scaled).ravel(order="F"), np.asarray(w_d).ravel(order="F"), np.asarray(w_prev),
            np.asarray(terminal).ravel(order="F"), np.asarray(disturbance, dtype=float),
            np.asarray(obstacles).ravel(order="F"),
        ])

    def violation(self, x: np.ndarray, g: np.ndarray, lbx: np.ndarray, ubx: np.ndarray) -> float:
        """Largest violation of the bounds of ``x`` and ``g`` (0 when the point is feasible)."""
        # the largest difference, or 0 (a NaN anywhere stays NaN)
        return float(np.max([0.0, (self.lbg - g).max(initial=0.0), (g - self.ubg).max(initial=0.0),
                             (lbx - x).max(initial=0.0), (x - ubx).max(initial=0.0)]))


def stage_function(params: ShipParameters, control_interval_s: float, substeps: int, max_obstacles: int,
                   q: Sequence[float], r: Sequence[float], r_rate: Sequence[float], slack_weight: float | None,
                   state_scale: np.ndarray, input_scale: np.ndarray) -> ca.Function:
    """One control interval of the NLP: ``stage(z, w, sigma, z_next, w_before, ref, w_d, d, obs, t0, state_on)``.

    Returns ``(cost, g)``: the stage cost (state error weighted by ``state_on``, input and
    input-rate terms, slack penalty) and the stage's constraints, first the 6 dynamics
    residuals ``z_next - F_s(z, w, d)``, then one clearance per RK4 substep and obstacle slot
    (substep-major).  ``t0`` [s] is the interval's start in prediction time.  Every interval
    of the horizon is this one function with other arguments, which is what lets the
    compiled NLP (:mod:`rhnc.control.nmpc_codegen`) hold one interval's code, called in a loop.
    """
    S, M = substeps, max_obstacles
    h = control_interval_s / S
    Fs = scaled_step(params, control_interval_s, S, state_scale, input_scale)
    n_sigma = 0 if slack_weight is None else 1
    z, w, sigma = ca.SX.sym("z", 6), ca.SX.sym("w", 2), ca.SX.sym("sigma", n_sigma)
    z_next, w_before = ca.SX.sym("z_next", 6), ca.SX.sym("w_before", 2)
    ref, w_d, dist = ca.SX.sym("ref", 6), ca.SX.sym("w_d", 2), ca.SX.sym("d", DISTURBANCE_SIZE)
    obs, t0, state_on = ca.SX.sym("obs", OBSTACLE_FIELDS, M), ca.SX.sym("t0"), ca.SX.sym("state_on")
    z_end, z_sub = Fs(z, w, dist)
    cost = stage_cost(z, w, sigma, w_before, ref, w_d, state_on, q, r, r_rate, slack_weight)
    relax = sigma[0] if n_sigma else 0
    # dynamics first, then the path constraints (fatrop's structure)
    g = [z_next - z_end] + [clearance + relax for clearance in clearances(z_sub, obs, t0, h, S, M, as_list=True)]
    return ca.Function("rhnc_stage", [z, w, sigma, z_next, w_before, ref, w_d, dist, obs, t0, state_on],
                       [cost, ca.vertcat(*g)])


def stage_cost(z, w, sigma, w_before, ref, w_d, state_on, q: Sequence[float], r: Sequence[float],
               r_rate: Sequence[float], slack_weight: float | None):
    """One interval's cost, written once for every backend (CasADi expressions of the scaled
    quantities; ``sigma`` is empty without slacks).

    ``state_on (e' Q e)`` with the heading error through ``2 (1 - cos e)`` (= e² near 0, no
    minimum at pi), ``(w - w_d)' R (w - w_d)``, the input rate ``(w - w_before)' R1 (w -
    w_before)`` and, with slacks, ``slack_weight (sigma + sigma²)`` (an exact L1 penalty
    plus a little curvature).
    """
    Q, R, R1 = ca.DM(list(q)), ca.DM(list(r)), ca.DM(list(r_rate))
    e = z - ref
    heading = 2.0 * (1.0 - ca.cos(e[2]))  # = e² near 0, no minimum at pi
    cost = state_on * (Q[0] * e[0] ** 2 + Q[1] * e[1] ** 2 + Q[2] * heading
                       + Q[3] * e[3] ** 2 + Q[4] * e[4] ** 2 + Q[5] * e[5] ** 2)
    cost += ca.sum1(R * (w - w_d) ** 2) + ca.sum1(R1 * (w - w_before) ** 2)
    if slack_weight is not None:
        cost += slack_weight * (sigma[0] + sigma[0] ** 2)
    return cost


def clearances(z_sub, obs, t0, h: float, substeps: int, max_obstacles: int, as_list: bool = False):
    """The collision constraints of one interval (>= 0 when kept), substep-major: one per RK4
    substep end ``z_sub[:, j]`` (at ``t0 + (j + 1) h`` [s]) and obstacle slot (module docstring)."""
    rows = []
    for j in range(substeps):
        t_sub = t0 + (j + 1) * h
        for i in range(max_obstacles):
            cx, cy, vx, vy, ox, oy, rho, growth, inflation, active = (obs[f, i] for f in range(OBSTACLE_FIELDS))
            dx = z_sub[0, j] - (cx + vx * t_sub + ox)
            dy = z_sub[1, j] - (cy + vy * t_sub + oy)
            radius = rho + growth * t_sub
            clearance = (dx**2 + dy**2) / radius**2 - 1.0 - inflation
            rows.append(active * clearance + (1.0 - active))
    return rows if as_list else ca.vertcat(*rows)


def terminal_cost(z_N, ref_N, P):
    """``e' P e`` with the terminal error ``e`` in the reference's along/cross-track frame."""
    eN = z_N - ref_N
    c, sn = ca.cos(ref_N[2]), ca.sin(ref_N[2])
    e_path = ca.vertcat(c * eN[0] + sn * eN[1], -sn * eN[0] + c * eN[1],
                        ca.atan2(ca.sin(eN[2]), ca.cos(eN[2])), eN[3], eN[4], eN[5])
    return ca.mtimes([e_path.T, P, e_path])


def build_problem(params: ShipParameters, horizon_steps: int, control_interval_s: float, substeps: int,
                  max_obstacles: int, q: Sequence[float], r: Sequence[float], r_rate: Sequence[float],
                  slack_weight: float | None, state_scale: np.ndarray, input_scale: np.ndarray) -> NMPCProblem:
    """Build the multiple-shooting NLP (cost and constraints in the module docstring).

    Two forms of the same NLP are built from one :func:`stage_function`: ``nlp``, every
    interval inlined into one SX expression graph (fastest when CasADi interprets it), and
    ``compact_nlp``, an MX graph that maps the stage function over the horizon (one
    interval's code and a loop when compiled to C).

    Parameters
    ----------
    params : ShipParameters
        Prediction model.
    horizon_steps, control_interval_s, substeps, max_obstacles
        N_c, delta [s], RK4 substeps per interval, obstacle slots.
    q, r, r_rate : sequence of float
        Diagonals of Q (6), R (2), R1 (2) on scaled quantities.
    slack_weight : float or None
        Weight of the per-stage collision slack (None: no slack variables).
    state_scale, input_scale : numpy.ndarray
        SI value = scaled value * scale.
    """
    N, S, M = horizon_steps, substeps, max_obstacles
    dt = control_interval_s
    stage = stage_function(params, dt, S, M, q, r, r_rate, slack_weight, state_scale, input_scale)
    n_sigma = 0 if slack_weight is None else 1
    stride = 8 + n_sigma
    size = 6 * (N + 1) + (2 + n_sigma) * N
    start_times = [k * dt for k in range(N)]
    state_on = [0.0] + [1.0] * (N - 1)  # z_0 is the measured state: no cost on it

    def nlp_of(kind):
        """The NLP in SX (every stage inlined) or MX (the stage function mapped)."""
        x = kind.sym("x", size)
        ref, w_d, w_prev = kind.sym("ref", 6, N + 1), kind.sym("w_d", 2, N), kind.sym("w_prev", 2)
        P, dist, obs = kind.sym("P", 6, 6), kind.sym("d", DISTURBANCE_SIZE), kind.sym("obs", OBSTACLE_FIELDS, M)
        blocks = ca.reshape(x[:N * stride], stride, N)
        Z, W, SIGMA = blocks[0:6, :], blocks[6:8, :], blocks[8:8 + n_sigma, :]
        z_N = x[N * stride:]
        Z_next = ca.horzcat(Z[:, 1:], z_N)
        W_before = ca.horzcat(w_prev, W[:, :N - 1])
        if kind is ca.SX:
            costs, gs = zip(*(stage(Z[:, k], W[:, k], SIGMA[:, k], Z_next[:, k], W_before[:, k], ref[:, k],
                                    w_d[:, k], dist, obs, start_times[k], state_on[k]) for k in range(N)))
            cost, g = sum(costs), ca.vertcat(*gs)
        else:
            costs, G = stage.map(N)(Z, W, SIGMA, Z_next, W_before, ref[:, :N], w_d, dist, obs,
                                    ca.DM(start_times).T, ca.DM(state_on).T)
            cost, g = ca.sum2(costs), ca.vec(G)
        cost += terminal_cost(z_N, ref[:, N], P)
        parameters = ca.vertcat(ca.vec(ref), ca.vec(w_d), w_prev, ca.vec(P), dist, ca.vec(obs))
        return {"x": x, "f": cost, "g": g, "p": parameters}

    n_path = S * M
    equality = ([True] * 6 + [False] * n_path) * N
    lbg = np.zeros(len(equality))
    ubg = np.array([0.0 if eq else np.inf for eq in equality])
    return NMPCProblem(
        nlp=nlp_of(ca.SX),
        equality=equality,
        lbg=lbg,
        ubg=ubg,
        z_index=np.array([[k * stride + i for i in range(6)] for k in range(N + 1)]),
        w_index=np.array([[k * stride + 6 + i for i in range(2)] for k in range(N)]),
        sigma_index=np.array([k * stride + 8 for k in range(N)]) if n_sigma else np.zeros(0, dtype=int),
        size=size,
        step=scaled_step(params, dt, S, state_scale, input_scale),
        compact_nlp=nlp_of(ca.MX),
    )


def solver_options(solver: str, equality: Sequence[bool], max_iterations: int, wall_time_s: float | None,
                   cpu_time_s: float | None = None, warm_start_duals: bool = False) -> dict:
    """``nlpsol`` options per solver: quiet, iteration-limited (IPOPT also wall-time-limited).

    ``warm_start_duals``: IPOPT starts from the multipliers passed with the guess
    (``warm_start_init_point``) instead of computing its own.
    """
    common = {"expand": True, "print_time": False, "error_on_fail": False}
    if solver == "ipopt":
        ipopt = {"print_level": 0, "sb": "yes", "max_iter": max_iterations, "tol": 1e-6,
                 "mu_strategy": "adaptive", "warm_start_init_point": "yes" if warm_start_duals else "no"}
        if warm_start_duals:
            ipopt.update(WARM_START_IPOPT)
        if wall_time_s is not None:
            ipopt["max_wall_time"] = float(wall_time_s)
        if cpu_time_s is not None:
            ipopt["max_cpu_time"] = float(cpu_time_s)
        return {**common, "ipopt": ipopt}
    if solver == "fatrop":
        return {**common, "structure_detection": "auto", "equality": list(equality), "debug": False,
                "fatrop": {"print_level": 0, "max_iter": max_iterations, "tol": ACCEPTABLE_VIOLATION,
                           "mu_init": FATROP_MU_INIT, "tol_acceptable": FATROP_ACCEPTABLE_TOL,
                           "acceptable_iter": FATROP_ACCEPTABLE_ITER}}
    return {
        **common,
        "qpsol": "qrqp",
        "qpsol_options": {"print_iter": False, "print_header": False, "print_info": False, "error_on_fail": False},
        "max_iter": max_iterations,
        "print_header": False,
        "print_iteration": False,
        "print_status": False,
        "convexify_strategy": "regularize",
        "tol_pr": 1e-6,
        "tol_du": 1e-6,
    }
