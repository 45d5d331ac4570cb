"""The NMPC's NLP compiled once, cached, reused; the same solution as interpreted; the fallback."""

import logging
import math
from pathlib import Path

import numpy as np
import pytest

from orchestrator.errors import ScenarioError
from orchestrator.participant import BuildContext
from rhnc.control.control_participant import ControlParticipant
from rhnc.control.nmpc import NMPCController, NMPCSettings
from rhnc.control.nmpc_codegen import CACHE_ENV, CODEGEN_ENV, NLPLibrary
from rhnc.navigation.reference_participant import line_or_turn_reference
from rhnc.ship.ship_model import load_parameter_set

NM = 1852.0
KNOT = NM / 3600.0
COURSE = math.radians(45.0)
SPEED = 18 * KNOT
#: a small problem (3 intervals, one obstacle slot) so that it compiles in seconds
SMALL = dict(horizon_steps=3, substeps=1, max_obstacles=1, control_interval_s=30.0, codegen=True)


@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv(CACHE_ENV, str(tmp_path / "cache"))
    monkeypatch.delenv(CODEGEN_ENV, raising=False)
    return tmp_path / "cache"


@pytest.fixture(scope="module")
def kcs():
    return load_parameter_set("default")


def solve_encounter(controller: NMPCController):
    """Two steps past an obstacle ahead (collision constraints on), the second warm-started."""
    N = controller.settings.horizon_steps
    state = np.array([0.0, 0.0, COURSE, SPEED, 0.0, 0.0])
    obstacle = np.array([[1500.0, 1500.0, 0.0, 0.0, 400.0]])
    solutions = []
    for k in range(2):
        t = k * controller.settings.control_interval_s
        reference = line_or_turn_reference(t + controller.settings.control_interval_s * np.arange(N + 1),
                                           (0.0, 0.0), COURSE, SPEED)
        solution = controller.solve(t, state, reference, obstacle, et=True)
        assert solution.success, solution.status
        solutions.append(solution)
        state = solution.states[1]
    return solutions


def assert_same_solutions(compiled: NMPCController, interpreted: NMPCController, tau_max: np.ndarray) -> None:
    for a, b in zip(solve_encounter(compiled), solve_encounter(interpreted)):
        assert a.iterations == b.iterations
        np.testing.assert_allclose(a.inputs / tau_max, b.inputs / tau_max, rtol=0, atol=1e-8)
        np.testing.assert_allclose(a.states[:, :2] / 230.0, b.states[:, :2] / 230.0, rtol=0, atol=1e-8)


def interpreted_twin(kcs, **settings) -> NMPCController:
    """The same problem with interpreted functions, solved in this process."""
    return NMPCController(kcs, NMPCSettings(**{**SMALL, "codegen": False}, **settings, wall_time_limit_s=None,
                                            cpu_time_limit_s=None))


def test_first_use_builds_and_caches_second_use_loads_same_solution(cache, kcs):
    builds = NLPLibrary.builds
    first = NMPCController(kcs, NMPCSettings(**SMALL))
    assert first.library.mode == "compiled"
    assert NLPLibrary.builds == builds + 1
    assert first.library.build_time_s > 0.0
    path = first.library.path
    assert path.parent == cache and path.is_file()
    stamp = path.stat().st_mtime_ns
    second = NMPCController(kcs, NMPCSettings(**SMALL))
    assert NLPLibrary.builds == builds + 1, "the cached library was rebuilt"
    assert second.library.path == path and second.library.build_time_s is None
    assert path.stat().st_mtime_ns == stamp
    assert not list(cache.glob("*.tmp.so"))
    # loaded from the cache, solved in the watchdog's forked worker: the interpreted solution
    assert_same_solutions(second, interpreted_twin(kcs), kcs.tau_max)
    # another problem (another weight) gets a library of its own
    other = NMPCController(kcs, NMPCSettings(**SMALL, r=(0.02, 0.01)))
    assert other.library.path != path and NLPLibrary.builds == builds + 2
    for controller in (first, second, other):
        controller.close()


def test_compiled_ipopt_gives_the_interpreted_solution(cache, kcs):
    compiled = NMPCController(kcs, NMPCSettings(**SMALL, solver="ipopt"))
    assert compiled.library.mode == "compiled"
    assert_same_solutions(compiled, interpreted_twin(kcs, solver="ipopt"), kcs.tau_max)
    compiled.close()


def test_no_compiler_keeps_the_interpreted_functions(cache, kcs, monkeypatch, caplog):
    monkeypatch.setenv("CC", "/nonexistent/cc")
    builds = NLPLibrary.builds
    with caplog.at_level(logging.WARNING, logger="rhnc.control.nmpc_codegen"):
        controller = NMPCController(kcs, NMPCSettings(**SMALL, wall_time_limit_s=None, cpu_time_limit_s=None))
    assert controller.library.mode == "interpreted" and NLPLibrary.builds == builds
    assert "no C compiler found" in caplog.text and "interpreted" in caplog.text
    summary = controller.library.summary()
    assert summary["codegen"] == "interpreted" and summary["codegen_library"] is None
    assert "no C compiler" in summary["codegen_note"]
    assert not cache.exists() or not list(cache.glob("*.so"))
    solve_encounter(controller)  # still solves


def test_failing_compiler_keeps_the_interpreted_functions(cache, kcs, monkeypatch, tmp_path):
    broken = tmp_path / "broken-cc"
    broken.write_text("#!/bin/sh\necho 'broken compiler' >&2\nexit 1\n")
    broken.chmod(0o755)
    monkeypatch.setenv("CC", str(broken))
    controller = NMPCController(kcs, NMPCSettings(**SMALL, wall_time_limit_s=None, cpu_time_limit_s=None))
    assert controller.library.mode == "interpreted"
    assert "compiling the NLP failed" in controller.library.reason
    assert not list(cache.glob("*.so")), "no half-written library left behind"


def test_control_participant_summary_says_which_was_used(cache, kcs):
    context = BuildContext("exp.toml: participants.ctrl", Path("."), 30.0, 0.0, 600.0)
    options = {"horizon_steps": 3, "substeps": 1, "max_obstacles": 1}
    summary = ControlParticipant.from_options("ctrl", {**options, "codegen": False}, context).summary()
    assert summary["codegen"] == "interpreted" and summary["codegen_note"] == "code generation off in the settings"
    summary = ControlParticipant.from_options("ctrl", options, context).summary()  # on by default
    assert summary["codegen"] == "compiled" and summary["codegen_library"].startswith(str(cache))
    with pytest.raises(ScenarioError, match=r"participants.ctrl: option 'codegen' must be true or false"):
        ControlParticipant.from_options("ctrl", {"codegen": "yes"}, context)
