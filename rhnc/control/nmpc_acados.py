"""The NMPC's optimal-control problem solved by acados: SQP with HPIPM, generated code cached.

An optional backend of :class:`rhnc.control.nmpc.NMPCController` (``solver = "acados"``).
The problem is the one :mod:`rhnc.control.nmpc_problem` states for nlpsol, written in
acados's stage-wise form:

* states ``[z (6), w_before (2)]``: the scaled ship state and the input of the interval
  before, so that the input-rate cost ``R1 (w - w_before)²`` is a stage cost; the
  dynamics ``z_next = F_s(z, w, d)`` (the same RK4 step, as a discrete model) and
  ``w_before_next = w``;
* inputs ``[w (2), sigma]``: the scaled forces and, with ``collision_slack_weight``, the
  stage's collision slack (bounded to zero in the hard attempt, free in the relaxed one);
* the cost as acados's external cost: the stage cost and the terminal cost of
  :mod:`rhnc.control.nmpc_problem` (:func:`~rhnc.control.nmpc_problem.stage_cost`,
  :func:`~rhnc.control.nmpc_problem.terminal_cost`), the same expressions, with the terminal
  weight P a parameter; its exact Hessian (see ``HESSIAN``);
* the clearances of every RK4 substep and obstacle slot as nonlinear inequalities ``h >= 0``
  (:func:`rhnc.control.nmpc_problem.clearances`, the same expressions);
* per stage the parameters (reference, feed-forward input, disturbance, obstacle slots,
  the interval's start, whether its state error counts, the terminal weight).

SQP to convergence (tolerance ``ACCEPTABLE_VIOLATION`` on acados's residuals) with the
controller's iteration limit: the solver bounds its own time, so it runs in this process without the watchdog's
worker.  Each solve is one call into C (``nmpc_acados_step.c``): the warm start, the
parameters and bounds of every stage are set there, not by a Python loop.

Packaging.  ``acados`` is not on the package index; ``comma-deps-acados`` (a third-party
wheel of an older acados: libacados, HPIPM, BLASFEO for AVX2 and the template renderer)
is, but it also carries a CasADi of its own, built for Python 3.12, installed as the
top-level ``casadi`` package: installed into the environment it would replace ours.  So it
is installed into a folder of its own (``INSTALL_COMMAND``), found through
``$RHNC_ACADOS_DIR`` (default ``~/.local/share/rhnc-cosim/acados``), and only its
``acados`` package is loaded from there; the code it generates is built with our CasADi.

Generated code is cached like the compiled NLP (:mod:`rhnc.control.nmpc_codegen`): one
folder ``acados_<key>`` in the same cache, keyed by a hash of the problem's functions
(serialized), the solver options, the wheel's version, the CasADi version and the
compiler; building one takes 25-50 s of processor time, once per machine.
"""

from __future__ import annotations

import contextlib
import ctypes
import dataclasses
import hashlib
import importlib.util
import json
import logging
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import casadi as ca
import numpy as np

from orchestrator.errors import ToolchainError
from rhnc.control.nmpc_codegen import _exclusive, cache_dir, find_compiler
from rhnc.control.nmpc_problem import (ACCEPTABLE_VIOLATION, DISTURBANCE_SIZE, FATROP_ACCEPTABLE_TOL,
                                       OBSTACLE_FIELDS, NMPCProblem, clearances, scaled_step, stage_cost,
                                       terminal_cost)
from rhnc.control.solver_watchdog import SolveOutcome

LOG = logging.getLogger(__name__)

#: environment variable naming the folder the acados wheel was installed into
ACADOS_DIR_ENV = "RHNC_ACADOS_DIR"
#: the wheel, pinned: the generated code and the C helper are written against its acados
ACADOS_WHEEL = "comma-deps-acados==0.2.2.post92"
#: default folder of the wheel
DEFAULT_ACADOS_DIR = Path("~/.local/share/rhnc-cosim/acados")
#: how to install it (the one line the error gives)
INSTALL_COMMAND = f"pip install --no-deps --target {DEFAULT_ACADOS_DIR} {ACADOS_WHEEL}"
#: bump when the way solvers are generated changes, so that old folders are not reused
RECIPE_VERSION = "4"
#: acados's infinity: bounds beyond it are treated as absent
ACADOS_INFINITY = 1.0e9
#: SQP status codes (acados's ``ACADOS_*`` return values) as the controller reports them
STATUS = {0: "Solve_Succeeded", 1: "acados_nan_detected", 2: "Maximum_Iterations_Exceeded",
          3: "acados_minimum_step", 4: "acados_qp_failure"}
#: Hessian of the SQP: the exact Hessian of the Lagrangian, its blocks mirrored to positive
#: definite ones where they are not.  The Gauss-Newton Hessian (tried with the cost written
#: as least squares) leaves out the clearances' curvature times their multipliers; it solved
#: the benchmark's closed loops (one and three targets) in the same time, but on a relaxed
#: problem started inside a domain (slack about 1) it ran out of its 200 iterations, full
#: steps or a merit line search alike, where fatrop and the exact Hessian solved it (168
#: iterations, the same slack and cost).  Without the dynamics' second derivatives
#: (``exact_hess_dyn`` off) the benchmark's one-target loop took 5 iterations at the median
#: instead of 2, and longer.
HESSIAN = "EXACT"
REGULARIZATION = "MIRROR"
#: the clearances' second derivatives in that Hessian (times their multipliers): left out.
#: With them every clearance row of every stage needs the RK4 substeps' second derivatives,
#: inactive slots too; without them, on the benchmark's one-target loop with the
#: co-simulation's four slots and slacks, the linearisation took 35 % less time and the SQP
#: fewer iterations (381 against 460 over 90 steps, at most 41 against 64), to inputs within
#: 1.3e-5 of tau_max of the full Hessian's
CONSTRAINT_CURVATURE = False
#: step-length rule: full steps.  A merit line search (MERIT_BACKTRACKING) failed one step
#: of the one-target benchmark loop at 200 iterations that full steps solved in 64
GLOBALIZATION = "FIXED_STEP"
#: acados's status when the SQP ran out of iterations
MAXIMUM_ITERATIONS = 2
#: largest stationarity residual of a point the SQP stopped at after its last iteration for the
#: controller to consider it (as fatrop's acceptable points, with fatrop's acceptable
#: tolerance; the controller uses it only when it keeps every constraint,
#: ``ACCEPTABLE_VIOLATION``).  Seen in Experiment 3a: 200 iterations ending on a feasible plan.
ACCEPTABLE_STATIONARITY = FATROP_ACCEPTABLE_TOL
#: QP iterations allowed per SQP iteration (HPIPM)
QP_ITERATIONS = 50
#: HPIPM's mode and warm start (1: from the last QP's solution).  On the benchmark's one-target
#: loop with four slots and slacks, SPEED with the warm start took the QPs from 1.21 to 0.70
#: ms median (its default, BALANCE, without warm start), the same 381 SQP iterations, inputs
#: within 1.3e-5 of tau_max (SPEED_ABS failed 26 of its 90 steps)
QP_MODE = "SPEED"
QP_WARM_START = 1
#: the C file compiled beside every generated solver
STEP_SOURCE = Path(__file__).with_name("nmpc_acados_step.c")


class AcadosUnavailable(ToolchainError):
    """acados was asked for and cannot be loaded: one line naming the option and the install."""

    exit_code = 2


def acados_folder() -> Path:
    """The folder the wheel was installed into (``$RHNC_ACADOS_DIR`` or the default)."""
    return Path(os.environ.get(ACADOS_DIR_ENV) or DEFAULT_ACADOS_DIR).expanduser()


def load_acados():
    """The wheel's ``acados`` package (its template and the C library's paths), or AcadosUnavailable."""
    if "acados" in sys.modules:
        return sys.modules["acados"]
    package = acados_folder() / "acados"
    init = package / "__init__.py"
    if not init.is_file():
        raise AcadosUnavailable(
            f"solver = 'acados' needs acados, not found in {package.parent} (${ACADOS_DIR_ENV}); "
            f"install it with: {INSTALL_COMMAND}")
    spec = importlib.util.spec_from_file_location("acados", init, submodule_search_locations=[str(package)])
    module = importlib.util.module_from_spec(spec)
    sys.modules["acados"] = module
    try:
        spec.loader.exec_module(module)
        import acados.acados_template  # noqa: F401  (the template, with our CasADi)
    except Exception as error:  # noqa: BLE001 - any failure to load is the same message to the user
        sys.modules.pop("acados", None)
        raise AcadosUnavailable(f"solver = 'acados': loading {package} failed ({type(error).__name__}: {error}); "
                                f"install it with: {INSTALL_COMMAND}") from error
    return module


@dataclasses.dataclass(frozen=True)
class AcadosLayout:
    """Where the NLP's decision and parameter vectors sit in acados's stage-wise arrays."""

    N: int
    n_sigma: int
    nx: int
    nu: int
    n_stage_parameters: int  # per stage
    stage_parameters: np.ndarray  # (N+1, np) indices into [p, constants]
    constants: np.ndarray  # t0 of every stage, then 0 and 1 (state_on)
    n_nlp_parameters: int  # length of the NLP's parameter vector
    w_prev: np.ndarray  # indices of w_prev in the NLP's parameter vector

    @staticmethod
    def of(problem: NMPCProblem, control_interval_s: float, max_obstacles: int) -> "AcadosLayout":
        N = problem.w_index.shape[0]
        n_sigma = 1 if problem.sigma_index.size else 0
        M = max_obstacles
        ref0, wd0 = 0, 6 * (N + 1)
        wprev0 = wd0 + 2 * N
        P0 = wprev0 + 2
        d0 = P0 + 36
        obs0 = d0 + DISTURBANCE_SIZE
        n_p = obs0 + OBSTACLE_FIELDS * M
        constants = np.concatenate([control_interval_s * np.arange(N + 1), [0.0, 1.0]])
        rows = []
        for k in range(N + 1):
            row = list(range(ref0 + 6 * k, ref0 + 6 * k + 6))
            row += list(range(wd0 + 2 * min(k, N - 1), wd0 + 2 * min(k, N - 1) + 2))
            row += list(range(d0, d0 + DISTURBANCE_SIZE)) + list(range(obs0, obs0 + OBSTACLE_FIELDS * M))
            row += [n_p + k, n_p + N + 1 + (0 if k == 0 else 1)]
            row += list(range(P0, P0 + 36))
            rows.append(row)
        stage = np.array(rows)
        return AcadosLayout(N=N, n_sigma=n_sigma, nx=8, nu=2 + n_sigma, n_stage_parameters=stage.shape[1],
                            stage_parameters=stage, constants=constants, n_nlp_parameters=n_p,
                            w_prev=np.arange(wprev0, wprev0 + 2))


def stage_symbols(M: int):
    """The stage parameter vector's parts: ref, w_d, d, obs (10 x M), t0, state_on, P (6 x 6)."""
    p = ca.SX.sym("p", 6 + 2 + DISTURBANCE_SIZE + OBSTACLE_FIELDS * M + 2 + 36)
    ref, w_d, dist = p[0:6], p[6:8], p[8:8 + DISTURBANCE_SIZE]
    o = 8 + DISTURBANCE_SIZE
    obs = ca.reshape(p[o:o + OBSTACLE_FIELDS * M], OBSTACLE_FIELDS, M)
    t0, state_on = p[o + OBSTACLE_FIELDS * M], p[o + OBSTACLE_FIELDS * M + 1]
    P = ca.reshape(p[o + OBSTACLE_FIELDS * M + 2:], 6, 6)  # column-major, as the NLP's vec(P)
    return p, ref, w_d, dist, obs, t0, state_on, P


def acados_model(name: str, params, settings, state_scale: np.ndarray, input_scale: np.ndarray):
    """The stage model of the OCP: dynamics, the NLP's stage and terminal costs, clearances (module docstring)."""
    from acados.acados_template import AcadosModel

    s = settings
    S, M = s.substeps, s.max_obstacles + s.coastline_slots
    n_sigma = 0 if s.collision_slack_weight is None else 1
    Fs = scaled_step(params, s.control_interval_s, S, state_scale, input_scale)
    x = ca.SX.sym("x", 8)
    u = ca.SX.sym("u", 2 + n_sigma)
    p, ref, w_d, dist, obs, t0, state_on, P = stage_symbols(M)
    z, w_before, w, sigma = x[0:6], x[6:8], u[0:2], u[2:2 + n_sigma]
    z_next, z_sub = Fs(z, w, dist)
    model = AcadosModel()
    model.name = name
    model.x, model.u, model.p = x, u, p
    model.disc_dyn_expr = ca.vertcat(z_next, w)
    model.cost_expr_ext_cost = stage_cost(z, w, sigma, w_before, ref, w_d, state_on, s.q, s.r, s.r_rate,
                                          s.collision_slack_weight)
    model.cost_expr_ext_cost_e = terminal_cost(z, ref, P)
    relax = sigma[0] if n_sigma else 0.0
    model.con_h_expr = clearances(z_sub, obs, t0, s.control_interval_s / S, S, M) + relax
    return model


def acados_ocp(acados, name: str, params, settings, state_scale: np.ndarray, input_scale: np.ndarray,
               max_iterations: int):
    """The NMPC's OCP as an ``AcadosOcp`` (module docstring), code to be generated as ``name``."""
    from acados.acados_template import AcadosOcp

    s = settings
    N = s.horizon_steps
    n_sigma = 0 if s.collision_slack_weight is None else 1
    model = acados_model(name, params, s, state_scale, input_scale)
    ocp = AcadosOcp(acados_path=str(Path(acados.DIR)))
    ocp.model = model
    ocp.dims.N = N
    nh = model.con_h_expr.shape[0]
    ocp.cost.cost_type = "EXTERNAL"
    ocp.cost.cost_type_e = "EXTERNAL"
    ocp.parameter_values = np.zeros(model.p.shape[0])
    ocp.constraints.x0 = np.zeros(8)
    ocp.constraints.idxbu = np.arange(2 + n_sigma)
    ocp.constraints.lbu = np.zeros(2 + n_sigma)
    ocp.constraints.ubu = np.zeros(2 + n_sigma)
    ocp.constraints.idxbx = np.array([2, 3])  # heading (Rules 8, 14-17 bounds), surge speed
    ocp.constraints.lbx = np.zeros(2)
    ocp.constraints.ubx = np.zeros(2)
    ocp.constraints.idxbx_e = np.array([2, 3])
    ocp.constraints.lbx_e = np.zeros(2)
    ocp.constraints.ubx_e = np.zeros(2)
    ocp.constraints.lh = np.zeros(nh)
    ocp.constraints.uh = np.full(nh, ACADOS_INFINITY)
    o = ocp.solver_options
    # acados weighs each stage's cost by the stage's time step; the model is discrete (its
    # own interval inside), so steps of 1 keep the NLP's cost as it is
    o.tf = float(N)
    o.integrator_type = "DISCRETE"
    o.nlp_solver_type = "SQP_RTI" if s.real_time_iterations else "SQP"
    o.globalization = GLOBALIZATION
    o.hessian_approx = HESSIAN
    o.regularize_method = REGULARIZATION
    o.exact_hess_constr = int(CONSTRAINT_CURVATURE)
    o.qp_solver = "PARTIAL_CONDENSING_HPIPM"
    o.qp_solver_iter_max = QP_ITERATIONS
    o.hpipm_mode = QP_MODE
    o.qp_solver_warm_start = QP_WARM_START
    o.nlp_solver_max_iter = max_iterations
    o.nlp_solver_tol_stat = ACCEPTABLE_VIOLATION
    o.nlp_solver_tol_eq = ACCEPTABLE_VIOLATION
    o.nlp_solver_tol_ineq = ACCEPTABLE_VIOLATION
    o.nlp_solver_tol_comp = ACCEPTABLE_VIOLATION
    o.print_level = 0
    o.ext_fun_compile_flags = "-O2"
    return ocp


def constraint_function(nlp: dict) -> ca.Function:
    """``rhnc_nlp_g(x, p) -> g``: the NLP's constraints at a point of its decision vector (the
    controller's check of a plan, compiled beside the solver: interpreted it cost 0.1 ms a step)."""
    return ca.Function("rhnc_nlp_g", [nlp["x"], nlp["p"]], [nlp["g"]])


def solver_key(ocp, compiler: str, nlp: dict) -> str:
    """Hash of what the generated solver is made from (module docstring)."""
    model = ocp.model
    functions = [ca.Function("f", [model.x, model.u, model.p], [expr])
                 for expr in (model.disc_dyn_expr, model.cost_expr_ext_cost, model.cost_expr_ext_cost_e,
                              model.con_h_expr)]
    functions.append(constraint_function(nlp))
    digest = hashlib.sha256()
    settings = {part: {key: repr(value) for key, value in sorted(vars(getattr(ocp, part)).items())}
                for part in ("solver_options", "dims", "cost", "constraints")}
    for part in (RECIPE_VERSION, ACADOS_WHEEL, ca.__version__, compiler, json.dumps(settings, sort_keys=True),
                 STEP_SOURCE.read_text()):
        digest.update(part.encode())
        digest.update(b"\0")
    for function in functions:
        digest.update(function.serialize().encode())
    return digest.hexdigest()


def _quiet_call(function, *args, **kwargs):
    """Run a template function with its prints sent to the log (the template prints progress)."""
    with tempfile.TemporaryFile(mode="w+") as sink:
        with contextlib.redirect_stdout(sink):
            result = function(*args, **kwargs)
        sink.seek(0)
        text = sink.read().strip()
    if text:
        LOG.debug("acados template: %s", text[-2000:])
    return result


def build_solver(acados, ocp, folder: Path, compiler: str, nlp: dict) -> None:
    """Generate the solver's C, compile it, the step helper and the NLP's constraint function
    into ``folder`` (atomically)."""
    from acados.acados_template import AcadosOcpSolver

    partial = folder.with_name(f".{folder.name}.{os.getpid()}.tmp")
    shutil.rmtree(partial, ignore_errors=True)
    partial.mkdir(parents=True)
    try:
        ocp.code_export_directory = str(partial / "c_generated_code")
        environment = {"ACADOS_SOURCE_DIR": acados.DIR, "TERA_PATH": acados.TERA_PATH,
                       "ACADOS_PYTHON_INTERFACE_PATH": acados.TEMPLATE_DIR}
        saved = {key: os.environ.get(key) for key in environment}
        os.environ.update(environment)
        try:
            with contextlib.chdir(partial):
                _quiet_call(AcadosOcpSolver.generate, ocp, json_file=str(partial / "ocp.json"))
                _quiet_call(AcadosOcpSolver.build, ocp.code_export_directory, verbose=False)
        finally:
            for key, value in saved.items():
                if value is None:
                    os.environ.pop(key, None)
                else:
                    os.environ[key] = value
        library = Path(ocp.code_export_directory) / f"libacados_ocp_solver_{ocp.model.name}.so"
        if not library.is_file():
            raise RuntimeError(f"acados did not build {library.name} (see the log at debug level)")
        shutil.move(str(library), partial / library.name)
        lib = acados.LIB_DIR
        subprocess.run([compiler, "-O2", "-fPIC", "-shared", "-o", str(partial / "rhnc_acados_step.so"),
                        str(STEP_SOURCE), f"-I{acados.INCLUDE_DIR}", f"-I{acados.INCLUDE_DIR}/blasfeo/include",
                        f"-I{acados.INCLUDE_DIR}/hpipm/include", f"-L{lib}", f"-Wl,-rpath,{lib}", "-lacados",
                        "-lhpipm", "-lblasfeo", "-lm"], check=True, capture_output=True, text=True)
        generator = ca.CodeGenerator("rhnc_nlp_g.c", {"with_header": False})
        generator.add(constraint_function(nlp))
        source = generator.generate(str(partial) + os.sep)
        subprocess.run([compiler, "-O2", "-fPIC", "-shared", "-o", str(partial / "rhnc_nlp_g.so"), source],
                       check=True, capture_output=True, text=True)
        shutil.rmtree(partial / "c_generated_code", ignore_errors=True)
        os.replace(partial, folder)
    finally:
        shutil.rmtree(partial, ignore_errors=True)


class AcadosLibrary:
    """The generated solver of one problem, built once per machine and cached (module docstring).

    Attributes
    ----------
    mode, path, build_time_s, reason
        As :class:`rhnc.control.nmpc_codegen.NLPLibrary` (``mode`` is always ``"compiled"``).
    """

    builds = 0

    def __init__(self, params, settings, state_scale, input_scale, nlp: dict) -> None:
        acados = load_acados()
        compiler = find_compiler()
        if compiler is None:
            raise AcadosUnavailable("solver = 'acados' needs a C compiler ($CC, cc, gcc or clang); none found")
        self.acados = acados
        self.real_time_iterations = settings.real_time_iterations
        probe = acados_ocp(acados, "rhnc_nmpc", params, settings, state_scale, input_scale, settings.max_iterations)
        key = solver_key(probe, compiler, nlp)
        self.name = f"rhnc_nmpc_{key[:10]}"
        self.path = cache_dir() / f"acados_{key[:24]}"
        self.build_time_s: float | None = None
        self.mode, self.reason = "compiled", ""
        if not self.path.is_dir():
            self.path.parent.mkdir(parents=True, exist_ok=True)
            with _exclusive(self.path.parent / f"{self.path.name}.lock"):
                if not self.path.is_dir():
                    start = time.perf_counter()
                    LOG.info("NMPC: generating and compiling the acados solver into %s (once per machine; "
                             "under a minute)", self.path)
                    ocp = acados_ocp(acados, self.name, params, settings, state_scale, input_scale,
                                     settings.max_iterations)
                    build_solver(acados, ocp, self.path, compiler, nlp)
                    AcadosLibrary.builds += 1
                    self.build_time_s = time.perf_counter() - start
        for dependency in ("libblasfeo.so", "libhpipm.so", "libqpOASES_e.so.3.1"):
            ctypes.CDLL(os.path.join(acados.LIB_DIR, dependency))
        libacados = ctypes.CDLL(os.path.join(acados.LIB_DIR, "libacados.so"))
        self.acados_options_set = libacados.ocp_nlp_solver_opts_set
        self.acados_options_set.restype = None
        self.acados_options_set.argtypes = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_char_p, ctypes.c_void_p]
        self.solver_library = ctypes.CDLL(str(self.path / f"libacados_ocp_solver_{self.name}.so"))
        self.step_library = ctypes.CDLL(str(self.path / "rhnc_acados_step.so"))
        self.constraints = ca.external("rhnc_nlp_g", str(self.path / "rhnc_nlp_g.so"))
        step = self.step = self.step_library.rhnc_acados_step
        step.restype = ctypes.c_int
        step.argtypes = [ctypes.c_void_p] * 8 + [ctypes.c_int] * 6 + [ctypes.c_void_p] * 10

    def function(self, suffix: str, restype=ctypes.c_void_p, argtypes=(ctypes.c_void_p,)):
        function = getattr(self.solver_library, f"{self.name}_acados_{suffix}")
        function.restype, function.argtypes = restype, list(argtypes)
        return function

    def summary(self) -> dict:
        return {"codegen": self.mode, "codegen_library": str(self.path), "codegen_build_s": self.build_time_s,
                "codegen_note": None}


class AcadosSolver:
    """One acados solver object (its own memory: iterate, multipliers) of an :class:`AcadosLibrary`.

    Its arguments live in arrays allocated once (``p``, ``x``, ``u``, bounds), filled in
    place by the caller; a solve is one call into C with their addresses, bound once.
    """

    def __init__(self, library: AcadosLibrary, layout: AcadosLayout, max_iterations: int) -> None:
        self.library, self.layout = library, layout
        self.capsule = library.function("create_capsule", argtypes=())()
        if library.function("create", ctypes.c_int)(self.capsule) != 0:
            raise RuntimeError("acados: creating the solver failed")
        get = {name: library.function(f"get_nlp_{name}")(self.capsule)
               for name in ("config", "dims", "in", "out", "solver", "opts")}
        if not library.real_time_iterations:  # one iteration per solve has no limit to set
            limit = ctypes.c_int(max_iterations)
            library.acados_options_set(get["config"], get["opts"], b"max_iter", ctypes.byref(limit))
        self._free = (library.function("free", ctypes.c_int), library.function("free_capsule", ctypes.c_int))
        L = layout
        self.p = np.zeros((L.N + 1, L.n_stage_parameters))
        self.x = np.zeros((L.N + 1, L.nx))
        self.u = np.zeros((L.N, L.nu))
        self.lbx0, self.ubx0 = np.zeros(L.nx), np.zeros(L.nx)
        # each side's bounds in one array (the states' of stages 1..N, then the inputs'), so
        # that one indexing fills it; lbx, lbu (ubx, ubu) are views into it
        self.lower, self.upper = np.zeros(L.N * (2 + L.nu)), np.zeros(L.N * (2 + L.nu))
        self.lbx, self.lbu = self.lower[:2 * L.N].reshape(L.N, 2), self.lower[2 * L.N:].reshape(L.N, L.nu)
        self.ubx, self.ubu = self.upper[:2 * L.N].reshape(L.N, 2), self.upper[2 * L.N:].reshape(L.N, L.nu)
        self.info = np.zeros(8)
        arrays = (self.x, self.u, self.p, self.lbx0, self.ubx0, self.lbx, self.ubx, self.lbu, self.ubu, self.info)
        self._arguments = (
            self.capsule, ctypes.cast(library.function("update_params", ctypes.c_int), ctypes.c_void_p),
            ctypes.cast(library.function("solve", ctypes.c_int), ctypes.c_void_p), get["config"], get["dims"],
            get["in"], get["out"], get["solver"], L.N, L.nx, L.nu, L.n_stage_parameters, 2, L.nu,
            *(array.ctypes.data for array in arrays))

    def __call__(self) -> int:
        """Solve from the arrays as they are filled; ``x``, ``u`` and ``info`` then hold the answer."""
        return self.library.step(*self._arguments)

    def close(self) -> None:
        if self.capsule is not None:
            self._free[0](self.capsule)
            self._free[1](self.capsule)
            self.capsule = None

    def __del__(self) -> None:
        with contextlib.suppress(Exception):
            self.close()


class AcadosSolvers:
    """The attempts' acados solvers behind the interface of :class:`rhnc.control.solver_watchdog.BoundedSolver`.

    ``solve(name, x0=, p=, lbx=, ubx=, lbg=, ubg=)`` takes the NLP's arguments as
    :mod:`rhnc.control.nmpc_problem` lays them out, hands them to acados stage by stage (index
    arrays, no Python loop) and returns a :class:`SolveOutcome` in the same layout.  The
    constraint bounds ``lbg``/``ubg`` are fixed by construction (dynamics = 0, clearances
    >= 0) and not read.  No worker process: the SQP's iteration limit bounds the solve.
    """

    in_worker = False

    def __init__(self, library: AcadosLibrary, problem: NMPCProblem, layout: AcadosLayout,
                 iterations: dict[str, int]) -> None:
        self.library, self.problem, self.layout = library, problem, layout
        self.iterations = dict(iterations)
        self.factories = dict.fromkeys(iterations)
        self._solvers: dict[str, AcadosSolver] = {}
        self.wall_time_s = None
        self.cpu_time_s = None
        self.timeouts = 0
        #: processor time of the last solve's call into C [s]: acados's own share of the step
        self.backend_time_s = float("nan")
        self._g_buffer = _Buffered(library.constraints)
        z, w, sigma = problem.z_index, problem.w_index, problem.sigma_index
        self._z, self._w, self._sigma = z, w, sigma
        self._bounded = np.concatenate([z[1:, 2:4].ravel(), (np.column_stack([w, sigma]) if sigma.size
                                                              else w).ravel()])
        self._inputs = np.column_stack([w, sigma]) if sigma.size else w
        # [p, constants]: what the stage parameters are taken from
        self._extended = np.concatenate([np.zeros(layout.n_nlp_parameters), layout.constants])

    def start(self) -> None:
        """Nothing to start: the solves run in this process."""

    def close(self) -> None:
        for solver in self._solvers.values():
            solver.close()
        self._solvers.clear()

    def solver(self, name: str) -> AcadosSolver:
        solver = self._solvers.get(name)
        if solver is None:
            solver = self._solvers[name] = AcadosSolver(self.library, self.layout, self.iterations[name])
        return solver

    def solve(self, name: str, x0, p, lbx, ubx, lbg=None, ubg=None, **_duals) -> SolveOutcome:
        start, cpu_start = time.perf_counter(), time.process_time()
        layout = self.layout
        solver = self.solver(name)
        w_prev = p[layout.w_prev]
        extended = self._extended
        extended[:p.size] = p
        np.take(extended, layout.stage_parameters, out=solver.p)
        x, u = solver.x, solver.u
        x[:, 0:6] = x0[self._z]
        x[0, 6:8] = w_prev
        x[1:, 6:8] = x0[self._w]
        u[:] = x0[self._inputs]
        solver.lbx0[:6], solver.lbx0[6:] = lbx[self._z[0]], w_prev
        solver.ubx0[:6], solver.ubx0[6:] = ubx[self._z[0]], w_prev
        for bound, values in ((solver.lower, lbx), (solver.upper, ubx)):
            np.take(values, self._bounded, out=bound)
            np.maximum(np.minimum(bound, ACADOS_INFINITY, out=bound), -ACADOS_INFINITY, out=bound)
        backend_start = time.process_time()
        status = solver()
        self.backend_time_s = time.process_time() - backend_start
        solution = np.empty(self.problem.size)
        solution[self._z] = x[:, 0:6]
        solution[self._inputs] = u
        g = self._g_buffer(solution, p)
        info = solver.info
        acceptable = status == MAXIMUM_ITERATIONS and float(info[4]) <= ACCEPTABLE_STATIONARITY
        return SolveOutcome(x=solution, g=g, f=float(info[3]), success=status == 0,
                            iterations=int(info[1]), status=STATUS.get(status, f"acados_status_{status}"),
                            wall_time_s=time.perf_counter() - start, cpu_time_s=time.process_time() - cpu_start,
                            lam_x=None, lam_g=None, acceptable=acceptable)


class _Buffered:
    """A CasADi function of numpy arrays through its argument buffers (one output)."""

    def __init__(self, function: ca.Function) -> None:
        self._arguments = [np.zeros(function.numel_in(i)) for i in range(function.n_in())]
        self._result = np.zeros(function.numel_out(0))
        self._buffer, self._evaluate = function.buffer()
        for i, array in enumerate(self._arguments):
            self._buffer.set_arg(i, array.data)  # type: ignore[call-arg]
        self._buffer.set_res(0, self._result.data)  # type: ignore[call-arg]

    def __call__(self, *values) -> np.ndarray:
        for array, value in zip(self._arguments, values):
            array[:] = value
        self._evaluate()
        return self._result.copy()
