"""Benchmark: NMPC solve times (N_c = 15, two obstacles active) per solver, and do-mpc on the same problem.

Closed loop: own ship from (0, 0) nm at 045 deg and 18 kn on a straight reference, the
paper's Eq. 32 head-on target (radius 1 nm) and a static obstacle of 1 nm radius just to
port of the track at (7.5, 6) nm; plant = the numpy model (RK4, 0.5 s); 20 s interval,
90 steps.  Every solver of :mod:`rhnc.nmpc` runs its own closed loop.  Then the same
optimal-control problem (scaled model, weights, DARE terminal weight, bounds, collision
constraints at the RK4 substeps, IPOPT) is built with do-mpc and solved at the states of
the default solver's trajectory, warm-started from its own previous solution.

Run: ``python bench/bench_nmpc.py`` (needs ``pip install do-mpc``).
"""

from __future__ import annotations

import argparse
import math
import time
import warnings

import casadi as ca
import numpy as np

from rhnc.nmpc import OBSTACLE_FIELDS, NMPCController, NMPCSettings, reference_inputs
from rhnc.reference_participant import line_or_turn_reference
from rhnc.ship_model import load_parameter_set, rk4_step
from rhnc.traffic import KNOT, NM

DT = 20.0
N = 15
COURSE = math.radians(45.0)
SPEED = 18 * KNOT


def obstacles_at(t: float) -> np.ndarray:
    target = np.array([4 * NM - 9 * KNOT * t, 4 * NM - 9 * KNOT * t, -9 * KNOT, -9 * KNOT, NM])
    island = np.array([7.5 * NM, 6.0 * NM, 0.0, 0.0, NM])
    return np.vstack([target, island])


def reference_at(t: float) -> np.ndarray:
    return line_or_turn_reference(t + DT * np.arange(N + 1), (0.0, 0.0), COURSE, SPEED)


def closed_loop(solver: str, steps: int, soft: bool = False):
    """Hard collision constraints by default: the same OCP as the do-mpc build below."""
    params = load_parameter_set("default")
    start = time.perf_counter()
    settings = NMPCSettings(solver=solver, horizon_steps=N, control_interval_s=DT, max_obstacles=2,
                            collision_slack_weight=1.0e4 if soft else None)
    controller = NMPCController(params, settings)
    build_s = time.perf_counter() - start
    state = np.array([0.0, 0.0, COURSE, SPEED, 0.0, 0.0])
    states, times, iterations, clearance = [], [], [], np.inf
    for k in range(steps):
        t = k * DT
        states.append(state.copy())
        solution = controller.solve(t, state, reference_at(t), obstacles_at(t), et=True)
        times.append(solution.solve_time_s)
        iterations.append(solution.iterations)
        for j in range(40):
            state = rk4_step(state, solution.tau, 0.5, 1, params)
            obs = obstacles_at(t + 0.5 * (j + 1))
            clearance = min(clearance, float(np.min(np.hypot(state[0] - obs[:, 0], state[1] - obs[:, 1]) - obs[:, 4])))
    return {
        "solver": solver, "build_s": build_s, "times": np.array(times), "iterations": np.array(iterations),
        "fallbacks": controller.fallback_count, "clearance_m": clearance, "states": np.array(states), "controller": controller,
    }


def do_mpc_times(reference_controller: NMPCController, states: np.ndarray):
    """Solve the same OCP with do-mpc (IPOPT) at the given states; wall times of make_step."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        import do_mpc

    c = reference_controller
    s = c.settings
    L = c.length_scale
    model = do_mpc.model.Model("discrete", "SX")
    z = model.set_variable("_x", "z", shape=(6, 1))
    w = model.set_variable("_u", "w", shape=(2, 1))
    ref = model.set_variable("_tvp", "ref", shape=(6, 1))
    w_d = model.set_variable("_tvp", "w_d", shape=(2, 1))
    obs = model.set_variable("_tvp", "obs", shape=(OBSTACLE_FIELDS * s.max_obstacles, 1))
    z_next, z_sub = c._F_scaled(z, w, ca.DM.zeros(5))  # no disturbance estimate
    model.set_rhs("z", z_next)
    q = s.q
    e = z - ref
    stage = q[0] * e[0] ** 2 + q[1] * e[1] ** 2 + q[2] * 2 * (1 - ca.cos(e[2])) + q[3] * e[3] ** 2 + q[4] * e[4] ** 2 + q[5] * e[5] ** 2
    model.set_expression("stage", stage)
    model.set_expression("input_cost", s.r[0] * (w[0] - w_d[0]) ** 2 + s.r[1] * (w[1] - w_d[1]) ** 2)
    P = ca.DM(c.terminal_weight(SPEED))
    cpsi, spsi = ca.cos(ref[2]), ca.sin(ref[2])
    e_path = ca.vertcat(cpsi * e[0] + spsi * e[1], -spsi * e[0] + cpsi * e[1], ca.atan2(ca.sin(e[2]), ca.cos(e[2])), e[3], e[4], e[5])
    model.set_expression("terminal", ca.mtimes([e_path.T, P, e_path]))
    h = s.control_interval_s / s.substeps
    # collision constraints at the substeps; the stage time offset is folded into the tvp
    # (obstacle positions at the stage start), so t_sub is the time within the interval
    clearances = []
    for j in range(s.substeps):
        for i in range(s.max_obstacles):
            cx, cy, vx, vy, ox, oy, rho, growth, inflation, active = (
                obs[OBSTACLE_FIELDS * i + f] for f in range(OBSTACLE_FIELDS))
            t_sub = (j + 1) * h
            dx = z_sub[0, j] - (cx + vx * t_sub + ox)
            dy = z_sub[1, j] - (cy + vy * t_sub + oy)
            radius = rho + growth * t_sub
            clearances.append(-(active * ((dx**2 + dy**2) / radius**2 - 1.0 - inflation) + (1.0 - active)))
    model.set_expression("collision", ca.vertcat(*clearances))
    model.setup()

    mpc = do_mpc.controller.MPC(model)
    mpc.settings.n_horizon = s.horizon_steps
    mpc.settings.t_step = s.control_interval_s
    mpc.settings.store_full_solution = False
    mpc.settings.nlpsol_opts = {"ipopt.print_level": 0, "ipopt.sb": "yes", "print_time": False, "ipopt.tol": 1e-6, "ipopt.max_iter": s.max_iterations, "ipopt.mu_strategy": "adaptive"}
    mpc.set_objective(lterm=model.aux["stage"] + model.aux["input_cost"], mterm=model.aux["terminal"])
    mpc.set_rterm(w=np.array(s.r_rate))
    mpc.bounds["lower", "_u", "w"] = -1.0
    mpc.bounds["upper", "_u", "w"] = 1.0
    mpc.bounds["lower", "_x", "z"] = np.array([-np.inf, -np.inf, -np.inf, 0.0, -np.inf, -np.inf])
    mpc.set_nl_cons("collision", model.aux["collision"], ub=0.0)

    current = {"origin": np.zeros(2), "t0": 0.0}
    tvp_template = mpc.get_tvp_template()

    def tvp_fun(t_now):
        t0 = current["t0"]
        ref_si = reference_at(t0)
        origin = current["origin"]
        ref_scaled = (ref_si - np.r_[origin, 0, 0, 0, 0]) / c.state_scale
        w_ref = reference_inputs(ref_si, s.control_interval_s, c.params) / c.input_scale
        for k in range(s.horizon_steps + 1):
            t_k = t0 + k * s.control_interval_s
            slots = c._obstacle_parameters(obstacles_at(t_k), origin, 1.25 * SPEED, True)
            tvp_template["_tvp", k, "ref"] = ref_scaled[k]
            tvp_template["_tvp", k, "w_d"] = w_ref[min(k, s.horizon_steps - 1)]
            tvp_template["_tvp", k, "obs"] = slots.ravel(order="F")
        return tvp_template

    mpc.set_tvp_fun(tvp_fun)
    mpc.setup()
    times, solver_times, failures = [], [], 0
    for k, state in enumerate(states):
        # positions relative to the state at each solve, as in rhnc.nmpc
        current["origin"] = state[:2].copy()
        current["t0"] = k * s.control_interval_s
        z0 = c._to_scaled(state, state[:2])
        if k == 0:
            mpc.x0 = z0
            mpc.u0 = c.params.equilibrium_tau(SPEED) / c.input_scale
            mpc.set_initial_guess()
        start = time.perf_counter()
        mpc.make_step(z0)
        times.append(time.perf_counter() - start)
        stats = mpc.solver_stats
        solver_times.append(stats.get("t_wall_total", np.nan))
        failures += 0 if stats.get("success", False) else 1
    return np.array(times), np.array(solver_times), failures


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=90)
    parser.add_argument("--no-do-mpc", action="store_true")
    args = parser.parse_args()
    rows = []
    runs = {}
    for solver in ("fatrop", "ipopt", "sqpmethod"):
        run = closed_loop(solver, args.steps)
        runs[solver] = run
        t = run["times"] * 1e3
        rows.append((f"rhnc {solver}", np.median(t), np.max(t), f"{np.median(run['iterations']):.0f}/{np.max(run['iterations'])}", run["fallbacks"], f"{run['clearance_m']:.1f}"))
    soft = closed_loop("fatrop", args.steps, soft=True)
    t = soft["times"] * 1e3
    rows.append(("rhnc fatrop, default", np.median(t), np.max(t),
                 f"{np.median(soft['iterations']):.0f}/{np.max(soft['iterations'])}", soft["fallbacks"],
                 f"{soft['clearance_m']:.1f}"))
    if not args.no_do_mpc:
        wall, solver_wall, failures = do_mpc_times(runs["fatrop"]["controller"], runs["fatrop"]["states"])
        rows.append(("do-mpc ipopt (make_step)", np.median(wall) * 1e3, np.max(wall) * 1e3, "-", failures, "-"))
        if np.any(np.isfinite(solver_wall)):
            rows.append(("do-mpc ipopt (solver only)", np.nanmedian(solver_wall) * 1e3, np.nanmax(solver_wall) * 1e3, "-", failures, "-"))
    print(f"NMPC N_c = {N}, interval {DT:.0f} s, 2 obstacles active, {args.steps} closed-loop steps")
    print(f"{'case':28s} {'median ms':>10s} {'max ms':>9s} {'iter med/max':>13s} {'fails':>6s} {'min clearance m':>16s}")
    for name, median, maximum, its, fails, clearance in rows:
        print(f"{name:28s} {median:10.2f} {maximum:9.2f} {its:>13s} {fails:>6} {clearance:>16s}")
    if not args.no_do_mpc:
        ours = np.median(runs["fatrop"]["times"])
        ours_ipopt = np.median(runs["ipopt"]["times"])
        print(f"median ratio do-mpc make_step / rhnc fatrop: {np.median(wall) / ours:.1f}x; / rhnc ipopt: {np.median(wall) / ours_ipopt:.1f}x")
    print("goals: median <= 5 ms, max <= 50 ms, >= 3x faster than do-mpc")


if __name__ == "__main__":
    main()
