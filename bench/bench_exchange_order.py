"""Gauss-Seidel against Jacobi exchange order: the same verdicts with the loop delay compensated.

Runs each scenario of ``scenarios/osp/`` (Experiments 2, 3a, 3b and a COLREG crossing, the
systems that are exported for OSP's libcosim) in our master twice: in our default order
(Gauss-Seidel, the controller stepping before the ship) and in libcosim's (Jacobi, every
participant from the values published before the communication point, so the controller's
decision reaches the ship one controller step later).  With ``--no-compensation`` the
controller and the navigation ignore that delay (``loop_delay_s = 0``, ``obstacle_age_s =
0``, the navigation's ``output_delay_s = 0`` in both orders): the behaviour a Jacobi master
saw before the delay was compensated (the model-error correction of the prediction over the
delay acts only over a delay, so it is off with it).

Printed per run: minimum separation margin min(distance) - (R + R_i) [nm], yaw-moment sign
changes per 100 solves, distance made good [nm] (Experiment 2: to arrival at the goal, or
the whole 480 min), whether the scenario's acceptance criteria pass, and for the Jacobi run
the made-good distance relative to the Gauss-Seidel run's.

    nice -n 10 python bench/bench_exchange_order.py [--only exp3b_head_on] [--no-compensation] \
        [--out docs/foreign-master-figures.md]
"""

from __future__ import annotations

import argparse
import logging
import tempfile
import tomllib
from pathlib import Path

import numpy as np
import pandas as pd

from orchestrator.geometry import NM
from orchestrator.run import run_scenario

REPO = Path(__file__).resolve().parents[1]
SCENARIOS = ("exp2_rhnc", "exp3a_static", "exp3b_head_on", "crossing_give_way")
ORDERS = ("gauss-seidel", "jacobi")


def measure(name: str, order: str, compensate: bool, results: Path) -> dict:
    overrides = {"simulation.exchange": order}
    path = REPO / "scenarios" / "osp" / f"{name}.toml"
    if not compensate:
        overrides["participants.ctrl.options.loop_delay_s"] = 0.0
        overrides["participants.ctrl.options.obstacle_age_s"] = 0.0
        participants = tomllib.loads(path.read_text())["participants"]
        for navigation in (n for n, spec in participants.items() if spec.get("type") == "navigation"):
            overrides[f"participants.{navigation}.options.output_delay_s"] = 0.0
    report = run_scenario(path, results, progress=False,
                          overrides=overrides, group=f"{name}_{order}")
    summary = report.summary
    analyses = summary.get("analyses", {})
    frame = pd.read_csv(report.folder / "timeseries.csv") if (report.folder / "timeseries.csv").exists() \
        else pd.read_parquet(report.folder / "timeseries.parquet")
    x, y = frame["ship.x"].to_numpy(), frame["ship.y"].to_numpy()
    voyage = analyses.get("voyage", {})
    made_good = voyage.get("made_good_nm", float(np.hypot(x[-1] - x[0], y[-1] - y[0]) / NM))
    return {
        "scenario": name, "order": order, "status": report.status,
        "margin_nm": analyses.get("encounter", {}).get("min_clearance_nm"),
        "sign_changes": summary["participants"]["ctrl"]["tau_r_sign_changes_per_100_solves"],
        "made_good_nm": made_good,
        "arrived": voyage.get("arrived"),
        "fallbacks": summary["participants"]["ctrl"]["fallback_count"],
        "acceptance": summary.get("acceptance", {}).get("passed"),
        "failed": [c["name"] for c in summary.get("acceptance", {}).get("criteria", []) if not c["passed"]],
    }


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", nargs="*", default=SCENARIOS, choices=SCENARIOS)
    parser.add_argument("--no-compensation", action="store_true",
                        help="loop_delay_s = obstacle_age_s = 0 and the navigation's output_delay_s = 0 in both orders")
    parser.add_argument("--out", default=None, help="also write the table as Markdown")
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.ERROR)
    rows = []
    with tempfile.TemporaryDirectory(prefix="bench-exchange-") as results:
        for name in args.only:
            ours = None
            for order in ORDERS:
                row = measure(name, order, not args.no_compensation, Path(results))
                ours = row["made_good_nm"] if order == "gauss-seidel" else ours
                row["made_good_vs_gs_pct"] = 100.0 * (row["made_good_nm"] / ours - 1.0)
                rows.append(row)
                print(row, flush=True)
    table = pd.DataFrame(rows)
    with pd.option_context("display.width", 200, "display.max_columns", 20):
        print(table.to_string(index=False, float_format=lambda v: f"{v:.3f}"))
    if args.out:
        lines = [f"# Exchange order: Gauss-Seidel against Jacobi (written by bench/bench_exchange_order.py"
                 f"{' --no-compensation' if args.no_compensation else ''})", "",
                 "| scenario | order | separation margin (nm) | tau_r sign changes / 100 solves | made good (nm) | "
                 "vs Gauss-Seidel | fallbacks | criteria not met |",
                 "|---|---|---|---|---|---|---|---|"]
        for row in rows:
            margin = "-" if row["margin_nm"] is None else f"{row['margin_nm']:+.4f}"
            lines.append(f"| {row['scenario']} | {row['order']} | {margin} | {row['sign_changes']:.2f} | "
                         f"{row['made_good_nm']:.2f} | {row['made_good_vs_gs_pct']:+.2f} % | {row['fallbacks']} | "
                         f"{', '.join(row['failed']) or 'none'} |")
        Path(args.out).write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
