"""Two runs or batches writing the same results folder at once: no corruption, no traceback."""

import os
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest

from orchestrator.batch import results_lock
from orchestrator.cli import main
from orchestrator.results import RunFolder

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[1]


def test_a_batch_finds_its_results_folder_held_and_says_by_whom(small_batch, tmp_path, capsys):
    root = tmp_path / "results" / "small"
    root.mkdir(parents=True)
    with results_lock(root):  # this process holds the folder, as a running batch would
        code = main(["batch", str(small_batch), "--results", str(tmp_path / "results"), "--no-progress"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2
    assert err == [f"error: {root}: another batch is writing this results folder (process {os.getpid()}); "
                   "wait for it to end, or give another --results folder"]
    assert not (root / "runs").exists() or not any((root / "runs").iterdir())  # it wrote nothing
    # released: the same batch now runs
    assert main(["batch", str(small_batch), "--results", str(tmp_path / "results"), "--no-progress",
                 "--workers", "1"]) == 3


def test_two_publishers_of_one_run_id_keep_both_runs(tmp_path):
    first = RunFolder(tmp_path, "scenario", "20260101T000000Z-abc")
    second = RunFolder(tmp_path, "scenario", "20260101T000000Z-abc")
    assert first.staging != second.staging  # each attempt stages apart
    first.write_json("summary.json", {"who": 1})
    second.write_json("summary.json", {"who": 2})
    assert first.publish() == tmp_path / "scenario" / "20260101T000000Z-abc"
    assert second.publish() == tmp_path / "scenario" / "20260101T000000Z-abc-2"
    assert (first.final / "summary.json").read_text() == '{\n  "who": 1\n}\n'
    assert (second.final / "summary.json").read_text() == '{\n  "who": 2\n}\n'
    assert sorted(p.name for p in (tmp_path / "scenario").iterdir()) == [
        "20260101T000000Z-abc", "20260101T000000Z-abc-2"]


def launch(args):
    return subprocess.Popen([sys.executable, "-m", "orchestrator", *args], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True,
                            env={**os.environ, "PYTHONPATH": f"{HERE}:{REPO}"})


@pytest.mark.slow
def test_the_same_batch_started_twice_at_once(small_batch, tmp_path):
    args = ["batch", str(small_batch), "--results", str(tmp_path / "results"), "--no-progress", "--workers", "1"]
    processes = [launch(args), launch(args)]
    outcomes = [(p.wait(timeout=300), *p.communicate()) for p in processes]
    for code, out, err in outcomes:
        assert "Traceback" not in err, err
        if code == 2:  # the other one held the folder
            assert "another batch is writing this results folder (process " in err
            assert len(err.strip().splitlines()) == 1
        else:  # ran it, or found it done by the other
            assert code == 3, err
            assert out.startswith("2/6 runs passed (6 finished)")
    assert 3 in [code for code, _, _ in outcomes]
    root = tmp_path / "results" / "small"
    table = pd.read_csv(root / "summary.csv")
    assert len(table) == 6 and set(table["status"]) == {"finished"} and table["passed"].sum() == 2
    assert not [p for p in (root / "runs").iterdir() if p.name.startswith(".")]


@pytest.mark.slow
def test_two_runs_of_one_scenario_at_once_write_two_folders(tmp_path):
    args = ["run", str(REPO / "scenarios" / "turning_circle.toml"), "--results", str(tmp_path), "--no-progress"]
    processes = [launch(args), launch(args)]
    for process in processes:
        out, err = process.communicate(timeout=300)
        assert process.returncode == 0, err
        assert "Traceback" not in err
    folders = sorted((tmp_path / "turning_circle").iterdir())
    assert len(folders) == 2 and not [p for p in folders if p.name.startswith(".")]
    for folder in folders:
        assert (folder / "summary.json").is_file() and (folder / "timeseries.parquet").is_file()
