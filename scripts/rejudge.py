"""Judge stored runs again with today's analyses, without running them again.

An analysis reads a run's recorded time series alone, so when the judgement changes (a new
reading of a rule, a fixed misreading), the runs of a batch need not be repeated to see what it
changes: this script reads each run's ``timeseries.parquet`` and ``summary.json`` (the scenario
file and the run's overrides in it), builds the scenario's co-simulation once per batch for its
wiring (which output feeds the obstacles, which participant is the ship, the controller's own
radius; nothing is stepped), runs the named analyses again, and writes the batch to
``--into <root>/<batch>/``: ``runs/<id>/summary.json`` with those analyses replaced (and
``rejudged``: the analyses and the time), ``timeseries.parquet`` linked to the original, and the
batch's ``batch.json`` and ``summary.csv`` copied (the latter's acceptance columns are the
original judgement's). The original folders are never written to. Then, for example::

    PYTHONPATH=. python scripts/rejudge.py results/suites_X/drawn_rhnc_colregs --into results/rejudged_X
    python -m rhnc.encounters.suite_report results/rejudged_X/drawn_rhnc_colregs

A run without a time series (failed before its first step) or whose scenario file is gone is
copied as it is and named on the standard error.
"""

from __future__ import annotations

import argparse
import json
import shutil
import sys
import time
from pathlib import Path

import pandas as pd

from orchestrator import analyses
from orchestrator.errors import ToolchainError
from orchestrator.master import CoSimulation
from orchestrator.scenario import load_scenario


def rejudge_batch(folder: Path, into: Path, names: tuple[str, ...]) -> tuple[int, int]:
    """Write ``folder``'s runs into ``into/<folder name>`` judged again; (judged, copied as they were)."""
    runs = sorted((folder / "runs").glob("*/summary.json"))
    if not runs:
        raise ToolchainError(f"{folder}: no runs/*/summary.json (not a batch results folder)")
    target = into / folder.name
    if target.resolve() == folder.resolve():
        raise ToolchainError(f"--into {into}: would overwrite the batch itself; give another folder")
    target.mkdir(parents=True, exist_ok=True)
    for name in ("batch.json", "summary.csv"):
        if (folder / name).exists():
            shutil.copy2(folder / name, target / name)
    cosim, judged, copied = None, 0, 0
    try:
        for path in runs:
            summary = json.loads(path.read_text())
            out = target / "runs" / path.parent.name
            out.mkdir(parents=True, exist_ok=True)
            series = path.parent / "timeseries.parquet"
            if series.exists() and not (out / series.name).exists():
                (out / series.name).symlink_to(series.resolve())
            if not series.exists() or not Path(summary.get("scenario", "")).exists():
                print(f"{path.parent}: no time series or scenario file; copied as it was", file=sys.stderr)
                (out / "summary.json").write_text(json.dumps(summary, indent=2))
                copied += 1
                continue
            scenario = load_scenario(summary["scenario"], summary.get("overrides") or {})
            if cosim is None:  # the wiring is the batch's, whatever a run's overrides
                cosim = CoSimulation(scenario, work_dir=None)
            frame = pd.read_parquet(series)
            for name in names:
                summary.setdefault("analyses", {})[name] = analyses.run_analysis(name, frame, scenario, cosim, out)
            summary["rejudged"] = {"analyses": list(names), "at": time.strftime("%Y-%m-%dT%H:%M:%S%z")}
            partial = out / "summary.json.partial"
            partial.write_text(json.dumps(summary, indent=2))
            partial.replace(out / "summary.json")
            judged += 1
    finally:
        if cosim is not None:
            cosim.close()
    return judged, copied


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("folders", nargs="+", type=Path, help="batch result folders (with runs/*/summary.json)")
    parser.add_argument("--into", type=Path, required=True, help="root folder the judged batches are written to")
    parser.add_argument("--analyses", nargs="+", default=["colregs"], help="analyses to run again (default: colregs)")
    args = parser.parse_args(argv)
    try:
        for folder in args.folders:
            judged, copied = rejudge_batch(folder, args.into, tuple(args.analyses))
            print(f"{folder.name}: {judged} runs judged again, {copied} copied as they were -> {args.into / folder.name}")
    except ToolchainError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
