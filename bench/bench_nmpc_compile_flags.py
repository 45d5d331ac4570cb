"""Benchmark: the NMPC's compiled NLP built with other compiler flags, side by side.

For each set of flags the same compact NLP (one target, N_c = 15, the benchmark problem of
:mod:`bench_nmpc`) is generated and compiled into the NMPC cache folder, then

* the Hessian of the Lagrangian and the constraint Jacobian are timed hot (2 000 calls in a
  row, the same arguments), and
* every flag set's controller sails the same closed loop (90 steps of 20 s, the numpy
  plant), in blocks of 10 steps in turn so that load changes fall on all alike; the first
  loop warms up, the next ``--rounds`` are counted.

    python bench/bench_nmpc_compile_flags.py [--flags=-O1 --flags="-O3 -march=native"] [--rounds 3] [--watchdog]

Prints build time, hot-loop times and the whole control step's processor time (median,
mean) per flag set; the first build of a flag set takes 8-15 s, later runs reuse it.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import bench_nmpc as bench  # noqa: E402
from rhnc.control import nmpc_codegen  # noqa: E402
from rhnc.ship.ship_model import load_parameter_set  # noqa: E402


def hot_ms(function, arguments, calls: int = 2000) -> float:
    function(*arguments)
    start = time.perf_counter()
    for _ in range(calls):
        function(*arguments)
    return (time.perf_counter() - start) / calls * 1e3


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--flags", action="append", metavar="FLAGS",
                        help='a compiler flag set, one string; repeat to compare several: --flags=-O1 '
                             '--flags="-O3 -march=native" (default: -O1, -O3, -O3 -march=native)')
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--targets", type=int, default=1, choices=[1, 3])
    parser.add_argument("--watchdog", action="store_true", help="solves in the forked worker (the default NMPC)")
    args = parser.parse_args()
    args.flags = args.flags or ["-O1", "-O3", "-O3 -march=native"]
    # libraries of other flags in a folder of their own, beside the NMPC's cache
    os.environ[nmpc_codegen.CACHE_ENV] = str(nmpc_codegen.cache_dir() / "flags-bench")
    params = load_parameter_set("default")
    rng = np.random.default_rng(0)
    loops, rows = {}, {}
    for flags in args.flags:
        # the probe and the key follow these flags; -march=native only when asked for
        nmpc_codegen.COMPILER_FLAGS = (*flags.split(), "-fPIC", "-shared")
        nmpc_codegen.NATIVE_FLAGS = ()
        nmpc_codegen.compiler_flags.cache_clear()
        builds = nmpc_codegen.NLPLibrary.builds
        loop = bench.ours(params, "fatrop", args.targets, True, args.watchdog)
        library = loop.controller.library
        if library.mode != "compiled":
            parser.error(f"flags {flags!r}: the NLP was not compiled ({library.reason})")
        solver = library.solver("hot")
        row = {"built": nmpc_codegen.NLPLibrary.builds > builds, "build_s": library.build_time_s}
        hessian, jacobian = solver.get_function("nlp_hess_l"), solver.get_function("nlp_jac_g")
        x, p, lam = (rng.random(hessian.size1_in(i)) for i in (0, 1, 3))
        row["hessian_ms"] = hot_ms(hessian, [x, p, 1.0, lam])
        row["jacobian_ms"] = hot_ms(jacobian, [x, p])
        loops[flags], rows[flags] = loop, row
    cpu = {flags: [] for flags in loops}
    for round_ in range(args.rounds + 1):
        for loop in loops.values():
            loop.k, loop.cpu = 0, []
            loop.state = np.array([0.0, 0.0, bench.COURSE_RAD, bench.SPEED_MPS, 0.0, 0.0])
        for _ in range(0, 90, 10):
            for loop in loops.values():
                for _ in range(10):
                    loop.advance()
        if round_:  # the first round warms up
            for flags, loop in loops.items():
                cpu[flags] += loop.cpu
    for loop in loops.values():
        loop.close()
    load = os.getloadavg()
    print(f"NMPC compiled with other flags: {args.targets} target(s), {'watchdog' if args.watchdog else 'in-process'}, "
          f"{args.rounds} x 90 closed-loop steps each; load average {load[0]:.1f}")
    print(f"{'flags':24s} {'build s':>8s} {'hess ms':>8s} {'jac ms':>8s} {'step cpu med':>12s} {'mean':>8s}")
    for flags, row in rows.items():
        build = "cached" if not row["built"] else f"{row['build_s']:.1f}"
        print(f"{flags:24s} {build:>8s} {row['hessian_ms']:8.3f} {row['jacobian_ms']:8.3f} {np.median(cpu[flags]) * 1e3:12.2f} "
              f"{np.mean(cpu[flags]) * 1e3:8.2f}")


if __name__ == "__main__":
    main()
