"""Benchmark: our whole NMPC step against do-mpc's whole ``make_step``, like for like, in one run.

The same optimal-control problem for every configuration: the scaled KCS prediction model
(RK4, 4 substeps per 20 s interval), N_c = 15, the default weights Q, R, R1 and the DARE
terminal weight, |tau| <= tau_max, 0 <= u <= 24 kn, hard collision constraints at every
RK4 substep (one slot per target, no slack), the same initial state and the same straight
reference at 18 kn.  Each configuration sails its own closed loop (90 steps of 20 s = 30
min) on the same plant model (the numpy 3-DOF KCS, RK4 at 0.5 s), with one target (the
paper's Eq. 32 head-on ship) and with three (head-on, a ship crossing from starboard and
a static obstacle near the track).

What is timed, per control step (``time.perf_counter`` around the call):

* ours: the whole ``NMPCController.solve()``: parameter packing, collision-domain slots,
  warm start (the shifted previous plan), the NLP solve, unpacking, fallback bookkeeping;
  with the watchdog (solver in a forked worker with CPU/wall limits, the default) and
  without it (in-process);
* do-mpc: the whole ``MPC.make_step()`` (its time-varying-parameter callback filling the
  same reference and obstacle slots, its warm start from the previous solution, IPOPT).

Solvers and settings, all in one table:

* IPOPT in both with the same options (tol 1e-6, MUMPS, max_iter 200, adaptive mu, print
  level 0), each tool at its defaults: ours interpreted, in-process, without multipliers
  carried over; do-mpc as it comes (it passes the last multipliers, which IPOPT ignores
  unless ``warm_start_init_point`` is set);
* IPOPT in both, each with its best settings: the last solve's multipliers as the start
  (``warm_start_init_point = yes`` and the same bound pushes and mu_init on both sides;
  ours shifts plan and multipliers by one interval, do-mpc reuses them unshifted, its own
  design), ours compiled (:mod:`rhnc.control.nmpc_codegen`) with and without the watchdog;
* ours with fatrop, compiled and interpreted;
* do-mpc with its own code generation (``compile_nlp``, gcc -O1) with
  ``--do-mpc-compiled`` (its build is cached in the NMPC cache folder; it took 16 minutes
  on this machine);
* ours with acados (:mod:`rhnc.control.nmpc_acados`: SQP, exact Hessian, HPIPM), in this
  process, when its wheel is installed.

Beside each whole step, the backend's own processor time (acados: the one call into C that
sets the stages and runs the SQP; nlpsol: the solver call; do-mpc: IPOPT's
``t_proc_total``) and the ratio of the two: what the Python around the solve costs.

The configurations advance in turn, one control step each, so that a change of the
machine's load during the run falls on all of them alike.  The first control step of every
configuration starts from the same state, so its applied
input tells whether both tools solve the same problem: the table gives its difference
from ours with IPOPT (as a fraction of tau_max).

Run: ``python bench/bench_nmpc.py [--steps 90] [--targets 1 3] [--do-mpc-compiled] [--block K] [--only TEXT ...]``
(needs ``pip install do-mpc``).  The machine's load (``os.getloadavg``) is printed with the
figures: on a shared machine, compare configurations of the same run only.
"""

from __future__ import annotations

import argparse
import contextlib
import math
import os
import time
import warnings

import casadi as ca
import numpy as np

from rhnc.control.nmpc import NMPCController, NMPCSettings, reference_inputs
from rhnc.control.nmpc_codegen import cache_dir
from rhnc.control.nmpc_problem import DISTURBANCE_SIZE, OBSTACLE_FIELDS, WARM_START_IPOPT
from rhnc.navigation.reference_participant import line_or_turn_reference
from rhnc.ship.ship_model import load_parameter_set, rk4_step
from rhnc.encounters.traffic import KNOT, NM

DT_S = 20.0
N = 15
COURSE_RAD = math.radians(45.0)
SPEED_MPS = 18 * KNOT
PLANT_DT_S = 0.5
IPOPT_OPTIONS = {"print_level": 0, "sb": "yes", "tol": 1e-6, "max_iter": 200, "mu_strategy": "adaptive",
                 "linear_solver": "mumps"}


def obstacles_at(t_s: float, targets: int) -> np.ndarray:
    """Rows x, y [m], vx, vy [m/s], radius [m] at ``t_s``: 1 or 3 targets."""
    rows = [[4 * NM - 9 * KNOT * t_s, 4 * NM - 9 * KNOT * t_s, -9 * KNOT, -9 * KNOT, NM]]  # Eq. 32, head-on
    if targets >= 3:
        rows.append([5.0 * NM, 8.0 * NM - 12 * KNOT * t_s, 0.0, -12 * KNOT, 0.8 * NM])  # crossing from starboard
        rows.append([7.5 * NM, 6.0 * NM, 0.0, 0.0, NM])  # static, just to port of the track
    return np.array(rows[:targets])


def reference_at(t_s: float) -> np.ndarray:
    return line_or_turn_reference(t_s + DT_S * np.arange(N + 1), (0.0, 0.0), COURSE_RAD, SPEED_MPS)


def settings(solver: str, targets: int, codegen: bool, watchdog: bool, warm_duals: bool = True) -> NMPCSettings:
    """The benchmark problem for our controller (hard constraints, one slot per target)."""
    limits = {} if watchdog else {"wall_time_limit_s": None, "cpu_time_limit_s": None}
    return NMPCSettings(solver=solver, horizon_steps=N, control_interval_s=DT_S, max_obstacles=targets,
                        collision_slack_weight=None, codegen=codegen, warm_start_duals=warm_duals, **limits)


class ClosedLoop:
    """One configuration's closed loop, advanced one control step at a time.

    ``step(t, state) -> (tau, solver_s, iterations, ok, worker_cpu_s, preparation_s)`` is the
    controller under test (``worker_cpu_s``: processor time spent in the watchdog's worker
    process on the call; ``preparation_s``: processor time spent on the fresh fatrop object
    the call used, outside the solve, which the CPU columns leave out and ``prep`` shows).
    All configurations advance in turn, step by step, so that a change of the machine's
    load during the run falls on all of them alike.
    """

    def __init__(self, step, targets: int, params, codegen: str, close=None) -> None:
        self.step, self.targets, self.params, self.codegen, self.close = step, targets, params, codegen, close
        self.state = np.array([0.0, 0.0, COURSE_RAD, SPEED_MPS, 0.0, 0.0])
        self.wall, self.cpu, self.solver, self.iterations, self.failures, self.taus = [], [], [], [], 0, []
        self.preparation, self.own_cpu = [], []
        self.clearance_m = np.inf
        self.k = 0

    def advance(self) -> None:
        t = self.k * DT_S
        start, cpu_start = time.perf_counter(), time.process_time()
        tau, solver_s, its, ok, worker_cpu_s, preparation_s, own_cpu_s = self.step(t, self.state)
        self.wall.append(time.perf_counter() - start)
        # in this process the preparation is inside the step: counted apart, as in the worker
        in_step = 0.0 if worker_cpu_s else preparation_s
        self.cpu.append(time.process_time() - cpu_start - in_step + worker_cpu_s)
        self.preparation.append(preparation_s)
        self.solver.append(solver_s)
        self.own_cpu.append(own_cpu_s)
        self.iterations.append(its)
        self.failures += 0 if ok else 1
        self.taus.append(np.array(tau, dtype=float))
        for j in range(int(DT_S / PLANT_DT_S)):
            self.state = rk4_step(self.state, tau, PLANT_DT_S, 1, self.params)
            obstacles = obstacles_at(t + PLANT_DT_S * (j + 1), self.targets)
            gaps = np.hypot(self.state[0] - obstacles[:, 0], self.state[1] - obstacles[:, 1]) - obstacles[:, 4]
            self.clearance_m = min(self.clearance_m, float(np.min(gaps)))
        self.k += 1

    def result(self) -> dict:
        return {"wall": np.array(self.wall), "cpu": np.array(self.cpu), "solver": np.array(self.solver), "iterations": np.array(self.iterations),
                "preparation": np.array(self.preparation), "own_cpu": np.array(self.own_cpu),
                "failures": self.failures, "clearance_m": self.clearance_m, "first_tau": self.taus[0],
                "codegen": self.codegen}


def ours(params, solver: str, targets: int, codegen: bool, watchdog: bool, warm_duals: bool = True) -> ClosedLoop:
    controller = NMPCController(params, settings(solver, targets, codegen, watchdog, warm_duals))
    # the backend's own processor time beside our whole step: acados's call into C (the SQP and
    # the setting of its stages), nlpsol's call (in the watchdog's worker when there is one)
    backend_time = getattr(controller.solvers, "backend_time_s", None)

    def step(t, state):
        if t == 0.0:
            controller.reset()
        solution = controller.solve(t, state, reference_at(t), obstacles_at(t, targets), et=True)
        worker_cpu_s = solution.solve_cpu_time_s if watchdog else 0.0
        own_cpu = controller.solvers.backend_time_s if backend_time is not None else solution.solve_cpu_time_s
        return (solution.tau, solution.solve_time_s, solution.iterations, solution.success, worker_cpu_s,
                solution.preparation_cpu_s, own_cpu)

    step(0.0, np.array([0.0, 0.0, COURSE_RAD, SPEED_MPS, 0.0, 0.0]))  # fork the worker, load the solver
    loop = ClosedLoop(step, targets, params, controller.library.mode, controller.close)
    loop.controller = controller
    return loop


def do_mpc_controller(params, targets: int, compiled: bool, warm_duals: bool = False, ipopt_options: dict | None = None):
    """The same OCP in do-mpc (discrete model = our RK4 step, IPOPT), and its step function.

    ``ipopt_options``: further IPOPT options, set after the common ones.
    """
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        import do_mpc

    ref_ctrl = NMPCController(params, settings("ipopt", targets, False, False))  # scales, P, domains
    s = ref_ctrl.settings
    model = do_mpc.model.Model("discrete", "SX")
    z = model.set_variable("_x", "z", shape=(6, 1))
    w = model.set_variable("_u", "w", shape=(2, 1))
    ref = model.set_variable("_tvp", "ref", shape=(6, 1))
    w_d = model.set_variable("_tvp", "w_d", shape=(2, 1))
    obs = model.set_variable("_tvp", "obs", shape=(OBSTACLE_FIELDS * targets, 1))
    z_next, z_sub = ref_ctrl._F_scaled(z, w, ca.DM.zeros(DISTURBANCE_SIZE))
    model.set_rhs("z", z_next)
    q = s.q
    e = z - ref
    model.set_expression("stage", q[0] * e[0] ** 2 + q[1] * e[1] ** 2 + q[2] * 2 * (1 - ca.cos(e[2]))
                         + q[3] * e[3] ** 2 + q[4] * e[4] ** 2 + q[5] * e[5] ** 2)
    model.set_expression("input_cost", s.r[0] * (w[0] - w_d[0]) ** 2 + s.r[1] * (w[1] - w_d[1]) ** 2)
    P = ca.DM(ref_ctrl.terminal_weight(SPEED_MPS))
    cpsi, spsi = ca.cos(ref[2]), ca.sin(ref[2])
    e_path = ca.vertcat(cpsi * e[0] + spsi * e[1], -spsi * e[0] + cpsi * e[1],
                        ca.atan2(ca.sin(e[2]), ca.cos(e[2])), e[3], e[4], e[5])
    model.set_expression("terminal", ca.mtimes([e_path.T, P, e_path]))
    h = s.control_interval_s / s.substeps
    # the tvp carries each stage's slots moved to the stage's start (centre + v k dt, radius
    # + growth k dt), so the substep time here is the time within the interval
    clearances = []
    for j in range(s.substeps):
        for i in range(targets):
            cx, cy, vx, vy, ox, oy, rho, growth, inflation, active = (obs[OBSTACLE_FIELDS * i + f]
                                                                      for f in range(OBSTACLE_FIELDS))
            t_sub = (j + 1) * h
            dx = z_sub[0, j] - (cx + vx * t_sub + ox)
            dy = z_sub[1, j] - (cy + vy * t_sub + oy)
            radius = rho + growth * t_sub
            clearance = (dx**2 + dy**2) / radius**2 - 1.0 - inflation
            clearances.append(-(active * clearance + (1.0 - active)))
    model.set_expression("collision", ca.vertcat(*clearances))
    model.setup()

    mpc = do_mpc.controller.MPC(model)
    mpc.settings.n_horizon = s.horizon_steps
    mpc.settings.t_step = s.control_interval_s
    mpc.settings.store_full_solution = False
    ipopt = {**IPOPT_OPTIONS, **({"warm_start_init_point": "yes", **WARM_START_IPOPT} if warm_duals else {}),
             **(ipopt_options or {})}
    mpc.settings.nlpsol_opts = {"print_time": False, **{f"ipopt.{k}": v for k, v in ipopt.items()}}
    mpc.set_objective(lterm=model.aux["stage"] + model.aux["input_cost"], mterm=model.aux["terminal"])
    mpc.set_rterm(w=np.array(s.r_rate))
    mpc.bounds["lower", "_u", "w"] = -1.0
    mpc.bounds["upper", "_u", "w"] = 1.0
    mpc.bounds["lower", "_x", "z"] = np.array([-np.inf, -np.inf, -np.inf, 0.0, -np.inf, -np.inf])
    mpc.bounds["upper", "_x", "z"] = np.array([np.inf, np.inf, np.inf, s.max_speed_mps / ref_ctrl.speed_scale,
                                               np.inf, np.inf])
    mpc.set_nl_cons("collision", model.aux["collision"], ub=0.0)

    now = {"t": 0.0, "state": np.zeros(6)}
    template = mpc.get_tvp_template()

    def tvp_fun(_t):
        t0, state = now["t"], now["state"]
        origin = state[:2]
        ref_si = reference_at(t0)
        ref_scaled = (ref_si - np.r_[origin, 0, 0, 0, 0]) / ref_ctrl.state_scale
        w_ref = reference_inputs(ref_si, s.control_interval_s, params) / ref_ctrl.input_scale
        closing = max(SPEED_MPS, math.hypot(state[3], state[4])) * 1.25  # as NMPCController.solve
        slots, _ = ref_ctrl.domains.parameters(obstacles_at(t0, targets), state, origin, closing, h,
                                               ref_ctrl.length_scale, True)
        for k in range(s.horizon_steps + 1):
            staged = slots.copy()
            staged[0:2] += staged[2:4] * k * s.control_interval_s
            staged[6] += staged[7] * k * s.control_interval_s
            template["_tvp", k, "ref"] = ref_scaled[k]
            template["_tvp", k, "w_d"] = w_ref[min(k, s.horizon_steps - 1)]
            template["_tvp", k, "obs"] = staged.ravel(order="F")
        return template

    mpc.set_tvp_fun(tvp_fun)
    with warnings.catch_warnings():  # do-mpc's own validity check calls numpy on CasADi values
        warnings.filterwarnings("ignore", category=FutureWarning, module="casadi")
        mpc.setup()
    if compiled:
        folder = cache_dir() / "do-mpc"
        folder.mkdir(parents=True, exist_ok=True)
        import do_mpc.optimizer as optimizer_module

        if not hasattr(optimizer_module, "nlpsol"):  # do-mpc 5.1's compile_nlp calls it without importing it
            optimizer_module.nlpsol = ca.nlpsol
        with contextlib.chdir(folder):
            name = f"nlp_dompc_{targets}"
            mpc.compile_nlp(overwrite=False, cname=f"{name}.c", libname=f"{name}.so")

    def step(t, state):
        now["t"], now["state"] = t, state
        z0 = ref_ctrl._to_scaled(state, state[:2])
        if t == 0.0:
            mpc.reset_history()
            mpc.x0 = z0
            mpc.u0 = params.equilibrium_tau(state[3]) / ref_ctrl.input_scale
            mpc.set_initial_guess()
        w0 = np.array(mpc.make_step(z0)).ravel()
        stats = mpc.solver_stats
        return (w0 * ref_ctrl.input_scale, stats.get("t_wall_total", np.nan), stats.get("iter_count", -1),
                bool(stats.get("success", False)), 0.0, 0.0, stats.get("t_proc_total", np.nan))

    return step


def do_mpc_run(params, targets: int, compiled: bool, warm_duals: bool = False,
               ipopt_options: dict | None = None) -> ClosedLoop:
    step = do_mpc_controller(params, targets, compiled, warm_duals, ipopt_options)
    step(0.0, np.array([0.0, 0.0, COURSE_RAD, SPEED_MPS, 0.0, 0.0]))
    return ClosedLoop(step, targets, params, "compiled" if compiled else "interpreted")


def acados_available() -> str:
    """Why acados is not run here, or "" when its wheel loads (``rhnc.control.nmpc_acados``)."""
    from rhnc.control.nmpc_acados import AcadosUnavailable, load_acados

    try:
        load_acados()
    except AcadosUnavailable as error:
        return str(error)
    return ""


def row(name: str, result: dict, baseline_tau: np.ndarray, tau_max: np.ndarray) -> str:
    wall = result["wall"] * 1e3
    cpu = result["cpu"] * 1e3
    solver = result["solver"] * 1e3
    its = result["iterations"]
    tau_gap = np.max(np.abs(result["first_tau"] - baseline_tau) / tau_max)
    solver_median = f"{np.median(solver):8.2f}" if np.all(np.isfinite(solver)) else f"{'-':>8s}"
    own = result["own_cpu"] * 1e3
    own_median = f"{np.median(own):7.2f}" if np.all(np.isfinite(own)) else f"{'-':>7s}"
    ratio = f"{np.median(cpu) / np.median(own):5.2f}" if np.all(np.isfinite(own)) else f"{'-':>5s}"
    return (f"{name:48s} {np.median(wall):8.2f} {np.percentile(wall, 95):8.2f} {np.max(wall):8.2f} "
            f"{solver_median} {np.median(cpu):7.2f} {np.max(cpu):7.2f} {own_median} {ratio} "
            f"{np.median(result['preparation']) * 1e3:5.2f} "
            f"{np.median(its):5.0f}/{np.max(its):<4d} {result['failures']:5d} "
            f"{result['clearance_m'] / NM:8.2f} {tau_gap:9.1e}")


#: the fastest backend, whose step the absolute goals are about
FASTEST_CONFIGURATION = "ours acados SQP, in-process"
#: the default controller
DEFAULT_CONFIGURATION = "ours fatrop compiled, watchdog"
#: do-mpc's step at its best settings, the speed-up goal's anchor
DO_MPC = "do-mpc ipopt make_step, warm duals"


def verdicts(targets: int, results: dict, others: bool) -> list[str]:
    """The goals this run can judge, each with its figure (processor time) and met / not met."""
    lines = []
    where = "beside other configurations' steps" if others else "alone"
    for name in (FASTEST_CONFIGURATION, DEFAULT_CONFIGURATION):
        ours = results.get(name)
        if ours is None:
            continue
        median, largest = np.median(ours["cpu"]) * 1e3, np.max(ours["cpu"]) * 1e3
        bound = 1.0 if targets == 1 else 1.5
        lines.append(f"{name}: whole step median <= {bound} ms and max <= 10 ms ({where}): {median:.2f} / "
                     f"{largest:.1f} ms, {'met' if median <= bound and largest <= 10.0 else 'not met'}")
        own = np.median(ours["own_cpu"]) * 1e3
        lines.append(f"{name}: whole step within 1.5x of the backend's own call: {median:.2f} / {own:.2f} ms = "
                     f"{median / own:.2f}x, {'met' if median <= 1.5 * own else 'not met'}")
        if DO_MPC in results:
            ratio = np.median(results[DO_MPC]["cpu"]) / np.median(ours["cpu"])
            lines.append(f"{name}: >= 10x faster than {DO_MPC}: {ratio:.1f}x, {'met' if ratio >= 10.0 else 'not met'}")
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=90)
    parser.add_argument("--targets", type=int, nargs="+", default=[1, 3], choices=[1, 3])
    parser.add_argument("--do-mpc-compiled", action="store_true", help="also do-mpc with compile_nlp (gcc -O1)")
    parser.add_argument("--no-do-mpc", action="store_true")
    parser.add_argument("--block", type=int, default=1,
                        help="steps each configuration sails before the next takes its turn (1: step by step; "
                             "the number of steps: each closed loop in one go, its caches its own)")
    parser.add_argument("--only", nargs="+", metavar="TEXT",
                        help="run only the configurations whose name contains one of these texts")
    args = parser.parse_args()
    if args.block < 1:
        parser.error(f"--block must be at least 1, got {args.block}")
    params = load_parameter_set("default")
    load_before = os.getloadavg()
    turns = "step by step" if args.block == 1 else f"in blocks of {args.block} steps"
    print(f"NMPC N_c = {N}, interval {DT_S:.0f} s, {args.steps} closed-loop steps, configurations in turn {turns}; "
          f"{os.cpu_count()} cores; load average {load_before[0]:.1f} / {load_before[1]:.1f} / {load_before[2]:.1f} before")
    configurations = [
        # IPOPT on both sides, each tool at its defaults: no multipliers carried over
        ("ours ipopt interpreted, cold duals, in-process", lambda t: ours(params, "ipopt", t, False, False, False)),
        ("do-mpc ipopt make_step", lambda t: do_mpc_run(params, t, False)),
        # IPOPT on both sides, each with its best settings: the last solve's multipliers
        ("ours ipopt compiled, warm duals, watchdog", lambda t: ours(params, "ipopt", t, True, True)),
        ("ours ipopt compiled, warm duals, in-process", lambda t: ours(params, "ipopt", t, True, False)),
        ("ours ipopt interpreted, warm duals, watchdog", lambda t: ours(params, "ipopt", t, False, True)),
        ("do-mpc ipopt make_step, warm duals", lambda t: do_mpc_run(params, t, False, True)),
        # fatrop (no warm start of the multipliers in its CasADi interface)
        ("ours fatrop compiled, watchdog", lambda t: ours(params, "fatrop", t, True, True)),
        ("ours fatrop compiled, in-process", lambda t: ours(params, "fatrop", t, True, False)),
        ("ours fatrop interpreted, watchdog", lambda t: ours(params, "fatrop", t, False, True)),
    ]
    missing = acados_available()
    if not missing:  # SQP bounded by its iteration limit: in this process, no watchdog
        configurations.append((FASTEST_CONFIGURATION, lambda t: ours(params, "acados", t, True, False)))
    if args.only:
        configurations = [c for c in configurations if any(text in c[0] for text in args.only)]
        if not configurations:
            parser.error(f"--only {' '.join(args.only)}: no configuration's name contains it")
    if args.no_do_mpc:
        configurations = [c for c in configurations if not c[0].startswith("do-mpc")]
    elif args.do_mpc_compiled:
        configurations.append(("do-mpc ipopt compiled make_step, warm duals",
                               lambda t: do_mpc_run(params, t, True, True)))
    for targets in args.targets:
        loops = {name: build(targets) for name, build in configurations}
        for first in range(0, args.steps, args.block):
            for loop in loops.values():  # in turn, a block of steps each
                for _ in range(min(args.block, args.steps - first)):
                    loop.advance()
        results = {}
        for name, loop in loops.items():
            results[name] = loop.result()
            if loop.close is not None:
                loop.close()
        baseline = next(iter(results.values()))["first_tau"]
        print(f"\n{targets} target(s); whole step [ms]: wall median, 95th percentile, max; solver-only wall median; "
              "processor time median and max (this process plus the watchdog's worker); own cpu: median processor "
              "time of the backend's own call (acados: the call into C; nlpsol: the solver call; do-mpc: IPOPT's "
              "t_proc_total), ratio: cpu med / own cpu; prep: median processor "
              "time of the fresh fatrop object, built outside the solve; tau0 diff: first input against the first row's")
        print(f"{'configuration':48s} {'median':>8s} {'p95':>8s} {'max':>8s} {'solver':>8s} {'cpu med':>7s} "
              f"{'cpu max':>7s} {'own cpu':>7s} {'ratio':>5s} {'prep':>5s} {'iter med/max':>10s} "
              f"{'fails':>5s} {'min gap nm':>8s} {'tau0 diff':>9s}")
        for name, result in results.items():
            if result["codegen"] not in name:
                name = f"{name} ({result['codegen']})"
            print(row(name, result, baseline, params.tau_max))
        pairs = [("do-mpc ipopt make_step", "ours ipopt interpreted, cold duals, in-process"),
                 ("do-mpc ipopt make_step, warm duals", "ours ipopt compiled, warm duals, watchdog"),
                 ("do-mpc ipopt make_step, warm duals", "ours ipopt compiled, warm duals, in-process"),
                 ("do-mpc ipopt make_step, warm duals", "ours fatrop compiled, watchdog"),
                 ("do-mpc ipopt make_step", "ours ipopt compiled, warm duals, watchdog"),
                 ("do-mpc ipopt make_step, warm duals", FASTEST_CONFIGURATION)]
        for theirs, mine in pairs:
            if theirs in results and mine in results:
                print(f"  median speed-up, {theirs} / {mine}: "
                      f"{np.median(results[theirs]['wall']) / np.median(results[mine]['wall']):.1f}x wall, "
                      f"{np.median(results[theirs]['cpu']) / np.median(results[mine]['cpu']):.1f}x processor time")
        others = any(not name.startswith("ours fatrop compiled") for name in results)
        for line in verdicts(targets, results, others):
            print(f"  goal: {line}")
    load_after = os.getloadavg()
    print(f"\nload average {load_after[0]:.1f} / {load_after[1]:.1f} / {load_after[2]:.1f} after")
    print(f"acados: {missing or 'run (' + FASTEST_CONFIGURATION + ')'}")
    print("goals: whole step median <= 1.0 ms (1 target) / 1.5 ms (3), max <= 10 ms; >= 10x faster than do-mpc's "
          "make_step; whole step within 1.5x of the backend's own call")


if __name__ == "__main__":
    main()
