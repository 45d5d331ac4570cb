"""Wall and processor time of the full Experiment 2 RHNC run (goal: at most 2 s on 2 cores, idle).

Each repeat is a fresh process doing what ``python -m orchestrator run
scenarios/exp2_rhnc.toml --no-progress`` does, so that imports count as they do for a
user.  Printed per repeat and as min and median over the repeats:

* ``wall``: the whole process, from its start to its exit (measured from outside),
* ``startup``: the interpreter's start and end (``wall`` less what the process measured),
* ``imports``: from the process's first line to the building of the co-simulation
  (module imports, command line, reading the scenario),
* ``build``: building the participants (the weather, the FMUs, the NMPC),
* ``loop``: the co-simulation loop (480 macro steps: 120 navigation plans, 480 NMPC
  solves, the KCS and MetOcean FMUs),
* ``results``: writing the results, figures excluded (time series, weather, analyses,
  summary),
* ``figures``: what the figures cost the run: starting their processes (after importing
  their code) and waiting for them to end (:mod:`orchestrator.figure_processes`),
* ``other``: the rest (closing the participants).

The same phases in processor time of the process (``cpu``: figures are drawn and the NMPC
may solve in processes of their own, whose time is ``children``, read when they have ended),
and the co-simulation loop split by participant: each participant's ``step`` calls in
processor time, and what is left of the loop, the master's own share (exchange, recording,
checks).

Also printed: whether the NMPC ran compiled (:mod:`rhnc.control.nmpc_codegen`; the first run on a
machine compiles it, 15-20 s), its solve times, and the load average before and
after each run.

    python bench/bench_exp2.py [--repeat 5] [--compare-interpreted] [--solver acados]

Another checkout's code (an older commit, for a before/after comparison) is measured by
putting it first on the path: ``PYTHONPATH=<checkout> python bench/bench_exp2.py``.
"""

from __future__ import annotations

import time

STARTED = time.perf_counter()  # before any other import: the child's imports are measured from here

import argparse  # noqa: E402
import json  # noqa: E402
import os  # noqa: E402
import statistics  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
from pathlib import Path  # noqa: E402

REPO = Path(__file__).resolve().parents[1]
SCENARIO = REPO / "scenarios" / "exp2_rhnc.toml"
PHASES = ("wall", "startup", "imports", "build", "loop", "results", "figures", "other")
CPU_PHASES = ("imports", "build", "loop", "results", "figures", "other", "children")
#: Prefix of the line a child process prints its measurements on.
MARK = "BENCH_EXP2 "
#: How ``--solver`` reaches the child process: the NMPC's backend for its runs.
SOLVER_ENV = "BENCH_EXP2_SOLVER"


def _timed(owner, name: str, phase: str, spent: dict, first: dict, cpu: dict | None = None) -> None:
    """Replace ``owner.name`` by a wrapper adding its duration to ``spent[phase]`` (and its
    processor time to ``cpu[phase]``)."""
    original = getattr(owner, name)

    def wrapper(*args, **kwargs):
        started, started_cpu = time.perf_counter(), time.process_time()
        first.setdefault(phase, started)
        try:
            return original(*args, **kwargs)
        finally:
            spent[phase] = spent.get(phase, 0.0) + time.perf_counter() - started
            if cpu is not None:
                cpu[phase] = cpu.get(phase, 0.0) + time.process_time() - started_cpu

    setattr(owner, name, wrapper)


def _calls_timed(cosim, by_participant: dict) -> None:
    """Time the calls of every participant of ``cosim`` in processor time, by participant: its
    ``step`` calls, and its ``setup``, ``terminate``, ``summary`` and ``tables`` together."""
    for participant in cosim.participants:
        spent = by_participant.setdefault(participant.name, {"step": 0.0, "set-up, end": 0.0})
        for method, kind in (("step", "step"), ("setup", "set-up, end"), ("terminate", "set-up, end"),
                             ("summary", "set-up, end"), ("tables", "set-up, end")):
            original = getattr(participant, method)

            def timed(*args, call=original, kind=kind, spent=spent, **kwargs):
                started = time.process_time()
                try:
                    return call(*args, **kwargs)
                finally:
                    spent[kind] += time.process_time() - started

            setattr(participant, method, timed)


def child(results: str) -> None:
    """One run as the command line does it, printing its phases as one JSON line."""
    import orchestrator.master as master
    import orchestrator.run as run
    from orchestrator.cli import console_main

    import resource

    spent: dict[str, float] = {}
    first: dict[str, float] = {}
    cpu: dict[str, float] = {}
    by_participant: dict[str, float] = {}
    imports_cpu: list[float] = []
    _timed(master.CoSimulation, "__init__", "build", spent, first, cpu)
    build = master.CoSimulation.__init__

    def built(self, *args, **kwargs):  # the imports end where the building starts
        imports_cpu.append(time.process_time())
        build(self, *args, **kwargs)
        _calls_timed(self, by_participant)

    master.CoSimulation.__init__ = built
    _timed(master.CoSimulation, "run", "loop", spent, first, cpu)
    _timed(run, "_write", "results", spent, first, cpu)
    try:
        import orchestrator.figure_processes as figure_processes
    except ImportError:  # a checkout from before figures were drawn aside: one after the other
        import orchestrator.analyses as analyses

        _timed(analyses, "draw_figure", "figures", spent, first, cpu)
    else:
        _timed(figure_processes, "start", "figures", spent, first, cpu)
        _timed(figure_processes.FigureDrawing, "collect", "figures", spent, first, cpu)
    solver = os.environ.get(SOLVER_ENV)
    if solver:  # the scenario as written, its NMPC on another backend
        load_scenario = run.load_scenario

        def with_solver(path, overrides=None):
            return load_scenario(path, {**(overrides or {}), "participants.ctrl.options.solver": solver})

        run.load_scenario = with_solver
    sys.argv = ["orchestrator", "run", str(SCENARIO), "--results", results, "--no-progress"]
    try:
        console_main()  # as python -m orchestrator, ending with SystemExit
    except SystemExit as done:
        code = done.code
    total = time.perf_counter() - STARTED
    phases = {
        "imports": first["build"] - STARTED,
        "build": spent["build"],
        "loop": spent["loop"],
        "results": spent["results"] - spent.get("figures", 0.0),
        "figures": spent.get("figures", 0.0),
    }
    phases["other"] = total - sum(phases.values())
    total_cpu = time.process_time()  # (from the interpreter's start)
    children = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu_phases = {
        "imports": imports_cpu[0],
        "build": cpu["build"],
        "loop": cpu["loop"],
        "results": cpu["results"] - cpu.get("figures", 0.0),
        "figures": cpu.get("figures", 0.0),
    }
    cpu_phases["other"] = total_cpu - sum(cpu_phases.values())
    cpu_phases["children"] = children.ru_utime + children.ru_stime
    loop = {name: spent for name, spent in by_participant.items()}
    loop["master (the rest of the loop)"] = {
        "step": cpu["loop"] - sum(spent[kind] for spent in by_participant.values() for kind in spent),
        "set-up, end": 0.0}
    summary_path = next(Path(results).rglob("summary.json"))
    participants = json.loads(summary_path.read_text())["participants"]
    control = {name: s for name, s in participants.items() if "solve_time_median_s" in s}
    print(MARK + json.dumps({"code": code, "inside": total, "phases": phases, "cpu": cpu_phases, "loop_cpu": loop,
                             "control": control}), flush=True)
    sys.exit(code)


def one_run(env: dict) -> dict:
    """A fresh process running the scenario; its phases, wall time and load average."""
    load = os.getloadavg()[0]
    with tempfile.TemporaryDirectory() as results:
        started = time.perf_counter()
        done = subprocess.run([sys.executable, __file__, "--child", results], env=env, capture_output=True,
                              text=True, cwd=REPO)
        wall = time.perf_counter() - started
    line = next((text for text in done.stdout.splitlines() if text.startswith(MARK)), None)
    if done.returncode != 0 or line is None:
        raise SystemExit(f"the run failed (exit {done.returncode}):\n{done.stdout[-2000:]}\n{done.stderr[-2000:]}")
    measured = json.loads(line[len(MARK):])
    measured["phases"] = {"wall": wall, "startup": wall - measured["inside"], **measured["phases"]}
    measured["load"] = (load, os.getloadavg()[0])
    return measured


def report(runs: list[dict]) -> None:
    print("run   " + " ".join(f"{p:>8}" for p in PHASES) + "   load before/after")
    for i, run in enumerate(runs, 1):
        print(f"{i:<5} " + " ".join(f"{run['phases'][p]:8.3f}" for p in PHASES)
              + f"   {run['load'][0]:.2f} / {run['load'][1]:.2f}")
    for label, pick in (("min", min), ("median", statistics.median)):
        print(f"{label:<6}" + " ".join(f"{pick(r['phases'][p] for r in runs):8.3f}" for p in PHASES))
    print("processor time of the process (children: the figures' and the solver's processes)")
    print("      " + " ".join(f"{p:>8}" for p in CPU_PHASES))
    for label, pick in (("min", min), ("median", statistics.median)):
        print(f"{label:<6}" + " ".join(f"{pick(r['cpu'][p] for r in runs):8.3f}" for p in CPU_PHASES))
    print("the loop by participant, processor time of its calls (median over the runs)")
    print(f"  {'':32s} {'steps':>8} {'set-up, terminate, summary':>27}")
    for name in runs[-1]["loop_cpu"]:
        steps, others = (statistics.median(r["loop_cpu"][name][kind] for r in runs) for kind in ("step", "set-up, end"))
        print(f"  {name:32s} {steps:8.3f} {others:27.3f}")
    for name, summary in runs[-1]["control"].items():
        print(f"{name}: NMPC {summary.get('solver', '')} {summary.get('codegen')}, median solve {summary['solve_time_median_s'] * 1e3:.1f} ms, "
              f"max {summary['solve_time_max_s'] * 1e3:.1f} ms, {summary['solves']} solves (last run)")
    best = min(r["phases"]["wall"] for r in runs)
    print(f"whole run, best of {len(runs)}: {best:.2f} s (goal <= 2 s on an idle machine: "
          f"{'met' if best <= 2.0 else 'not met'})")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--compare-interpreted", action="store_true",
                        help="then the same runs with the NMPC's functions interpreted (RHNC_NMPC_CODEGEN=0)")
    parser.add_argument("--solver", help="the NMPC's backend (option 'solver' of participant ctrl: fatrop, "
                        "acados, ipopt); the scenario's own by default")
    parser.add_argument("--child", metavar="RESULTS", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        child(args.child)
        return
    from rhnc.control.nmpc_codegen import CODEGEN_ENV

    print(f"load average before: {' / '.join(f'{v:.2f}' for v in os.getloadavg())} ({os.cpu_count()} cores); "
          "times in s")
    for mode in [None, "0"] if args.compare_interpreted else [None]:
        env = dict(os.environ)
        if args.solver:
            env[SOLVER_ENV] = args.solver
            print(f"-- NMPC solver: {args.solver}")
        if mode is not None:
            env[CODEGEN_ENV] = mode
            print(f"-- {CODEGEN_ENV}={mode}")
        report([one_run(env) for _ in range(args.repeat)])
    print(f"load average after: {' / '.join(f'{v:.2f}' for v in os.getloadavg())}")


if __name__ == "__main__":
    main()
