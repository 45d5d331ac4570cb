"""Summary of encounter-suite batches: separation, COLREG side and verdicts, fallbacks, solve times.

Reads the batch folders written by ``python -m orchestrator batch`` (their ``runs/*/summary.json``)
and prints one Markdown row per batch::

    python -m rhnc.suite_report results/suites/imazu_nmpc results/suites/imazu_rhnc ...

Columns: runs; runs keeping R + R_i from every obstacle; runs passed on the COLREG side
(every target with a side rule: head-on port to port, astern of a crossing ship we give way
to, no turn to port as stand-on) out of the runs with such a target, and the same per
target; runs whose every applicable rule verdict passed; runs with a solver fallback; the
median and largest NMPC solve time over all runs.
"""

from __future__ import annotations

import argparse
import json
from collections import Counter
from pathlib import Path


def summarise(folder) -> dict:
    """Counts and figures of one batch folder (see the module docstring)."""
    folder = Path(folder)
    summaries = [json.loads(path.read_text()) for path in sorted((folder / "runs").glob("*/summary.json"))]
    counts: Counter = Counter()
    solve_max, solve_median, failed_rules = [], [], Counter()
    for summary in summaries:
        counts["runs"] += 1
        analyses = summary.get("analyses", {})
        encounter, colregs = analyses.get("encounter", {}), analyses.get("colregs", {})
        control = summary.get("participants", {}).get("ctrl", {})
        counts["finished"] += summary.get("status") == "finished"
        counts["separation"] += bool(encounter.get("separation_respected"))
        side = colregs.get("side_correct")
        counts["side_runs"] += side is not None
        counts["side_ok"] += side is True
        for target in colregs.get("targets", []):
            if target.get("side_correct") is not None:
                counts["side_targets"] += 1
                counts["side_targets_ok"] += bool(target["side_correct"])
        counts["verdict_ok"] += colregs.get("verdict") in ("pass", "not applicable")
        failed_rules.update(colregs.get("rules_failed", []))
        counts["fallback_runs"] += (control.get("fallback_count") or 0) > 0
        if control.get("solve_time_max_s") is not None:
            solve_max.append(control["solve_time_max_s"])
            solve_median.append(control["solve_time_median_s"])
    return {"batch": folder.name, **counts, "rules_failed": dict(failed_rules),
            "solve_max_ms": 1000.0 * max(solve_max) if solve_max else None,
            "solve_median_ms": 1000.0 * sorted(solve_median)[len(solve_median) // 2] if solve_median else None}


def markdown(rows: list[dict]) -> str:
    lines = ["| batch | runs | separation >= R + R_i | COLREG side (runs) | COLREG side (targets) | all verdicts pass "
             "| runs with fallback | NMPC solve median / max [ms] | rules failed (runs) |",
             "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        rules = ", ".join(f"{k.replace('rule_', 'R')}: {v}" for k, v in sorted(r["rules_failed"].items())) or "-"
        solve = (f"{r['solve_median_ms']:.0f} / {r['solve_max_ms']:.0f}" if r["solve_max_ms"] is not None else "-")
        lines.append(f"| {r['batch']} | {r['runs']} | {r['separation']}/{r['runs']} | {r['side_ok']}/{r['side_runs']} "
                     f"| {r['side_targets_ok']}/{r['side_targets']} | {r['verdict_ok']}/{r['runs']} "
                     f"| {r['fallback_runs']} | {solve} | {rules} |")
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description="tabulate encounter-suite batch results")
    parser.add_argument("folders", nargs="+", help="batch result folders (results/<batch>)")
    args = parser.parse_args(argv)
    print(markdown([summarise(folder) for folder in args.folders]))  # noqa: T201 - a command's output
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
