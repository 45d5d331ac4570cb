"""Summary of encounter-suite batches: separation, COLREG side and verdicts, fallbacks, solve times.

Reads the batch folders written by ``python -m orchestrator batch`` (their ``runs/*/summary.json``)
and prints one Markdown table with a row per batch::

    python -m rhnc.encounters.suite_report results/suites/imazu_rhnc_colregs results/suites/random1_rhnc_colregs ...

With ``--write docs/encounters.md`` (repeatable: ``--write README.md`` too) the table replaces the one between the lines
``<!-- suite-table:begin -->`` and ``<!-- suite-table:end -->`` of that file instead (the
file is left untouched if either marker is missing).

Columns: runs; runs that met their stop condition (the suites' ``stop_when``: the goal
reached) before the step limit; runs keeping R + R_i from every obstacle that started outside it, and
the same per target; runs with a target that started inside R + R_i (the situation begins inside
the domain: no controller can then keep R + R_i), judged apart by their own criterion, the range
opening at once (its closest approach within 60 s of the start), and the same per target; runs passed on the COLREG side (every target with a side rule: head-on
port to port, astern of a crossing ship we give way to, no turn to port as stand-on) out of
the runs with such a target, and the same per target; runs whose every applicable rule
verdict passed; per rule, the targets it passed out of those it applied to; targets whose class
was decided within the borderline band of a boundary; runs with a
solver fallback and the fallbacks in all; the median and largest NMPC solve time [ms, wall
clock] and the largest solve CPU time [ms].

With ``--failures`` it prints instead one line per failing target (or run), by class:
``separation`` (started outside, CPA < R + R_i), ``inside`` (started inside, range not opened
within 60 s), ``side`` (COLREG side wrong), ``rule_8`` ... ``rule_17`` (that verdict failed; the
reason follows), ``fallback`` (a run with solver fallbacks, with the other classes it failed
by, ``only`` when none)::

    python -m rhnc.encounters.suite_report --failures results/suites/drawn_rhnc_colregs
"""

from __future__ import annotations

import argparse
import json
import sys
from collections import Counter
from pathlib import Path

from orchestrator.marked_blocks import replace_between

RULES = ("rule_8", "rule_13", "rule_14", "rule_15", "rule_16", "rule_17")
BEGIN = "<!-- suite-table:begin -->"
END = "<!-- suite-table:end -->"


def summarise(folder) -> dict:
    """Counts and figures of one batch folder (see the module docstring)."""
    folder = Path(folder)
    summaries = [json.loads(path.read_text()) for path in sorted((folder / "runs").glob("*/summary.json"))]
    counts: Counter = Counter()
    solve_max, solve_median, cpu_max, failed_rules = [], [], [], Counter()
    rule_passed, rule_applied = Counter(), Counter()
    for summary in summaries:
        counts["runs"] += 1
        analyses = summary.get("analyses", {})
        encounter, colregs = analyses.get("encounter", {}), analyses.get("colregs", {})
        control = summary.get("participants", {}).get("ctrl", {})
        counts["finished"] += summary.get("status") == "finished"
        counts["stopped"] += str(summary.get("reason", "")).startswith("stopped at")
        targets = colregs.get("targets", [])
        if "separation_kept" in colregs:  # over the targets that started outside R + R_i
            counts["separation"] += bool(colregs["separation_kept"])
        else:
            counts["separation"] += bool(encounter.get("separation_respected"))
        if colregs.get("started_inside"):
            counts["inside_runs"] += 1
            opened = colregs.get("started_inside_opened")
            counts["inside_kept"] += bool(colregs.get("started_inside_range_kept") if opened is None else opened)
        side = colregs.get("side_correct")
        counts["side_runs"] += side is not None
        counts["side_ok"] += side is True
        for target in targets:
            if target.get("started_inside"):
                counts["inside_targets"] += 1
                counts["inside_targets_opened"] += bool(target.get("range_opened_in_time",
                                                                   target.get("range_kept_from_start")))
            else:
                counts["outside_targets"] += 1
                counts["outside_targets_kept"] += bool(target.get("separation_kept"))
            counts["borderline_targets"] += bool(target.get("borderline"))
            if target.get("side_correct") is not None:
                counts["side_targets"] += 1
                counts["side_targets_ok"] += bool(target["side_correct"])
            for rule in RULES:
                if target.get(rule) in ("pass", "fail"):
                    rule_applied[rule] += 1
                    rule_passed[rule] += target[rule] == "pass"
        counts["verdict_ok"] += colregs.get("verdict") in ("pass", "not applicable")
        failed_rules.update(colregs.get("rules_failed", []))
        fallbacks = control.get("fallback_count") or 0
        counts["fallback_runs"] += fallbacks > 0
        counts["fallbacks"] += fallbacks
        if control.get("solve_time_max_s") is not None:
            solve_max.append(control["solve_time_max_s"])
            solve_median.append(control["solve_time_median_s"])
        if control.get("solve_cpu_time_max_s") is not None:
            cpu_max.append(control["solve_cpu_time_max_s"])
    return {"batch": folder.name, **counts, "rules_failed": dict(failed_rules),
            "rules": {rule: (rule_passed[rule], rule_applied[rule]) for rule in RULES},
            "solve_max_ms": 1000.0 * max(solve_max) if solve_max else None,
            "solve_median_ms": 1000.0 * sorted(solve_median)[len(solve_median) // 2] if solve_median else None,
            "solve_cpu_max_ms": 1000.0 * max(cpu_max) if cpu_max else None}


def run_situations(folder) -> dict[str, str]:
    """Run id -> the situation file its run was drawn from, from the batch folder's
    ``batch.json`` (empty without one; runs of a batch without situations map to '')."""
    batch_json = Path(folder) / "batch.json"
    if not batch_json.is_file():
        return {}
    return {run["run_id"]: str(run.get("parameters", {}).get("situation", ""))
            for run in json.loads(batch_json.read_text()).get("runs", [])}


def failures(folder) -> list[tuple[str, str, str, str, str]]:
    """Every failing target of a batch folder, by class (see the module docstring), as
    (class, batch, run id, target, detail) rows; a run with fallbacks is one row."""
    folder = Path(folder)
    situations = run_situations(folder)
    rows = []
    for path in sorted((folder / "runs").glob("*/summary.json")):
        summary = json.loads(path.read_text())
        run = path.parent.name
        where = f"{run} {situations.get(run, '')}".strip()
        colregs = summary.get("analyses", {}).get("colregs", {})
        failed = set()
        for target in colregs.get("targets", []):
            name = f"target {target.get('obstacle')} {target.get('encounter_class')}"
            reasons = target.get("reasons", {})
            if target.get("started_inside"):
                if not target.get("range_opened_in_time", target.get("range_kept_from_start")):
                    rows.append(("inside", folder.name, where, name, f"range opened after "
                                 f"{target.get('range_opening_s') or 0:.0f} s, initial {target.get('initial_range_nm', 0):.2f} nm"))
                    failed.add("inside")
            elif not target.get("separation_kept"):
                rows.append(("separation", folder.name, where, name,
                             f"CPA {target.get('cpa_nm', 0):.3f} nm < {target.get('required_nm', 0):.2f} nm"))
                failed.add("separation")
            if target.get("side_correct") is False:
                rows.append(("side", folder.name, where, name, f"passing {target.get('passing_side')}, "
                             f"manoeuvre {target.get('manoeuvre_side')}, crossed {target.get('crossed')}"))
                failed.add("side")
            for rule in RULES:
                if target.get(rule) == "fail":
                    rows.append((rule, folder.name, where, name, reasons.get(rule, "")))
                    failed.add(rule)
        fallbacks = summary.get("participants", {}).get("ctrl", {}).get("fallback_count") or 0
        if fallbacks:
            rows.append(("fallback", folder.name, where, f"{fallbacks} fallbacks",
                         ", ".join(sorted(failed)) or "only"))
    return rows


def markdown(rows: list[dict]) -> str:
    """One Markdown table, a row per batch summary (:func:`summarise`)."""
    rule_heads = " | ".join(rule.replace("rule_", "R") for rule in RULES)
    lines = ["| batch | runs | arrived | separation >= R + R_i (started outside): runs | targets "
             "| started inside: range opened within 60 s (runs) | targets "
             "| COLREG side (runs) | COLREG side (targets) | all verdicts pass | " + rule_heads
             + " | borderline classes (targets) | runs with fallback (fallbacks) | NMPC solve median / max [ms] "
             "| max solve CPU [ms] |",
             "|---|---|---|---|---|---|---|---|---|---|" + "---|" * len(RULES) + "---|---|---|---|"]
    for r in rows:
        solve = (f"{r['solve_median_ms']:.0f} / {r['solve_max_ms']:.0f}" if r["solve_max_ms"] is not None else "-")
        cpu = f"{r['solve_cpu_max_ms']:.0f}" if r.get("solve_cpu_max_ms") is not None else "-"
        inside = f"{r.get('inside_kept', 0)}/{r.get('inside_runs', 0)}" if r.get("inside_runs") else "-"
        rules = " | ".join(f"{p}/{a}" if a else "-" for p, a in (r["rules"][rule] for rule in RULES))
        inside_targets = (f"{r.get('inside_targets_opened', 0)}/{r['inside_targets']}" if r.get("inside_targets")
                          else "-")
        lines.append(f"| {r['batch']} | {r['runs']} | {r.get('stopped', 0)}/{r['runs']} "
                     f"| {r['separation']}/{r['runs']} | {r.get('outside_targets_kept', 0)}/{r.get('outside_targets', 0)} "
                     f"| {inside} | {inside_targets} "
                     f"| {r['side_ok']}/{r['side_runs']} | {r['side_targets_ok']}/{r['side_targets']} "
                     f"| {r['verdict_ok']}/{r['runs']} | {rules} | {r.get('borderline_targets', 0)} "
                     f"| {r['fallback_runs']} ({r.get('fallbacks', 0)}) | {solve} | {cpu} |")
    return "\n".join(lines)


def with_table(path, table: str) -> str:
    """The text of ``path`` with ``table`` between :data:`BEGIN` and :data:`END` (ValueError
    naming the file when they are missing)."""
    text = replace_between(Path(path).read_text(), BEGIN, END, table)
    if text is None:
        raise ValueError(f"{path}: no '{BEGIN}' ... '{END}' lines to write the table between")
    return text


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description="tabulate encounter-suite batch results")
    parser.add_argument("folders", nargs="+", help="batch result folders (results/<batch>)")
    parser.add_argument("--write", metavar="MARKDOWN", action="append", help="write the table between the "
                        "suite-table markers of this file instead of printing it (repeat for several files)")
    parser.add_argument("--failures", action="store_true", help="list every failing target by class instead")
    args = parser.parse_args(argv)
    missing = [folder for folder in args.folders if not (Path(folder) / "runs").is_dir()]
    if missing:
        print(f"suite_report: {missing[0]}: no runs/ folder (not a batch result)", file=sys.stderr)  # noqa: T201
        return 2
    if args.failures:
        for row in sorted(row for folder in args.folders for row in failures(folder)):
            print("\t".join(row))  # noqa: T201 - a command's output
        return 0
    table = markdown([summarise(folder) for folder in args.folders])
    if args.write:
        try:
            texts = {path: with_table(path, table) for path in args.write}   # every file before one is written
            for path, text in texts.items():
                Path(path).write_text(text)
        except (OSError, ValueError) as error:
            print(f"suite_report: {error}", file=sys.stderr)  # noqa: T201 - a command's error
            return 2
    else:
        print(table)  # noqa: T201 - a command's output
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
