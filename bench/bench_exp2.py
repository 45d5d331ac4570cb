"""Wall time of the full Experiment 2 RHNC run (goal: at most 3 s on 2 cores).

Prints the co-simulation loop time (480 macro steps: 120 navigation plans, 480 NMPC
solves, the KCS and MetOcean FMUs), the whole ``run_scenario`` time including results,
figures and set-up, the real-time factor, and whether the NMPC ran compiled
(:mod:`rhnc.nmpc_codegen`; the first run on a machine compiles it, about a minute).

    python bench/bench_exp2.py [--repeat 3] [--compare-interpreted]
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
SCENARIO = REPO / "scenarios" / "exp2_rhnc.toml"


def measure(scenario, repeat: int) -> tuple[float, float, float, dict]:
    """Best co-simulation loop time, best ``run_scenario`` time [s], simulated time [s], control summaries."""
    from orchestrator.master import CoSimulation
    from orchestrator.run import run_scenario

    loops, totals, simulated, control = [], [], 0.0, {}
    for _ in range(repeat):
        cosim = CoSimulation(scenario)
        started = time.perf_counter()
        outcome = cosim.run(progress=False)
        loops.append(time.perf_counter() - started)
        control = {p.name: p.summary() for p in cosim.participants if hasattr(p, "controller")}
        cosim.close()
        simulated = outcome.steps_done * scenario.simulation.dt_s
        with tempfile.TemporaryDirectory() as results:
            started = time.perf_counter()
            run_scenario(SCENARIO, results, progress=False)
            totals.append(time.perf_counter() - started)
    return min(loops), min(totals), simulated, control


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--compare-interpreted", action="store_true",
                        help="then the same runs with the NMPC's functions interpreted (RHNC_NMPC_CODEGEN=0)")
    args = parser.parse_args()
    from orchestrator.scenario import load_scenario
    from rhnc.nmpc_codegen import CODEGEN_ENV

    scenario = load_scenario(SCENARIO)
    modes = [None, "0"] if args.compare_interpreted else [None]
    print(f"load average before: {' / '.join(f'{v:.1f}' for v in os.getloadavg())} ({os.cpu_count()} cores)")
    for mode in modes:
        if mode is not None:
            os.environ[CODEGEN_ENV] = mode
        best, total, simulated, control = measure(scenario, args.repeat)
        for name, summary in control.items():
            print(f"{name}: NMPC {summary['codegen']}, median solve {summary['solve_time_median_s'] * 1e3:.1f} ms, "
                  f"max {summary['solve_time_max_s'] * 1e3:.1f} ms, {summary['solves']} solves")
        print(f"simulated time                     {simulated / 60:.0f} min")
        print(f"co-simulation loop (best of {args.repeat})     {best:6.2f} s   real-time factor {simulated / best:,.0f}"
              "   (goal <= 3 s)")
        print(f"run_scenario incl. results+figures {total:6.2f} s")
    print(f"load average after: {' / '.join(f'{v:.1f}' for v in os.getloadavg())}")


if __name__ == "__main__":
    main()
