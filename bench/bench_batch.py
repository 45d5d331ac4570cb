"""Speed-up of the batch runner's local pool: 2 workers against 1 on a 20-run batch.

Two kinds of batch: ``encounters`` (default), the first 20 drawn encounters of
``batches/encounters_50.toml`` (closed-loop NMPC runs of Experiment 3b, the batch runner's
real use), and ``turning``, the turning circle at a 0.1 s step with a drawn surge force
(short runs, where the pool's fixed costs weigh more).  The batch time includes starting
the pool's worker processes and writing the table and overview.  Goal: at least
1.8x with 2 workers (on a machine with 2 idle cores).

    python bench/bench_batch.py [--kind encounters|turning] [--runs 20] [--dt 0.1]
"""

from __future__ import annotations

import argparse
import os
import tempfile
import textwrap
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]

BATCH = """
[batch]
name = "bench"
scenario = "{scenario}"
[set]
"simulation.dt_s" = {dt}
"outputs.figures" = []
[monte_carlo]
seed = 1
runs = {runs}
[monte_carlo.uniform]
"participants.helm.options.tau_u_N" = [5.0e5, 1.0e6]
[[acceptance]]
metric = "status"
op = "=="
value = "finished"
"""


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=20)
    parser.add_argument("--dt", type=float, default=0.1, help="turning: macro step [s]; smaller = longer runs")
    parser.add_argument("--kind", choices=("encounters", "turning"), default="encounters")
    args = parser.parse_args()

    from orchestrator.batch import run_batch

    load = os.getloadavg()
    with tempfile.TemporaryDirectory(prefix="bench-batch-") as tmp:
        if args.kind == "encounters":
            batch = REPO / "batches" / f".bench-encounters-{os.getpid()}.toml"
            text = (REPO / "batches" / "encounters_50.toml").read_text()
            batch.write_text(text.replace("runs = 50", f"runs = {args.runs}", 1))
            label = f"{args.runs} drawn encounters (Experiment 3b, NMPC)"
        else:
            batch = Path(tmp) / "bench.toml"
            batch.write_text(textwrap.dedent(BATCH.format(scenario=REPO / "scenarios" / "turning_circle.toml",
                                                          dt=args.dt, runs=args.runs)))
            label = f"{args.runs} runs of the turning circle at dt = {args.dt} s"
        times, tables = {}, {}
        try:
            for workers in (1, 2):
                started = time.perf_counter()
                report = run_batch(batch, Path(tmp) / f"results-{workers}", workers=workers, progress=False)
                times[workers] = time.perf_counter() - started
                tables[workers] = report.table
                assert (report.table["status"] == "finished").all(), report.table[["status", "reason"]]
        finally:
            if args.kind == "encounters":
                batch.unlink()
        print(f"{label}, {os.cpu_count()} cores, load average before: {load[0]:.2f}")
        for workers in (1, 2):
            print(f"{workers} worker{'s' if workers > 1 else ' '}: {times[workers]:6.2f} s "
                  f"(a run's simulation {tables[workers]['wall_time_s'].mean():.2f} s on average)")
        print(f"speed-up : {times[1] / times[2]:.2f}x (goal >= 1.8x)")


if __name__ == "__main__":
    main()
