"""What a batch's worker records for one run and what a resume redoes, tested without a pool:
the run folders a killed or failed attempt leaves are written here as it leaves them, and the
scenario run is a stand-in, so each case takes milliseconds (the slow tests in
``test_crash_safe_batch.py`` and ``test_batch.py`` do the same through real workers)."""

import json
import logging
import signal
import subprocess
import sys

import pytest

from orchestrator import batch_run, interrupts
from orchestrator import run as run_module
from orchestrator.batch_run import RunTask, execute_run, needs_redo, pending_runs, pool_execute, record_lost_run, write_failure
from orchestrator.batch_spec import RunSpec
from orchestrator.errors import ResultsError, ToolchainError
from orchestrator.time_limits import TIMED_OUT


@pytest.fixture(scope="module")
def dead_pid():
    """The id of a process that has ended (a staging folder named after it is stale)."""
    ended = subprocess.Popen([sys.executable, "-c", "pass"])
    ended.wait()
    return ended.pid


def run(run_id):
    return RunSpec(run_id=run_id, index=int(run_id[1:]), overrides={}, parameters={})


def publish(root, run_id, summary):
    folder = root / "runs" / run_id
    folder.mkdir(parents=True)
    (folder / "summary.json").write_text(summary if isinstance(summary, str) else json.dumps(summary))
    (folder / "timeseries.csv").write_text("t\n0\n")
    return folder


def staging(root, run_id, pid):
    folder = root / "runs" / f".{run_id}.{pid}-0a1b2c3d.partial"
    folder.mkdir(parents=True)
    (folder / "timeseries.parquet").write_text("cut short")
    return folder


SUMMARIES = {
    "r1": None,  # never started, or killed before publishing
    "r2": {"status": "finished"},
    "r3": {"status": "interrupted", "reason": "interrupted by the user (Ctrl-C)"},
    "r4": {"status": "failed", "reason": "killed by SIGKILL", "infrastructure": True},
    "r5": {"status": "failed", "reason": "victim: RuntimeError: a bug of its own", "infrastructure": False},
    "r6": {"status": TIMED_OUT, "reason": "participant 'nap' did not return from its step"},
    "r7": "{not json",
}


@pytest.fixture
def batch(tmp_path):
    for run_id, summary in SUMMARIES.items():
        if summary is not None:
            publish(tmp_path, run_id, summary)
    return tmp_path, [run(run_id) for run_id in SUMMARIES]


def test_a_resume_redoes_runs_without_a_result_interrupted_or_lost_to_the_machine_and_clears_their_folders(batch):
    root, runs = batch
    todo = [r.run_id for r in pending_runs(root, runs)]
    assert todo == ["r1", "r3", "r4", "r7"]
    for run_id in ("r3", "r4", "r7"):
        assert not (root / "runs" / run_id).exists()
    for run_id in ("r2", "r5", "r6"):  # kept as they were
        assert (root / "runs" / run_id / "timeseries.csv").is_file()


def test_with_retry_failed_a_resume_also_redoes_the_runs_that_failed_or_timed_out_on_their_own(batch):
    root, runs = batch
    assert [r.run_id for r in pending_runs(root, runs, retry_failed=True)] == ["r1", "r3", "r4", "r5", "r6", "r7"]
    assert [p.name for p in (root / "runs").iterdir()] == ["r2"]


@pytest.mark.parametrize("summary, retry_failed, redo", [
    ({"status": "finished"}, False, False), ({"status": "finished"}, True, False),
    ({"status": "interrupted"}, False, True),
    ({"status": "failed", "infrastructure": True}, False, True),
    ({"status": "finished", "infrastructure": True}, False, True),  # the flag alone decides
    ({"status": "failed"}, False, False), ({"status": "failed"}, True, True),
    ({"status": TIMED_OUT}, False, False), ({"status": TIMED_OUT}, True, True),
    ({"status": "passed"}, True, False),
])
def test_which_published_runs_a_resume_redoes(summary, retry_failed, redo):
    assert needs_redo(summary, retry_failed) is redo


def test_a_resume_clears_the_staging_folders_of_ended_attempts_of_every_run_but_not_of_live_ones(tmp_path, dead_pid):
    publish(tmp_path, "r2", {"status": "finished"})
    stale = [staging(tmp_path, "r1", dead_pid), staging(tmp_path, "r2", dead_pid)]
    live = staging(tmp_path, "r1", 1)  # a process still running (init)
    assert [r.run_id for r in pending_runs(tmp_path, [run("r1"), run("r2")])] == ["r1"]
    assert not any(folder.exists() for folder in stale)
    assert live.is_dir()


def test_a_summary_is_read_from_the_run_folder_and_an_unreadable_one_is_none(tmp_path):
    assert batch_run.read_summary(publish(tmp_path, "r1", {"status": "finished", "x": 1})) == {"status": "finished",
                                                                                              "x": 1}
    assert batch_run.read_summary(publish(tmp_path, "r2", "[1, ")) is None
    assert batch_run.read_summary(tmp_path / "runs" / "r3") is None


def task(root, run_id="r1"):
    return RunTask(scenario="s.toml", batch_root=str(root), run_id=run_id, overrides={"x": 1})


def summary_of(root, run_id="r1"):
    return json.loads((root / "runs" / run_id / "summary.json").read_text())


class Report:
    status = "finished"
    reason = ""


def test_a_worker_runs_the_scenario_into_the_batch_folder_after_clearing_its_stale_staging(tmp_path, monkeypatch,
                                                                                          dead_pid):
    stale = staging(tmp_path, "r1", dead_pid)
    calls = []

    def fake(scenario, results_root, **kwargs):
        calls.append((scenario, results_root, kwargs, stale.exists()))
        return Report()

    monkeypatch.setattr(run_module, "run_scenario", fake)
    assert execute_run(task(tmp_path)) == {"status": "finished", "reason": ""}
    assert calls == [("s.toml", str(tmp_path), {"progress": False, "run_id": "r1", "overrides": {"x": 1},
                                                 "group": "runs"}, False)]


@pytest.mark.parametrize("error, reason, infrastructure", [
    (ResultsError("results: cannot write results here: disk full"), "results: cannot write results here: disk full",
     True),
    (ToolchainError("s.toml: participants.ctrl: no such type"), "s.toml: participants.ctrl: no such type", False),
    (OSError(28, "No space left on device"), "OSError: [Errno 28] No space left on device", True),
    (ValueError("a bug of its own"), "ValueError: a bug of its own", False),
])
def test_a_run_that_cannot_start_is_recorded_as_failed_with_its_reason_and_whose_fault(tmp_path, monkeypatch, error,
                                                                                      reason, infrastructure):
    def fake(*args, **kwargs):
        raise error

    monkeypatch.setattr(run_module, "run_scenario", fake)
    record = execute_run(task(tmp_path))
    assert record == {"status": "failed", "reason": reason, "infrastructure": infrastructure}
    summary = summary_of(tmp_path)
    assert (summary["status"], summary["reason"], summary["infrastructure"]) == ("failed", reason, infrastructure)
    # a resume redoes exactly the failures that were not the run's own
    assert [r.run_id for r in pending_runs(tmp_path, [run("r1")])] == (["r1"] if infrastructure else [])


def test_a_run_stopped_by_ctrl_c_is_interrupted_and_records_nothing(tmp_path, monkeypatch):
    def fake(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(run_module, "run_scenario", fake)
    assert execute_run(task(tmp_path)) == {"status": "interrupted", "reason": "interrupted by the user (Ctrl-C)"}
    assert not (tmp_path / "runs" / "r1").exists()


def test_a_failure_that_cannot_be_recorded_either_is_returned_and_logged(tmp_path, monkeypatch, caplog):
    def fake(*args, **kwargs):
        raise ValueError("a bug")

    def unwritable(*args, **kwargs):
        raise ResultsError("results: read-only")

    monkeypatch.setattr(run_module, "run_scenario", fake)
    monkeypatch.setattr(batch_run, "write_failure", unwritable)
    with caplog.at_level(logging.WARNING, logger="orchestrator.batch_run"):
        record = execute_run(task(tmp_path))
    assert record == {"status": "failed", "reason": "ValueError: a bug", "infrastructure": False}
    assert "run r1: its failure could not be recorded either: results: read-only" in caplog.text


@pytest.mark.parametrize("record, status, infrastructure", [
    ({"status": "worker_died", "reason": "killed by SIGKILL", "infrastructure": True}, "failed", True),
    ({"status": TIMED_OUT, "reason": "the batch ended its worker"}, TIMED_OUT, False),
])
def test_a_lost_run_is_recorded_with_the_workers_status_and_a_resume_redoes_only_the_machines_losses(
        tmp_path, dead_pid, record, status, infrastructure):
    stale = staging(tmp_path, "r1", dead_pid)  # what the killed worker was writing
    record_lost_run(task(tmp_path), record)
    summary = summary_of(tmp_path)
    assert (summary["status"], summary["reason"], summary["infrastructure"]) == (status, record["reason"],
                                                                                 infrastructure)
    assert not stale.exists()
    assert [r.run_id for r in pending_runs(tmp_path, [run("r1")])] == (["r1"] if infrastructure else [])


@pytest.mark.parametrize("published", [{"status": "finished"}, {"status": "failed", "reason": "its own"}])
def test_a_lost_run_that_published_its_end_keeps_it(tmp_path, published):
    publish(tmp_path, "r1", published)
    record_lost_run(task(tmp_path), {"status": "worker_died", "reason": "killed", "infrastructure": True})
    assert summary_of(tmp_path) == published
    assert [p.name for p in (tmp_path / "runs").iterdir()] == ["r1"]  # no second record beside it


def test_a_lost_run_that_cannot_be_recorded_is_logged(tmp_path, monkeypatch, caplog):
    def unwritable(*args, **kwargs):
        raise OSError("read-only file system")

    monkeypatch.setattr(batch_run, "write_failure", unwritable)
    with caplog.at_level(logging.WARNING, logger="orchestrator.batch_run"):
        record_lost_run(task(tmp_path), {"status": "worker_died", "reason": "killed"})
    assert "run r1: could not record that its worker died: read-only file system" in caplog.text


def test_a_failure_record_replaces_an_interrupted_attempt_in_place(tmp_path, dead_pid):
    publish(tmp_path, "r1", {"status": "interrupted"})
    stale = staging(tmp_path, "r1", dead_pid)
    folder = write_failure(tmp_path, task(tmp_path), "killed by SIGKILL", status="failed", infrastructure=True)
    assert folder == tmp_path / "runs" / "r1"
    assert sorted(p.name for p in (tmp_path / "runs").iterdir()) == ["r1"]
    assert not stale.exists()
    assert sorted(p.name for p in folder.iterdir()) == ["summary.json"]  # the attempt's files are gone
    assert summary_of(tmp_path) == {"scenario": "s.toml", "overrides": {"x": 1}, "run_id": "r1", "status": "failed",
                                    "reason": "killed by SIGKILL", "infrastructure": True,
                                    "recorded_by": "batch runner (the run produced no results)"}


def test_a_failure_record_defaults_to_failed_and_not_the_machines_fault(tmp_path):
    write_failure(tmp_path, task(tmp_path), "no such type")
    summary = summary_of(tmp_path)
    assert (summary["status"], summary["infrastructure"]) == ("failed", False)


def test_a_pool_worker_runs_its_run_under_the_stop_handlers_and_puts_them_back(tmp_path, monkeypatch):
    seen = []

    def fake(*args, **kwargs):
        seen.append((signal.getsignal(signal.SIGINT), signal.getsignal(signal.SIGTERM)))
        return Report()

    before = (signal.getsignal(signal.SIGINT), signal.getsignal(signal.SIGTERM))
    monkeypatch.setattr(run_module, "run_scenario", fake)
    assert pool_execute(task(tmp_path)) == {"status": "finished", "reason": ""}
    assert seen == [(interrupts._on_signal, interrupts._on_signal)]
    assert (signal.getsignal(signal.SIGINT), signal.getsignal(signal.SIGTERM)) == before


def test_a_failure_record_never_replaces_a_run_that_published_how_it_ended(tmp_path):
    publish(tmp_path, "r1", {"status": "finished"})
    folder = write_failure(tmp_path, task(tmp_path), "killed by SIGKILL")
    assert summary_of(tmp_path) == {"status": "finished"}  # the run's own word stands
    assert (tmp_path / "runs" / "r1" / "timeseries.csv").is_file()
    assert folder == tmp_path / "runs" / "r1-2" and summary_of(tmp_path, "r1-2")["reason"] == "killed by SIGKILL"
