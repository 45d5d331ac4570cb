"""Command line: ``python -m orchestrator {run,validate,build,export,plan,compare,batch,identify} ...``.

Known errors (bad scenario, missing FMU, failed model) print one line and exit non-zero:
2 for bad input, 3 for a run that failed or missed its acceptance criteria, 130 for
Ctrl-C or SIGTERM (see :mod:`orchestrator.interrupts`).
"""

from __future__ import annotations

import argparse
import logging
import sys

from orchestrator import __version__

log = logging.getLogger("orchestrator")

EXIT_RUN_FAILED = 3
EXIT_INTERRUPTED = 130
#: Failed runs a batch lists on the console; the rest are counted and found in summary.csv.
MAX_FAILURES_SHOWN = 20


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="python -m orchestrator",
                                     description="RHNC co-simulation toolchain (FMI 2.0 co-simulation master).")
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    parser.add_argument("-v", "--verbose", action="store_true", help="log debug messages")
    sub = parser.add_subparsers(dest="command", required=True)
    run = sub.add_parser("run", help="run a scenario and write results/<scenario>/<run-id>/")
    run.add_argument("scenario", help="scenario TOML file")
    run.add_argument("--results", default="results", help="results folder (default: ./results)")
    run.add_argument("--no-progress", action="store_true", help="no progress bar")
    validate = sub.add_parser("validate", help="check a scenario and its FMUs without running it")
    validate.add_argument("scenario", help="scenario TOML file")
    build = sub.add_parser("build", help="compile the FMUs in models/ into fmus/ (FMI 2.0) or fmus/fmi3/")
    build.add_argument("models", nargs="*", help="model names (default: all)")
    build.add_argument("--fmi-version", choices=("2.0", "3.0", "all"), default="2.0",
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
    plan = sub.add_parser("plan", help="run an offline planning experiment (e.g. Experiment 1)")
    plan.add_argument("scenario", help="offline planning TOML file")
    plan.add_argument("--results", default="results", help="results folder (default: ./results)")
    batch = sub.add_parser("batch", help="run a batch of scenario variations into results/<batch>/ (resumable)")
    batch.add_argument("batch", help="batch TOML file")
    batch.add_argument("--workers", type=int, default=None, help="local worker processes (default: one per core)")
    batch.add_argument("--scheduler", default=None, metavar="ADDRESS",
                       help="run on a Dask distributed cluster, tcp://host:8786 or tls://host:8786 (instead of the "
                            "local pool; docs/batch.md)")
    batch.add_argument("--tls-ca", default=None, metavar="FILE", help="tls:// scheduler: the cluster's CA certificate")
    batch.add_argument("--tls-cert", default=None, metavar="FILE", help="tls:// scheduler: this client's certificate")
    batch.add_argument("--tls-key", default=None, metavar="FILE", help="tls:// scheduler: this client's private key")
    batch.add_argument("--results", default="results", help="results folder (default: ./results)")
    batch.add_argument("--retry-failed", action="store_true", help="redo runs recorded as failed")
    batch.add_argument("--no-progress", action="store_true", help="no progress bar")
    identify = sub.add_parser("identify", help="fit the NMPC's 3-DOF model on a scenario's plant FMU "
                                               "(manoeuvres through its mapping) into a parameter-set file")
    identify.add_argument("scenario", help="scenario TOML file whose plant FMU (and mapping) to identify")
    identify.add_argument("--tau-u-max-N", type=float, default=None, help="largest surge force of the ship [N]")
    identify.add_argument("--tau-r-max-Nm", type=float, default=None, help="largest yaw moment of the ship [N m]")
    identify.add_argument("--speed-kn", type=float, default=18.0, help="service speed of the manoeuvres (default 18)")
    identify.add_argument("--plant", default=None, help="participant name of the plant (default: the one ship FMU)")
    identify.add_argument("--set", dest="set_name", default=None, help="name of the set (default: the FMU's model name)")
    identify.add_argument("--out", default=None, help="also write the parameter-set file here")
    identify.add_argument("--results", default="results", help="results folder (default: ./results)")
    return parser


def main(argv=None) -> int:
    """Entry point; returns the exit code."""
    from orchestrator.errors import ToolchainError

    from orchestrator import interrupts

    args = _parser().parse_args(argv)
    _configure_logging(args.verbose)
    try:
        with interrupts.handle_signals():
            try:
                return _COMMANDS[args.command](args)
            except KeyboardInterrupt:  # stopped before or between runs (set-up, building)
                print(f"error: {interrupts.reason()}", file=sys.stderr)
                return EXIT_INTERRUPTED
    except ToolchainError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return exc.exit_code


#: Loggers of this toolchain; ``-v`` shows their debug lines, not those of the libraries.
OWN_LOGGERS = ("orchestrator", "rhnc")


def _configure_logging(verbose: bool) -> None:
    logging.basicConfig(level=logging.WARNING, format="%(levelname)s %(name)s: %(message)s")
    for name in OWN_LOGGERS:
        logging.getLogger(name).setLevel(logging.DEBUG if verbose else logging.NOTSET)


def _run(args) -> int:
    from orchestrator.run import run_scenario

    report = run_scenario(args.scenario, args.results, progress=not args.no_progress)
    print(f"{report.status}: results in {report.folder}")
    for line in _key_lines(report.summary):
        print(f"  {line}")
    if report.status == "interrupted":
        print(f"error: {report.reason}", file=sys.stderr)
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
    from orchestrator.validate import validate_scenario

    problems = validate_scenario(args.scenario)
    for problem in problems:
        print(f"error: {problem}", file=sys.stderr)
    if problems:
        return 2
    print(f"ok: {args.scenario}")
    return 0


def _build(args) -> int:
    from orchestrator import fmu_build

    names = args.models or fmu_build.model_names()
    versions = fmu_build.FMI_VERSIONS if args.fmi_version == "all" else (args.fmi_version,)
    for version in versions:
        for name in names:
            print(fmu_build.build_fmu(name, fmi_version=version))
    return 0


def _plan(args) -> int:
    from pathlib import Path

    from rhnc.offline_planning import run_offline_planning

    folder = run_offline_planning(Path(args.scenario), Path(args.results))
    print(f"finished: results in {folder}")
    return 0


def _batch(args) -> int:
    from orchestrator.batch import run_batch

    if args.workers is not None and args.workers < 1:
        print("error: --workers must be at least 1", file=sys.stderr)
        return 2
    tls = {"ca": args.tls_ca, "cert": args.tls_cert, "key": args.tls_key}
    report = run_batch(args.batch, args.results, workers=args.workers, scheduler=args.scheduler,
                       progress=not args.no_progress, retry_failed=args.retry_failed,
                       tls=tls if any(tls.values()) else None)
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


def _compare(args) -> int:
    from orchestrator.compare import run_comparison

    from orchestrator import interrupts

    folder = run_comparison(args.comparison, args.results, progress=not args.no_progress)
    if interrupts.stop_requested():  # its runs stopped as interrupted: the table is incomplete
        print(f"interrupted: results in {folder}")
        print(f"error: {interrupts.reason()}", file=sys.stderr)
        return EXIT_INTERRUPTED
    print(f"finished: results in {folder}")
    print((folder / "table.md").read_text())
    return 0


def _identify(args) -> int:
    from rhnc.identify_run import run_identify

    report = run_identify(args.scenario, args.results, plant=args.plant, speed_kn=args.speed_kn,
                          tau_u_max_N=args.tau_u_max_N, tau_r_max_Nm=args.tau_r_max_Nm,
                          set_name=args.set_name, out=args.out)
    held = report.report["open_loop_errors"][f"held_out: {report.report['held_out']}"]
    print(f"finished: results in {report.folder}")
    print(f"  parameter set '{report.report['set']}' in {report.parameter_file}")
    print(f"  held-out {report.report['held_out']}: heading RMS {held['heading_rms_deg']:.2f} deg, "
          f"speed RMS {held['speed_rms_kn']:.3f} kn")
    return 0


def _export(args) -> int:
    from orchestrator.errors import ScenarioError
    from orchestrator.export import export_participant
    from orchestrator.osp_export import export_osp_system

    if args.osp:
        if args.participants:
            raise ScenarioError("export --osp exports every participant; name none")
        print(export_osp_system(args.scenario, args.out))
        return 0
    if not args.participants:
        raise ScenarioError("export: name the participants to export, or give --osp for the whole scenario")
    for name in args.participants:
        print(export_participant(args.scenario, name, args.out))
    return 0


_COMMANDS = {"run": _run, "validate": _validate, "build": _build, "plan": _plan, "batch": _batch,
             "compare": _compare, "export": _export, "identify": _identify}


def console_main() -> None:
    """Console-script entry point."""
    sys.exit(main())
