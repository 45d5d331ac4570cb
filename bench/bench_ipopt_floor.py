"""Benchmark: how little processor time IPOPT itself needs for one of our NMPC solves.

The like-for-like goal sets our whole NMPC step against do-mpc's whole ``make_step`` with
IPOPT in both. Whatever our code around the solver does, our step cannot take less than
IPOPT's own work on the same problem; this script measures that floor and sets it beside a
fifth of do-mpc's step:

1. our controller (IPOPT, compiled NLP, warm-started duals, in-process) and do-mpc (IPOPT,
   warm-started duals) each sail the closed loop of :mod:`bench_nmpc` (same problem, same
   plant), one after the other; every solver call of ours is recorded with its arguments,
   its processor time and the share CasADi reports for the NLP's functions (the recording,
   a copy of the arguments and a second ``stats()`` call, adds a few hundredths of a
   millisecond to our whole step's figure);
2. ``bench/ipopt_floor.cpp`` is compiled against the IPOPT shipped in the casadi wheel
   and replays every recorded call on the same compiled NLP library, without CasADi:
   with a new IPOPT application per solve (what CasADi does) and with one application
   kept between solves (``ReOptimizeTNLP``), each call repeated ``--repeat`` times.

    python bench/bench_ipopt_floor.py [--targets 1 3] [--steps 90] [--repeat 5] [--ipopt NAME=VALUE ...]

``--ipopt`` sets further IPOPT options in all three, our controller, do-mpc and the direct
replays, to see whether an option lowers the floor more than do-mpc's step: e.g. ``--ipopt
nlp_scaling_method=none mumps_scaling=0``.

Needs a C++ compiler (``$CXX``, else ``c++`` or ``g++``) and the compiled NLP (the NMPC's
default). Prints medians over the calls and whether a fifth of do-mpc's step leaves room
for IPOPT's own solve.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import casadi
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import bench_nmpc as bench  # noqa: E402
from rhnc.control import nmpc, solver_watchdog  # noqa: E402
from rhnc.ship.ship_model import load_parameter_set  # noqa: E402

DRIVER_SOURCE = Path(__file__).resolve().parent / "ipopt_floor.cpp"
ARRAYS = ("x0", "p", "lbx", "ubx", "lbg", "ubg", "lam_x0", "lam_g0")


def option_value(text: str) -> int | float | str:
    """An IPOPT option's value as written: an integer, a number or a string (as the driver reads it)."""
    for kind in (int, float):
        with contextlib.suppress(ValueError):
            return kind(text)
    return text


def parse_options(pairs: list[str]) -> dict:
    return {name: option_value(value) for name, value in (pair.split("=", 1) for pair in pairs)}


@contextlib.contextmanager
def our_ipopt_options(extra: dict):
    """Our controller's IPOPT options with ``extra`` set after them, while the block runs."""
    original = nmpc.solver_options

    def with_extra(*args, **kwargs):
        options = original(*args, **kwargs)
        if "ipopt" in options:
            options["ipopt"] = {**options["ipopt"], **extra}
        return options
    nmpc.solver_options = with_extra
    try:
        yield
    finally:
        nmpc.solver_options = original


def compile_driver(work: Path) -> Path:
    """Build ``ipopt_floor.cpp`` against the casadi wheel's IPOPT headers and library."""
    compiler = os.environ.get("CXX") or shutil.which("c++") or shutil.which("g++")
    if compiler is None:
        sys.exit("bench_ipopt_floor: no C++ compiler ($CXX, c++ or g++) on the PATH")
    casadi_dir = Path(casadi.__file__).resolve().parent
    if not (casadi_dir / "include" / "coin-or" / "IpTNLP.hpp").is_file():
        sys.exit(f"bench_ipopt_floor: the casadi wheel at {casadi_dir} has no IPOPT headers (include/coin-or)")
    binary = work / "ipopt_floor"
    subprocess.run([compiler, "-O2", "-std=c++17", f"-I{casadi_dir / 'include'}", str(DRIVER_SOURCE), "-o", str(binary),
                    f"-L{casadi_dir}", "-l:libipopt.so.3", f"-Wl,-rpath,{casadi_dir}", "-ldl"], check=True)
    return binary


def recorded_arguments(arguments: dict) -> dict[str, np.ndarray]:
    """The call's arrays; multipliers the call did not pass are zero (IPOPT's own start)."""
    sizes = {"lam_x0": np.size(arguments["x0"]), "lam_g0": np.size(arguments["lbg"])}
    return {name: np.asarray(arguments[name], dtype=float).ravel() if name in arguments else np.zeros(sizes[name])
            for name in ARRAYS}


class Recorder:
    """Wraps the solver call of :mod:`rhnc.control.solver_watchdog` to keep every call's figures."""

    def __init__(self) -> None:
        self.calls: list[dict] = []
        self._original = solver_watchdog._timed_call

    def __enter__(self) -> "Recorder":
        def recorded(solver, arguments):
            outcome = self._original(solver, arguments)
            stats = solver.stats()
            self.calls.append({
                "arguments": recorded_arguments(arguments),
                "cpu_s": outcome.cpu_time_s,
                "functions_s": sum(value for key, value in stats.items() if key.startswith("t_proc_nlp")),
                "iterations": outcome.iterations,
                "x": np.asarray(outcome.x, dtype=float).ravel(),
            })
            return outcome
        solver_watchdog._timed_call = recorded
        return self

    def __exit__(self, *exc) -> None:
        solver_watchdog._timed_call = self._original


def write_calls(calls: list[dict], path: Path) -> None:
    with path.open("wb") as file:
        np.array([len(calls)], dtype=np.int64).tofile(file)
        for call in calls:
            for name in ARRAYS:
                values = call["arguments"][name]
                np.array([values.size], dtype=np.int64).tofile(file)
                values.astype(np.float64).tofile(file)


def replay(binary: Path, library: Path, calls_file: Path, repeat: int, mode: str,
           options: list[str]) -> list[tuple[float, int, int, np.ndarray]]:
    done = subprocess.run([str(binary), str(library), str(calls_file), str(repeat), mode, *options],
                          capture_output=True, text=True)
    if done.returncode != 0:
        sys.exit(done.stderr.strip() or f"bench_ipopt_floor: the replay ({mode}) ended with code {done.returncode}")
    output = done.stdout
    rows = []
    for line in output.splitlines():
        fields = line.split()
        rows.append((float(fields[0]), int(fields[1]), int(fields[2]), np.array(fields[3:], dtype=float)))
    return rows


def sail(loop, steps: int) -> np.ndarray:
    for _ in range(steps):
        loop.advance()
    return np.array(loop.cpu)


def measure(targets: int, steps: int, repeat: int, binary: Path, work: Path, options: list[str]) -> None:
    params = load_parameter_set("default")
    extra = parse_options(options)
    with Recorder() as recorder, our_ipopt_options(extra):
        ours = bench.ours(params, "ipopt", targets, True, False)
        library = ours.controller.library.path
        if library is None:
            sys.exit(f"bench_ipopt_floor: the NLP is interpreted here ({ours.controller.library.reason}); "
                     "the replay needs the compiled library")
        recorder.calls.clear()  # the set-up solve is not part of the closed loop
        ours_cpu = sail(ours, steps)
    ours.close()
    do_mpc_cpu = sail(bench.do_mpc_run(params, targets, False, True, extra), steps)
    calls = recorder.calls
    calls_file = work / f"calls_{targets}.bin"
    write_calls(calls, calls_file)
    fresh = replay(binary, library, calls_file, repeat, "fresh", options)
    reuse = replay(binary, library, calls_file, repeat, "reuse", options)

    casadi_cpu = np.array([call["cpu_s"] for call in calls])
    functions = np.array([call["functions_s"] for call in calls])
    iterations = np.array([call["iterations"] for call in calls])
    same_iterations = {mode: float(np.mean([row[2] == its for row, its in zip(rows, iterations)]))
                       for mode, rows in (("fresh", fresh), ("reuse", reuse))}
    x_gap = max(float(np.max(np.abs(row[3] - call["x"]))) for rows in (fresh, reuse) for row, call in zip(rows, calls))
    fifth = np.median(do_mpc_cpu) / 5
    floor = np.median([row[0] for row in reuse])  # IPOPT's own solve at its cheapest

    def ms(values) -> str:
        return f"{np.median(values) * 1e3:6.3f}"

    print(f"\n{targets} target(s), {len(calls)} solves (median {np.median(iterations):.0f} iterations, "
          f"max {iterations.max()}); processor time, median [ms]:")
    print(f"  do-mpc make_step, IPOPT, warm duals (whole step)        {ms(do_mpc_cpu)}   a fifth: {fifth * 1e3:.3f}")
    print(f"  ours, whole solve() step, in-process                    {ms(ours_cpu)}")
    print(f"  ours, IPOPT call through CasADi                         {ms(casadi_cpu)}"
          f"   of it the NLP's functions {ms(functions)}")
    print(f"  IPOPT direct, new application per solve                 {ms([row[0] for row in fresh])}")
    print(f"  IPOPT direct, one application kept (ReOptimizeTNLP)     {ms(floor)}"
          f"   less the functions: {(floor - np.median(functions)) * 1e3:.3f}")
    print(f"  replays: same iteration count as CasADi in {same_iterations['fresh']:.0%} (fresh) / "
          f"{same_iterations['reuse']:.0%} (kept) of the solves; largest |x - x_casadi| {x_gap:.1e}")
    rest = np.median(ours_cpu) - np.median(casadi_cpu)
    if floor < fifth:
        room = (f"leaves {(fifth - floor) * 1e3:.3f} ms for the rest of our step, which takes "
                f"{rest * 1e3:.3f} ms now (whole step less the CasADi call)")
    else:
        room = "leaves no room: 5x with IPOPT is out of reach on this problem"
    print(f"  5x over do-mpc with IPOPT: a fifth of its step ({fifth * 1e3:.3f} ms) less IPOPT's own solve at its "
          f"cheapest ({floor * 1e3:.3f} ms) {room}")

def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--targets", type=int, nargs="+", default=[1, 3], choices=[1, 3])
    parser.add_argument("--steps", type=int, default=90)
    parser.add_argument("--repeat", type=int, default=5, help="replays of each recorded solve (their mean is its time)")
    parser.add_argument("--ipopt", nargs="+", default=[], metavar="NAME=VALUE",
                        help="further IPOPT options for our controller, do-mpc and the direct replays")
    args = parser.parse_args()
    if args.steps < 1 or args.repeat < 1:
        parser.error("--steps and --repeat must be at least 1")
    for pair in args.ipopt:
        if "=" not in pair or pair.startswith("="):
            parser.error(f"--ipopt {pair}: write NAME=VALUE")
    load = os.getloadavg()
    print(f"{os.cpu_count()} cores; load average {load[0]:.1f} / {load[1]:.1f} / {load[2]:.1f} before; "
          f"casadi {casadi.__version__}; further IPOPT options (ours, do-mpc, replays): {' '.join(args.ipopt) or 'none'}")
    with tempfile.TemporaryDirectory(prefix="ipopt-floor-") as work:
        start = time.perf_counter()
        binary = compile_driver(Path(work))
        print(f"driver compiled in {time.perf_counter() - start:.1f} s")
        check = subprocess.run([str(binary), "--check", *args.ipopt], capture_output=True, text=True)
        if check.returncode != 0:  # before any run, so that a misspelt option costs nothing
            sys.exit(check.stderr.strip() or f"bench_ipopt_floor: --ipopt {' '.join(args.ipopt)} refused")
        for targets in args.targets:
            measure(targets, args.steps, args.repeat, binary, Path(work), args.ipopt)
    load = os.getloadavg()
    print(f"\nload average {load[0]:.1f} / {load[1]:.1f} / {load[2]:.1f} after")


if __name__ == "__main__":
    main()
