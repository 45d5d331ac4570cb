"""Evaluations to the first failure: an optimiser's search against uniform random sampling of the same ranges.

Reads a comparison file (``bench/search_vs_random.toml``: the search file, the failure
threshold, seeds and budgets, declared before running) and, per seed, runs the optimiser
until its first failure (at most ``optimiser_budget`` evaluations), then random sampling
until its first failure or ``baseline_factor`` times the optimiser's count (its budget when
it found none), at most ``baseline_budget``.  Prints per seed both counts and their ratio
(``> N``: none found within N evaluations), the lowest objective each reached, then the
medians; ``--write FILE`` also writes the table as Markdown (docs/search-results.md).
Searches already done in ``--results`` are read, not run again (searches resume), so an
interrupted comparison goes on where it stopped; ``--as-run`` runs nothing and tables what
the folders hold (a search stopped before its first loss or budget: ``> N, stopped``).
``--searches FOLDER ...`` adds one line per other search folder (e.g. the search against
today's controller): evaluations done, failures, the lowest objective.

    nice -n 10 python bench/bench_search.py bench/search_vs_random.toml --write docs/search-results.md
"""

from __future__ import annotations

import argparse
import datetime as dt
import statistics
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated

from pydantic import PlainValidator

from orchestrator.marked_blocks import replace_between

EXIT_BAD_INPUT = 2


def _comparison_table():
    from orchestrator.search_spec import SAMPLERS, MAX_EVALUATIONS
    from orchestrator.toml_input import Finite, PositiveInt, Text, TomlTable, fail, one_of

    def seeds(value):
        if (not isinstance(value, list) or not value or len(set(value)) != len(value)
                or not all(isinstance(v, int) and not isinstance(v, bool) and v >= 0 for v in value)):
            raise fail("must be a list of different non-negative integers, e.g. [1, 2, 3]")
        return value

    def budget(value):
        if isinstance(value, bool) or not isinstance(value, int) or not 1 <= value <= MAX_EVALUATIONS:
            raise fail(f"must be a positive integer (at most {MAX_EVALUATIONS})")
        return value

    class ComparisonTable(TomlTable):
        search: Text
        fails_below_nm: Finite
        seeds: Annotated[list[int], PlainValidator(seeds)]
        optimiser: Annotated[str, one_of(SAMPLERS)] = "tpe"
        optimiser_budget: Annotated[int, PlainValidator(budget)]
        baseline: Annotated[str, one_of(SAMPLERS)] = "random"
        baseline_factor: PositiveInt = 5
        baseline_budget: Annotated[int, PlainValidator(budget)]
        workers: PositiveInt = 1

    return ComparisonTable


@dataclass(frozen=True)
class Count:
    """One sampler's search on one seed."""

    first_failure: int | None  # evaluation of the first failure (from 1), None: none within `budget`
    budget: int  # evaluations done when none was found
    lowest: float | None
    stopped: bool = False  # stopped before its first failure or its budget (--as-run)

    def shown(self) -> str:
        if self.first_failure is not None:
            return str(self.first_failure)
        return f"> {self.budget}{', stopped' if self.stopped else ''}"


def load_comparison(path: Path):
    """The checked comparison file; the search file's path resolved against it."""
    from orchestrator.toml_input import checked, read_toml

    data, _ = read_toml(path, "comparison")
    table = checked(_comparison_table(), data, str(path))
    search = (path.parent / table.search).resolve()
    if not search.is_file():
        from orchestrator.errors import ScenarioError

        raise ScenarioError(f"{path}: 'search': no such file {search}")
    return table, search


def count(search: Path, results: Path, sampler: str, seed: int, budget: int, fails_below: float,
          workers: int) -> Count:
    """Run (or read) the search with ``sampler`` and ``seed`` until its first failure or ``budget``."""
    from orchestrator.search import run_search

    report = run_search(search, results, workers=workers, progress=False, evaluations=budget, sampler=sampler,
                        seed=seed, fails_below=fails_below, until_failure=True)
    if report.interrupted:
        raise KeyboardInterrupt
    return Count(report.first_failure, budget, report.best)


def read_count(folder: Path, budget: int) -> Count | None:
    """What a search folder holds (``search.json``, written when a search ends or is stopped), or None."""
    import json

    try:
        saved = json.loads((folder / "search.json").read_text())
    except (OSError, ValueError):
        return None
    done = int(saved.get("evaluations_done", 0))
    first = saved.get("first_failure")
    return Count(first, done if first is None else budget, saved.get("best"), first is None and done < budget)


def search_line(folder: Path) -> str:
    """One search's outcome: evaluations done, failures (by its threshold), the lowest objective, acceptance."""
    import json

    import pandas as pd

    saved = json.loads((folder / "search.json").read_text())
    table = pd.read_csv(folder / "summary.csv")
    done = table[table["status"] != "not run"]
    lowest = done["objective"].min()
    worst = done.loc[done["objective"].idxmin(), "run_id"] if done["objective"].notna().any() else None
    return (f"`{saved['search'].split('/')[-1]}` ({saved['sampler']}, seed {saved['seed']}): {len(done)} of "
            f"{saved['evaluations']} evaluations run; {int(done['failure'].sum())} below {saved['fails_below']} "
            f"(first: {saved.get('first_failure') or 'none'}); lowest {saved['objective'].split('.')[-1]} "
            f"{lowest:.3f} (run {worst}); {int((~done['passed'].astype(bool)).sum())} not passing its acceptance "
            f"criteria ({'; '.join(saved['acceptance'])}); {int(done['objective'].isna().sum())} without an objective")


def ratio(optimiser: Count, baseline: Count) -> str:
    if optimiser.first_failure is None:
        return "-"
    value = (baseline.first_failure or baseline.budget) / optimiser.first_failure
    return f"{'>= ' if baseline.first_failure is None else ''}{value:.1f}"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("comparison", help="comparison file (bench/search_vs_random.toml)")
    parser.add_argument("--results", default="results/bench_search", help="results folder")
    parser.add_argument("--seeds", type=int, nargs="+", default=None, help="only these of the file's seeds")
    parser.add_argument("--write", default=None, help="also write the table as Markdown to this file")
    parser.add_argument("--readme", default=None, help="replace the search summary between the markers "
                        "<!-- MARKER:begin --> and <!-- MARKER:end --> of this file (README.md)")
    parser.add_argument("--readme-marker", default="search-summary", help="the markers' name for --readme "
                        "(default search-summary; one block per declared comparison)")
    parser.add_argument("--as-run", action="store_true", help="run nothing: table what the results folders hold")
    parser.add_argument("--searches", nargs="*", default=[], help="other search folders to add a line for")
    args = parser.parse_args(argv)
    from orchestrator.errors import ScenarioError

    path = Path(args.comparison)
    try:
        table, search = load_comparison(path)
    except (ScenarioError, OSError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    if args.readme:
        try:
            replace_block(Path(args.readme), args.readme_marker, "", dry=True)
        except (OSError, ValueError) as exc:
            print(f"error: --readme {exc}", file=sys.stderr)
            return EXIT_BAD_INPUT
    seeds = table.seeds if args.seeds is None else args.seeds
    unknown = [s for s in seeds if s not in table.seeds]
    if unknown:
        print(f"error: --seeds {unknown}: not among {path}'s seeds {table.seeds}", file=sys.stderr)
        return EXIT_BAD_INPUT
    opt, base = table.optimiser, table.baseline
    from orchestrator.search_spec import load_search

    name = load_search(search).name  # the folder each search writes under its --results
    header = (f"| seed | {opt}: evaluations to the first loss | {base}: evaluations to the first loss | ratio | "
              f"{opt}: lowest margin [nm] | {base}: lowest margin [nm] |")
    rows = [header, "|---:|---:|---:|---:|---:|---:|"]
    print(f"{search.name}: loss = separation margin < {table.fails_below_nm} nm; {opt} up to "
          f"{table.optimiser_budget}, {base} up to {table.baseline_factor} x that (at most {table.baseline_budget})")
    print(header)
    counts = []
    try:
        for seed in seeds:
            folders = [Path(args.results) / f"{sampler}-seed{seed}" for sampler in (opt, base)]
            if args.as_run:
                found = read_count(folders[0] / name, table.optimiser_budget)
                if found is None:
                    continue
            else:
                found = count(search, folders[0], opt, seed, table.optimiser_budget, table.fails_below_nm,
                              table.workers)
            reach = found.first_failure or table.optimiser_budget
            budget = min(table.baseline_factor * reach, table.baseline_budget)
            if args.as_run:
                drawn = (read_count(folders[1] / name, budget)
                         or Count(None, 0, None, stopped=True))
            else:
                drawn = count(search, folders[1], base, seed, budget, table.fails_below_nm, table.workers)
            counts.append((seed, found, drawn))
            lows = ["none" if c.lowest is None else f"{c.lowest:.3f}" for c in (found, drawn)]
            row = f"| {seed} | {found.shown()} | {drawn.shown()} | {ratio(found, drawn)} | {lows[0]} | {lows[1]} |"
            rows.append(row)
            print(row, flush=True)
    except KeyboardInterrupt:
        print("interrupted: rerun the same command to go on", file=sys.stderr)
        return 130
    met = sum(1 for _, f, d in counts if f.first_failure is not None
              and (d.first_failure or d.budget) >= table.baseline_factor * f.first_failure)
    found_by = [f.first_failure for _, f, _ in counts if f.first_failure is not None]
    lines = [f"{opt} found a loss on {len(found_by)} of {len(counts)} seeds"
             + (f" (median {statistics.median(found_by):g} evaluations)" if found_by else ""),
             f"{base} needed at least {table.baseline_factor} times as many on {met} of {len(counts)} seeds"]
    others = [search_line(Path(folder)) for folder in args.searches]
    for line in lines + others:
        print(line)
    if args.write:
        command = "nice -n 10 python bench/bench_search.py " + " ".join(sys.argv[1:] if argv is None else argv)
        text = ["# Search against random sampling: evaluations to the first separation loss", "",
                f"Generated by `{command}` on {dt.date.today().isoformat()} from the comparison declared in "
                f"`{args.comparison}` (search file `{Path(table.search).as_posix().removeprefix('../')}`; a loss is a "
                f"separation margin below {table.fails_below_nm} nm).  `> N`: none within N evaluations.", "",
                *rows, "", *[f"- {line}" for line in lines], ""]
        if others:
            text += ["## Other searches", "", *[f"- {line}" for line in others], ""]
        Path(args.write).write_text("\n".join(text))
    if args.readme:
        verdict = ("met" if counts and met == len(counts) and len(counts) >= 3 else "**not met**")
        block = [*rows, "", *[f"- {line}" for line in lines + others], "",
                 f"**Goal** (the optimiser finds a loss within {table.optimiser_budget} evaluations where random "
                 f"sampling needs at least {table.baseline_factor} times as many, on every seed of at least three): "
                 f"{verdict} on the seeds run ({len(counts)} of {len(table.seeds)} declared)."]
        replace_block(Path(args.readme), args.readme_marker, "\n".join(block))
    return 0


def replace_block(path: Path, marker: str, body: str, dry: bool = False) -> None:
    """Replace the text between ``<!-- marker:begin -->`` and ``<!-- marker:end -->`` in ``path``."""
    begin, end = f"<!-- {marker}:begin -->", f"<!-- {marker}:end -->"
    text = replace_between(path.read_text(), begin, end, body)
    if text is None:
        raise ValueError(f"{path}: no {begin} ... {end} block to replace")
    if not dry:
        path.write_text(text)


if __name__ == "__main__":
    sys.exit(main())
