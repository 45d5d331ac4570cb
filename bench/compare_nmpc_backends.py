"""Scenario runs with each NMPC backend: trajectories against the first backend's, run summaries' step times.

Each scenario is run once per backend (``--solvers``, default fatrop then acados) as a user
runs it (``python -m orchestrator run``, a process of its own): a copy of the scenario beside
it with ``solver = "<backend>"`` in every control participant's options, removed afterwards.
Printed per run: the processor time of the whole command (start to exit, from the child's
resource usage) and its wall time, the controller's run-summary figures (whole NMPC step
and solver call, processor time, median and max; solves, fallbacks), and the largest
distance between the ship's positions and those of the first backend's run at the same
times [m].

Run: ``python bench/compare_nmpc_backends.py [--scenarios scenarios/exp3a_static.toml ...]
[--solvers fatrop acados acados+rti] [--results DIR]`` (``acados+rti``: acados's real-time
iterations, ``real_time_iterations = true``).  acados needs its wheel
(``rhnc.control.nmpc_acados.INSTALL_COMMAND``).  The machine's load is printed beside the
figures.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
import tomllib
from pathlib import Path

import numpy as np
import pandas as pd

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_SCENARIOS = ("scenarios/exp3a_static.toml", "scenarios/exp3b_head_on.toml", "scenarios/exp2_rhnc.toml")


def with_solver(text: str, solver: str) -> str:
    """The scenario's TOML with ``solver = "<solver>"`` in every control participant's options
    (``acados+rti``: acados with ``real_time_iterations = true``)."""
    backend, _, variant = solver.partition("+")
    extra = ["real_time_iterations = true"] if variant == "rti" else []
    scenario = tomllib.loads(text)
    lines = text.splitlines()
    for name, participant in scenario.get("participants", {}).items():
        if participant.get("type") != "control":
            continue
        header = f"[participants.{name}.options]"
        if header in lines:
            at = lines.index(header)
            lines = [line for i, line in enumerate(lines) if not (i > at and line.strip().startswith("solver ")
                                                                  and i < _next_table(lines, at))]
            lines[at + 1:at + 1] = [f'solver = "{backend}"', *extra]
        else:
            lines += ["", header, f'solver = "{backend}"', *extra]
    return "\n".join(lines) + "\n"


def _next_table(lines: list[str], at: int) -> int:
    for i in range(at + 1, len(lines)):
        if lines[i].startswith("["):
            return i
    return len(lines)


def run(scenario: Path, solver: str, results: Path) -> dict:
    """Run the scenario with ``solver``; the summary, the time series, processor and wall time."""
    copy = scenario.with_name(f".{scenario.stem}.{solver}.{os.getpid()}.toml")
    copy.write_text(with_solver(scenario.read_text(), solver))
    out = results / solver
    try:
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        start = time.perf_counter()
        done = subprocess.run([sys.executable, "-m", "orchestrator", "run", str(copy), "--results", str(out),
                               "--no-progress"], capture_output=True, text=True, cwd=ROOT, check=False)
        wall = time.perf_counter() - start
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
    finally:
        copy.unlink()
    if done.returncode != 0:
        raise SystemExit(f"{scenario.name} with {solver}: exit {done.returncode}: {done.stderr.strip()[-400:]}")
    folder = max(out.glob("*/*/summary.json"), key=lambda path: path.stat().st_mtime).parent
    summary = json.loads((folder / "summary.json").read_text())
    table = next(folder.glob("timeseries.*"))
    series = pd.read_parquet(table) if table.suffix == ".parquet" else pd.read_csv(table)
    cpu = (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime)
    return {"summary": summary, "series": series, "cpu_s": cpu, "wall_s": wall}


def positions(series: pd.DataFrame) -> dict[str, np.ndarray]:
    """Every ship's (x, y) [m] columns by participant: ``<name>.x``, ``<name>.y``."""
    found = {}
    for column in series.columns:
        if column.endswith(".x") and column[:-2] + ".y" in series.columns and "[" not in column:
            name = column[:-2]
            found[name] = series[[f"{name}.x", f"{name}.y"]].to_numpy()
    return found


def controller_rows(summary: dict) -> list[str]:
    rows = []
    for name, figures in summary.get("participants", {}).items():
        if "step_cpu_time_median_s" not in figures:
            continue
        ms = {key: (figures.get(key) or float("nan")) * 1e3 for key in (
            "step_cpu_time_median_s", "step_cpu_time_max_s", "solve_cpu_time_median_s", "solve_cpu_time_max_s")}
        rows.append(f"{name} [{figures.get('solver')}, {figures.get('codegen')}]: step "
                    f"{ms['step_cpu_time_median_s']:.2f} / {ms['step_cpu_time_max_s']:.1f} ms, solver call "
                    f"{ms['solve_cpu_time_median_s']:.2f} / {ms['solve_cpu_time_max_s']:.1f} ms (median / max), "
                    f"{figures.get('solves')} solves, {figures.get('fallback_count')} fallbacks")
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenarios", nargs="+", default=list(DEFAULT_SCENARIOS))
    parser.add_argument("--solvers", nargs="+", default=["fatrop", "acados"])
    parser.add_argument("--results", type=Path, default=None, help="results folder (default: a temporary one)")
    args = parser.parse_args()
    load = os.getloadavg()
    print(f"load average {load[0]:.1f} / {load[1]:.1f} / {load[2]:.1f}; {os.cpu_count()} cores; processor times")
    with tempfile.TemporaryDirectory(prefix="rhnc-backends-") as scratch:
        results = args.results or Path(scratch)
        for name in args.scenarios:
            scenario = (ROOT / name).resolve()
            print(f"\n{scenario.name}")
            first = None
            for solver in args.solvers:
                outcome = run(scenario, solver, results)
                summary = outcome["summary"]
                acceptance = summary.get("acceptance") or {}
                line = (f"  {solver:8s} command {outcome['cpu_s']:.2f} s processor, {outcome['wall_s']:.2f} s wall; "
                        f"status {summary.get('status')}")
                if acceptance.get("criteria"):
                    met = sum(1 for c in acceptance["criteria"] if c.get("passed"))
                    line += f", acceptance {met}/{len(acceptance['criteria'])}"
                if first is None:
                    first = positions(outcome["series"])
                else:
                    other = positions(outcome["series"])
                    gaps = {ship: float(np.max(np.hypot(*(other[ship] - first[ship]).T)))
                            for ship in first if ship in other and len(other[ship]) == len(first[ship])}
                    line += "; largest distance from " + args.solvers[0] + "'s track: " + ", ".join(
                        f"{ship} {gap:.3g} m" for ship, gap in gaps.items())
                print(line)
                for row in controller_rows(summary):
                    print(f"    {row}")
    load = os.getloadavg()
    print(f"\nload average {load[0]:.1f} / {load[1]:.1f} / {load[2]:.1f} after")


if __name__ == "__main__":
    main()
