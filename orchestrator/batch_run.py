"""One run of a batch, as a worker does it, and what a resume redoes.

:func:`execute_run` runs one run into ``<batch_root>/runs/<run_id>/`` (or records why it
could not start); :func:`pending_runs` picks the runs a batch (re)starts with, clearing the
folders of attempts that ended without publishing.  The executors of
:mod:`orchestrator.batch` (local pool, Dask) call these; nothing here knows which one runs it.
"""

from __future__ import annotations

import json
import logging
import shutil
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from orchestrator import interrupts
from orchestrator.batch_spec import RunSpec
from orchestrator.errors import ResultsError, ToolchainError
from orchestrator.results import stale_staging
from orchestrator.time_limits import TIMED_OUT

log = logging.getLogger(__name__)

WORKER_DIED = "the worker process died during the run (crash, or killed by the system)"


class BatchError(ToolchainError):
    """A batch cannot be run (cluster unreachable, results folder unusable)."""

    exit_code = 2


@dataclass(frozen=True)
class RunTask:
    """What a worker needs to run one run (small and picklable)."""

    scenario: str
    batch_root: str
    run_id: str
    overrides: dict[str, Any]


# -- checks and resumption ------------------------------------------------------------------
def pending_runs(root: Path, runs: list[RunSpec], retry_failed: bool = False) -> list[RunSpec]:
    """The runs to do: without a published result, interrupted, or failed for infrastructure reasons.

    A run recorded as failed for an infrastructure reason (its worker killed from outside, a
    full disk, a results folder that could not be written) is redone; a run that failed on
    its own (a model error, a crash of its own, a time limit) is kept unless
    ``retry_failed``.  Stale folders of the runs to do are cleared, but never a staging
    folder whose process is still running.
    """
    todo = []
    for run in runs:
        folder = root / "runs" / run.run_id
        for staging in stale_staging(folder.parent, run.run_id):
            shutil.rmtree(staging, ignore_errors=True)
        summary = read_summary(folder)
        if summary is not None and not needs_redo(summary, retry_failed):
            continue
        shutil.rmtree(folder, ignore_errors=True)
        todo.append(run)
    return todo


def needs_redo(summary: dict, retry_failed: bool = False) -> bool:
    """A published run a resume does again: interrupted, failed for an infrastructure reason, or
    (with ``retry_failed``) failed or timed out on its own."""
    status = summary.get("status")
    if status == "interrupted" or summary.get("infrastructure"):
        return True
    return retry_failed and status in ("failed", TIMED_OUT)


def read_summary(folder: Path) -> dict | None:
    try:
        return json.loads((folder / "summary.json").read_text())
    except (OSError, ValueError):
        return None


# -- the work of one run (in a worker) -----------------------------------------------------------
def execute_run(task: RunTask) -> dict[str, Any]:
    """Run one run into ``<batch_root>/runs/<run_id>/``; returns its status and reason.

    A scenario that cannot start (:class:`ToolchainError`, or a participant raising while
    it is built) is recorded as a failed run with the reason, so the batch goes on.
    """
    from orchestrator.run import run_scenario

    # a worker that died while running this id left its staging folder behind
    for staging in stale_staging(Path(task.batch_root) / "runs", task.run_id):
        shutil.rmtree(staging, ignore_errors=True)
    infrastructure = False
    try:
        report = run_scenario(task.scenario, task.batch_root, progress=False, run_id=task.run_id,
                              overrides=task.overrides, group="runs")
        return {"status": report.status, "reason": report.reason}
    except KeyboardInterrupt:
        return {"status": "interrupted", "reason": "interrupted by the user (Ctrl-C)"}
    except ResultsError as exc:  # the disk or the folder, not the run: a resume redoes it
        reason, infrastructure = str(exc), True
    except ToolchainError as exc:
        reason = str(exc)
    except OSError as exc:  # the machine (disk full while building, files gone): a resume redoes it
        reason, infrastructure = f"{type(exc).__name__}: {exc}", True
    except Exception as exc:  # a participant's own bug while building: record it, go on
        reason = f"{type(exc).__name__}: {exc}"
    try:
        write_failure(Path(task.batch_root), task, reason, infrastructure=infrastructure)
    except (OSError, ToolchainError) as exc:  # nothing can be written: the run stays to do
        log.warning("run %s: its failure could not be recorded either: %s", task.run_id, exc)
    return {"status": "failed", "reason": reason, "infrastructure": infrastructure}


def record_lost_run(task: RunTask, record: dict) -> None:
    """A run whose worker died or was ended: keep what the run published, else record why."""
    published = read_summary(Path(task.batch_root) / "runs" / task.run_id)
    if published is not None and published.get("status") not in ("interrupted", None):
        return  # e.g. a run its own watchdog ended after writing its status (timed out)
    try:
        write_failure(Path(task.batch_root), task, record["reason"], status=record["status"].replace(
            "worker_died", "failed"), infrastructure=bool(record.get("infrastructure")))
    except (OSError, ToolchainError) as exc:
        log.warning("run %s: could not record that its worker died: %s", task.run_id, exc)


def write_failure(batch_root: Path, task: RunTask, reason: str, status: str = "failed",
                  infrastructure: bool = False) -> Path:
    """Publish a run folder holding only a ``summary.json`` with ``status`` and ``reason``.

    ``infrastructure`` marks a failure that is not the run's (its worker killed from
    outside, a full disk): a resume redoes such a run.
    """
    from orchestrator.results import RunFolder

    for staging in stale_staging(batch_root / "runs", task.run_id):
        shutil.rmtree(staging, ignore_errors=True)
    # an earlier attempt of this run cut short (e.g. its worker stopped by the broken pool's
    # shutdown) is stale, as pending_runs treats it on a resume, and so is a summary that says
    # nothing of how the run ended: this record replaces it
    earlier = batch_root / "runs" / task.run_id
    summary = read_summary(earlier)
    if summary is not None and summary.get("status") in ("interrupted", None):
        shutil.rmtree(earlier, ignore_errors=True)
    folder = RunFolder(batch_root, "runs", task.run_id)
    folder.write_json("summary.json", {"scenario": task.scenario, "overrides": task.overrides,
                                       "run_id": task.run_id, "status": status, "reason": reason,
                                       "infrastructure": infrastructure,
                                       "recorded_by": "batch runner (the run produced no results)"})
    return folder.publish()


def pool_execute(task: RunTask) -> dict[str, Any]:
    # a running run stops on Ctrl-C as a single run does (status interrupted, folder kept)
    with interrupts.handle_signals():
        return execute_run(task)
