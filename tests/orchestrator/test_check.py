"""``python -m orchestrator check``: another master's CSV files judged by a scenario's criteria.

Bad input (a missing file, no time column, a file of no participant, a scenario without
criteria) is one line naming it, exit 2, nothing written.  The timing: a master records a
Python participant's outputs at the end of its step; ``check`` moves them back to the
decision time, so that FMPy-style files of our own run give our own figures.
"""

from pathlib import Path

import pandas as pd
import pytest

from orchestrator.cli import main
from orchestrator.foreign_results import _header
from orchestrator.run import run_scenario

REPO = Path(__file__).resolve().parents[2]
STEPS = 72  # 6 min: the ships close to about 1.9 nm


@pytest.fixture(scope="module")
def short_exp3b(tmp_path_factory):
    text = (REPO / "scenarios" / "osp" / "exp3b_head_on.toml").read_text().replace("steps = 320", f"steps = {STEPS}")
    path = tmp_path_factory.mktemp("scenario") / "exp3b_short.toml"
    path.write_text(text)
    return path


def test_a_libcosim_header_keeps_the_commas_inside_brackets():
    assert _header("Time,StepCount,x,reference[0,0],reference[15,6],obstacles[0,4]\n") == \
        ["Time", "StepCount", "x", "reference[0,0]", "reference[15,6]", "obstacles[0,4]"]


@pytest.mark.parametrize("content, file_name, message", [
    (None, "missing.csv", "missing.csv: no such results file"),
    ("a,b\n1,2\n", "ship.csv", "ship.csv: no time column ('Time' of libcosim, 'time' of FMPy or 'time_s')"),
    ("time,x\n0,1\n", "boat.csv", "boat.csv: no participant 'boat' in "),
])
def test_bad_results_are_refused_naming_the_file(short_exp3b, tmp_path, capsys, content, file_name, message):
    path = tmp_path / file_name
    if content is not None:
        path.write_text(content)
    summary = tmp_path / "summary.json"
    assert main(["check", str(path), "--scenario", str(short_exp3b), "--summary", str(summary)]) == 2
    assert message in capsys.readouterr().err
    assert not summary.exists()


def test_a_scenario_without_criteria_is_refused(tmp_path, capsys):
    path = tmp_path / "ship.csv"
    path.write_text("time,x\n0,1\n")
    assert main(["check", str(path), "--scenario", str(REPO / "scenarios" / "turning_circle.toml")]) == 2
    assert "turning_circle.toml: no [[acceptance]] criteria to judge by" in capsys.readouterr().err


def test_fmpy_style_files_of_our_run_give_our_figures(short_exp3b, tmp_path, capsys):
    """Per-participant files as an FMI master records them (a Python participant's outputs at the
    end of its step): check gives our run's separation and sign changes."""
    report = run_scenario(short_exp3b, tmp_path / "ours", progress=False)
    ours = pd.read_csv(report.folder / "timeseries.csv") if (report.folder / "timeseries.csv").exists() \
        else pd.read_parquet(report.folder / "timeseries.parquet")
    steps = {"ref": 20.0, "traffic": 5.0, "ctrl": 20.0, "ship": 0.0}  # Python participants: recorded at t + h
    files = []
    for name, delay in steps.items():
        columns = [c for c in ours.columns if c.startswith(name + ".")]
        table = ours[["time_s", *columns]].rename(columns={"time_s": "time", **{c: c[len(name) + 1:] for c in columns}})
        table["time"] = table["time"] + delay
        if delay:  # what the master shows before the first step ends: the set-up's outputs
            table = pd.concat([table.iloc[:1].assign(time=0.0), table[table["time"] <= ours["time_s"].max()]])
        path = tmp_path / f"{name}.csv"
        table.to_csv(path, index=False)
        files.append(str(path))
    summary = tmp_path / "summary.json"
    code = main(["check", *files, "--scenario", str(short_exp3b), "--summary", str(summary)])
    import json

    theirs = json.loads(summary.read_text())
    assert code == (0 if report.summary["acceptance"]["passed"] else 3)
    mine = report.summary
    assert theirs["analyses"]["encounter"]["min_clearance_nm"] == pytest.approx(
        mine["analyses"]["encounter"]["min_clearance_nm"], abs=1e-9)
    assert mine["analyses"]["encounter"]["min_clearance_nm"] < 2.0  # closing at 16 m/s: a 5 s shift is 0.04 nm
    assert theirs["participants"]["ctrl"] == {
        "solves": mine["participants"]["ctrl"]["solves"],
        "tau_r_sign_changes_per_100_solves": mine["participants"]["ctrl"]["tau_r_sign_changes_per_100_solves"]}
    assert "accepted" in capsys.readouterr().out
