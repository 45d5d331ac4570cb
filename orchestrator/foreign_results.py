"""Judge a run made by another FMI master by the scenario's acceptance criteria (``check``).

``python -m orchestrator check RESULTS.csv [...] --scenario S.toml`` reads what another
master wrote, lays it out as our own time series, runs the scenario's ``[outputs]``
analyses on it, recomputes the participants' figures their outputs determine
(:meth:`~orchestrator.participant.Participant.summary_from_outputs`: the NMPC's yaw-moment
sign changes per 100 solves) and evaluates the scenario's ``[[acceptance]]`` criteria.

Layouts read:

- OSP's libcosim (its file observer, ``CosimObserver.create_to_dir``): one CSV per
  simulator, named ``<simulator>_<date>_<time>.csv``, columns ``Time``, ``StepCount`` and
  one per variable, the variable's name followed by `` [value reference causality type]``;
- FMPy (``fmpy.util.write_csv`` of ``simulate_fmu``'s result): column ``time`` and one per
  variable of one FMU; the participant is the file's name (``ship.csv``) or ``--participant``;
- our own ``timeseries.csv``: ``time_s`` and ``<participant>.<port>`` columns.

Timing: a master reads a participant's outputs after its step from ``t`` and records them
at ``t + h``.  For an FMU (a dynamic participant) that is the state at ``t + h``, as in our
time series; a Python participant's outputs were decided at ``t`` (the obstacles' positions
at ``t``, the force held from ``t``), and our time series records them at ``t``: their
columns are moved back by that participant's step.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pandas as pd

from orchestrator.errors import ScenarioError

#: libcosim's variable column: ``name [reference causality type]``
_LIBCOSIM_COLUMN = re.compile(r"^(?P<name>.+?) \[\d+ \w+ \w+\]$")
#: libcosim's file name: ``<simulator>_<yyyymmdd>_<hhmmss>_<ms>.csv`` (the date part optional)
_LIBCOSIM_FILE = re.compile(r"^(?P<name>.+?)(_\d{8}_\d{6}(_\d+)?)?$")


def read_results(paths, scenario, participant: str | None = None) -> pd.DataFrame:
    """One time series (``time_s`` and ``<participant>.<port>`` columns) from another master's CSV files.

    Raises
    ------
    ScenarioError
        A file that is missing, has no time column, or belongs to no participant of the
        scenario; the message names the file.
    """
    names = [spec.name for spec in scenario.participants]
    parts = []
    for path in map(Path, paths):
        if not path.is_file():
            raise ScenarioError(f"{path}: no such results file")
        try:
            with path.open(newline="") as handle:
                header = _header(handle.readline())
            table = pd.read_csv(path, header=None, skiprows=1, names=header)
        except (ValueError, OSError, UnicodeDecodeError) as exc:
            raise ScenarioError(f"{path}: not a CSV file: {exc}") from None
        if "time_s" in table.columns:  # ours
            parts.append(table.set_index("time_s"))
            continue
        time = next((c for c in ("Time", "time") if c in table.columns), None)
        if time is None:
            raise ScenarioError(f"{path}: no time column ('Time' of libcosim, 'time' of FMPy or 'time_s')")
        owner = participant if participant is not None and len(paths) == 1 else _owner(path, names)
        if owner not in names:
            raise ScenarioError(f"{path}: no participant '{owner}' in {scenario.path} (participants: "
                                f"{', '.join(names)}); name the file after one, or give --participant")
        columns = {}
        for column in table.columns:
            if column in (time, "StepCount"):
                continue
            match = _LIBCOSIM_COLUMN.match(column)
            columns[column] = f"{owner}.{match.group('name') if match else column}"
        part = table.rename(columns=columns).drop(columns=[c for c in ("StepCount",) if c in table.columns])
        parts.append(part.set_index(time))
    frame = pd.concat([part[~part.index.duplicated(keep="last")] for part in parts], axis=1).sort_index()
    frame = frame.ffill()
    frame.index.name = "time_s"
    return frame


def _header(line: str) -> list[str]:
    """Column names of a CSV header whose names may hold unquoted commas inside brackets.

    libcosim writes ``reference[0,0]`` as it is, so a plain CSV reader splits it in two.
    """
    import csv

    names, pending = [], ""
    for token in next(csv.reader([line.rstrip("\r\n")])):
        pending = f"{pending},{token}" if pending else token
        if pending.count("[") <= pending.count("]"):
            names.append(pending.strip())
            pending = ""
    if pending:
        names.append(pending.strip())
    return names


def _owner(path: Path, names) -> str:
    match = _LIBCOSIM_FILE.match(path.stem)  # every non-empty stem matches
    stem = match.group("name") if match is not None else path.stem
    # the longest participant name the stem starts with (a libcosim name has a date after it)
    matches = [name for name in names if stem == name or stem.startswith(name + "_")]
    return max(matches, key=len) if matches else stem


def our_timing(frame: pd.DataFrame, cosim) -> pd.DataFrame:
    """Move each Python participant's columns back by its step (see the module docstring)."""
    sim = cosim.scenario.simulation
    grid = sim.start_s + sim.dt_s * np.arange(sim.steps + 1)
    times = frame.index.to_numpy(dtype=float)
    # the rows of our grid that the other master recorded (libcosim: every base step)
    at = np.searchsorted(times, grid - 1e-9 * max(1.0, sim.dt_s))
    keep = at < len(times)
    out = pd.DataFrame({"time_s": grid[keep]})
    for participant in cosim.participants:
        columns = [c for c in frame.columns if c.startswith(participant.name + ".")]
        if not columns:
            continue
        shift = 0.0 if participant.outputs_at_step_end else cosim.every[participant.name] * sim.dt_s
        rows = np.searchsorted(times, grid[keep] + shift - 1e-9 * max(1.0, sim.dt_s))
        rows = np.minimum(rows, len(times) - 1)
        block = frame[columns].to_numpy()[rows]
        out = pd.concat([out, pd.DataFrame(block, columns=columns)], axis=1)
    return out


def judge(paths, scenario_path, participant: str | None = None) -> dict:
    """The summary of another master's run: analyses, participants' figures, acceptance verdicts."""
    from orchestrator import acceptance, analyses
    from orchestrator.master import CoSimulation
    from orchestrator.scenario import load_scenario

    scenario = load_scenario(scenario_path)
    if not scenario.acceptance:
        raise ScenarioError(f"{scenario_path}: no [[acceptance]] criteria to judge by")
    raw = read_results(paths, scenario, participant)
    cosim = CoSimulation(scenario)
    try:
        frame = our_timing(raw, cosim)
        summary: dict = {"scenario": str(scenario.path), "status": "finished", "reason": "",
                         "results": [str(p) for p in paths], "analyses": {}, "participants": {}}
        for name in scenario.outputs.analyses:
            try:
                summary["analyses"][name] = analyses.run_analysis(name, frame, scenario, cosim, Path(cosim.work_dir))
            except (KeyError, LookupError) as exc:
                raise ScenarioError(f"{', '.join(map(str, paths))}: analysis '{name}' needs a column the results "
                                    f"lack: {exc}") from None
        sim = scenario.simulation
        for p in cosim.participants:
            columns = [c for c in frame.columns if c.startswith(p.name + ".")]
            if not columns:
                continue
            every = cosim.every[p.name]
            steps = frame["time_s"].to_numpy() < sim.start_s + sim.steps * sim.dt_s - 1e-9
            rows = frame[steps].iloc[::every]  # one row per step of the participant
            figures = p.summary_from_outputs({c[len(p.name) + 1:]: rows[c].to_numpy() for c in columns})
            if figures:
                summary["participants"][p.name] = figures
        verdicts = acceptance.evaluate(scenario.acceptance, summary)
        summary["acceptance"] = {
            "passed": all(v.passed for v in verdicts),
            "criteria": [{"name": v.name, "criterion": c.describe(), "passed": v.passed, "value": v.value,
                          "reason": v.reason} for v, c in zip(verdicts, scenario.acceptance)]}
        return summary
    finally:
        cosim._terminate_all()
        cosim.close()
