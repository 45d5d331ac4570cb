"""Batch runner: many runs of one scenario on a local process pool or a Dask cluster, resumable.

``results/<batch>/`` holds

* ``runs/<run-id>/``: each run's results folder, published atomically by
  :func:`orchestrator.run.run_scenario` (or a ``summary.json`` with status ``failed`` and
  the reason when the run could not start or its worker died),
* ``batch.json``: the batch file, the base scenario's hash and every run's id and overrides,
* ``summary.parquet`` and ``summary.csv``: one row per run (parameters, figures,
  verdicts, status and reason), rebuilt from the run folders after every batch,
* ``overview.png``: pass/fail counts and the distributions of the key figures.

A run folder with a ``summary.json`` is done: rerunning the batch skips it (runs that were
interrupted, or failed for an infrastructure reason such as a killed worker or a full disk,
are redone; runs that failed on their own too with ``retry_failed``).  The batch holds a
lock on its results folder, and its workers die with it (:mod:`orchestrator.worker_pool`),
so a resume started at once after the batch was killed finds no worker still writing.  Runs are deterministic, so
the table does not depend on the executor or the number of workers, except for the
columns in :data:`NONDETERMINISTIC_COLUMNS`.
"""

from __future__ import annotations

import contextlib
import json
import logging
import math
import os
import time as wallclock
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from orchestrator import acceptance, interrupts
from orchestrator.batch_spec import BatchSpec, RunSpec, load_batch
# WORKER_DIED, BatchError, RunTask and execute_run are part of this module's interface too
from orchestrator.batch_run import (WORKER_DIED, BatchError, RunTask, execute_run, pending_runs,  # noqa: F401
                                    pool_execute, read_summary, record_lost_run)
from orchestrator.dask_executor import DaskExecutor, check_scheduler
from orchestrator.errors import ScenarioError, ToolchainError
from orchestrator.time_limits import TIMED_OUT

log = logging.getLogger(__name__)

#: Table columns that depend on the machine, not on the run's inputs.
NONDETERMINISTIC_COLUMNS = ("wall_time_s",)
#: Figures shown in the overview whenever the table has them (suffix match).
OVERVIEW_FIGURES = ("min_separation_nm", "cost_per_nm", "co2_per_nm")


@dataclass
class BatchReport:
    """How a batch ended and where its table is."""

    folder: Path
    table: Any  # pandas.DataFrame
    ran: int
    skipped: int
    interrupted: bool
    wall_time_s: float

    @property
    def passed(self) -> int:
        return int(self.table["passed"].sum())

    @property
    def total(self) -> int:
        return len(self.table)


def run_batch(path, results_root="results", workers: int | None = None, scheduler: str | None = None,
              progress: bool = True, retry_failed: bool = False, tls: dict | None = None) -> BatchReport:
    """Run every run of the batch file ``path`` not yet done, then rebuild its table.

    Parameters
    ----------
    path : path-like
        The batch TOML file.
    results_root : path-like
        Results folder; the batch writes ``results_root/<batch name>/``.
    workers : int, optional
        Local worker processes (default: one per core).  Ignored with ``scheduler``.
    scheduler : str, optional
        Address of a Dask distributed scheduler (``tcp://host:8786``); its workers must
        import this package and see the scenario and the results folder at the same paths.
    progress : bool
        Show a progress bar (tqdm).
    retry_failed : bool
        Redo runs recorded as failed (by default a failed run counts as done).
    tls : dict, optional
        ``{"ca": ..., "cert": ..., "key": ...}``: PEM files for a ``tls://`` scheduler
        (:mod:`orchestrator.dask_executor`).

    Raises
    ------
    ScenarioError
        For a malformed batch file or an override the scenario does not accept.
    BatchError
        When the Dask scheduler cannot be reached, or its address and TLS files do not fit.
    """
    started = wallclock.perf_counter()
    tls_files = check_scheduler(scheduler, **(tls or {})) if scheduler is not None or tls else None
    spec = load_batch(path)
    runs = spec.runs()
    check_against_scenario(spec, runs)
    root = Path(results_root) / spec.name
    executor = (DaskExecutor(scheduler, tls_files) if scheduler is not None
                else LocalPool(workers or os.cpu_count() or 1))
    executor.connect()  # a scheduler that cannot be reached or refuses: nothing is written yet
    try:
        with interrupts.handled():  # Ctrl-C/SIGTERM stop it from any caller, not only the command line
            return _run_pending(spec, runs, root, executor, progress, retry_failed, started)
    finally:
        executor.close()


def _run_pending(spec: BatchSpec, runs: list[RunSpec], root: Path, executor, progress: bool, retry_failed: bool,
                 started: float) -> BatchReport:
    """Run the runs of ``spec`` not yet done into ``root`` with ``executor``; the table after."""
    (root / "runs").mkdir(parents=True, exist_ok=True)
    with results_lock(root):
        _write_json_atomic(root / "batch.json", _manifest(spec, runs))
        todo = pending_runs(root, runs, retry_failed)
        tasks = [RunTask(str(spec.scenario), str(root.resolve()), run.run_id, run.overrides) for run in todo]
        bar = _progress_bar(len(runs), len(runs) - len(todo), spec.name, progress)
        interrupted = False
        results = executor.run(tasks)
        try:
            for task, record in results:
                if record["status"] in ("worker_died", TIMED_OUT):
                    record_lost_run(task, record)
                if bar is not None:
                    bar.update(1)
        except KeyboardInterrupt:
            interrupted = True
            interrupts.acknowledge()  # the pool lets the running runs end and write their folders
        finally:
            with interrupts.deferred():
                results.close()
            if bar is not None:
                bar.close()
        with interrupts.deferred():
            # runs that published a folder during this batch, including those that ended
            # (finished or interrupted) while the pool shut down after a Ctrl-C
            ran = sum(read_summary(root / "runs" / task.run_id) is not None for task in tasks)
            table = batch_table(spec, root)
            write_table(table, root)
            write_overview(table, spec, root / "overview.png")
            from orchestrator.report import write_report

            write_report(root)
    return BatchReport(root, table, ran, len(runs) - len(todo), interrupted, wallclock.perf_counter() - started)


LOCK_NAME = ".batch.lock"


@contextlib.contextmanager
def results_lock(root: Path) -> Iterator[None]:
    """Hold the batch results folder ``root`` for this process (an OS lock, freed if it dies).

    A second batch writing the same folder would clear the first one's staging folders and
    mix their tables; it stops instead with a message naming the holder's process id.
    """
    import fcntl

    lock_path = root / LOCK_NAME
    handle = open(lock_path, "a+")
    try:
        fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        handle.seek(0)
        holder = handle.read().strip() or "unknown"
        handle.close()
        raise BatchError(f"{root}: another batch is writing this results folder (process {holder}); "
                         "wait for it to end, or give another --results folder") from None
    try:
        handle.seek(0)
        handle.truncate()
        handle.write(f"{os.getpid()}\n")
        handle.flush()
        yield
    finally:
        handle.seek(0)
        handle.truncate()
        fcntl.flock(handle, fcntl.LOCK_UN)
        handle.close()


# -- checks and resumption ------------------------------------------------------------------
def check_against_scenario(spec: BatchSpec, runs: list[RunSpec]) -> None:
    """Every run's overrides load, and the first run's participants build.

    An error names the batch file and the batch key the scenario rejects.
    """
    from orchestrator.master import CoSimulation
    from orchestrator.scenario import load_scenario

    def fails(overrides, build: bool) -> str | None:
        try:
            scenario = load_scenario(spec.scenario, overrides)
            if build:
                CoSimulation(scenario).close()
        except ToolchainError as exc:
            return str(exc)
        return None

    for run in runs:
        problem = fails(run.overrides, build=run.index == 0)
        if problem is None:
            continue
        for key, value in run.overrides.items():
            if fails({key: value}, build=run.index == 0) is not None:
                situation = bool(spec.situations) and key in spec.situations[0].overrides
                table = ("set" if key in spec.fixed else "grid" if key in spec.grid
                         else "situations" if situation else "monte_carlo")
                raise ScenarioError(f"{spec.path}: '{table}.\"{key}\"' (run {run.index}, value {_short(value)}): "
                                    f"the scenario does not accept it: {problem}")
        raise ScenarioError(f"{spec.path}: run {run.index}: the scenario does not accept its overrides: {problem}")


# -- executors ----------------------------------------------------------------------------------
class LocalPool:
    """Local worker processes (``spawn``), one run each at a time (see :mod:`orchestrator.worker_pool`)."""

    def __init__(self, workers: int) -> None:
        self.workers = max(1, int(workers))

    def connect(self) -> None:
        """Nothing to reach: the workers start with the first run."""

    def close(self) -> None:
        """The pool ends with its runs."""

    def run(self, tasks: list[RunTask]) -> Iterator[tuple[RunTask, dict]]:
        """Yield ``(task, record)`` as runs complete; closing the generator stops the pool."""
        from orchestrator.worker_pool import WorkerPool

        yield from WorkerPool(self.workers, pool_execute).run(tasks)


# -- the table and the overview -------------------------------------------------------------------
def batch_table(spec: BatchSpec, root: Path, runs: list[RunSpec] | None = None):
    """One row per run of ``spec`` (or of ``runs``), read from ``root/runs/<id>/summary.json``.

    Columns: ``run_id``, ``index``, ``param:<key>`` per varied parameter, ``status``,
    ``reason``, one column per figure (acceptance metrics and ``report.columns``, by their
    dotted path), ``ok:<criterion>`` per criterion, ``passed`` (finished and every criterion
    met), ``failed_criteria`` and ``wall_time_s``.  A run never started has status
    ``not run``.
    """
    import pandas as pd

    figures = list(dict.fromkeys([c.metric for c in spec.acceptance] + list(spec.report_columns)))
    rows = []
    for run in spec.runs() if runs is None else runs:
        summary = read_summary(root / "runs" / run.run_id) or {"status": "not run", "reason": "no results yet"}
        row = {"run_id": run.run_id, "index": run.index}
        row.update({f"param:{k}": v for k, v in run.parameters.items()})
        row.update(status=summary.get("status"), reason=summary.get("reason", ""))
        for path in figures:
            try:
                row[path] = acceptance.lookup(summary, path)
            except acceptance.MissingFigure:
                row[path] = None
        verdicts = acceptance.evaluate(spec.acceptance, summary)
        row.update({f"ok:{v.name}": v.passed for v in verdicts})
        row["passed"] = summary.get("status") == "finished" and all(v.passed for v in verdicts)
        row["failed_criteria"] = "; ".join(f"{v.name}: {v.reason}" for v in verdicts if not v.passed)
        row["wall_time_s"] = summary.get("wall_time_s")
        rows.append(row)
    table = pd.DataFrame(rows)
    for column in table.columns:
        table[column] = _uniform_column(table[column])
    return table


def _uniform_column(column):
    """Numbers stay numbers; anything else becomes text (JSON for lists and tables), for Parquet."""
    import pandas as pd

    values = [v for v in column if v is not None and not (isinstance(v, float) and math.isnan(v))]
    if all(isinstance(v, bool) for v in values):
        return column.astype("boolean") if len(values) < len(column) else column.astype(bool)
    if all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in values):
        return pd.to_numeric(column).astype(float) if len(values) < len(column) or any(
            isinstance(v, float) for v in values) else column.astype("int64")
    return column.map(lambda v: None if v is None else v if isinstance(v, str) else json.dumps(v, sort_keys=True))


def write_table(table, root: Path) -> None:
    """``summary.parquet`` and ``summary.csv``, each replaced atomically."""
    for name, write in (("summary.parquet", lambda p: table.to_parquet(p, index=False)),
                        ("summary.csv", lambda p: table.to_csv(p, index=False))):
        staging = root / f".{name}.partial"
        write(staging)
        os.replace(staging, root / name)


def write_overview(table, spec: BatchSpec, target: Path) -> Path:
    """One page: runs by outcome, and histograms of the key figures present in the table."""
    from matplotlib.figure import Figure

    outcome = table.apply(lambda r: "passed" if r["passed"] else r["status"] if r["status"] != "finished"
                          else "criteria not met", axis=1)
    numeric = [c for c in table.columns if c not in ("index", "wall_time_s") and not c.startswith(("param:", "ok:"))
               and table[c].dtype.kind in "fi" and table[c].notna().any()]
    numeric = sorted(numeric, key=lambda c: not c.endswith(OVERVIEW_FIGURES))[:5]  # stable: key figures first
    fig = Figure(figsize=(11, 7.5), layout="constrained")
    axes = fig.subplots(2, 3).ravel()
    order = ["passed", "criteria not met", "failed", "interrupted", "not run"]
    counts = outcome.value_counts()
    labels = [k for k in order if k in counts] + [k for k in counts.index if k not in order]
    colors = {"passed": "tab:green", "criteria not met": "tab:orange", "failed": "tab:red"}
    axes[0].bar(labels, [counts[k] for k in labels], color=[colors.get(k, "tab:gray") for k in labels])
    axes[0].set_title("runs by outcome")
    axes[0].set_ylabel("runs")
    for ax, column in zip(axes[1:], numeric):
        values = table[column].dropna()
        ax.hist(values, bins=min(20, max(5, len(values) // 3)), color="tab:blue", alpha=0.8)
        for criterion in spec.acceptance:
            if criterion.metric == column and isinstance(criterion.value, (int, float)) and not isinstance(criterion.value, bool):
                ax.axvline(criterion.value, color="tab:red", ls="--", label=f"{criterion.op} {criterion.value:g}")
                ax.legend()
        ax.set_title(column, fontsize=9)
        ax.set_ylabel("runs")
    for ax in axes[1 + len(numeric):]:
        ax.axis("off")
    passed = int(table["passed"].sum())
    fig.suptitle(f"{spec.name}: {passed}/{len(table)} runs passed ({100.0 * passed / max(len(table), 1):.0f} %)")
    fig.savefig(target, dpi=100)
    return target


# -- helpers --------------------------------------------------------------------------------------
def _manifest(spec: BatchSpec, runs: list[RunSpec]) -> dict:
    return {"batch": str(spec.path), "name": spec.name, "scenario": str(spec.scenario),
            "scenario_sha256": spec.scenario_sha256, "description": spec.description,
            "acceptance": [c.describe() for c in spec.acceptance], "report_series": list(spec.report_series),
            "runs": [{"run_id": r.run_id, "index": r.index, "overrides": r.overrides, "parameters": r.parameters}
                     for r in runs]}


def _write_json_atomic(target: Path, data: dict) -> None:
    staging = target.parent / f".{target.name}.partial"
    staging.write_text(json.dumps(data, indent=2) + "\n")
    os.replace(staging, target)


def _progress_bar(total: int, initial: int, name: str, enabled: bool):
    if not enabled:
        return None
    from tqdm import tqdm

    return tqdm(total=total, initial=initial, desc=name, unit="run")


def _short(value, limit: int = 60) -> str:
    text = json.dumps(value, default=str)
    return text if len(text) <= limit else text[:limit - 3] + "..."
