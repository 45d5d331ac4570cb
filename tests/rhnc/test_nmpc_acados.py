"""The acados backend: the same plans as fatrop on the same problem, its cache, its error when missing.

The tests that solve need acados (``rhnc.control.nmpc_acados.INSTALL_COMMAND``) and are
skipped with the reason without it; the controllers are built once per module (generating and
compiling a solver takes 25-50 s the first time on a machine, then it is read from the cache).
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest

from orchestrator.cli import main
from orchestrator.geometry import KNOT, NM
from rhnc.control import nmpc_acados
from rhnc.control.nmpc import NMPCController, NMPCSettings
from rhnc.control.nmpc_acados import AcadosUnavailable
from rhnc.ship.ship_model import load_parameter_set, rk4_step

DT_S, N = 20.0, 15
COURSE_RAD = math.radians(45.0)
SPEED_MPS = 18 * KNOT
ROOT = Path(__file__).resolve().parents[2]


def _acados_missing() -> str:
    try:
        nmpc_acados.load_acados()
    except AcadosUnavailable as error:
        return str(error)
    return ""


MISSING = _acados_missing()
needs_acados = pytest.mark.skipif(bool(MISSING), reason=f"acados not installed: {MISSING}")


def reference_at(t_s: float) -> np.ndarray:
    """A straight reference at 18 kn on a course of 045 from the origin, at the horizon's nodes."""
    times = t_s + DT_S * np.arange(N + 1)
    distance = SPEED_MPS * times
    return np.column_stack([distance * math.cos(COURSE_RAD), distance * math.sin(COURSE_RAD),
                            np.full(N + 1, COURSE_RAD), np.full(N + 1, SPEED_MPS), np.zeros(N + 1), np.zeros(N + 1)])


def head_on(t_s: float) -> np.ndarray:
    """The paper's head-on target (Eq. 32): from (4, 4) nm on the reciprocal course at 9 kn."""
    return np.array([[4 * NM - 9 * KNOT * t_s, 4 * NM - 9 * KNOT * t_s, -9 * KNOT, -9 * KNOT, NM]])


def settings(solver: str, slack: float | None) -> NMPCSettings:
    return NMPCSettings(solver=solver, horizon_steps=N, control_interval_s=DT_S, max_obstacles=1,
                        collision_slack_weight=slack, wall_time_limit_s=None, cpu_time_limit_s=None)


@pytest.fixture(scope="module")
def params():
    return load_parameter_set("default")


@pytest.fixture(scope="module")
def pair(params):
    """fatrop and acados controllers of the benchmark problem (hard constraints), built once."""
    if MISSING:
        pytest.skip(f"acados not installed: {MISSING}")
    return NMPCController(params, settings("fatrop", None)), NMPCController(params, settings("acados", None))


def closed_loop(controller, params, steps: int) -> tuple[list, list]:
    """Plans and applied inputs of ``steps`` control steps of a closed loop past the head-on target."""
    controller.reset()
    state = np.array([0.0, 0.0, COURSE_RAD, SPEED_MPS, 0.0, 0.0])
    plans, solutions = [], []
    for k in range(steps):
        t = k * DT_S
        solution = controller.solve(t, state, reference_at(t), head_on(t), et=True)
        plans.append(solution.states.copy())
        solutions.append(solution)
        state = rk4_step(state, solution.tau, DT_S, 40, params)
    return plans, solutions


@needs_acados
def test_acados_sails_the_closed_loop_of_fatrop_past_a_head_on_target(pair, params):
    """The same OCP: over 25 steps (the target's domain active from about step 12) every applied
    input within 1e-3 of tau_max of fatrop's and every planned position within 1 m."""
    fatrop, acados = pair
    plans_f, solutions_f = closed_loop(fatrop, params, 25)
    plans_a, solutions_a = closed_loop(acados, params, 25)
    assert all(s.success for s in solutions_a) and all(s.success for s in solutions_f)
    taus = np.array([(a.tau - f.tau) / params.tau_max for a, f in zip(solutions_a, solutions_f)])
    assert np.max(np.abs(taus)) < 1e-3
    assert max(np.max(np.hypot(*(a[:, :2] - f[:, :2]).T)) for a, f in zip(plans_a, plans_f)) < 1.0
    # the plans turn away from the target (not a trivial straight line) and report a cost like fatrop's
    assert max(abs(a.tau[1]) for a in solutions_a) > 0.1 * params.tau_max[1]
    assert abs(solutions_a[15].cost - solutions_f[15].cost) < 1e-4 * max(1.0, abs(solutions_f[15].cost))
    assert max(s.constraint_violation for s in solutions_a) < 1e-6


@needs_acados
def test_acados_relaxes_the_clearance_with_the_slack_fatrop_finds(params):
    """Started inside the target's domain, the hard problem has no solution: both backends give
    the plan of the relaxed problem, with the same slack and the same first input."""
    fatrop = NMPCController(params, settings("fatrop", 1.0e4))
    acados = NMPCController(params, settings("acados", 1.0e4))
    state = np.array([0.0, 0.0, COURSE_RAD, SPEED_MPS, 0.0, 0.0])
    target = np.array([[0.3 * NM, 0.3 * NM, -9 * KNOT, -9 * KNOT, NM]])
    f = fatrop.solve(0.0, state, reference_at(0.0), target, et=True)
    a = acados.solve(0.0, state, reference_at(0.0), target, et=True)
    assert f.success and a.success and f.collision_slack > 0.0
    assert a.collision_slack == pytest.approx(f.collision_slack, rel=1e-3)
    assert np.max(np.abs(a.tau - f.tau) / params.tau_max) < 1e-3
    assert a.cost == pytest.approx(f.cost, rel=1e-4)


@needs_acados
def test_a_second_controller_of_the_same_problem_reads_the_cached_solver(pair, params):
    builds = nmpc_acados.AcadosLibrary.builds
    again = NMPCController(params, settings("acados", None))
    assert nmpc_acados.AcadosLibrary.builds == builds and again.library.build_time_s is None
    assert again.library.path == pair[1].library.path and again.library.summary()["codegen"] == "compiled"


@needs_acados
def test_the_solver_key_changes_with_the_problem(params):
    acados = nmpc_acados.load_acados()
    scale, inputs = np.array([230.0, 230.0, 1.0, 1.0, 1.0, 1.0 / 230.0]), params.tau_max
    from rhnc.control.nmpc_problem import build_problem

    def key(**changes):
        s = NMPCSettings(**{**dict(solver="acados", horizon_steps=N, control_interval_s=DT_S, max_obstacles=1),
                            **changes})
        problem = build_problem(params, s.horizon_steps, s.control_interval_s, s.substeps, s.max_obstacles, s.q,
                                s.r, s.r_rate, s.collision_slack_weight, scale, inputs)
        ocp = nmpc_acados.acados_ocp(acados, "probe", params, s, scale, inputs, s.max_iterations)
        return nmpc_acados.solver_key(ocp, "cc", problem.nlp)

    first = key()
    assert key() == first
    assert key(q=(0.2, 0.1, 10.0, 1.0, 1.0, 1.0)) != first
    assert key(max_obstacles=2) != first


def test_without_acados_a_run_asking_for_it_stops_with_the_option_and_the_install_command(tmp_path, monkeypatch,
                                                                                       capsys):
    monkeypatch.setenv(nmpc_acados.ACADOS_DIR_ENV, str(tmp_path / "nowhere"))
    monkeypatch.delitem(sys.modules, "acados", raising=False)
    code, error = _run_with_options(tmp_path, capsys, 'solver = "acados"')
    assert code == 2
    assert len(error) == 1 and "option 'solver'" in error[0] and nmpc_acados.INSTALL_COMMAND in error[0]
    assert str(tmp_path / "nowhere") in error[0] and not (tmp_path / "results").exists()


def _run_with_options(tmp_path, capsys, lines: str) -> tuple[int, list[str]]:
    """Run Experiment 3b with ``lines`` added to the controller's options: exit code, stderr lines."""
    text = (ROOT / "scenarios" / "exp3b_head_on.toml").read_text()
    scenario = ROOT / "scenarios" / f".test_acados_options_{tmp_path.name}.toml"
    scenario.write_text(text.replace("[participants.ctrl.options]\n", f"[participants.ctrl.options]\n{lines}\n"))
    try:
        code = main(["run", str(scenario), "--results", str(tmp_path / "results"), "--no-progress"])
    finally:
        scenario.unlink()
    return code, capsys.readouterr().err.strip().splitlines()


def test_real_time_iterations_without_acados_as_the_solver_is_refused_naming_the_option(tmp_path, capsys):
    with pytest.raises(ValueError, match="real_time_iterations needs solver = 'acados', got solver = 'fatrop'"):
        NMPCSettings(solver="fatrop", real_time_iterations=True)
    code, error = _run_with_options(tmp_path, capsys, "real_time_iterations = true")
    assert code == 2 and len(error) == 1 and "real_time_iterations needs solver = 'acados'" in error[0]
    assert "ctrl" in error[0] and not (tmp_path / "results").exists()
    code, error = _run_with_options(tmp_path, capsys, 'solver = "acados"\nreal_time_iterations = "yes"')
    assert code == 2 and len(error) == 1 and "option 'real_time_iterations' must be true or false" in error[0]
