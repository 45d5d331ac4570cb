"""How the processor-time bound of the NMPC's solves acted in encounter batches, batch by batch.

For each batch folder written by ``python -m orchestrator batch`` (its ``runs/*/summary.json``)::

    python scripts/solve_time_bound.py results/heldout_<commit>/*

prints one Markdown row: runs, NMPC solves, solves stopped at an iteration cap from the
measured pace (``iteration_capped_steps``), solves the worker's timer ended
(``timeout_count``) and the runs they were in, the largest solve's processor time and the
largest whole control step's (the solve and the Python around it) [ms].  A folder without
runs exits 2 naming it.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

HEADER = ("| batch | runs | solves | solves stopped at a pace cap | timer stops (runs) "
          "| largest solve [ms CPU] | largest step [ms CPU] |\n|---|---|---|---|---|---|---|")


def bound_row(folder: Path) -> str:
    """The Markdown row of one batch folder."""
    controls = [json.loads(path.read_text()).get("participants", {}).get("ctrl", {})
                for path in sorted((folder / "runs").glob("*/summary.json"))]
    solves = sum(int(c.get("solves") or 0) for c in controls)
    capped = sum(int(c.get("iteration_capped_steps") or 0) for c in controls)
    stops = [int(c.get("timeout_count") or 0) for c in controls]
    solve_max = max((c.get("solve_cpu_time_max_s") or 0.0 for c in controls), default=0.0)
    step_max = max((c.get("step_cpu_time_max_s") or 0.0 for c in controls), default=0.0)
    return (f"| {folder.parent.name}/{folder.name} | {len(controls)} | {solves} | {capped} | {sum(stops)} ({sum(s > 0 for s in stops)}) "
            f"| {solve_max * 1000:.0f} | {step_max * 1000:.0f} |")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description="the NMPC's processor-time bound in encounter batches")
    parser.add_argument("folders", nargs="+", type=Path, help="batch result folders (results/<batch>)")
    args = parser.parse_args(argv)
    missing = [folder for folder in args.folders if not (folder / "runs").is_dir()]
    if missing:
        print(f"solve_time_bound: {missing[0]}: no runs/ folder (not a batch result)", file=sys.stderr)  # noqa: T201
        return 2
    print("\n".join([HEADER, *(bound_row(folder) for folder in args.folders)]))  # noqa: T201 - a command's output
    return 0


if __name__ == "__main__":
    sys.exit(main())
