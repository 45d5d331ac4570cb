"""The NMPC's nonlinear program: scaled prediction model, cost, collision domains, layout.

The problem is built once as CasADi expressions with parameters (reference, feed-forward
and previous input, terminal weight, disturbance estimate, obstacle domains) and handed
to ``nlpsol`` by :class:`rhnc.nmpc.NMPCController`; everything that changes from one solve
to the next is a parameter, so the same compiled problem serves every step.

Prediction model: the 3-DOF ship of :mod:`rhnc.ship_model` plus a disturbance vector
``d = [c_n, c_e, w_u, w_v, w_r]`` held constant over the horizon: a current (north, east
[m/s]) added to the position rates and body-frame forces (surge, sway [N], yaw moment
[N m]) added to the force balances.  With ``d = 0`` it is the paper's Eq. 16; the
disturbance observer (:mod:`rhnc.disturbance_observer`) supplies ``d`` when it is on.

Collision domain of obstacle slot i at prediction time t (fields of ``OBSTACLE_FIELDS``):

    |p - (c_i + v_i t + o_i)|² / (rho_i + g_i t)² >= 1 + inflation_i,

a circle around the obstacle's constant-velocity prediction ``c_i + v_i t``, its centre
moved by ``o_i`` (the COLREG offset: ahead of and to starboard of a target, see
:mod:`rhnc.nmpc_colregs`) and its radius ``rho_i`` growing by ``g_i`` per second (the
margin for prediction error, which grows with the prediction time).  ``inflation_i``
widens the circle so that the straight chord between two admissible substep points
cannot cut the circle either.  An inactive slot (``active = 0``) turns into ``1 >= 0``.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

import casadi as ca
import numpy as np

from rhnc.ship_model import ShipParameters, casadi_derivatives

#: Parameters per obstacle slot: cx, cy [L], vx, vy [L/s], offset x, y [L], rho [L],
#: growth [L/s], inflation [-], active [0/1].
OBSTACLE_FIELDS = 10
#: Disturbance parameters: current north, east [m/s]; w_u, w_v [N]; w_r [N m].
DISTURBANCE_SIZE = 5


def disturbed_derivatives(params: ShipParameters) -> ca.Function:
    """``f(X[6], tau[2], d[5]) -> Xdot[6]``: the prediction model with a constant disturbance."""
    f = casadi_derivatives(params)
    state = ca.SX.sym("X", 6)
    tau = ca.SX.sym("tau", 2)
    d = ca.SX.sym("d", DISTURBANCE_SIZE)
    extra = ca.vertcat(d[0], d[1], 0.0, d[2] / params.m11, d[3] / params.m22, d[4] / params.m33)
    return ca.Function("ship_fd", [state, tau, d], [f(state, tau) + extra])


def disturbed_rk4(params: ShipParameters, dt_s: float, substeps: int) -> ca.Function:
    """``F(X, tau, d) -> (X_next, Xs)``: RK4 over ``dt_s`` [s]; ``Xs`` the substep ends (6 x substeps)."""
    f = disturbed_derivatives(params)
    state = ca.SX.sym("X", 6)
    tau = ca.SX.sym("tau", 2)
    d = ca.SX.sym("d", DISTURBANCE_SIZE)
    h = dt_s / substeps
    x = state
    columns = []
    for _ in range(substeps):
        k1 = f(x, tau, d)
        k2 = f(x + 0.5 * h * k1, tau, d)
        k3 = f(x + 0.5 * h * k2, tau, d)
        k4 = f(x + h * k3, tau, d)
        x = x + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
        columns.append(x)
    return ca.Function("ship_Fd", [state, tau, d], [x, ca.horzcat(*columns)])


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

    @staticmethod
    def parameters(ref_scaled: np.ndarray, w_d: np.ndarray, w_prev: np.ndarray, terminal: np.ndarray,
                   disturbance: np.ndarray, obstacles: np.ndarray) -> np.ndarray:
        """Stack the parameter vector in the order the problem declared it."""
        return np.concatenate([
            np.asarray(ref_scaled).ravel(order="F"), np.asarray(w_d).ravel(order="F"), np.asarray(w_prev),
            np.asarray(terminal).ravel(order="F"), np.asarray(disturbance, dtype=float),
            np.asarray(obstacles).ravel(order="F"),
        ])


def build_problem(params: ShipParameters, horizon_steps: int, control_interval_s: float, substeps: int,
                  max_obstacles: int, q: Sequence[float], r: Sequence[float], r_rate: Sequence[float],
                  slack_weight: float | None, state_scale: np.ndarray, input_scale: np.ndarray) -> NMPCProblem:
    """Build the multiple-shooting NLP (cost and constraints in the module docstring).

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
    h = dt / S
    Fs = scaled_step(params, dt, S, state_scale, input_scale)
    soft = slack_weight is not None

    Z = [ca.SX.sym(f"z{k}", 6) for k in range(N + 1)]
    W = [ca.SX.sym(f"w{k}", 2) for k in range(N)]
    SIGMA = [ca.SX.sym(f"sigma{k}", 1 if soft else 0) for k in range(N)]
    ref = ca.SX.sym("ref", 6, N + 1)
    w_d = ca.SX.sym("w_d", 2, N)
    w_prev = ca.SX.sym("w_prev", 2)
    P = ca.SX.sym("P", 6, 6)
    dist = ca.SX.sym("d", DISTURBANCE_SIZE)
    obs = ca.SX.sym("obs", OBSTACLE_FIELDS, M)
    Q, R, R1 = ca.DM(list(q)), ca.DM(list(r)), ca.DM(list(r_rate))

    def stage_state_cost(z, zr):
        e = z - zr
        heading = 2.0 * (1.0 - ca.cos(e[2]))
        return (Q[0] * e[0] ** 2 + Q[1] * e[1] ** 2 + Q[2] * heading
                + Q[3] * e[3] ** 2 + Q[4] * e[4] ** 2 + Q[5] * e[5] ** 2)

    cost = 0
    g, lbg, ubg, equality = [], [], [], []
    for k in range(N):
        Z_next, Z_sub = Fs(Z[k], W[k], dist)
        if k > 0:
            cost += stage_state_cost(Z[k], ref[:, k])
        cost += ca.sum1(R * (W[k] - w_d[:, k]) ** 2)
        cost += ca.sum1(R1 * (W[k] - (W[k - 1] if k > 0 else w_prev)) ** 2)
        relax = 0
        if soft:
            cost += slack_weight * (SIGMA[k][0] + SIGMA[k][0] ** 2)
            relax = SIGMA[k][0]
        # dynamics of stage k first, then its path constraints (fatrop's structure)
        g.append(Z[k + 1] - Z_next)
        lbg += [0.0] * 6
        ubg += [0.0] * 6
        equality += [True] * 6
        for j in range(S):
            t_sub = k * dt + (j + 1) * h
            for i in range(M):
                cx, cy, vx, vy, ox, oy, rho, growth, inflation, active = (obs[f, i] for f in range(OBSTACLE_FIELDS))
                dx = Z_sub[0, j] - (cx + vx * t_sub + ox)
                dy = Z_sub[1, j] - (cy + vy * t_sub + oy)
                radius = rho + growth * t_sub
                clearance = (dx**2 + dy**2) / radius**2 - 1.0 - inflation
                g.append(active * clearance + (1.0 - active) + relax)
                lbg.append(0.0)
                ubg.append(ca.inf)
                equality.append(False)
    # terminal cost in the reference's along/cross-track frame
    eN = Z[N] - ref[:, N]
    c, sn = ca.cos(ref[2, N]), ca.sin(ref[2, N])
    e_path = ca.vertcat(c * eN[0] + sn * eN[1], -sn * eN[0] + c * eN[1],
                        ca.atan2(ca.sin(eN[2]), ca.cos(eN[2])), eN[3], eN[4], eN[5])
    cost += ca.mtimes([e_path.T, P, e_path])

    decision = []
    for k in range(N):
        decision += [Z[k], W[k], SIGMA[k]]
    decision.append(Z[N])
    n_sigma = 1 if soft else 0
    parameters = ca.vertcat(ca.vec(ref), ca.vec(w_d), w_prev, ca.vec(P), dist, ca.vec(obs))
    nlp = {"x": ca.vertcat(*decision), "f": cost, "g": ca.vertcat(*g), "p": parameters}
    stride = 8 + n_sigma
    return NMPCProblem(
        nlp=nlp,
        equality=equality,
        lbg=np.array(lbg, dtype=float),
        ubg=np.array(ubg, dtype=float),
        z_index=np.array([[k * stride + i for i in range(6)] for k in range(N + 1)]),
        w_index=np.array([[k * stride + 6 + i for i in range(2)] for k in range(N)]),
        sigma_index=np.array([k * stride + 8 for k in range(N)]) if soft else np.zeros(0, dtype=int),
        size=6 * (N + 1) + (2 + n_sigma) * N,
        step=Fs,
    )


def solver_options(solver: str, equality: Sequence[bool], max_iterations: int, wall_time_s: float | None,
                   cpu_time_s: float | None = None) -> dict:
    """``nlpsol`` options per solver: quiet, iteration-limited (IPOPT also wall-time-limited)."""
    common = {"expand": True, "print_time": False, "error_on_fail": False}
    if solver == "ipopt":
        ipopt = {"print_level": 0, "sb": "yes", "max_iter": max_iterations, "tol": 1e-6,
                 "mu_strategy": "adaptive", "warm_start_init_point": "no"}
        if wall_time_s is not None:
            ipopt["max_wall_time"] = float(wall_time_s)
        if cpu_time_s is not None:
            ipopt["max_cpu_time"] = float(cpu_time_s)
        return {**common, "ipopt": ipopt}
    if solver == "fatrop":
        return {**common, "structure_detection": "auto", "equality": list(equality), "debug": False,
                "fatrop": {"print_level": 0, "max_iter": max_iterations, "tol": 1e-6, "mu_init": 1e-1}}
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
