"""Yaw-moment chattering and COLREG verdicts of the give-way crossing's system on other Imazu problems.

The exported COLREG system (``scenarios/osp/crossing_give_way.toml``: the COLREG-aware NMPC
on a straight reference, 20 s control interval, R = 0, R_i = 1 nm) with the targets of a
fixed set of Imazu's problems (1 head-on, 2 crossing from starboard, 3 overtaking, 4
crossing from port, 5 and 10 two targets), each placed to meet the own ship at (7.5, 0) nm
after 25 min as ``scenarios/situations/imazu/`` tabulates them, run in our master in both
exchange orders.  Printed per run: yaw-moment sign changes per 100 solves, fallbacks, the
least separation margin min(distance) - (R + R_i) [nm] and the verdict of each of the
scenario's acceptance criteria.

    nice -n 10 python bench/bench_colregs_chattering.py [--problems 1 2 4] [--orders gauss-seidel] \
        [--out docs/colregs-chattering-figures.md]
"""

from __future__ import annotations

import argparse
import json
import logging
import math
import tempfile
from pathlib import Path

from orchestrator.run import run_scenario

REPO = Path(__file__).resolve().parents[1]
SCENARIO = REPO / "scenarios" / "osp" / "crossing_give_way.toml"
PROBLEMS = (1, 2, 3, 4, 5, 10)
ORDERS = ("gauss-seidel", "jacobi")
MEET_NM = (7.5, 0.0)
MEET_MIN = 25.0


def imazu_targets(problem: int) -> list[dict]:
    """The targets of Imazu's problem as the traffic participant's option (north, east in nm, kn)."""
    situation = json.loads((REPO / "scenarios" / "situations" / "imazu" / f"imazu_{problem:02d}.json").read_text())
    targets = []
    for ship in situation["targetShips"]:
        speed, course = ship["initial"]["sog"], math.radians(ship["initial"]["cog"])
        north, east = speed * math.cos(course), speed * math.sin(course)
        targets.append({"start_nm": [MEET_NM[0] - north * MEET_MIN / 60.0, MEET_NM[1] - east * MEET_MIN / 60.0],
                        "velocity_kn": [north, east], "radius_nm": 1.0})
    return targets


def measure(problem: int, order: str, results: Path) -> dict:
    report = run_scenario(SCENARIO, results, progress=False, group=f"imazu{problem:02d}_{order}",
                          overrides={"simulation.exchange": order,
                                     "participants.traffic.options.targets": imazu_targets(problem)})
    summary = report.summary
    criteria = {c["name"]: c["passed"] for c in summary.get("acceptance", {}).get("criteria", [])}
    return {"problem": problem, "order": order, "status": report.status,
            "sign_changes": summary["participants"]["ctrl"]["tau_r_sign_changes_per_100_solves"],
            "fallbacks": summary["participants"]["ctrl"]["fallback_count"],
            "margin_nm": summary.get("analyses", {}).get("encounter", {}).get("min_clearance_nm"),
            "failed": [name for name, passed in criteria.items() if not passed]}


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--problems", nargs="*", type=int, default=PROBLEMS)
    parser.add_argument("--orders", nargs="*", default=ORDERS, choices=ORDERS)
    parser.add_argument("--out", default=None, help="also write the table as Markdown")
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.ERROR)
    rows = []
    with tempfile.TemporaryDirectory(prefix="bench-chattering-") as results:
        for problem in args.problems:
            for order in args.orders:
                rows.append(measure(problem, order, Path(results)))
                print(rows[-1], flush=True)
    if args.out:
        lines = ["# COLREG give-way system on Imazu's problems: chattering and verdicts "
                 "(written by bench/bench_colregs_chattering.py)", "",
                 "| Imazu problem | order | tau_r sign changes / 100 solves | separation margin (nm) | fallbacks | "
                 "criteria not met |", "|---|---|---|---|---|---|"]
        for row in rows:
            margin = "-" if row["margin_nm"] is None else f"{row['margin_nm']:+.3f}"
            lines.append(f"| {row['problem']} | {row['order']} | {row['sign_changes']:.2f} | {margin} | "
                         f"{row['fallbacks']} | {', '.join(row['failed']) or 'none'} |")
        Path(args.out).write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
