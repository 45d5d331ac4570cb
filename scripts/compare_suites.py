"""What changed between two measurements of the same encounter suites, situation by situation.

Two results roots (each holding batch folders written by ``python -m orchestrator batch``, or
judged again by ``scripts/rejudge.py``) are compared batch by batch on the runs of the same
situation::

    PYTHONPATH=. python scripts/compare_suites.py results/suites_<before> results/suites_<after> \\
        drawn2035_rhnc_colregs trafficgen55g_rhnc_colregs ...

Per batch it prints, for every failure class of ``suite_report --failures`` (``separation``,
``inside``, ``side``, ``rule_8`` ... ``rule_17``, ``fallback``, and ``fallback only``: a run
whose fallbacks are its only failure), the runs failing it before and after, and the situations
that went from pass to fail and back; then the arrival: the runs that arrived in both, the mean
change of the arrival time (positive: later) and the runs arriving more than 10 and 30 min later
or earlier. A total over all batches closes. The two sides must hold the same situations; a
batch missing on either side is named and skipped.

Compare like with like: both sides judged by the same analyses (judge the older runs again with
``scripts/rejudge.py`` when the analysis changed in between).
"""

from __future__ import annotations

import argparse
import json
import re
import sys
from collections import Counter
from pathlib import Path

from rhnc.encounters.suite_report import failures, run_situations

CLASSES = ("separation", "inside", "side", "rule_8", "rule_13", "rule_14", "rule_15", "rule_16",
           "rule_17", "fallback", "fallback only")
STOPPED = re.compile(r"stopped at t = ([0-9.]+) s")


def situations(batch: Path) -> dict[str, str]:
    """Run id -> situation of a batch folder (the run id for a run without one)."""
    return {run: situation or run for run, situation in run_situations(batch).items()}


def failed_classes(batch: Path) -> dict[str, set[str]]:
    """Situation -> the failure classes of its run (every situation of the batch, empty when it passed)."""
    by_run = situations(batch)
    result: dict[str, set[str]] = {situation: set() for situation in by_run.values()}
    for kind, _batch, where, _target, detail in failures(batch):
        run = where.split(" ", 1)[0]
        situation = by_run.get(run, run)
        result.setdefault(situation, set()).add(kind)
        if kind == "fallback" and detail == "only":
            result[situation].add("fallback only")
    return result


def arrival_s(batch: Path) -> dict[str, float]:
    """Situation -> the time its run stopped on arrival [s] (runs that arrived only)."""
    by_run = situations(batch)
    result = {}
    for path in sorted((batch / "runs").glob("*/summary.json")):
        summary = json.loads(path.read_text())
        match = STOPPED.match(str(summary.get("reason", "")))
        if summary.get("status") == "finished" and match and "arrived" in str(summary.get("reason")):
            result[by_run.get(path.parent.name, path.parent.name)] = float(match.group(1))
    return result


def compare(before: Path, after: Path) -> tuple[list[str], Counter, list[float]]:
    """Lines describing one batch's changes, the run counts per class (``before:<class>``,
    ``after:<class>``) and the arrival changes [s] of the runs that arrived in both."""
    old, new = failed_classes(before), failed_classes(after)
    if set(old) != set(new):
        raise SystemExit(f"{after}: not the same situations as {before} "
                         f"({len(set(old) ^ set(new))} differ); compare runs of one suite")
    counts: Counter = Counter()
    lines = [f"{after.name}: {len(new)} situations"]
    for kind in CLASSES:
        worse = sorted(situation for situation in new if kind in new[situation] and kind not in old[situation])
        better = sorted(situation for situation in new if kind in old[situation] and kind not in new[situation])
        before_runs = counts[f"before:{kind}"] = sum(kind in classes for classes in old.values())
        after_runs = counts[f"after:{kind}"] = sum(kind in classes for classes in new.values())
        if before_runs or after_runs:
            text = f"  {kind}: {before_runs} -> {after_runs} runs"
            if worse:
                text += f"; now failing: {', '.join(Path(s).stem for s in worse)}"
            if better:
                text += f"; now passing: {', '.join(Path(s).stem for s in better)}"
            lines.append(text)
    old_arrival, new_arrival = arrival_s(before), arrival_s(after)
    both = sorted(set(old_arrival) & set(new_arrival))
    changes = [new_arrival[situation] - old_arrival[situation] for situation in both]
    lines.append(f"  arrived: {len(old_arrival)} -> {len(new_arrival)}; {arrival_line(changes)}")
    return lines, counts, changes


def arrival_line(changes: list[float]) -> str:
    if not changes:
        return "no run arrived in both"
    minutes = [change / 60.0 for change in changes]
    return (f"in both {len(minutes)}, mean change {sum(minutes) / len(minutes):+.1f} min, "
            f"later by > 10 min {sum(m > 10 for m in minutes)}, > 30 min {sum(m > 30 for m in minutes)} "
            f"(worst {max(minutes):+.0f} min), earlier by > 10 min {sum(m < -10 for m in minutes)}")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("before", type=Path, help="results root of the earlier measurement")
    parser.add_argument("after", type=Path, help="results root of the later measurement")
    parser.add_argument("batches", nargs="+", help="batch names (folders under both roots)")
    args = parser.parse_args(argv)
    for root in (args.before, args.after):
        if not root.is_dir():
            print(f"error: {root}: no such results folder", file=sys.stderr)
            return 2
    total: Counter = Counter()
    all_changes: list[float] = []
    for name in args.batches:
        before, after = args.before / name, args.after / name
        missing = [str(folder) for folder in (before, after) if not (folder / "batch.json").is_file()]
        if missing:
            print(f"{name}: skipped, no batch in {', '.join(missing)}")
            continue
        lines, counts, changes = compare(before, after)
        print("\n".join(lines))
        total.update(counts)
        all_changes.extend(changes)
    print("total: " + ", ".join(f"{kind} {total[f'before:{kind}']} -> {total[f'after:{kind}']}"
                                for kind in CLASSES if total[f"before:{kind}"] or total[f"after:{kind}"]))
    print(f"total arrival: {arrival_line(all_changes)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
