"""Failure paths that keep the results: whatever a participant or the disk does, a run ends with
one clear line and a non-zero exit, keeps what was computed (or leaves nothing half-written),
and no temporary ``rhnc-run-*`` folder outlives it."""

import errno
import json
import os
import tempfile
from pathlib import Path

import pytest

from orchestrator.cli import main

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[1]

MISBEHAVING = """
[simulation]
name = "misbehaving"
steps = 10
dt_s = 1.0
[participants.clock]
type = "python"
class = "sample_participants:Clock"
[participants.bad]
type = "python"
class = "sample_participants:Misbehaving"
[participants.bad.options]
how = "{how}"
at_s = 3.0
[outputs]
format = "csv"
figures = []
"""


@pytest.fixture
def private_tmp(tmp_path, monkeypatch):
    """Temporary folders of the run go to a folder of this test, to count what is left there."""
    folder = tmp_path / "tmp"
    folder.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(folder))
    return folder


def run(path, results, capsys):
    code = main(["run", str(path), "--results", str(results), "--no-progress"])
    captured = capsys.readouterr()
    assert "Traceback" not in captured.err
    return code, captured


def published(captured) -> tuple[Path, dict]:
    folder = Path(captured.out.split("results in ")[1].split()[0])
    return folder, json.loads((folder / "summary.json").read_text())


# (how, steps done, clock steps: the clock steps before the misbehaving participant)
@pytest.mark.parametrize("how, steps, clock_steps, reason", [
    ("exit", 3, 4, "error: bad: called sys.exit(5)"),
    ("terminate", 10, 10, "error: bad: terminate() raised OSError: device busy"),
    ("summary", 10, 10, "error: bad: summary raised ZeroDivisionError: division by zero"),
    ("unserialisable", 10, 10, "error: bad: its summary cannot be written to JSON (cannot write object to JSON)"),
])
def test_a_participant_failing_outside_its_step_keeps_the_run(write_scenario, tmp_path, capsys, private_tmp,
                                                               how, steps, clock_steps, reason):
    code, captured = run(write_scenario(MISBEHAVING.format(how=how)), tmp_path / "results", capsys)
    assert code == 3
    assert captured.err.strip().splitlines()[-1] == reason
    folder, summary = published(captured)
    assert summary["status"] == "failed"
    assert summary["simulation"]["steps_done"] == steps
    # header and one row per communication point the clock stepped at (t = 0 .. clock_steps - 1 s)
    assert len((folder / "timeseries.csv").read_text().splitlines()) == 1 + clock_steps
    assert summary["participants"]["clock"] == {"steps": clock_steps}  # the other participant's figures are kept
    assert (folder / "clock_calls.csv").is_file()
    assert list(private_tmp.iterdir()) == []


def test_from_options_raising_is_one_line_and_leaves_nothing(write_scenario, tmp_path, capsys, private_tmp):
    code, captured = run(write_scenario(MISBEHAVING.format(how="options")), tmp_path / "results", capsys)
    assert code == 2
    assert captured.err.strip().splitlines() == [
        f"error: {tmp_path / 'scenario.toml'}: participants.bad: sample_participants:Misbehaving could not be "
        "built from its options: ValueError: gain must be positive"]
    assert not (tmp_path / "results").exists()
    assert list(private_tmp.iterdir()) == []  # the run's rhnc-run-* folder is gone too


def test_a_set_up_failure_with_analyses_keeps_its_folder(tmp_path, capsys, private_tmp, monkeypatch):
    """A participant's NaN output at set-up (a scenario's own numbers are refused before the
    run): the run fails in its set-up, the voyage analysis is not evaluated (it used to end
    in KeyError 'ship.x' and lose the folder)."""
    monkeypatch.syspath_prepend(str(Path(__file__).parent))
    text = (REPO / "scenarios" / "turning_circle.toml").read_text()
    text = text.replace('analyses = ["turning_circle"]', 'analyses = ["voyage"]')
    text += '\n[participants.sensor]\ntype = "python"\nclass = "sample_participants:Misbehaving"\n' \
            '[participants.sensor.options]\nhow = "nan_setup"\n'
    path = tmp_path / "nan.toml"
    path.write_text(text)
    code, captured = run(path, tmp_path / "results", capsys)
    assert code == 3
    assert captured.err.strip().splitlines() == ["error: sensor: output 'ok' is not finite at t = 0 s"]
    folder, summary = published(captured)
    assert summary["status"] == "failed"
    assert summary["analyses"]["voyage"]["evaluated"] is False
    assert list(private_tmp.iterdir()) == []


def test_a_results_folder_that_cannot_be_written_is_one_line(write_scenario, tmp_path, capsys, private_tmp):
    blocker = tmp_path / "results"
    blocker.write_text("a file where the results folder should be")
    code, captured = run(write_scenario(MISBEHAVING.format(how="none")), blocker, capsys)
    assert code == 4
    assert captured.err.strip().splitlines() == [f"error: {blocker / 'misbehaving'}: cannot write results here: "
                                                 "Not a directory"]
    assert list(private_tmp.iterdir()) == []


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes into read-only folders")
def test_a_read_only_results_folder_is_one_line(write_scenario, tmp_path, capsys):
    results = tmp_path / "results"
    results.mkdir()
    results.chmod(0o555)
    try:
        code, captured = run(write_scenario(MISBEHAVING.format(how="none")), results, capsys)
    finally:
        results.chmod(0o755)
    assert code == 4
    assert captured.err.strip().splitlines() == [f"error: {results / 'misbehaving'}: cannot write results here: "
                                                 "Permission denied"]


def test_a_read_only_results_folder_as_root_sees_it_is_one_line(write_scenario, tmp_path, capsys, monkeypatch):
    """The same as above where the tests run as root: the folder refuses through the OS error it would give."""
    real_mkdir = Path.mkdir

    def refuse(self, *args, **kwargs):
        if tmp_path / "results" in self.parents:
            raise PermissionError(errno.EACCES, os.strerror(errno.EACCES), str(self))
        return real_mkdir(self, *args, **kwargs)

    monkeypatch.setattr(Path, "mkdir", refuse)
    code, captured = run(write_scenario(MISBEHAVING.format(how="none")), tmp_path / "results", capsys)
    assert code == 4
    assert captured.err.strip().splitlines() == [
        f"error: {tmp_path / 'results' / 'misbehaving'}: cannot write results here: Permission denied"]


def test_a_full_disk_while_writing_leaves_nothing_half_written(write_scenario, tmp_path, capsys, monkeypatch,
                                                              private_tmp):
    from orchestrator import results

    def full(self, name, data):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(results.RunFolder, "write_json", full)
    code, captured = run(write_scenario(MISBEHAVING.format(how="none")), tmp_path / "results", capsys)
    assert code == 4
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1 and "the results could not be written (No space left on device); nothing was kept " \
                               "(the run itself: finished)" in lines[0]
    assert not (tmp_path / "results").exists()  # no staging folder, no run folder, no folder made for them
    assert list(private_tmp.iterdir()) == []


@pytest.mark.parametrize("how, where", [
    ("interrupt_summary", "while the summary of participant 'bad' was collected"),
    ("interrupt_terminate", "while participant 'bad' was terminated"),
])
def test_ctrl_c_after_the_last_step_keeps_every_step(write_scenario, tmp_path, capsys, private_tmp, how, where):
    """Ctrl-C while the participants are terminated or their summaries collected: every step is
    kept, the other participants' summaries too, exit 130."""
    code, captured = run(write_scenario(MISBEHAVING.format(how=how)), tmp_path / "results", capsys)
    assert code == 130
    assert captured.err.strip().splitlines()[-1] == f"error: interrupted by the user (Ctrl-C) after the last step, {where}"
    folder, summary = published(captured)
    assert summary["status"] == "interrupted"
    assert summary["simulation"]["steps_done"] == 10
    assert len((folder / "timeseries.csv").read_text().splitlines()) == 1 + 10
    assert summary["participants"]["clock"] == {"steps": 10}
    if how == "interrupt_summary":  # the one whose summary the Ctrl-C cut short says so
        assert summary["participants"]["bad"] == {"error": "not collected: interrupted by the user (Ctrl-C)"}
    assert list(private_tmp.iterdir()) == []
