"""``[[acceptance]]`` in a scenario: checked after a single run; unmet criteria exit 3 and are named."""

import json
import re
from pathlib import Path

import pytest

from orchestrator.cli import main
from orchestrator.errors import ScenarioError
from orchestrator.scenario import load_scenario

REPO = Path(__file__).resolve().parents[2]

CRITERIA = """
[[acceptance]]
name = "tight turn"
metric = "analyses.turning_circle.tactical_diameter_L"
op = "<="
value = {limit}

[[acceptance]]
name = "finished"
metric = "status"
op = "=="
value = "finished"
"""


def turning_circle_with(tmp_path, criteria: str) -> Path:
    path = tmp_path / "turning.toml"
    path.write_text((REPO / "scenarios" / "turning_circle.toml").read_text() + criteria)
    return path


def test_criteria_met_exit_0_and_are_recorded(tmp_path, capsys):
    path = turning_circle_with(tmp_path, CRITERIA.format(limit=5.0))
    assert main(["run", str(path), "--results", str(tmp_path / "results"), "--no-progress"]) == 0
    out = capsys.readouterr().out
    assert "  acceptance: 2/2 criteria met" in out
    summary = json.loads((Path(out.split("results in ")[1].split()[0]) / "summary.json").read_text())
    assert summary["acceptance"]["passed"] is True
    assert [c["criterion"] for c in summary["acceptance"]["criteria"]] == [
        "analyses.turning_circle.tactical_diameter_L <= 5.0", 'status == "finished"']


def test_a_criterion_not_met_exits_3_and_is_named(tmp_path, capsys):
    path = turning_circle_with(tmp_path, CRITERIA.format(limit=3.0))  # the KCS turns in 3.28 L
    assert main(["run", str(path), "--results", str(tmp_path / "results"), "--no-progress"]) == 3
    captured = capsys.readouterr()
    assert captured.out.startswith("finished: results in ")  # the run itself finished, results kept
    assert "  acceptance: 1/2 criteria met" in captured.out
    err = captured.err.strip().splitlines()
    assert len(err) == 1
    assert re.fullmatch(r"error: acceptance criterion not met: tight turn: "
                        r"analyses\.turning_circle\.tactical_diameter_L = 3\.2\d+, not <= 3", err[0]), err


def test_a_malformed_criterion_is_refused_before_the_run(tmp_path, capsys):
    path = turning_circle_with(tmp_path, CRITERIA.format(limit=5.0).replace('op = "<="', 'op = "=<"'))
    with pytest.raises(ScenarioError, match=r"turning.toml: 'acceptance\[0\].op' must be one of < <= == != >= >, got '=<'"):
        load_scenario(path)
    assert main(["run", str(path), "--results", str(tmp_path / "results"), "--no-progress"]) == 2
    assert not (tmp_path / "results").exists()


@pytest.mark.slow
def test_a_run_that_breaks_separation_does_not_exit_0(tmp_path, capsys):
    """Experiment 3a with the collision constraints off sails through the obstacle's circle."""
    text = (REPO / "scenarios" / "exp3a_static.toml").read_text()
    text = text.replace("et_default = 1.0", "et_default = 0.0").replace("steps = 440", "steps = 300")
    path = tmp_path / "exp3a_blind.toml"
    path.write_text(text)
    assert main(["run", str(path), "--results", str(tmp_path / "results"), "--no-progress"]) == 3
    err = capsys.readouterr().err
    assert "error: acceptance criterion not met: separation kept: analyses.encounter.min_clearance_nm = -" in err
