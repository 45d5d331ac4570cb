"""Peak memory (resident set size) of whole runs: Experiment 2 and a ten-times-longer voyage.

Each case runs ``run_scenario`` in a fresh process and reads that process's peak RSS from
the kernel (``wait4``'s ``ru_maxrss``), so imports, FMUs, the NMPC, the analyses and the
figures are all counted.  The time series is written in Parquet row groups as the run
goes (:mod:`orchestrator.recorder`), so the peak should hardly grow with the voyage's
length; the printed growth per 1,000 steps says how flat it is.

Experiment 2 itself (480 macro steps of 60 s, 100 x 100 nm) is the first case.  For the
length comparison both voyages run Experiment 2's loop on a map ten times as large (its
weather generator over 0..1000 nm at 10 nm, goal at (1000, 1000) nm): 480 steps, and
sailed until arrival (about 4,700 steps, at most ``--factor`` x 480), so every step records
the same columns and only the length differs.

    python bench/bench_memory.py [--repo PATH] [--factor 10]

``--repo`` runs another checkout's code (e.g. an export of an older commit) for a
before/after comparison.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]

CHILD = """
import json, sys
from orchestrator.run import run_scenario
report = run_scenario(sys.argv[1], sys.argv[2], progress=False, overrides=json.loads(sys.argv[3]) or None)
print(json.dumps({"status": report.status, "steps": report.summary["simulation"]["steps_done"]}))
"""


def peak_rss(repo: Path, scenario: Path, overrides: dict) -> tuple[float, dict, float]:
    """Peak RSS [MiB] of one run in a child process, its status line and its wall time [s]."""
    with tempfile.TemporaryDirectory() as results:
        started = time.perf_counter()
        process = subprocess.Popen([sys.executable, "-c", CHILD, str(scenario), results, json.dumps(overrides)],
                                   stdout=subprocess.PIPE, text=True, cwd=repo,
                                   env={**os.environ, "PYTHONPATH": str(repo)})
        _, status, usage = os.wait4(process.pid, 0)
        wall = time.perf_counter() - started
        out = process.stdout.read()
        if os.waitstatus_to_exitcode(status) != 0:
            raise SystemExit(f"the run failed: {out}")
        return usage.ru_maxrss / 1024.0, json.loads(out.strip().splitlines()[-1]), wall


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repo", type=Path, default=REPO, help="checkout whose code to run (default: this one)")
    parser.add_argument("--factor", type=int, default=10, help="how many times longer the long voyage is")
    args = parser.parse_args()
    scenario = args.repo / "scenarios" / "exp2_rhnc.toml"
    large_map = {"metocean.x_range_nm": [0.0, 1000.0], "metocean.y_range_nm": [0.0, 1000.0],
                 "metocean.resolution_nm": 10.0, "participants.nav.options.goal_nm": [1000.0, 1000.0],
                 "participants.goal.options.goal_nm": [1000.0, 1000.0]}
    cases = [("Experiment 2", {}),
             ("large map, 480 steps", {**large_map, "simulation.steps": 480}),
             ("large map, to arrival", {**large_map, "simulation.steps": 480 * args.factor})]
    print(f"code: {args.repo}; load average {os.getloadavg()[0]:.1f}")
    measured = []
    for label, overrides in cases:
        rss, report, wall = peak_rss(args.repo, scenario, overrides)
        measured.append((report["steps"], rss))
        print(f"{label:>24}: {report['steps']:5d} steps ({report['status']}), peak RSS {rss:7.1f} MiB, "
              f"wall {wall:6.1f} s", flush=True)
    (short_steps, short_rss), (long_steps, long_rss) = measured[1:]
    growth = (long_rss - short_rss) / max(long_steps - short_steps, 1) * 1000.0
    print(f"growth: {growth:.2f} MiB per 1,000 steps ({long_rss / short_rss:.2f}x the short run's peak)")


if __name__ == "__main__":
    main()
