"""Command line: ``python -m orchestrator {run,validate,build,export,compare,batch,...} ...``.

Installed packages add subcommands through the entry-point group ``rhnc_cosim.commands``
(the ship domain adds ``plan`` and ``identify``, :mod:`rhnc.cosim.commands`).

Known errors (bad scenario, missing FMU, failed model) print one line and exit non-zero:
2 for bad input, 3 for a run that failed or missed its acceptance criteria, 130 for
Ctrl-C or SIGTERM (see :mod:`orchestrator.interrupts`).
"""

from __future__ import annotations

import argparse
import gc
import logging
import sys
from typing import NoReturn

from orchestrator import __version__
from orchestrator.fmu_sources import FMI_VERSIONS

log = logging.getLogger("orchestrator")

EXIT_RUN_FAILED = 3
EXIT_INTERRUPTED = 130
#: Failed runs a batch lists on the console; the rest are counted and found in summary.csv.
MAX_FAILURES_SHOWN = 20


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="python -m orchestrator",
                                     description="RHNC co-simulation toolchain (FMI " + " and ".join(FMI_VERSIONS)
                                     + " co-simulation master).")
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    parser.add_argument("-v", "--verbose", action="store_true", help="log debug messages")
    sub = parser.add_subparsers(dest="command", required=True)
    _add_scenario_commands(sub)
    _add_batch_commands(sub)
    for name, command in _plugin_commands().items():
        command.add_arguments(sub.add_parser(name, help=command.help))
    return parser


def _add_scenario_commands(sub) -> None:
    """The commands on one scenario or comparison: run, validate, build, compare, export, check."""
    run = sub.add_parser("run", help="run a scenario and write results/<scenario>/<run-id>/")
    run.add_argument("scenario", help="scenario TOML file")
    run.add_argument("--results", default="results", help="results folder (default: ./results)")
    run.add_argument("--no-progress", action="store_true", help="no progress bar")
    validate = sub.add_parser("validate", help="check a scenario and its FMUs without running it")
    validate.add_argument("scenario", help="scenario TOML file")
    validate.add_argument("--trust-code", action="store_true",
                          help="also import type = \"python\" participant classes that come with the scenario "
                               "(its folder or the current folder); only for code you trust")
    build = sub.add_parser("build", help="compile the FMUs in models/ into fmus/ (FMI 2.0) or fmus/fmi3/")
    build.add_argument("models", nargs="*", help="model names (default: all)")
    build.add_argument("--fmi-version", choices=(*FMI_VERSIONS, "all"), default="2.0",
                       help="FMI standard of the FMUs (default 2.0; 'all' builds both)")
    compare = sub.add_parser("compare", help="run several scenarios side by side (Table 3; fair voyage comparisons "
                             "at equal arrival time with [voyage], docs/compare-format.md)")
    compare.add_argument("comparison", help="comparison TOML file")
    compare.add_argument("--results", default="results", help="results folder (default: ./results)")
    compare.add_argument("--no-progress", action="store_true", help="no progress bar")
    export = sub.add_parser("export", help="pack Python participants of a scenario as FMI 2.0 FMUs, "
                                           "or the whole scenario as an OSP system (--osp)")
    export.add_argument("scenario", help="scenario TOML file")
    export.add_argument("participants", nargs="*", help="names of the participants to export (e.g. ctrl nav)")
    export.add_argument("--out", default="fmus/exported", help="folder for the FMUs (default: fmus/exported)")
    export.add_argument("--osp", action="store_true",
                        help="export every participant and write OspSystemStructure.xml for OSP's libcosim")
    check = sub.add_parser("check", help="judge another FMI master's results (libcosim's or FMPy's CSV files) by "
                                         "a scenario's acceptance criteria")
    check.add_argument("results", nargs="+", help="CSV files: libcosim's (one per simulator), FMPy's, or ours")
    check.add_argument("--scenario", required=True, help="the scenario whose [[acceptance]] criteria judge")
    check.add_argument("--participant", default=None,
                       help="the participant a single FMPy CSV file belongs to (default: the file's name)")
    check.add_argument("--summary", default=None, metavar="FILE", help="also write the summary as JSON")


def _add_batch_commands(sub) -> None:
    """The commands on many runs: batch, search, report."""
    batch = sub.add_parser("batch", help="run a batch of scenario variations into results/<batch>/ (resumable)")
    batch.add_argument("batch", help="batch TOML file")
    _add_pool_arguments(batch, "run on a Dask distributed cluster, tcp://host:8786 or tls://host:8786 (instead of "
                               "the local pool; docs/batch.md)")
    batch.add_argument("--results", default="results", help="results folder (default: ./results)")
    batch.add_argument("--retry-failed", action="store_true", help="redo runs recorded as failed")
    batch.add_argument("--no-progress", action="store_true", help="no progress bar")
    search = sub.add_parser("search", help="search a batch file's [monte_carlo] ranges for the runs that minimise "
                                           "an objective (optuna; resumable; docs/search.md)")
    search.add_argument("search", help="search TOML file (a batch file with a [search] table)")
    search.add_argument("--evaluations", type=int, default=None, help="budget (default: the file's)")
    search.add_argument("--sampler", default=None, help="tpe, cmaes, tpe-restart, tpe-periodic or random (default: the file's)")
    search.add_argument("--seed", type=int, default=None, help="the optimiser's seed (default: the file's)")
    search.add_argument("--fails-below", type=float, default=None, metavar="X",
                        help="a run whose objective is below X is a failure (default: the file's fails_below); "
                             "relabels runs, the optimiser minimises the same")
    search.add_argument("--until-failure", action="store_true",
                        help="stop after the round that holds the first failure")
    _add_pool_arguments(search, "a Dask scheduler, as for batch")
    search.add_argument("--results", default="results", help="results folder (default: ./results)")
    search.add_argument("--no-progress", action="store_true", help="no progress bar")
    report = sub.add_parser("report", help="write report.html (a static page) for a batch or search results folder")
    report.add_argument("folder", help="results/<batch> or results/<search>")


def _add_pool_arguments(command, scheduler_help: str) -> None:
    """Where a batch or search runs: local workers or a Dask scheduler, with its TLS files."""
    command.add_argument("--workers", type=int, default=None, help="local worker processes (default: one per core)")
    command.add_argument("--scheduler", default=None, metavar="ADDRESS", help=scheduler_help)
    command.add_argument("--tls-ca", default=None, metavar="FILE", help="tls:// scheduler: the cluster's CA certificate")
    command.add_argument("--tls-cert", default=None, metavar="FILE", help="tls:// scheduler: this client's certificate")
    command.add_argument("--tls-key", default=None, metavar="FILE", help="tls:// scheduler: this client's private key")


def main(argv=None) -> int:
    """Entry point; returns the exit code."""
    from orchestrator.errors import ToolchainError

    from orchestrator import interrupts

    args = _parser().parse_args(argv)
    _configure_logging(args.verbose)
    try:
        with interrupts.handle_signals():
            try:
                if args.command in _COMMANDS:
                    return _COMMANDS[args.command](args)
                return _plugin_commands()[args.command].run(args)
            except KeyboardInterrupt:  # stopped before or between runs (set-up, building)
                print(f"error: {interrupts.reason()}", file=sys.stderr)
                return EXIT_INTERRUPTED
    except ToolchainError as exc:
        print(f"error: {one_line(exc)}", file=sys.stderr)
        return exc.exit_code


def own_loggers() -> tuple[str, ...]:
    """Loggers of this toolchain: the master's and every package registering entry points.

    ``-v`` shows their debug lines, not those of the libraries they use.
    """
    from orchestrator import plugins

    return plugins.toolchain_loggers()


#: The loggers an earlier ``-v`` command of this process set to DEBUG.
_verbose_loggers: tuple[str, ...] = ()


def _configure_logging(verbose: bool) -> None:
    """Warnings for everyone; with ``verbose`` our own debug lines too.

    The toolchain's loggers are looked up (every entry-point group read) only for ``-v``:
    a command without it just undoes what an earlier ``-v`` command of this process did.
    """
    global _verbose_loggers
    logging.basicConfig(level=logging.WARNING, format="%(levelname)s %(name)s: %(message)s")
    for name in _verbose_loggers:
        logging.getLogger(name).setLevel(logging.NOTSET)
    _verbose_loggers = own_loggers() if verbose else ()
    for name in _verbose_loggers:
        logging.getLogger(name).setLevel(logging.DEBUG)


def _run(args) -> int:
    from orchestrator.run import run_scenario

    from orchestrator import interrupts

    report = run_scenario(args.scenario, args.results, progress=not args.no_progress)
    print(f"{report.status}: results in {report.folder}")
    for line in _key_lines(report.summary):
        print(f"  {line}")
    if report.status == "interrupted":
        print(f"error: {report.reason}", file=sys.stderr)
        return EXIT_INTERRUPTED
    if interrupts.stop_requested():  # the signal came while the results were written: they are complete
        print(f"error: {interrupts.reason()} while the results were written; they were completed first",
              file=sys.stderr)
        return EXIT_INTERRUPTED
    if not report.ok:
        print(f"error: {report.reason}", file=sys.stderr)
        return EXIT_RUN_FAILED
    if not report.passed:
        for line in report.failed_criteria:
            print(f"error: acceptance criterion not met: {line}", file=sys.stderr)
        return EXIT_RUN_FAILED
    return 0


def _key_lines(summary) -> list[str]:
    lines = [f"steps {summary['simulation']['steps_done']}/{summary['simulation']['steps_planned']}, "
             f"wall time {summary['wall_time_s']:.2f} s"]
    for name, figures in summary.get("analyses", {}).items():
        if figures.get("evaluated") is False:
            lines.append(f"{name}: {figures.get('note', 'not evaluated')}")
            continue
        shown = ", ".join(f"{k} {v:.4g}" for k, v in figures.items()
                          if isinstance(v, (int, float)) and not isinstance(v, bool))
        lines.append(f"{name}: {shown}")
    criteria = summary.get("acceptance", {}).get("criteria", [])
    if criteria:
        lines.append(f"acceptance: {sum(c['passed'] for c in criteria)}/{len(criteria)} criteria met")
    return lines


def _validate(args) -> int:
    from orchestrator.validate import check_scenario

    report = check_scenario(args.scenario, trust_code=args.trust_code)
    for problem in report.problems:
        print(f"error: {one_line(problem)}", file=sys.stderr)
    if report.problems:
        return 2
    print(f"ok: {args.scenario}")
    for note in report.notes:
        print(f"  note: {one_line(note)}")
    return 0


def one_line(text: object) -> str:
    """A message on one line: line breaks and other control characters escaped."""
    return "".join(c if c.isprintable() else c.encode("unicode_escape").decode("ascii") for c in str(text))


def _build(args) -> int:
    from orchestrator import fmu_build

    names = args.models or fmu_build.model_names()
    versions = fmu_build.FMI_VERSIONS if args.fmi_version == "all" else (args.fmi_version,)
    for version in versions:
        for name in names:
            print(fmu_build.build_fmu(name, fmi_version=version))
    return 0


def _workers_refused(args) -> bool:
    """Say so (one line) when ``--workers`` is below one: a batch's or a search's exit 2."""
    if args.workers is not None and args.workers < 1:
        print("error: --workers must be at least 1", file=sys.stderr)
        return True
    return False


def _tls_files(args) -> dict | None:
    """The ``--tls-*`` files given, or None."""
    tls = {"ca": args.tls_ca, "cert": args.tls_cert, "key": args.tls_key}
    return tls if any(tls.values()) else None


def _batch(args) -> int:
    from orchestrator.batch import run_batch

    if _workers_refused(args):
        return 2
    report = run_batch(args.batch, args.results, workers=args.workers, scheduler=args.scheduler,
                       progress=not args.no_progress, retry_failed=args.retry_failed, tls=_tls_files(args))
    table = report.table
    counts = ", ".join(f"{count} {status}" for status, count in table["status"].value_counts().items())
    print(f"{report.passed}/{report.total} runs passed ({counts}); ran {report.ran}, "
          f"skipped {report.skipped} already done; wall time {report.wall_time_s:.1f} s")
    print(f"  table: {report.folder / 'summary.parquet'} (and .csv), overview: {report.folder / 'overview.png'}")
    failed = table[~table["passed"]]
    for _, row in failed.head(MAX_FAILURES_SHOWN).iterrows():
        print(f"  {row['run_id']} {row['status']}: {row['reason'] or row['failed_criteria']}")
    if len(failed) > MAX_FAILURES_SHOWN:
        print(f"  ... and {len(failed) - MAX_FAILURES_SHOWN} more not passed: every one is in "
              f"{report.folder / 'summary.csv'} (columns status, reason, failed_criteria)")
    if report.interrupted:
        print("interrupted: rerun the same command to finish the batch", file=sys.stderr)
        return EXIT_INTERRUPTED
    return 0 if report.passed == report.total else EXIT_RUN_FAILED


def _search(args) -> int:
    from orchestrator.search import run_search

    if _workers_refused(args):
        return 2
    report = run_search(args.search, args.results, workers=args.workers, scheduler=args.scheduler,
                        progress=not args.no_progress, tls=_tls_files(args),
                        evaluations=args.evaluations, sampler=args.sampler, seed=args.seed,
                        fails_below=args.fails_below, until_failure=args.until_failure)
    first = (f"first at evaluation {report.first_failure}" if report.first_failure is not None else "none found")
    best = "none" if report.best is None else f"{report.best:.4g}"
    print(f"{len(report.table)} evaluations ({report.evaluated} run now); lowest objective {best}; "
          f"{report.failures} failures, {first}; wall time {report.wall_time_s:.1f} s")
    print(f"  report: {report.folder / 'report.html'}, worst cases: {report.folder / 'worst'}")
    if report.interrupted:
        print("interrupted: rerun the same command to resume the search", file=sys.stderr)
        return EXIT_INTERRUPTED
    return 0


def _report(args) -> int:
    from orchestrator.report import write_report

    print(write_report(args.folder))
    return 0


def _compare(args) -> int:
    from orchestrator.compare import failed_runs_of, run_comparison

    from orchestrator import interrupts

    folder = run_comparison(args.comparison, args.results, progress=not args.no_progress)
    if interrupts.stop_requested():  # its runs stopped as interrupted: the table is incomplete
        print(f"interrupted: results in {folder}")
        print(f"error: {interrupts.reason()}", file=sys.stderr)
        return EXIT_INTERRUPTED
    failed = failed_runs_of(folder)
    print(f"{'failed' if failed else 'finished'}: results in {folder}")
    print((folder / "table.md").read_text())
    if failed:
        listing = "; ".join(f"{label} ({reason})" for label, reason in failed.items())
        print(f"error: {len(failed)} run(s) of the comparison failed: {one_line(listing)}", file=sys.stderr)
        return EXIT_RUN_FAILED
    return 0


def _export(args) -> int:
    from orchestrator.errors import ScenarioError
    from orchestrator.export import check_exportable, export_participant, nothing_left_on_failure
    from orchestrator.osp_export import export_osp_system
    from orchestrator.scenario import load_scenario

    if args.osp:
        if args.participants:
            raise ScenarioError("export --osp exports every participant; name none")
        with nothing_left_on_failure(args.out):
            print(export_osp_system(args.scenario, args.out))
        return 0
    if not args.participants:
        raise ScenarioError("export: name the participants to export, or give --osp for the whole scenario")
    check_exportable(load_scenario(args.scenario), args.scenario, args.participants)  # all refused before one is built
    with nothing_left_on_failure(args.out):
        written = [export_participant(args.scenario, name, args.out) for name in args.participants]
    for path in written:
        print(path)
    return 0


def _check(args) -> int:
    import json
    from pathlib import Path

    from orchestrator.foreign_results import judge
    from orchestrator.results import json_default

    summary = judge(args.results, args.scenario, args.participant)
    criteria = summary["acceptance"]["criteria"]
    width = max(len(c["name"]) for c in criteria)
    for criterion in criteria:
        verdict = "pass" if criterion["passed"] else "FAIL"
        value = criterion["value"]
        shown = f"{value:.6g}" if isinstance(value, float) else json.dumps(value, default=json_default)
        print(f"{verdict}  {criterion['name']:<{width}}  {criterion['criterion']}  (value: {shown})"
              + (f"  {criterion['reason']}" if not criterion["passed"] else ""))
    if args.summary:
        Path(args.summary).write_text(json.dumps(summary, indent=1, default=json_default))
    passed = summary["acceptance"]["passed"]
    print("accepted" if passed else "not accepted")
    return 0 if passed else EXIT_RUN_FAILED


_COMMANDS = {"run": _run, "validate": _validate, "build": _build, "batch": _batch,
             "compare": _compare, "export": _export, "check": _check, "search": _search, "report": _report}


def _plugin_commands() -> dict:
    """Subcommands installed packages register (``rhnc_cosim.commands``: ``plan``, ``identify``, ...)."""
    from orchestrator import plugins

    commands = {}
    for name in plugins.names("commands"):
        if name in _COMMANDS:
            log.warning("ignoring the registered command '%s': a built-in command has that name", name)
            continue
        commands[name] = plugins.load("commands", name)
    return commands


def console_main() -> None:
    """Console-script entry point (and ``python -m orchestrator``)."""
    exit_process(main())


def exit_process(code: int) -> NoReturn:
    """End the process with exit code ``code``, leaving its objects to the operating system.

    At exit the interpreter's last garbage collections walk every object still alive (the
    libraries' modules, the run's data), about 0.2 s after a run; frozen, they are skipped.
    Exit handlers still run (temporary folders removed, solver workers stopped), and so
    does the flushing of the standard streams.
    """
    gc.freeze()
    sys.exit(code)
