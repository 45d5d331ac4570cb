"""Run a scenario end to end: load, build, step, analyse, write results."""

from __future__ import annotations

import contextlib
import gc
import logging
import math
import shutil
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pandas as pd

from orchestrator import acceptance, interrupts, leftovers
from orchestrator.errors import ResultsError, ToolchainError, is_disk_full
from orchestrator.figure_processes import FIGURE_SPOOL
from orchestrator.master import CoSimulation
from orchestrator.recorder import ColumnFrame
from orchestrator.results import RunFolder, new_run_id, versions
from orchestrator.scenario import Scenario, load_scenario

log = logging.getLogger(__name__)

#: Folder in the staging folder where the time series is written during the run (removed on publish).
SPOOL = ".timeseries-spool"


@dataclass
class RunReport:
    """Where a run's results are and how it ended."""

    folder: Path
    status: str
    reason: str
    summary: dict[str, Any]

    @property
    def ok(self) -> bool:
        """The run finished (its acceptance criteria are another matter: :attr:`passed`)."""
        return self.status == "finished"

    @property
    def failed_criteria(self) -> list[str]:
        """``name: reason`` of each of the scenario's acceptance criteria not met."""
        criteria = self.summary.get("acceptance", {}).get("criteria", [])
        return [f"{c['name']}: {c['reason']}" for c in criteria if not c["passed"]]

    @property
    def passed(self) -> bool:
        """Finished, and every acceptance criterion of the scenario met."""
        return self.ok and not self.failed_criteria


def run_scenario(path, results_root="results", progress: bool = True, run_id: str | None = None,
                 overrides=None, group: str | None = None) -> RunReport:
    """Run the scenario in ``path`` and write ``results_root/<group>/<run-id>/``.

    ``group`` defaults to the scenario's name; ``overrides`` are dotted-key values applied
    to the scenario (see :func:`~orchestrator.scenario.load_scenario`).  Errors in the
    scenario or its FMUs raise before anything is written
    (:class:`~orchestrator.errors.ToolchainError`).  A failure during the run is
    reported in the returned status; its results are written all the same.
    """
    scenario = load_scenario(path, overrides)
    # build first: input refused before the run leaves no folder behind
    cosim = CoSimulation(scenario, work_dir=None)
    leftovers.remove_abandoned_staging(Path(results_root))  # of runs whose process died
    try:
        folder = RunFolder(Path(results_root), group or scenario.simulation.name,
                           run_id or new_run_id(scenario.sha256))
    except BaseException:
        cosim.close()
        raise
    try:
        with interrupts.emergency_writer(
                lambda why, status: _write_emergency(scenario, cosim, folder, overrides, why, status)), \
                _built_objects_frozen():
            outcome = cosim.run(progress=progress, spool=folder.path(SPOOL))
            with interrupts.deferred():
                try:
                    report = _write(scenario, cosim, outcome, folder, overrides)
                except OSError as exc:  # disk full, folder removed: keep nothing half-written
                    raise ResultsError(
                        f"{folder.final}: the results could not be written ({exc.strerror or exc}); nothing was "
                        f"kept (the run itself: {outcome.status}"
                        f"{', ' + outcome.reason if outcome.reason else ''})") from exc
    except BaseException:
        folder.discard()
        raise
    finally:
        cosim.close()
    return report


@contextlib.contextmanager
def _built_objects_frozen() -> Iterator[None]:
    """Leave what is built by now (modules, participants, weather) out of the garbage
    collector's full passes while the run steps and writes its results.

    A full pass walks every object alive, some 0.08 s after an NMPC run's imports, though
    hardly any of these becomes garbage during the run; frozen, they are walked again once
    the run is over.  Objects someone else froze are left as they are.
    """
    if gc.get_freeze_count():
        yield
        return
    gc.freeze()
    try:
        yield
    finally:
        gc.unfreeze()


def _write_emergency(scenario: Scenario, cosim: CoSimulation, folder: RunFolder, overrides, why: str,
                     status: str) -> None:
    """What a watchdog keeps of a run whose participant did not return: status and time series."""
    sim = scenario.simulation
    recorder = getattr(cosim, "recorder", None)
    if recorder is not None:
        recorder.finish()  # the call in progress never returns: the rows up to the latest output are final
        recorder.write_csv(folder.path("timeseries.csv"))
        recorder.discard_spool()
    shutil.rmtree(folder.path(FIGURE_SPOOL), ignore_errors=True)  # figures still being drawn are not kept
    folder.write_json("summary.json", {
        "scenario": str(scenario.path), "scenario_name": sim.name, "scenario_sha256": scenario.sha256,
        "overrides": dict(overrides or {}), "run_id": folder.final.name, "status": status,
        "reason": why, "versions": versions(),
        "simulation": {"start_s": sim.start_s, "stop_s": sim.stop_s, "dt_s": sim.dt_s,
                       "steps_planned": sim.steps, "steps_done": getattr(cosim, "steps_done", 0)},
        "timeseries": "timeseries.csv" if recorder is not None else None,
        "analyses": {}, "participants": {}})
    print(f"{status}: results in {folder.publish()}", flush=True)
    cosim.remove_files()  # the process ends next: no temporary folder may outlive the run


def _write(scenario: Scenario, cosim: CoSimulation, outcome, folder: RunFolder, overrides) -> RunReport:
    from orchestrator import figure_processes

    recorder = outcome.recorder
    recorder.finish()
    series_name = "timeseries.parquet" if scenario.outputs.format == "parquet" else "timeseries.csv"
    if scenario.outputs.format == "parquet":
        recorder.write_parquet(folder.path(series_name))
        frame = ColumnFrame(folder.path(series_name))
    else:  # CSV for the user; the analyses read the spool merged into a Parquet file, removed below
        recorder.write_csv(folder.path(series_name))
        recorder.write_parquet(folder.path(SPOOL) / "merged.parquet")
        frame = ColumnFrame(folder.path(SPOOL) / "merged.parquet")
    # the figures are drawn aside while the rest is written
    drawing = figure_processes.start(scenario.outputs.figures if outcome.steps_done else (), frame, scenario,
                                     cosim, folder.staging)
    try:
        report = _write_rest(scenario, cosim, outcome, folder, overrides, series_name, frame, drawing)
    finally:
        drawing.cancel()  # nothing left to end once collected
    return report


def _write_rest(scenario: Scenario, cosim: CoSimulation, outcome, folder: RunFolder, overrides, series_name: str,
                frame, drawing) -> RunReport:
    from orchestrator import analyses

    recorder = outcome.recorder
    if cosim.metocean is not None:
        cosim.metocean.to_netcdf(folder.path("metocean.nc"))
    for name, rows in outcome.participant_tables.items():
        pd.DataFrame(rows).to_csv(folder.path(f"{name}.csv"), index=False)
    figures: dict[str, Any] = {}
    status, reason = outcome.status, outcome.reason
    for name in scenario.outputs.analyses:
        if outcome.steps_done == 0:  # a verdict on an empty time series would claim too much
            figures[name] = {"evaluated": False, "note": "not evaluated: the run made no steps"}
            continue
        try:
            figures[name] = analyses.run_analysis(name, frame, scenario, cosim, folder.staging)
        except Exception as exc:  # an analysis of a failed run's partial series, or its own bug
            if is_disk_full(exc):  # the disk, not the analysis: nothing of the run is kept
                raise
            text = str(exc) if isinstance(exc, ToolchainError) else f"{type(exc).__name__}: {exc}"
            log.debug("analysis '%s' raised", name, exc_info=True)
            figures[name] = {"error": text}
            if status == "finished":
                status, reason = "failed", f"analysis '{name}': {text}"
    figure_files, figure_errors = drawing.collect()
    sim = scenario.simulation
    summary = {
        "scenario": str(scenario.path),
        "scenario_name": sim.name,
        "scenario_sha256": scenario.sha256,
        "overrides": dict(overrides or {}),
        "run_id": folder.final.name,
        "status": status,
        "reason": reason,
        "versions": versions(),
        "simulation": {"start_s": sim.start_s, "stop_s": sim.stop_s, "dt_s": sim.dt_s,
                       "steps_planned": sim.steps, "steps_done": outcome.steps_done},
        "wall_time_s": round(outcome.wall_time_s, 4),
        "real_time_factor": _ratio(outcome.steps_done * sim.dt_s, outcome.wall_time_s),
        "metocean": cosim.metocean.source if cosim.metocean is not None else None,
        "timeseries": series_name,
        "tables": [f"{name}.csv" for name in outcome.participant_tables],
        "figures": figure_files,
        "figure_errors": figure_errors,
        "analyses": figures,
        "participants": outcome.participant_summaries,
    }
    if scenario.acceptance:
        verdicts = acceptance.evaluate(scenario.acceptance, summary)
        summary["acceptance"] = {
            "passed": all(v.passed for v in verdicts),
            "criteria": [{"name": v.name, "criterion": c.describe(), "passed": v.passed, "value": v.value,
                          "reason": v.reason} for v, c in zip(verdicts, scenario.acceptance)]}
    folder.write_json("summary.json", summary)
    recorder.discard_spool()
    final = folder.publish()
    return RunReport(final, status, reason, summary)


def _ratio(simulated: float, wall: float):
    return round(simulated / wall, 1) if wall > 0 and math.isfinite(simulated / wall) else None
