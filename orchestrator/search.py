"""Adversarial scenario search: an optimiser picks the runs of a batch to find where its objective is lowest.

A search file (:mod:`orchestrator.search_spec`) declares ranges under ``[monte_carlo]`` and
an objective; each evaluation is one run of the base scenario, picked by an optuna sampler
(TPE, CMA-ES, or uniform random sampling of the same ranges) from the evaluations before it,
and run on the batch's executors (local worker processes or a Dask cluster).
``results/<search>/`` holds

* ``runs/<run-id>/``: every evaluation's results folder, as a batch writes them,
* ``trials.jsonl``: the journal, one line per evaluation asked (its number, the optimiser's
  values and their distributions, the run id and overrides), written before the round runs,
* ``search.json``: the settings, the space, and how far the search got,
* ``summary.parquet``/``.csv``: one row per evaluation, ``progress.png``, ``boundary.csv``
  and ``boundary.png`` (how the objective varies over each parameter), ``worst/`` (the
  worst evaluations as one-run batch files) and ``report.html``
  (:mod:`orchestrator.search_results`, :mod:`orchestrator.report`).

Evaluations are asked in rounds of ``per_round`` (run in parallel); each is asked of a
sampler seeded from the search's seed and the evaluation's number, so the search depends
on its seed and on the results before it, never on the number of workers.  A search stopped
at any point (Ctrl-C or SIGTERM, wherever ``run_search`` is called from, or ``kill -9``) resumes by running the same command again: the journal's
evaluations without a published run are run first, every journaled evaluation is given
back to a fresh optimiser, and the search goes on; a larger ``--evaluations`` extends a
finished search.
"""

from __future__ import annotations

import json
import logging
import os
import time as wallclock
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from orchestrator import interrupts
from orchestrator.batch import LocalPool, _progress_bar, _write_json_atomic, check_against_scenario, results_lock
from orchestrator.batch_run import (TIMED_OUT, BatchError, RunTask, needs_redo, read_summary,
                                    record_lost_run)
from orchestrator.batch_spec import RunSpec, draw_overrides, run_id
from orchestrator.dask_executor import DaskExecutor, check_scheduler
from orchestrator.search_journal import JOURNAL, append_journal, drop_torn_tail, objective_of, read_journal, run_spec_of
from orchestrator.search_spec import SearchSpec, load_search

log = logging.getLogger(__name__)

#: Seeds of the per-evaluation samplers: ``seed * SEED_STRIDE + evaluation``.
SEED_STRIDE = 1_000_003


@dataclass
class SearchReport:
    """How a search ended, what it found and where its results are."""

    folder: Path
    table: Any  # pandas.DataFrame, one row per evaluation
    evaluated: int  # evaluations run by this command
    interrupted: bool
    first_failure: int | None  # the evaluation (counted from 1) of the first failure, or None
    failures: int
    best: float | None
    wall_time_s: float


class TrialChoices:
    """The values of one evaluation, suggested by an optuna trial (the space's fixed values kept)."""

    def __init__(self, trial) -> None:
        self.trial = trial

    def number(self, name: str, span) -> float:
        return span.low if span.high <= span.low else self.trial.suggest_float(name, span.low, span.high)

    def index(self, name: str, options) -> int:
        if len(options) == 1:
            return 0
        primitive = all(v is None or isinstance(v, (bool, int, float, str)) for v in options)
        if primitive and len({json.dumps(v) for v in options}) == len(options):
            return list(options).index(self.trial.suggest_categorical(name, list(options)))
        return int(self.trial.suggest_categorical(name, list(range(len(options)))))

    def integer(self, name: str, low: int, high: int) -> int:
        return low if high <= low else self.trial.suggest_int(name, low, high)

    def normal(self, name: str, mean: float, sd: float) -> float:  # refused by load_search
        raise ValueError(f"{name}: a normal distribution is not a searchable range")


def make_sampler(kind: str, seed: int, evaluation: int):
    """A fresh optuna sampler for evaluation number ``evaluation`` (0-based) of a search seeded ``seed``."""
    import optuna

    stream = (seed * SEED_STRIDE + evaluation) % 2**32
    if kind == "random":
        return optuna.samplers.RandomSampler(seed=stream)
    if kind == "cmaes":
        return optuna.samplers.CmaEsSampler(seed=stream)
    if kind in ("tpe-restart", "tpe-periodic"):
        from orchestrator.search_samplers import PERIOD, RestartingTPE

        return RestartingTPE(seed=stream, period=PERIOD if kind == "tpe-periodic" else None)
    return optuna.samplers.TPESampler(seed=stream, multivariate=True, group=True, constant_liar=True)


def run_search(path, results_root="results", workers: int | None = None, scheduler: str | None = None,
               progress: bool = True, tls: dict | None = None, evaluations: int | None = None,
               sampler: str | None = None, seed: int | None = None, report: bool = True,
               fails_below: float | None = None, until_failure: bool = False) -> SearchReport:
    """Run (or resume, or extend) the search of the file ``path``.

    Parameters
    ----------
    path : path-like
        The search file: a batch file with ``[monte_carlo]`` ranges and a ``[search]`` table.
    results_root : path-like
        Results folder; the search writes ``results_root/<search name>/``.
    workers, scheduler, tls, progress
        As for :func:`orchestrator.batch.run_batch`.
    evaluations, sampler, seed, fails_below
        Replace the file's budget, optimiser, seed and failure threshold.
    until_failure : bool
        Stop after the round that holds the first failure (or at once when the journal holds
        one): to count the evaluations a sampler needs to find a failure, not to spend the
        rest of the budget.  The search is the same as without it up to that round.
    report : bool
        Write ``report.html`` at the end.

    Raises
    ------
    ScenarioError
        For a malformed file, or an override the scenario does not accept.
    BatchError
        When the folder holds another search (other settings), or the cluster cannot be reached.
    """
    import optuna

    started = wallclock.perf_counter()
    tls_files = check_scheduler(scheduler, **(tls or {})) if scheduler is not None or tls else None
    spec = load_search(path, evaluations, sampler, seed, fails_below)
    _check_a_point(spec)
    root = Path(results_root) / spec.name
    (root / "runs").mkdir(parents=True, exist_ok=True)
    optuna.logging.set_verbosity(optuna.logging.WARNING)
    with interrupts.handled(), results_lock(root), warnings.catch_warnings():  # Ctrl-C/SIGTERM, from any caller
        warnings.simplefilter("ignore", optuna.exceptions.ExperimentalWarning)
        _check_same_search(spec, root)
        journal = read_journal(root / JOURNAL)
        drop_torn_tail(root / JOURNAL, journal)
        executor = (DaskExecutor(scheduler, tls_files) if scheduler is not None
                    else LocalPool(workers or os.cpu_count() or 1))
        study = optuna.create_study(direction="minimize", sampler=make_sampler(spec.sampler, spec.seed, 0))
        bar = _progress_bar(spec.evaluations, 0, spec.name, progress)
        evaluated, interrupted = _run_evaluations(spec, root, executor, study, journal, bar, until_failure)
        interrupted = interrupted or bool(interrupts.stop_requested())
        with interrupts.deferred():
            table, found = _write_outputs(spec, root, report)
    return SearchReport(root, table, evaluated, interrupted, found["first_failure"], found["failures"],
                        found["best"], wallclock.perf_counter() - started)


def _run_evaluations(spec: SearchSpec, root: Path, executor, study, journal: list[dict], bar,
                     until_failure: bool) -> tuple[int, bool]:
    """Run the journal's evaluations left without a published run, give the journal to ``study``, then
    ask, journal and run new rounds up to the budget (or a failure, with ``until_failure``, or a stop
    request); returns (evaluations run by this command, interrupted).  The bar is closed at the end."""
    evaluated, interrupted = 0, False
    try:
        pending = [entry for entry in journal if not _done(root, entry["run_id"])]
        if pending:
            evaluated += _evaluate(spec, root, executor, [run_spec_of(entry) for entry in pending], bar)
        for entry in journal:
            study.add_trial(_frozen_trial(spec, root, entry))
            if bar is not None:
                bar.update(1)
        failure_seen = until_failure and any(_failed(spec, root, entry["run_id"]) for entry in journal)
        while len(journal) < spec.evaluations and not failure_seen and not interrupts.stop_requested():
            trials, entries = _ask_round(spec, study, min(spec.per_round, spec.evaluations - len(journal)))
            append_journal(root / JOURNAL, entries)
            journal.extend(entries)
            evaluated += _evaluate(spec, root, executor, [run_spec_of(entry) for entry in entries], bar)
            failure_seen = _tell_round(spec, root, study, trials, entries, until_failure)
    except KeyboardInterrupt:
        interrupted = True
        interrupts.acknowledge()
    finally:
        if bar is not None:
            bar.close()
    return evaluated, interrupted


def _ask_round(spec: SearchSpec, study, size: int) -> tuple[list, list[dict]]:
    """Ask ``study`` for ``size`` evaluations, each of a sampler seeded by its number; returns the
    trials and their journal entries."""
    trials, entries = [], []
    for _ in range(size):
        number = len(study.trials)
        study.sampler = make_sampler(spec.sampler, spec.seed, number)
        trial = study.ask()
        overrides, parameters = draw_overrides(spec.monte_carlo, TrialChoices(trial))
        overrides = {**spec.batch.fixed, **overrides}
        entries.append(_entry(spec, trial, overrides, parameters, study.trials[trial.number].system_attrs))
        trials.append(trial)
    return trials, entries


def _tell_round(spec: SearchSpec, root: Path, study, trials: list, entries: list[dict],
                until_failure: bool) -> bool:
    """Tell ``study`` the objective of each evaluation of a round run; returns whether the round
    holds a failure (looked for only with ``until_failure``)."""
    import optuna

    failure_seen = False
    for trial, entry in zip(trials, entries):
        value = objective_of(spec, root, entry["run_id"])
        if value is None:
            study.tell(trial, state=optuna.trial.TrialState.FAIL)
        else:
            study.tell(trial, value)
        failure_seen = failure_seen or (until_failure and _failed(spec, root, entry["run_id"]))
    return failure_seen


def _write_outputs(spec: SearchSpec, root: Path, report: bool) -> tuple[Any, dict]:
    """Write the search's table, figures, ``search.json`` (and ``report.html`` with ``report``) from
    the journal as a resume reads it; returns the table and the findings."""
    from orchestrator import search_results

    journal = read_journal(root / JOURNAL)  # as a resume reads it
    table = search_results.write_outputs(spec, root, journal)
    found = search_results.findings(spec, table)
    _write_json_atomic(root / "search.json", {**_settings(spec), **found,
                                              "evaluations_done": int((table["status"] != "not run").sum())})
    if report:
        from orchestrator.report import write_report

        write_report(root)
    return table, found


def _entry(spec: SearchSpec, trial, overrides: dict, parameters: dict, system_attrs: dict) -> dict:
    from optuna.distributions import distribution_to_json

    return {"number": trial.number, "run_id": run_id(spec.batch.scenario_sha256, overrides),
            "overrides": overrides, "parameters": parameters, "values": trial.params,
            "distributions": {k: distribution_to_json(d) for k, d in trial.distributions.items()},
            "system_attrs": system_attrs}


def _frozen_trial(spec: SearchSpec, root: Path, entry: dict):
    import optuna
    from optuna.distributions import json_to_distribution

    value = objective_of(spec, root, entry["run_id"])
    state = optuna.trial.TrialState.COMPLETE if value is not None else optuna.trial.TrialState.FAIL
    return optuna.trial.create_trial(
        state=state, value=value, params=entry["values"], system_attrs=entry.get("system_attrs") or {},
        distributions={k: json_to_distribution(d) for k, d in entry["distributions"].items()})


def _check_a_point(spec: SearchSpec) -> None:
    """Refuse what the scenario does not accept before anything is written: one point of the space
    (every varied count at its largest), its overrides loaded and its participants built."""
    from orchestrator.search_spec import _SpaceRecorder

    overrides, parameters = draw_overrides(spec.monte_carlo, _SpaceRecorder())
    overrides = {**spec.batch.fixed, **overrides}
    check_against_scenario(spec.batch, [RunSpec(run_id(spec.batch.scenario_sha256, overrides), 0, overrides,
                                                 parameters)])


# -- evaluating -----------------------------------------------------------------------------------
def _failed(spec: SearchSpec, root: Path, identifier: str) -> bool:
    """The evaluation's run is a failure by the search's threshold, or by its ``[[acceptance]]`` without one."""
    from orchestrator import acceptance

    summary = read_summary(root / "runs" / identifier)
    passed = (summary is not None and summary.get("status") == "finished"
              and all(v.passed for v in acceptance.evaluate(spec.batch.acceptance, summary)))
    return spec.is_failure(objective_of(spec, root, identifier), passed)


def _done(root: Path, identifier: str) -> bool:
    summary = read_summary(root / "runs" / identifier)
    return summary is not None and not needs_redo(summary)


def _evaluate(spec: SearchSpec, root: Path, executor, runs: list[RunSpec], bar) -> int:
    """Run the runs not yet done (two evaluations may be the same run); returns how many ran."""
    import shutil

    from orchestrator.results import stale_staging

    todo, seen = [], set()
    for run in runs:
        if run.run_id in seen or _done(root, run.run_id):
            continue
        seen.add(run.run_id)
        for staging in stale_staging(root / "runs", run.run_id):
            shutil.rmtree(staging, ignore_errors=True)
        shutil.rmtree(root / "runs" / run.run_id, ignore_errors=True)  # interrupted or lost: redone
        todo.append(RunTask(str(spec.batch.scenario), str(root.resolve()), run.run_id, run.overrides))
    results = executor.run(todo)
    try:
        for task, record in results:
            if record["status"] in ("worker_died", TIMED_OUT):
                record_lost_run(task, record)
    finally:
        with interrupts.deferred():
            results.close()
    if bar is not None:
        bar.update(len(runs))
    if interrupts.stop_requested():
        raise KeyboardInterrupt
    return len(todo)


# -- settings -------------------------------------------------------------------------------------
def _settings(spec: SearchSpec) -> dict:
    return {"search": str(spec.batch.path), "name": spec.name, "scenario": str(spec.batch.scenario),
            "description": spec.batch.description, "evaluations": spec.evaluations,
            "fails_below": spec.fails_below, "worst": spec.worst, "space": spec.space,
            "acceptance": [c.describe() for c in spec.batch.acceptance],
            "report_series": list(spec.batch.report_series), **spec.identity()}


def _check_same_search(spec: SearchSpec, root: Path) -> None:
    """A folder holds one search: resuming with another seed, sampler, space or objective is refused."""
    try:
        earlier = json.loads((root / "search.json").read_text())
    except (OSError, ValueError):
        if read_journal(root / JOURNAL):
            raise BatchError(f"{root}: holds a search journal without its search.json; give another --results "
                             "folder") from None
        _write_json_atomic(root / "search.json", {**_settings(spec), "evaluations_done": 0})
        return
    for key, value in spec.identity().items():
        if json.dumps(earlier.get(key), sort_keys=True) != json.dumps(value, sort_keys=True):
            raise BatchError(f"{root}: this folder holds a search with another '{key}' "
                             f"({json.dumps(earlier.get(key), default=str)[:80]}); resume it with the same file and "
                             "options, or give another --results folder")
