"""Print the traffic suites' figures of docs/traffic.md from batch results: separation and COLREG side side by side.

Reads ``<results>/<batch>/batch.json`` and each run's ``summary.json`` of the batches named,
matches runs by their situation file (else their index) and prints one Markdown table:
per run and batch the minimum clearance beyond R + R_i [nm], the COLREG side and verdict,
and for batches with a tracker its position/velocity RMS and track breaks, for batches with
autonomous targets their mutual turns into each other; then a summary line per batch.
The tracker's figures are recomputed from each run's recorded series (so a change of
their definition needs no rerun)::

    python scripts/traffic_suites_table.py results imazu_nmpc_colregs imazu_nmpc_colregs_ais
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path


def tracking_from_timeseries(run_folder: Path) -> dict:
    """The tracking figures recomputed from a run's recorded series with the current
    :func:`rhnc.encounters.tracking_errors.tracking_errors` (participants named ``traffic``
    and ``tracker``, as in the suites' scenarios)."""
    import pandas as pd

    from orchestrator.analyses import array_output
    from rhnc.encounters.tracking_errors import tracking_errors

    frame = pd.read_parquet(run_folder / "timeseries.parquet")
    valid = array_output(frame, "tracker.track_valid")
    estimates = array_output(frame, "tracker.obstacles")[:, :valid.shape[1], :]
    return tracking_errors(frame["time_s"].to_numpy(), array_output(frame, "traffic.targets"), estimates, valid)


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
            if "tracking" in runs[key].get("analyses", {}):
                runs[key]["analyses"]["tracking"] = tracking_from_timeseries(summary.parent)
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
              f"{sum(side is False for side in sides)}; verdict fail in "
              f"{sum(s['analyses'].get('colregs', {}).get('verdict') == 'fail' for s in runs.values())}; runs with a "
              f"solver fallback {sum((s.get('participants', {}).get('ctrl', {}).get('fallback_count') or 0) > 0 for s in runs.values())}")
        tracked = [s["analyses"]["tracking"] for s in runs.values() if "tracking" in s.get("analyses", {})]
        if tracked:
            rms = [t["position_rms_max_m"] for t in tracked if t["position_rms_max_m"] is not None]
            speed = [t["velocity_rms_max_mps"] for t in tracked if t["velocity_rms_max_mps"] is not None]
            print(f"  tracker: position RMS {min(rms):.1f}-{max(rms):.1f} m, velocity RMS {min(speed):.2f}-"
                  f"{max(speed):.2f} m/s, track breaks {sum(t['track_breaks'] for t in tracked)}, targets never "
                  f"tracked {sum(t['targets_never_tracked'] for t in tracked)}")
        autonomous = [s["analyses"]["traffic_colregs"] for s in runs.values()
                      if "traffic_colregs" in s.get("analyses", {})]
        if autonomous:
            print(f"  targets: kept R_i in {sum(a['targets_separation_kept'] for a in autonomous)}/{len(autonomous)}, "
                  f"side wrong in {sum(a['targets_side_correct'] is False for a in autonomous)}, mutual turns into "
                  f"each other {sum(a['mutual_turns_into_each_other'] for a in autonomous)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
