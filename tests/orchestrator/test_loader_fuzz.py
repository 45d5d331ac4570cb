"""A fixed-seed sample of the fuzz campaign (scripts/fuzz_scenarios.py), fed to the loader in
process: every generated scenario either loads or is refused with one ScenarioError line;
any other exception (a traceback for the user) fails the test."""

import shutil
from pathlib import Path

import pytest

from orchestrator.errors import ToolchainError
from orchestrator.scenario import load_scenario
from orchestrator.validate import check_scenario
from script_module import module_of_file

REPO = Path(__file__).resolve().parents[2]
SAMPLE = 120
#: Base scenarios cheap enough to build in full (no NMPC, no planner) for the validate part.
CHEAP = {"turning_circle.toml", "turning_circle_mmg.toml", "zigzag_10_10.toml", "zigzag_mmg.toml",
         "zigzag_20_20_mmg.toml", "moving_storm_demo.toml"}


def _fuzz_module():
    return module_of_file(REPO / "scripts" / "fuzz_scenarios.py", "fuzz_scenarios")


@pytest.fixture(scope="module")
def cases(tmp_path_factory):
    fuzz = _fuzz_module()
    folder = tmp_path_factory.mktemp("fuzz")
    shutil.copytree(REPO / "scenarios", folder / "scenarios")
    written = []
    for case in fuzz.generate(SAMPLE, seed=2026, run_every=0):
        path = folder / "scenarios" / case.base.relative_to(REPO / "scenarios").parent / f"fuzz_{case.index}.toml"
        path.write_text(case.text, encoding="utf-8")
        written.append((case, path))
    return written


def test_the_generator_is_deterministic_and_covers_the_known_inputs():
    fuzz = _fuzz_module()
    first, again = fuzz.generate(40, seed=3), fuzz.generate(40, seed=3)
    assert [c.text for c in first] == [c.text for c in again]
    assert len({c.base for c in fuzz.generate(200, seed=3)}) == len(fuzz.base_scenarios()) >= 20
    mutations = [m for c in fuzz.generate(1200, seed=0) for m in c.mutations]
    for dotted, _ in fuzz.KNOWN_BAD:
        assert any(dotted.split(".")[-1] in m for m in mutations), dotted


def test_every_sampled_scenario_loads_or_is_refused_with_one_line(cases):
    refused = 0
    for case, path in cases:
        try:
            load_scenario(path)
        except ToolchainError as exc:
            refused += 1
            assert "\n" not in str(exc) and str(path) in str(exc), (case.mutations, str(exc))
        # any other exception propagates and fails the test, naming the case
    assert 0 < refused < len(cases)


@pytest.fixture(scope="module")
def cheap_cases(tmp_path_factory):
    """The first 30 sampled cases whose base is cheap (the share of cheap bases falls as
    scenarios are added, so they are drawn from a longer sample than ``cases``)."""
    fuzz = _fuzz_module()
    folder = tmp_path_factory.mktemp("fuzz_cheap")
    shutil.copytree(REPO / "scenarios", folder / "scenarios")
    written = []
    for case in fuzz.generate(10 * SAMPLE, seed=2026, run_every=0):
        if case.base.name in CHEAP and len(written) < 30:
            path = folder / "scenarios" / case.base.relative_to(REPO / "scenarios").parent / f"fuzz_{case.index}.toml"
            path.write_text(case.text, encoding="utf-8")
            written.append((case, path))
    return written


def test_sampled_scenarios_of_cheap_bases_validate_or_are_refused_with_one_line(cheap_cases):
    checked = 0
    for case, path in cheap_cases:
        report = check_scenario(path)
        checked += 1
        assert all("\n" not in problem for problem in report.problems), case.mutations
    assert checked >= 20
