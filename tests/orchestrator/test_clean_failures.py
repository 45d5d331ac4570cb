"""Failing cleanly: no folder for refused input, the right subcommand named, the participant
that raised named, no verdicts on a run without steps, only the toolchain's log lines, and
batch consoles that list every failure and count what ran."""

import json
import os
import re
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from orchestrator import cli
from orchestrator.cli import main

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[1]


def test_a_missing_fmu_leaves_no_results_folder(tmp_path, capsys):
    path = tmp_path / "missing.toml"
    path.write_text((REPO / "scenarios" / "turning_circle.toml").read_text().replace('fmu = "KCS"', 'fmu = "x.fmu"'))
    assert main(["run", str(path), "--results", str(tmp_path / "results"), "--no-progress"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "participants.ship.fmu: FMU file not found" in err[0]
    assert not (tmp_path / "results").exists()


@pytest.mark.parametrize("command", ["run", "validate"])
@pytest.mark.parametrize("file, kind, right", [
    ("scenarios/exp1_cost_vs_emission.toml", "an offline planning file (it has 'planner')", "plan"),
    ("scenarios/exp2_table3.toml", "a comparison file (it has 'runs')", "compare"),
    ("batches/turning_grid.toml", "a batch file (it has 'batch')", "batch"),
])
def test_another_kind_of_file_names_the_subcommand_for_it(tmp_path, capsys, command, file, kind, right):
    path = REPO / file
    args = [command, str(path)] + (["--results", str(tmp_path), "--no-progress"] if command == "run" else [])
    assert main(args) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"error: {path}: {kind}, not a scenario: use 'python -m orchestrator {right} {path}'"]
    assert list(tmp_path.iterdir()) == []


SETUP_FAILS = """
[simulation]
name = "setup_fails"
steps = 10
dt_s = 1.0
[participants.clock]
type = "python"
class = "sample_participants:Clock"
[participants.solver]
type = "python"
class = "sample_participants:Crash"
[participants.solver.options]
in_setup = true
[outputs]
analyses = ["turning_circle"]
"""


def test_a_set_up_failure_names_the_participant_and_evaluates_nothing(write_scenario, tmp_path, capsys):
    path = write_scenario(SETUP_FAILS)
    assert main(["run", str(path), "--results", str(tmp_path), "--no-progress"]) == 3
    captured = capsys.readouterr()
    assert "error: solver: LinAlgError: Failed to find a finite solution." in captured.err
    assert "  turning_circle: not evaluated: the run made no steps" in captured.out
    folder = Path(captured.out.split("results in ")[1].split()[0])
    summary = json.loads((folder / "summary.json").read_text())
    assert summary["status"] == "failed" and summary["simulation"]["steps_done"] == 0
    assert summary["analyses"] == {"turning_circle": {"evaluated": False,
                                                      "note": "not evaluated: the run made no steps"}}


def test_verbose_shows_the_toolchains_log_lines_only(tmp_path):
    result = subprocess.run(
        [sys.executable, "-m", "orchestrator", "-v", "run", str(REPO / "scenarios" / "turning_circle.toml"),
         "--results", str(tmp_path), "--no-progress"], capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stderr
    loggers = re.findall(r"^(?:DEBUG|INFO|WARNING|ERROR|CRITICAL) ([\w.]+):", result.stderr, flags=re.M)
    assert loggers, result.stderr  # -v does show our debug lines
    assert {name.split(".")[0] for name in loggers} <= {"orchestrator", "rhnc"}, sorted(set(loggers))


def test_a_batch_console_counts_the_failures_it_does_not_list(write_small_batch, tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(cli, "MAX_FAILURES_SHOWN", 3)
    results = tmp_path / "results"
    assert main(["batch", str(write_small_batch()), "--results", str(results), "--no-progress", "--workers", "1"]) == 3
    out = capsys.readouterr().out
    assert len(re.findall(r"^  \w+ finished: fast enough", out, flags=re.M)) == 3
    assert f"  ... and 1 more not passed: every one is in {results / 'small' / 'summary.csv'}" in out


def test_an_interrupted_batch_counts_the_runs_that_ended_after_the_interrupt(write_small_batch, tmp_path, capsys):
    """The first run sends Ctrl-C to the batch process; it still completes and is counted."""
    from test_batch import BATCH

    text = BATCH.replace("[grid]", "[set]\n\"participants.helm.options.interrupt_batch_at_s\" = 100.0\n\n[grid]")
    results = tmp_path / "results"
    assert main(["batch", str(write_small_batch(text)), "--results", str(results), "--no-progress", "--workers", "1"]) == 130
    captured = capsys.readouterr()
    assert captured.out.startswith("0/6 runs passed (")
    assert "; ran 1, skipped 0 already done" in captured.out.splitlines()[0]
    assert "interrupted: rerun the same command to finish the batch" in captured.err


ARRAY_STOP = """
[simulation]
name = "array_stop"
steps = 5
dt_s = 1.0
stop_when = "clock.vector > 0"
[participants.clock]
type = "python"
class = "sample_participants:Clock"
[participants.after]
type = "python"
class = "sample_participants:Misbehaving"
[participants.after.options]
how = "none"
[outputs]
figures = []
"""


@pytest.mark.parametrize("command", [["validate"], ["run", "--no-progress"]])
def test_a_stop_condition_on_an_array_port_is_refused_before_the_run(write_scenario, tmp_path, capsys, monkeypatch,
                                                                     command):
    """It used to pass validate and fail the run after one step with a TypeError blamed on the
    participant stepped last."""
    monkeypatch.syspath_prepend(str(Path(__file__).parent))
    path = write_scenario(ARRAY_STOP)
    results = ["--results", str(tmp_path / "results")] if command[0] == "run" else []
    assert main([*command, *results, str(path)]) == 2
    assert capsys.readouterr().err.strip().splitlines() == [
        f"error: {path}: simulation.stop_when 'clock.vector > 0': output 'vector' of 'clock' is an array of shape "
        "(2,); a stop condition needs an output that is one number"]
    assert not (tmp_path / "results").exists()


@pytest.mark.parametrize("command", [["validate"], ["run", "--no-progress"]])
def test_what_a_participant_compiles_while_it_is_built_is_said_on_stderr(tmp_path, command):
    """A first validate on a fresh machine compiles the NMPC for a minute or more: the line
    the participant logs about it is shown, the toolchain's other INFO lines are not."""
    path = tmp_path / "compiling.toml"
    path.write_text(textwrap.dedent("""\
        [simulation]
        name = "compiling"
        steps = 3
        dt_s = 1.0
        [participants.model]
        type = "python"
        class = "sample_participants:Compiling"
        [outputs]
        figures = []
        """))
    results = ["--results", str(tmp_path / "results")] if command[0] == "run" else []
    done = subprocess.run([sys.executable, "-m", "orchestrator", *command, *results, str(path)], capture_output=True,
                          text=True, env={**os.environ, "PYTHONPATH": f"{HERE}:{REPO}"}, timeout=300)
    assert done.returncode == 0, done.stderr
    assert done.stderr.splitlines() == [
        "INFO orchestrator.sample_build: compiling its model into /cache/model.so (once per machine)"]
