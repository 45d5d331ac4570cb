"""Print the traffic suites' figures of docs/traffic.md from batch results: separation and COLREG side side by side.

Reads ``<results>/<batch>/batch.json`` and each run's ``summary.json`` of the batches named,
matches runs by their situation file (else their index) and prints one Markdown table:
per run and batch the minimum clearance beyond R + R_i [nm], the COLREG side and verdict,
and for batches with a tracker its position/velocity RMS and track breaks, for batches with
autonomous targets their mutual turns into each other; then a summary line per batch::

    python scripts/traffic_suites_table.py results imazu_nmpc_colregs imazu_nmpc_colregs_ais
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path


def load(results: Path, batch: str) -> dict[str, dict]:
    """Run key -> summary.json of one batch (runs without a summary are left out)."""
    folder = results / batch
    index = json.loads((folder / "batch.json").read_text())
    runs = {}
    for run in index["runs"]:
        summary = folder / "runs" / run["run_id"] / "summary.json"
        if summary.is_file():
            key = run.get("parameters", {}).get("situation") or f"run {run['index']}"
            runs[key] = json.loads(summary.read_text())
    return runs


def cells(summary: dict) -> list[str]:
    analyses = summary.get("analyses", {})
    encounter, colregs = analyses.get("encounter", {}), analyses.get("colregs", {})
    clearance = encounter.get("min_clearance_nm")
    out = [f"{clearance:.3f}" if isinstance(clearance, float) else "-",
           {True: "yes", False: "**no**", None: "n/a"}.get(colregs.get("side_correct"), "-"),
           str(colregs.get("verdict", "-"))]
    tracking = analyses.get("tracking")
    if isinstance(tracking, dict) and "position_rms_max_m" in tracking:
        rms, speed = tracking.get("position_rms_max_m"), tracking.get("velocity_rms_max_mps")
        out.append(f"{rms:.1f} m / {speed:.2f} m/s, {tracking.get('track_breaks')} breaks"
                   if rms is not None else "never tracked")
    traffic = analyses.get("traffic_colregs")
    if isinstance(traffic, dict) and "mutual_turns_into_each_other" in traffic:
        out.append(f"mutual {traffic['mutual_turns_into_each_other']}, targets kept R_i "
                   f"{'yes' if traffic.get('targets_separation_kept') else '**no**'}")
    return out


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("results", type=Path)
    parser.add_argument("batches", nargs="+")
    args = parser.parse_args(argv)
    tables = {batch: load(args.results, batch) for batch in args.batches}
    keys = sorted(set().union(*tables.values()))
    widths = {batch: len(cells(next(iter(t.values())))) if t else 3 for batch, t in tables.items()}
    header = ["run"] + [f"{batch}: {name}" for batch in args.batches
                        for name in ["clearance nm", "side", "verdict", "tracker", "autonomy"][:widths[batch]]]
    print("| " + " | ".join(header) + " |")
    print("|" + "---|" * len(header))
    for key in keys:
        row = [key]
        for batch in args.batches:
            summary = tables[batch].get(key)
            row += cells(summary) if summary else ["(not run)"] * widths[batch]
        print("| " + " | ".join(row) + " |")
    print()
    for batch, runs in tables.items():
        clearances = [s["analyses"]["encounter"]["min_clearance_nm"] for s in runs.values()
                      if isinstance(s.get("analyses", {}).get("encounter", {}).get("min_clearance_nm"), float)]
        sides = [s["analyses"]["colregs"].get("side_correct") for s in runs.values() if "colregs" in s.get("analyses", {})]
        print(f"- {batch}: {len(runs)} runs; separation kept in {sum(c >= 0 for c in clearances)}/{len(clearances)} "
              f"(smallest clearance {min(clearances, default=float('nan')):.3f} nm); COLREG side wrong in "
              f"{sum(side is False for side in sides)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
