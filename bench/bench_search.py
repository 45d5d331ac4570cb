"""Evaluations until the first failure: an optimiser's search against uniform random sampling of the same ranges.

Runs the search file once per seed with each sampler (``--samplers``, default TPE and
random) into ``--results``, each with a budget of ``--evaluations``, and prints per seed
the evaluation at which each found its first failure (``-`` : none within the budget),
the number of failures and the lowest objective, then the medians.  A search already
done in the results folder is read, not run again (the searches resume).

    nice -n 10 python bench/bench_search.py batches/search_rhnc.toml --seeds 1 2 3 --evaluations 30
"""

from __future__ import annotations

import argparse
import statistics
import sys
from pathlib import Path


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("search", help="search file")
    parser.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3])
    parser.add_argument("--samplers", nargs="+", default=["tpe", "random"])
    parser.add_argument("--evaluations", type=int, default=30)
    parser.add_argument("--workers", type=int, default=1)
    parser.add_argument("--results", default="results/bench_search")
    args = parser.parse_args(argv)
    from orchestrator.search import run_search

    found: dict[str, list] = {sampler: [] for sampler in args.samplers}
    print(f"{args.search}: evaluations to the first failure (budget {args.evaluations})")
    print(f"{'seed':>5} " + " ".join(f"{s:>28}" for s in args.samplers))
    for seed in args.seeds:
        cells = []
        for sampler in args.samplers:
            report = run_search(args.search, Path(args.results) / f"{sampler}-seed{seed}", workers=args.workers,
                                progress=False, evaluations=args.evaluations, sampler=sampler, seed=seed)
            if report.interrupted:
                print("interrupted: rerun the same command to go on", file=sys.stderr)
                return 130
            found[sampler].append(report.first_failure)
            first = "-" if report.first_failure is None else str(report.first_failure)
            best = "none" if report.best is None else f"{report.best:.3f}"
            cells.append(f"first {first:>4}, {report.failures:>3} fail, min {best:>7}")
        print(f"{seed:>5} " + " ".join(f"{c:>28}" for c in cells), flush=True)
    for sampler, firsts in found.items():
        hits = [f for f in firsts if f is not None]
        # a seed without a failure counts as beyond the budget: the median is then a lower bound
        ranked = [f if f is not None else args.evaluations + 1 for f in firsts]
        print(f"{sampler}: found a failure with {len(hits)}/{len(firsts)} seeds; median evaluations to the first "
              f"{statistics.median(ranked):g}{' (>' + str(args.evaluations) + ' counted as budget + 1)' if len(hits) < len(firsts) else ''}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
