"""A run whose worker died or was ended: the batch records why, unless the run published its own end."""

import json

import pytest

from orchestrator.batch_run import RunTask, record_lost_run


def _task(tmp_path):
    return RunTask(scenario="s.toml", batch_root=str(tmp_path), run_id="r0001", overrides={"x": 1})


def _publish(tmp_path, summary):
    folder = tmp_path / "runs" / "r0001"
    folder.mkdir(parents=True)
    (folder / "summary.json").write_text(json.dumps(summary))


def _summary(tmp_path):
    return json.loads((tmp_path / "runs" / "r0001" / "summary.json").read_text())


LOST = {"status": "worker_died", "reason": "its worker process died (signal 9)", "infrastructure": True}


def test_a_run_that_published_nothing_is_recorded_as_failed_with_the_reason(tmp_path):
    record_lost_run(_task(tmp_path), LOST)
    summary = _summary(tmp_path)
    assert (summary["status"], summary["reason"], summary["infrastructure"]) == (
        "failed", "its worker process died (signal 9)", True)
    assert summary["overrides"] == {"x": 1}


@pytest.mark.parametrize("published", [{"status": "interrupted", "reason": "stopped"}, {"reason": "no status"}])
def test_an_interrupted_or_statusless_summary_is_replaced_by_the_record(tmp_path, published):
    # a worker stopped by the broken pool's shutdown leaves an "interrupted" run: kept, it
    # would read as a run the user stopped, and the resume would not see why it was lost
    _publish(tmp_path, published)
    record_lost_run(_task(tmp_path), LOST)
    summary = _summary(tmp_path)
    assert summary["status"] == "failed" and summary["reason"] == LOST["reason"]


def test_a_run_that_published_its_own_end_keeps_it(tmp_path):
    # e.g. its own watchdog ended it after writing "timed_out": the run's word stands
    _publish(tmp_path, {"status": "timed_out", "reason": "wall-clock limit"})
    record_lost_run(_task(tmp_path), {**LOST, "status": "ended"})
    assert _summary(tmp_path) == {"status": "timed_out", "reason": "wall-clock limit"}
