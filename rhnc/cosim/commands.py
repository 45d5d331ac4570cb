"""The ship domain's subcommands of ``python -m orchestrator``: ``plan`` and ``identify``.

Registered in the entry-point group ``rhnc_cosim.commands``; each object gives the
subcommand's ``help``, adds its arguments to the parser the command line hands it and runs
with the parsed arguments, returning the exit code (:mod:`orchestrator.cli`).
"""

from __future__ import annotations

from pathlib import Path


class PlanCommand:
    """``plan S.toml``: an offline planning experiment (the paper's Experiment 1)."""

    help = "run an offline planning experiment (e.g. Experiment 1)"

    @staticmethod
    def add_arguments(parser) -> None:
        parser.add_argument("scenario", help="offline planning TOML file")
        parser.add_argument("--results", default="results", help="results folder (default: ./results)")

    @staticmethod
    def run(args) -> int:
        from rhnc.navigation.offline_planning import run_offline_planning

        folder = run_offline_planning(Path(args.scenario), Path(args.results))
        print(f"finished: results in {folder}")
        return 0


class IdentifyCommand:
    """``identify S.toml``: fit the NMPC's 3-DOF model on a scenario's plant FMU."""

    help = ("fit the NMPC's 3-DOF model on a scenario's plant FMU "
            "(manoeuvres through its mapping) into a parameter-set file")

    @staticmethod
    def add_arguments(parser) -> None:
        parser.add_argument("scenario", help="scenario TOML file whose plant FMU (and mapping) to identify")
        parser.add_argument("--tau-u-max-N", type=float, default=None, help="largest surge force of the ship [N]")
        parser.add_argument("--tau-r-max-Nm", type=float, default=None, help="largest yaw moment of the ship [N m]")
        parser.add_argument("--speed-kn", type=float, default=18.0,
                            help="service speed of the manoeuvres (default 18)")
        parser.add_argument("--plant", default=None, help="participant name of the plant (default: the one ship FMU)")
        parser.add_argument("--set", dest="set_name", default=None,
                            help="name of the set (default: the FMU's model name)")
        parser.add_argument("--out", default=None, help="also write the parameter-set file here")
        parser.add_argument("--ship", default=None,
                            help="the ship's particulars (a name in ships/ or a ship TOML file): bound the mass "
                                 "matrix of the model class with the hull polynomial, which is fitted only with them")
        parser.add_argument("--results", default="results", help="results folder (default: ./results)")

    @staticmethod
    def run(args) -> int:
        from rhnc.cosim.identify_horizon import nmpc_horizon
        from rhnc.ship.identify_run import run_identify

        report = run_identify(args.scenario, args.results, plant=args.plant, speed_kn=args.speed_kn,
                              tau_u_max_N=args.tau_u_max_N, tau_r_max_Nm=args.tau_r_max_Nm,
                              set_name=args.set_name, out=args.out, ship=args.ship,
                              horizon=nmpc_horizon(args.scenario, args.plant))
        held = report.report["open_loop_errors"][f"held_out: {report.report['held_out']}"]
        print(f"finished: results in {report.folder}")
        print(f"  parameter set '{report.report['set']}' in {report.parameter_file}")
        print(f"  held-out {report.report['held_out']}: heading RMS {held['heading_rms_deg']:.2f} deg, "
              f"speed RMS {held['speed_rms_kn']:.3f} kn")
        return 0


PLAN = PlanCommand()
IDENTIFY = IdentifyCommand()
