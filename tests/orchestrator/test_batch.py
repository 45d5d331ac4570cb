"""Batches: identical tables on every executor, resumption, failed runs, batch-file errors, the CLI."""

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pandas as pd
import pytest

from orchestrator.batch import NONDETERMINISTIC_COLUMNS, WORKER_DIED, run_batch
from orchestrator.batch_spec import load_batch
from orchestrator.cli import main

REPO = Path(__file__).resolve().parents[2]

SCENARIO = """\
connections = ["helm.tau_u -> ship.tau_u", "helm.tau_r -> ship.tau_r"]

[simulation]
name = "short_turn"
stop_s = 300.0
dt_s = 5.0

[participants.helm]
type = "python"
class = "test_batch_participants:TestHelm"
[participants.helm.options]
tau_u_N = 7.7e5

[participants.ship]
fmu = "KCS"
[participants.ship.parameters]
u0 = 9.26

[outputs]
analyses = ["turning_circle"]
figures = []
"""

BATCH = """\
[batch]
name = "small"
scenario = "short_turn.toml"

[grid]
"participants.helm.options.tau_u_N" = [5.0e5, 9.0e5]

[monte_carlo]
seed = 11
runs = 3
[monte_carlo.uniform]
"participants.ship.parameters.u0" = [6.0, 9.0]

[[acceptance]]
name = "fast enough"
metric = "analyses.turning_circle.approach_speed_kn"
op = ">="
value = 15.0

[[acceptance]]
name = "finished"
metric = "status"
op = "=="
value = "finished"
"""


@pytest.fixture
def batch_file(tmp_path):
    (tmp_path / "short_turn.toml").write_text(SCENARIO)

    def write(text=BATCH, name="small.toml"):
        path = tmp_path / name
        path.write_text(textwrap.dedent(text))
        return path

    return write


def _comparable(table):
    return table.drop(columns=list(NONDETERMINISTIC_COLUMNS)).sort_values("run_id").reset_index(drop=True)


def _mtimes(root: Path) -> dict[str, int]:
    return {p.name: (p / "summary.json").stat().st_mtime_ns for p in (root / "runs").iterdir() if not p.name.startswith(".")}


@pytest.mark.slow
def test_local_pool_and_dask_cluster_give_identical_tables(batch_file, tmp_path):
    from distributed import LocalCluster

    path = batch_file()
    one = run_batch(path, tmp_path / "one", workers=1, progress=False)
    two = run_batch(path, tmp_path / "two", workers=2, progress=False)
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=False, dashboard_address=None) as cluster:
        dask = run_batch(path, tmp_path / "dask", scheduler=cluster.scheduler_address, progress=False)
    assert one.total == 6 and one.ran == 6 and set(one.table["status"]) == {"finished"}
    # the draws of u0 vary the outcome: the table is not trivially constant
    assert one.table["param:participants.ship.parameters.u0"].nunique() == 3
    assert 0 < one.passed < 6
    pd.testing.assert_frame_equal(_comparable(one.table), _comparable(two.table))
    pd.testing.assert_frame_equal(_comparable(one.table), _comparable(dask.table))
    saved = pd.read_parquet(tmp_path / "dask" / "small" / "summary.parquet")
    pd.testing.assert_frame_equal(_comparable(saved), _comparable(dask.table))
    assert (tmp_path / "one" / "small" / "overview.png").stat().st_size > 10_000
    assert sorted(p.name for p in (tmp_path / "one" / "small" / "runs").iterdir()) == sorted(one.table["run_id"])


@pytest.mark.slow
def test_rerun_skips_finished_runs_and_redoes_only_the_rest(batch_file, tmp_path):
    path = batch_file()
    first = run_batch(path, tmp_path, workers=2, progress=False)
    root = first.folder
    ids = list(first.table["run_id"])
    # a killed batch leaves: runs never started, a staging folder, a run interrupted mid-way
    import shutil

    shutil.rmtree(root / "runs" / ids[0])
    shutil.rmtree(root / "runs" / ids[1])
    (root / "runs" / f".{ids[1]}.partial").mkdir()
    interrupted = root / "runs" / ids[2] / "summary.json"
    interrupted.write_text(json.dumps({**json.loads(interrupted.read_text()), "status": "interrupted"}))
    untouched = {k: v for k, v in _mtimes(root).items() if k not in ids[:3]}
    second = run_batch(path, tmp_path, workers=2, progress=False)
    assert (second.ran, second.skipped) == (3, 3)
    assert {k: v for k, v in _mtimes(root).items() if k in untouched} == untouched
    assert not list((root / "runs").glob(".*"))
    pd.testing.assert_frame_equal(_comparable(first.table), _comparable(second.table))
    third = run_batch(path, tmp_path, workers=2, progress=False)
    assert (third.ran, third.skipped) == (0, 6)


def test_run_ids_are_stable_and_draws_do_not_shift(batch_file, tmp_path):
    runs = load_batch(batch_file()).runs()
    assert [r.run_id for r in runs] == [r.run_id for r in load_batch(batch_file()).runs()]
    more = load_batch(batch_file(BATCH.replace("runs = 3", "runs = 5"), "more.toml")).runs()
    # five draws per grid point: the first three are the three of the smaller batch
    assert {r.run_id for r in runs} <= {r.run_id for r in more}
    other_seed = load_batch(batch_file(BATCH.replace("seed = 11", "seed = 12"), "seed.toml")).runs()
    assert not {r.run_id for r in runs} & {r.run_id for r in other_seed}


@pytest.mark.slow
def test_crashed_worker_and_failing_scenario_are_recorded_and_the_batch_completes(batch_file, tmp_path):
    path = batch_file(BATCH.replace('"participants.helm.options.tau_u_N" = [5.0e5, 9.0e5]',
                                    '"participants.helm.options.tau_u_N" = [5.0e5, 9.0e5]\n'
                                    '"participants.helm.options.die_at_s" = [1.0e9, 100.0]\n'
                                    '"participants.helm.options.refuse" = [false, true]'))
    report = run_batch(path, tmp_path, workers=2, progress=False)
    table = report.table
    assert report.total == 24 and not report.interrupted
    dies = table["param:participants.helm.options.die_at_s"] == 100.0
    refuses = table["param:participants.helm.options.refuse"]
    assert set(table.loc[refuses, "reason"].str.extract(r"(options\.refuse: this helm refuses to be built)")[0]) == {
        "options.refuse: this helm refuses to be built"}
    assert set(table.loc[dies & ~refuses, "reason"]) == {f"{WORKER_DIED}: exit code 17"}
    assert set(table.loc[~dies & ~refuses, "status"]) == {"finished"}
    assert set(table.loc[dies | refuses, "status"]) == {"failed"}
    assert not table.loc[dies | refuses, "passed"].any()
    summary = json.loads((report.folder / "runs" / table.loc[dies & ~refuses, "run_id"].iloc[0] / "summary.json").read_text())
    assert summary["status"] == "failed" and summary["overrides"]["participants.helm.options.die_at_s"] == 100.0


def test_missing_metric_fails_its_criterion_with_a_reason(batch_file, tmp_path):
    path = batch_file(BATCH.replace("analyses.turning_circle.approach_speed_kn", "analyses.encounter.min_separation_nm"))
    report = run_batch(path, tmp_path, workers=1, progress=False)
    assert report.passed == 0 and set(report.table["status"]) == {"finished"}
    assert set(report.table["failed_criteria"]) == {
        "fast enough: 'analyses.encounter.min_separation_nm' not in summary.json (no 'encounter' at 'analyses')"}


@pytest.mark.parametrize("change, message", [
    (("scenario = ", "scenaro = "), "unknown key 'batch.scenaro' (valid: name, scenario, description)"),
    (("seed = 11", "seed = -3"), "'monte_carlo.seed' must be a non-negative integer, got -3"),
    (("seed = 11", 'seed = "eleven"'), "'monte_carlo.seed' must be a non-negative integer, got 'eleven'"),
    (("[grid]", '[grid]\n"simulation.warp" = [1, 2]'),
     "'grid.\"simulation.warp\"' (run 0, value 1): the scenario does not accept it: "),
    (("[grid]", '[grid]\n"participants.helm.options.rudder" = [1, 2]'),
     "'grid.\"participants.helm.options.rudder\"' (run 0, value 1): the scenario does not accept it: "),
    (("op = \">=\"", "op = \"=>\""), "'acceptance[0].op' must be one of < <= == != >= >, got '=>'"),
    (("runs = 3", "runs = 3\nwarp = 1"), "unknown key 'monte_carlo.warp'"),
])
def test_malformed_batch_is_one_line_naming_file_and_key_exit_2(batch_file, tmp_path, capsys, change, message):
    path = batch_file(BATCH.replace(*change), "bad.toml")
    assert main(["batch", str(path), "--results", str(tmp_path / "results"), "--no-progress"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"error: {path}") and message in err[0]
    assert not (tmp_path / "results").exists()


def test_batch_through_the_command_line_as_a_user_would(batch_file, tmp_path):
    """Seed 11 draws u0 so that 4 of the 6 runs approach at 12-13 kn, below the 15 kn criterion."""
    path = batch_file()
    result = subprocess.run([sys.executable, "-m", "orchestrator", "batch", str(path), "--workers", "2",
                             "--results", str(tmp_path / "results"), "--no-progress"],
                            capture_output=True, text=True, timeout=120,
                            env={**os.environ, "PYTHONPATH": str(Path(__file__).parent)})
    assert result.returncode == 3, result.stderr
    assert result.stdout.startswith("2/6 runs passed (6 finished); ran 6, skipped 0 already done")
    failures = [line for line in result.stdout.splitlines() if "fast enough:" in line]
    assert len(failures) == 4  # every failed run is listed


def test_batch_that_passes_exits_0(batch_file, tmp_path, capsys):
    path = batch_file(BATCH.replace("value = 15.0", "value = 5.0"))
    assert main(["batch", str(path), "--workers", "1", "--results", str(tmp_path / "results"), "--no-progress"]) == 0
    assert capsys.readouterr().out.startswith("6/6 runs passed (6 finished); ran 6, skipped 0 already done")


@pytest.mark.slow
def test_the_shipped_turning_grid_passes_its_own_criteria(tmp_path):
    # a shipped example whose runs fail its own acceptance would teach a new user nothing
    spec = load_batch(REPO / "batches" / "turning_grid.toml")
    assert len(spec.runs()) == 12
    assert main(["batch", str(REPO / "batches" / "turning_grid.toml"), "--workers", "1",
                 "--results", str(tmp_path), "--no-progress"]) == 0
    table = pd.read_parquet(tmp_path / "turning_grid" / "summary.parquet")
    assert len(table) == 12 and table["passed"].all()
