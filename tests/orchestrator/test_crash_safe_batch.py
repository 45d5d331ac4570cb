"""Crash-safe batches: a batch killed with SIGKILL leaves no worker behind, and a resume
started at once finishes every run; a resume redoes runs that failed for infrastructure
reasons (a killed worker, a full disk) and keeps those that failed on their own."""

import errno
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import psutil
import pytest

from orchestrator.batch import RunTask, execute_run, pending_runs, run_batch
from orchestrator.batch_spec import load_batch

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[1]

SLEEPY = """
[simulation]
name = "sleepy"
steps = 5
dt_s = 1.0
step_timeout_s = 7200.0
[participants.clock]
type = "python"
class = "sample_participants:Clock"
[participants.nap]
type = "python"
class = "sample_participants:Sleeper"
[participants.nap.options]
at_s = 2.0
unless_exists = "{marker}"
[outputs]
format = "csv"
figures = []
"""

BATCH = """
[batch]
name = "crashy"
scenario = "{scenario}"
[grid]
"participants.clock.options" = [{{}}, {{nan_at_s = 1.0e9}}, {{nan_at_s = 2.0e9}}]
[[acceptance]]
metric = "status"
op = "=="
value = "finished"
"""


def children(pid: int) -> list[int]:
    """The batch's worker processes (not multiprocessing's resource tracker)."""
    found = []
    try:
        for child in psutil.Process(pid).children():
            try:
                if not any("resource_tracker" in part for part in child.cmdline()):
                    found.append(child.pid)
            except psutil.Error:  # ended meanwhile
                continue
    except psutil.Error:
        return []
    return found


def alive(pid: int) -> bool:
    try:  # a zombie has ended
        return psutil.Process(pid).status() != psutil.STATUS_ZOMBIE
    except psutil.Error:
        return False


@pytest.mark.slow
@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc for the workers")
def test_a_batch_killed_with_sigkill_leaves_no_worker_and_resumes_at_once(tmp_path):
    marker = tmp_path / "wake"
    (tmp_path / "sleepy.toml").write_text(SLEEPY.format(marker=marker))
    batch = tmp_path / "crashy.toml"
    batch.write_text(BATCH.format(scenario="sleepy.toml"))
    results = tmp_path / "results"
    process = subprocess.Popen(
        [sys.executable, "-m", "orchestrator", "batch", str(batch), "--results", str(results), "--workers", "2",
         "--no-progress"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        env={**os.environ, "PYTHONPATH": f"{HERE}:{REPO}"})
    sleeping = 0
    for line in process.stdout:  # both workers inside a run that would sleep for an hour
        sleeping += line.startswith("sleeper: sleeping")
        if sleeping == 2:
            break
    assert sleeping == 2, process.communicate()
    workers = children(process.pid)
    assert len(workers) == 2
    process.kill()  # SIGKILL: no handler, no clean-up
    process.wait()
    marker.write_text("")  # from now on the runs do not sleep
    report = run_batch(batch, results, workers=2, progress=False)  # the resume, at once
    assert [pid for pid in workers if alive(pid)] == []  # the killed batch's workers died with it
    table = report.table
    assert list(table["status"]) == ["finished"] * 3 and report.passed == 3
    assert report.ran == 3 and report.skipped == 0  # the two cut short and the one never started
    runs = results / "crashy" / "runs"
    assert sorted(p.name for p in runs.iterdir()) == sorted(table["run_id"])  # no staging folder, no -2 copy
    for run_id in table["run_id"]:
        summary = json.loads((runs / run_id / "summary.json").read_text())
        assert summary["simulation"]["steps_done"] == 5


KILLED = """
[simulation]
name = "killed"
steps = 4
dt_s = 1.0
[participants.victim]
type = "python"
class = "sample_participants:SelfKiller"
[participants.victim.options]
at_s = 2.0
unless_exists = "{marker}"
[outputs]
format = "csv"
figures = []
"""


def by_crash(table) -> dict:
    return {bool(row["param:participants.victim.options.crash"]): row for _, row in table.iterrows()}


@pytest.mark.slow
def test_a_resume_redoes_runs_killed_from_outside_and_keeps_those_that_failed_on_their_own(tmp_path):
    marker = tmp_path / "spare"
    (tmp_path / "killed.toml").write_text(KILLED.format(marker=marker))
    batch = tmp_path / "killed_batch.toml"
    batch.write_text(BATCH.format(scenario="killed.toml").replace(
        '"participants.clock.options" = [{}, {nan_at_s = 1.0e9}, {nan_at_s = 2.0e9}]',
        '"participants.victim.options.crash" = [false, true]'))
    first = by_crash(run_batch(batch, tmp_path, workers=2, progress=False).table)
    assert (first[False]["status"], first[True]["status"]) == ("failed", "failed")
    assert first[False]["reason"].endswith("killed by SIGKILL")
    assert first[True]["reason"] == "victim: RuntimeError: a bug of its own"
    own = tmp_path / "crashy" / "runs" / first[True]["run_id"] / "summary.json"
    kept = own.read_text()
    marker.write_text("")  # the machine has memory again
    second = run_batch(batch, tmp_path, workers=2, progress=False)
    table = by_crash(second.table)
    assert (table[False]["status"], table[True]["status"]) == ("finished", "failed")
    assert (second.ran, second.skipped) == (1, 1)
    assert own.read_text() == kept  # the run that failed on its own was not redone


def test_a_run_that_could_not_write_its_results_is_redone_on_resume(tmp_path, monkeypatch):
    from orchestrator import run as run_module

    (tmp_path / "killed.toml").write_text(KILLED.format(marker=tmp_path))  # the marker exists: no kill
    batch = tmp_path / "disk.toml"
    batch.write_text(BATCH.format(scenario="killed.toml").replace(
        '"participants.clock.options" = [{}, {nan_at_s = 1.0e9}, {nan_at_s = 2.0e9}]',
        '"participants.victim.options.at_s" = [2.0]'))
    spec = load_batch(batch)
    (run_spec,) = spec.runs()
    root = tmp_path / "results" / spec.name
    (root / "runs").mkdir(parents=True)

    def full(*args, **kwargs):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(run_module, "_write", full)
    task = RunTask(str(spec.scenario), str(root), run_spec.run_id, run_spec.overrides)
    record = execute_run(task)
    assert record["status"] == "failed" and record["infrastructure"] is True
    assert "No space left on device" in record["reason"]
    summary = json.loads((root / "runs" / run_spec.run_id / "summary.json").read_text())
    assert summary["status"] == "failed" and summary["infrastructure"] is True
    assert [r.run_id for r in pending_runs(root, spec.runs())] == [run_spec.run_id]  # redone on resume
    monkeypatch.undo()
    assert execute_run(task)["status"] == "finished"
    assert pending_runs(root, spec.runs()) == []


def test_a_worker_past_its_call_deadline_is_ended_by_the_batch(tmp_path):
    """Native code holding the interpreter lock: neither the run nor its watchdog can act, the batch can."""
    from orchestrator import worker_pool

    pool = worker_pool.WorkerPool(1, _hold_the_lock)
    (task, record), = list(pool.run(["hold"]))  # without the batch's deadline: an hour
    assert task == "hold" and record["status"] == "timed out" and record["infrastructure"] is False
    assert record["reason"] == ("participant 'hog' did not return from its step; the call held the interpreter "
                                "lock, so the batch ended its worker")


def _hold_the_lock(task):
    import ctypes

    from orchestrator import time_limits

    time_limits._publish_deadline(time.monotonic() + 0.5, "participant 'hog' did not return from its step")
    ctypes.PyDLL(None).sleep(3600)  # PyDLL: the interpreter lock is held throughout
    return {"status": "finished"}


def test_a_resume_never_clears_the_staging_folder_of_a_process_still_running(tmp_path):
    from orchestrator.results import stale_staging

    runs = tmp_path / "runs"
    runs.mkdir()
    other = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    ended = subprocess.Popen([sys.executable, "-c", "pass"])
    ended.wait()
    try:
        alive_staging = runs / f".abc123.{other.pid}-0a1b2c3d.partial"
        dead_staging = runs / f".abc123.{ended.pid}-0a1b2c3d.partial"
        for folder in (alive_staging, dead_staging):
            folder.mkdir()
            (folder / "timeseries.parquet").write_text("being written")
        assert stale_staging(runs, "abc123") == [dead_staging]
    finally:
        other.kill()
        other.wait()
    assert stale_staging(runs, "abc123") == sorted([alive_staging, dead_staging])  # its owner has ended now


TIMED = """
[simulation]
name = "timed"
steps = 6
dt_s = 1.0
step_timeout_s = 1.0
[participants.clock]
type = "python"
class = "sample_participants:Clock"
[participants.nap]
type = "python"
class = "sample_participants:Sleeper"
[participants.nap.options]
at_s = 2.0
"""


@pytest.mark.slow
def test_timed_out_runs_in_a_batch_keep_their_status_and_are_not_redone(tmp_path):
    """One run stopped at its limit in Python, one whose participant swallows the limit and is
    ended with its worker process after its status was written; a resume keeps both."""
    (tmp_path / "timed.toml").write_text(TIMED)
    batch = tmp_path / "timed_batch.toml"
    batch.write_text(BATCH.format(scenario="timed.toml").replace(
        '"participants.clock.options" = [{}, {nan_at_s = 1.0e9}, {nan_at_s = 2.0e9}]',
        '"participants.nap.options.swallow" = [false, true]'))
    first = run_batch(batch, tmp_path, workers=2, progress=False)
    rows = {bool(r["param:participants.nap.options.swallow"]): r for _, r in first.table.iterrows()}
    for swallow in (False, True):
        assert rows[swallow]["status"] == "timed out"
        assert rows[swallow]["reason"].startswith("participant 'nap' did not return from its step at t = 2 s")
    assert rows[True]["reason"].endswith("so the process was ended")  # by the run's own watchdog
    summary = json.loads((tmp_path / "crashy" / "runs" / rows[True]["run_id"] / "summary.json").read_text())
    assert summary["simulation"]["steps_done"] == 2 and summary["timeseries"] == "timeseries.csv"
    runs = tmp_path / "crashy" / "runs"
    assert sorted(p.name for p in runs.iterdir()) == sorted(first.table["run_id"])  # no second record of it
    second = run_batch(batch, tmp_path, workers=2, progress=False)
    assert (second.ran, second.skipped) == (0, 2)


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc for the process state")
def test_a_staging_folder_of_an_ended_but_unreaped_process_is_stale(tmp_path):
    """A killed worker that nobody reaps (a container without an init that reaps orphans) is a
    zombie: the signal check still finds its pid, yet it will never write its folder again."""
    from orchestrator.results import stale_staging

    pid = os.fork()
    if pid == 0:  # the child ends at once and stays unreaped until the end of this test
        os._exit(0)
    try:
        for _ in range(200):  # until the child has ended
            if psutil.Process(pid).status() == psutil.STATUS_ZOMBIE:
                break
            time.sleep(0.01)
        ended = tmp_path / f".run1.{pid}-abcd.partial"
        ours = tmp_path / f".run1.{os.getppid()}-abcd.partial"  # a live process (pytest's parent)
        ended.mkdir()
        ours.mkdir()
        assert stale_staging(tmp_path, "run1") == [ended]
    finally:
        os.waitpid(pid, 0)
