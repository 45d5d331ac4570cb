"""What ending runs by the separation watch saves, and that it judges every run as its full run does.

Two ways, both over a fixed sample of a search's evaluations:

* ``--rerun FOLDER --watched SEARCH.toml -n N``: the first N evaluations journaled in the
  search folder FOLDER (full runs), each run again here in this process, once as it was and
  once with the ``[set]`` of the search file SEARCH.toml (the watch and its stop): steps and
  processor time of each (this process and its ended children: the NMPC's solver process), and whether the two are judged alike (separation margin, each
  target's closest approach);
* ``--pairs FULL WATCHED``: two search folders of the same seed and sampler, one on full
  runs and one on runs ended by the watch; every evaluation both journaled with the same
  values is compared (a search whose objectives are the same asks the same evaluations, so
  the ended search replays the full one until it has run further).

Prints one line per run and the totals; exits 1 when any run is judged otherwise.

    nice -n 15 python bench/bench_separation_watch.py --rerun results/bench_search/random-seed1/search_rhnc_search \\
        --watched batches/search_rhnc_watched.toml -n 6
    python bench/bench_separation_watch.py --pairs results/bench_search/tpe-seed1/search_rhnc_search \\
        results/bench_search_watched/tpe-seed1/search_rhnc_watched_search
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import tomllib
from pathlib import Path

EXIT_BAD_INPUT = 2


def judged(summary: dict) -> tuple:
    """What a run is judged on: its separation margin and each target's closest approach."""
    colregs = summary.get("analyses", {}).get("colregs", {})
    return colregs.get("separation_margin_nm"), tuple(t["cpa_nm"] for t in colregs.get("targets", []))


def _journal(folder: Path) -> list[dict]:
    from orchestrator.search_journal import JOURNAL, read_journal

    entries = read_journal(folder / JOURNAL)
    if not entries:
        raise ValueError(f"{folder}: no search journal ({JOURNAL})")
    return entries


def _summary(folder: Path, run_id: str) -> dict | None:
    try:
        return json.loads((folder / "runs" / run_id / "summary.json").read_text())
    except (OSError, ValueError):
        return None


def processor_time_s() -> float:
    """Processor time of this process and of its ended children (the NMPC's solver process, figures) [s]."""
    import os

    times = os.times()
    return times.user + times.system + times.children_user + times.children_system


def rerun(folder: Path, watched: Path, count: int) -> list[dict]:
    """Run the first ``count`` evaluations of ``folder`` as they were and with ``watched``'s ``[set]``."""
    from orchestrator.run import run_scenario

    settings = json.loads((folder / "search.json").read_text())
    scenario = Path(settings["scenario"])
    stop = tomllib.loads(watched.read_text()).get("set")
    if not stop:
        raise ValueError(f"{watched}: no [set] table (the watch and its stop)")
    rows = []
    with tempfile.TemporaryDirectory() as scratch:
        for entry in _journal(folder)[:count]:
            row = {"evaluation": entry["number"] + 1, "run_id": entry["run_id"]}
            for label, overrides in (("full", entry["overrides"]), ("ended", {**entry["overrides"], **stop})):
                started = processor_time_s()
                report = run_scenario(scenario, scratch, progress=False, run_id=f"{label}-{entry['run_id']}",
                                      overrides=overrides, group="runs")
                row[f"{label}_cpu_s"] = processor_time_s() - started
                row[f"{label}_steps"] = report.summary["simulation"]["steps_done"]
                row[label] = judged(report.summary)
            rows.append(row)
            _print(row)
    return rows


def pairs(full: Path, ended: Path) -> list[dict]:
    """Evaluations journaled with the same values in both folders, both run."""
    rows = []
    for mine, theirs in zip(_journal(full), _journal(ended)):
        if mine["values"] != theirs["values"]:
            break  # the searches part here (or were never the same)
        first, second = _summary(full, mine["run_id"]), _summary(ended, theirs["run_id"])
        if first is None or second is None:
            break
        row = {"evaluation": mine["number"] + 1, "run_id": mine["run_id"], "full": judged(first),
               "ended": judged(second), "full_steps": first["simulation"]["steps_done"],
               "ended_steps": second["simulation"]["steps_done"]}
        rows.append(row)
        _print(row)
    return rows


def _print(row: dict) -> None:
    cpu = (f", processor {row['full_cpu_s']:.1f} s -> {row['ended_cpu_s']:.1f} s" if "full_cpu_s" in row else "")
    margin = row["full"][0]
    print(f"evaluation {row['evaluation']} ({row['run_id']}): margin {margin if margin is None else f'{margin:.4f}'} "
          f"nm, {'alike' if row['full'] == row['ended'] else 'JUDGED OTHERWISE ' + str(row['ended'])}; steps "
          f"{row['full_steps']} -> {row['ended_steps']}{cpu}", flush=True)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    mode = parser.add_mutually_exclusive_group(required=True)
    mode.add_argument("--rerun", metavar="FOLDER", help="a search folder of full runs: run its first N evaluations")
    mode.add_argument("--pairs", nargs=2, metavar=("FULL", "WATCHED"), help="two search folders to compare")
    parser.add_argument("--watched", metavar="SEARCH", help="with --rerun: the search file whose [set] ends runs")
    parser.add_argument("-n", type=int, default=6, help="with --rerun: evaluations to run (default 6)")
    args = parser.parse_args(argv)
    try:
        if args.rerun:
            if not args.watched or args.n < 1:
                raise ValueError("--rerun needs --watched SEARCH.toml and -n of at least 1")
            rows = rerun(Path(args.rerun), Path(args.watched), args.n)
        else:
            rows = pairs(Path(args.pairs[0]), Path(args.pairs[1]))
    except (OSError, ValueError, KeyError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    otherwise = [row for row in rows if row["full"] != row["ended"]]
    steps = [sum(row[f"{label}_steps"] for row in rows) for label in ("full", "ended")]
    line = (f"{len(rows)} runs: {len(rows) - len(otherwise)} judged alike, {len(otherwise)} otherwise; steps "
            f"{steps[0]} -> {steps[1]} ({100 * (1 - steps[1] / max(steps[0], 1)):.0f} % fewer)")
    if rows and "full_cpu_s" in rows[0]:
        cpu = [sum(row[f"{label}_cpu_s"] for row in rows) for label in ("full", "ended")]
        line += f"; processor time {cpu[0]:.1f} s -> {cpu[1]:.1f} s ({100 * (1 - cpu[1] / cpu[0]):.0f} % less)"
    print(line)
    return 1 if otherwise else 0


if __name__ == "__main__":
    sys.exit(main())
