"""Processor time of the NMPC's control steps in encounter-suite results: per solve and per iteration.

Reads the ``ctrl`` telemetry of every run of the batch folders given (``runs/*/timeseries.parquet``)
and prints, per folder, the largest processor time of one control step (both solver attempts),
its percentiles, the processor time per solver iteration (steps of more than 30 iterations,
where the fixed cost of a call weighs little) and the steps over 200 ms.  The iteration budget
of the COLREG suites (``iteration_budget``) is chosen from the last of these.

    python bench/bench_solve_budget.py /tmp/suites/imazu_rhnc_colregs /tmp/suites/drawn_rhnc_colregs ...
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import pandas as pd

LIMIT_S = 0.2


def figures(folder: Path) -> dict:
    cpu, per_iteration, over = [], [], 0
    for path in sorted(folder.glob("runs/*/timeseries.parquet")):
        frame = pd.read_parquet(path, columns=["ctrl.solve_cpu_time_s", "ctrl.iterations"])
        steps = frame["ctrl.solve_cpu_time_s"].to_numpy()
        iterations = frame["ctrl.iterations"].to_numpy()
        cpu.append(steps)
        long = iterations > 30
        per_iteration.append(steps[long] / iterations[long])
        over += int(np.sum(steps > LIMIT_S))
    cpu_all = np.concatenate(cpu) if cpu else np.zeros(0)
    per = np.concatenate(per_iteration) if per_iteration else np.zeros(0)
    return {"runs": len(cpu), "steps": cpu_all.size, "over": over,
            "cpu_ms": 1000.0 * np.percentile(cpu_all, [50, 99, 100]) if cpu_all.size else None,
            "per_iteration_ms": 1000.0 * np.percentile(per, [50, 90, 100]) if per.size else None}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folders", nargs="+", type=Path)
    args = parser.parse_args(argv)
    for folder in args.folders:
        f = figures(folder)
        cpu = "-" if f["cpu_ms"] is None else " / ".join(f"{v:.0f}" for v in f["cpu_ms"])
        per = "-" if f["per_iteration_ms"] is None else " / ".join(f"{v:.2f}" for v in f["per_iteration_ms"])
        print(f"{folder.name}: {f['runs']} runs, {f['steps']} steps; step CPU median / p99 / max {cpu} ms; "  # noqa: T201
              f"per iteration median / p90 / max {per} ms; steps over {1000 * LIMIT_S:.0f} ms: {f['over']}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
