"""Bring your own ship: Experiments 2, 3a and 3b on two plants the KCS prediction model was not
made for, side by side: the third-party S175 (force level, other names and units) and the
KCS in MMG form behind the allocation participant (actuator level).

For each plant and experiment, three NMPC set-ups in one run of this script (same
scenario, same solver): the KCS model (what the NMPC used before), the model `identify`
fitted on the plant with the disturbance observer off, and the same with the observer on
(the shipped scenarios).  Printed and written to docs/own-ship-figures.md: separation
margin min(distance) - (R + R_i), distance from the track at the end (Experiment 3: the
cross-track error; Experiment 2: the distance from the navigation's reference at the last
sample), tau_r sign changes per 100 solves, fallbacks, the clearance-margin growth, the
model check; for Experiment 2 also the distance left to the goal.

    python bench/bench_own_ship.py [--exp2-steps N] [--plants S175 KCSMMG KVLCC2] [--out docs/own-ship-figures.md]

The second test ship, the KVLCC2 tanker (models/KVLCC2), runs its own scenarios at force
level and through the allocation (scenarios/own_ship/*_kvlcc2_*.toml: its service speed of
15.5 kn, the runs longer by 18/15.5 to cover the same distance), with the shipped set-up only.
So does the S175 through the allocation (scenarios/own_ship/*_s175_alloc.toml: its actuator
interface, actuator_mode = 1, behind the allocation with ships/S175.toml).

The identified models are written by the commands below.  identify chooses the model class
by its held-out error over the NMPC's prediction horizon (horizon_steps times the control
interval) and records that set-up in the file; so each NMPC set-up has its own file, identified
on a scenario with that set-up: Experiments 3a and 3b (15 intervals of 20 s, 300 s) share one,
Experiment 2 (15 intervals of 60 s, 900 s) has its own.  A run with a set identified for another
set-up says so in its model check.

    # Experiments 3a and 3b: 15 x 20 s
    python -m orchestrator identify scenarios/own_ship/exp3a_s175_kcs_model.toml \\
        --tau-u-max-N 8e5 --tau-r-max-Nm 1.65e8 --out scenarios/own_ship/S175_identified.toml
    python -m orchestrator identify scenarios/own_ship/exp3a_s175_alloc.toml --tau-u-max-N 1.136e6 \\
        --tau-r-max-Nm 1.41e8 --set S175 --ship S175 --out scenarios/own_ship/S175_alloc_identified.toml
    python -m orchestrator identify scenarios/exp3a_static_mmg.toml --tau-u-max-N 1.8e6 \\
        --tau-r-max-Nm 2.4e8 --set KCSMMG --out scenarios/KCSMMG_identified.toml
    python -m orchestrator identify scenarios/own_ship/exp3a_kvlcc2_force.toml --tau-u-max-N 2.35e6 \\
        --tau-r-max-Nm 5.87e8 --speed-kn 15.5 --set KVLCC2 --out scenarios/own_ship/KVLCC2_identified.toml
    python -m orchestrator identify scenarios/own_ship/exp3a_kvlcc2_alloc.toml --tau-u-max-N 2.35e6 \\
        --tau-r-max-Nm 5.87e8 --speed-kn 15.5 --set KVLCC2 --ship KVLCC2 \\
        --out scenarios/own_ship/KVLCC2_alloc_identified.toml
    # Experiment 2: 15 x 60 s
    python -m orchestrator identify scenarios/own_ship/exp2_s175_identified.toml \\
        --tau-u-max-N 8e5 --tau-r-max-Nm 1.65e8 --out scenarios/own_ship/S175_exp2_identified.toml
    python -m orchestrator identify scenarios/own_ship/exp2_s175_alloc.toml --tau-u-max-N 1.136e6 \\
        --tau-r-max-Nm 1.41e8 --set S175 --ship S175 --out scenarios/own_ship/S175_alloc_exp2_identified.toml
    python -m orchestrator identify scenarios/exp2_rhnc_mmg.toml --tau-u-max-N 1.8e6 \\
        --tau-r-max-Nm 2.4e8 --set KCSMMG --out scenarios/KCSMMG_exp2_identified.toml
    python -m orchestrator identify scenarios/own_ship/exp2_kvlcc2_force.toml --tau-u-max-N 2.35e6 \\
        --tau-r-max-Nm 5.87e8 --speed-kn 15.5 --set KVLCC2 --out scenarios/own_ship/KVLCC2_exp2_identified.toml
    python -m orchestrator identify scenarios/own_ship/exp2_kvlcc2_alloc.toml --tau-u-max-N 2.35e6 \\
        --tau-r-max-Nm 5.87e8 --speed-kn 15.5 --set KVLCC2 --ship KVLCC2 \\
        --out scenarios/own_ship/KVLCC2_alloc_exp2_identified.toml
"""

from __future__ import annotations

import argparse
import datetime
import json
import logging
import os
import re
import sys
import tempfile
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pandas as pd

from orchestrator.geometry import NM

REPO = Path(__file__).resolve().parents[1]
OWN = REPO / "scenarios" / "own_ship"
GOAL_NM = (100.0, 100.0)
ARRIVAL_RADIUS_NM = 0.5   # the goal participant's arrival_radius_nm in the Experiment 2 scenarios

#: plant -> experiment -> scenario file (the shipped set-up: identified model, observer on)
SCENARIOS = {
    "S175 (force level, mapped)": {
        "exp3a": OWN / "exp3a_s175_identified.toml",
        "exp3b": OWN / "exp3b_s175_identified.toml",
        "exp2": OWN / "exp2_s175_identified.toml",
    },
    "S175 + allocation (actuator level, mapped)": {
        "exp3a": OWN / "exp3a_s175_alloc.toml",
        "exp3b": OWN / "exp3b_s175_alloc.toml",
        "exp2": OWN / "exp2_s175_alloc.toml",
    },
    "KCSMMG + allocation (actuator level)": {
        "exp3a": REPO / "scenarios" / "exp3a_static_mmg.toml",
        "exp3b": REPO / "scenarios" / "exp3b_head_on_mmg.toml",
        "exp2": REPO / "scenarios" / "exp2_rhnc_mmg.toml",
    },
    "KVLCC2 (force level, mapped)": {
        "exp3a": OWN / "exp3a_kvlcc2_force.toml",
        "exp3b": OWN / "exp3b_kvlcc2_force.toml",
        "exp2": OWN / "exp2_kvlcc2_force.toml",
    },
    "KVLCC2 + allocation (actuator level, mapped)": {
        "exp3a": OWN / "exp3a_kvlcc2_alloc.toml",
        "exp3b": OWN / "exp3b_kvlcc2_alloc.toml",
        "exp2": OWN / "exp2_kvlcc2_alloc.toml",
    },
}
#: Plants measured with the shipped set-up only (identified model, observer on): the second
#: test ship, and the S175 through the allocation, whose KCS-model and observer-off runs would
#: say nothing new.
SHIPPED_ONLY = ("KVLCC2", "S175 + allocation")
KCS_MODEL = {"participants.ctrl.options.model_file": (REPO / "models" / "KCS" / "parameter_sets.toml").as_posix(),
             "participants.ctrl.options.model_set": "default",
             "participants.ctrl.options.disturbance_observer": False}
SETUPS = {
    "KCS model": KCS_MODEL,
    "identified, observer off": {"participants.ctrl.options.disturbance_observer": False},
    "identified + observer": {},
}


def reference_error_m(frame: pd.DataFrame) -> np.ndarray:
    """Distance [m] of the ship from the navigation's reference at every sample."""
    from rhnc.control.control_participant import interpolate_reference

    pattern = re.compile(r"nav\.reference\[(\d+),(\d+)\]")
    cells = [(int(m.group(1)), int(m.group(2)), c) for c in frame.columns if (m := pattern.fullmatch(c))]
    rows = 1 + max(i for i, _, _ in cells)
    errors = []
    for _, sample in frame.iterrows():
        reference = np.zeros((rows, 7))
        for i, j, column in cells:
            reference[i, j] = sample[column]
        if not np.all(np.diff(reference[:, 0]) > 0):
            continue
        x, y = interpolate_reference(reference, np.array([sample["time_s"]]))[0, :2]
        errors.append(np.hypot(sample["ship.x"] - x, sample["ship.y"] - y))
    return np.array(errors)


def measure(path: Path, overrides: dict, results: str, experiment: str) -> dict:
    """One run's figures."""
    from orchestrator.run import run_scenario

    from orchestrator.errors import ToolchainError

    try:
        report = run_scenario(path, results, progress=False, overrides=overrides or None)
        summary, folder = report.summary, report.folder
        error = "" if summary["status"] == "finished" else (str(summary.get("reason") or "").splitlines() or [""])[0]
    except ToolchainError as exc:   # a run that failed part-way still has its summary and samples
        folder = max(Path(results).glob("*/*/summary.json"), key=lambda p: p.stat().st_mtime).parent
        summary, error = json.loads((folder / "summary.json").read_text()), str(exc).splitlines()[0]
    report = SimpleNamespace(summary=summary, folder=folder)
    ctrl = report.summary["participants"]["ctrl"]
    row = {"sign": ctrl["tau_r_sign_changes_per_100_solves"], "fallbacks": ctrl["fallback_count"],
           "growth_kn": ctrl.get("clearance_margin_growth_kn", 0.0), "check": ctrl["model_check"]["check"],
           "status": report.summary["status"], "error": error}
    if experiment == "exp2":
        frame = pd.read_parquet(report.folder / "timeseries.parquet")
        error = reference_error_m(frame)
        row["separation_m"] = None
        row["track_end_nm"] = error[-1] / NM
        row["track_rms_m"] = float(np.sqrt(np.mean(error ** 2)))
        row["left_nm"] = float(np.hypot(frame["ship.x"].iloc[-1] - GOAL_NM[0] * NM,
                                        frame["ship.y"].iloc[-1] - GOAL_NM[1] * NM) / NM)
        row["minutes"] = report.summary["simulation"]["steps_done"]
    else:
        encounter = report.summary["analyses"]["encounter"]
        row["separation_m"] = encounter["min_clearance_nm"] * NM
        row["track_end_nm"] = encounter["cross_track_end_nm"]
    return row


def goals_met(experiment: str, row: dict) -> bool:
    """Separation >= R + R_i, within 0.2 nm of the track at the end, <= 10 sign changes per 100 solves;
    Experiment 2 arrives (ends within the goal's arrival radius)."""
    separated = row["left_nm"] <= ARRIVAL_RADIUS_NM if experiment == "exp2" else row["separation_m"] >= 0.0
    return separated and row["track_end_nm"] <= 0.2 and row["sign"] <= 10.0


def table(rows: list[tuple[str, str, str, dict]]) -> list[str]:
    lines = ["| plant | experiment | NMPC | separation - (R + R_i) [m] | from the track at the end [nm] "
             "| tau_r sign changes / 100 solves | goals met | fallbacks | margin growth [kn] | model check |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for plant, experiment, setup, row in rows:
        separation = "-" if row["separation_m"] is None else f"{row['separation_m']:+.1f}"
        extra = ""
        if experiment == "exp2":
            extra = f" ({row['left_nm']:.2f} nm to the goal after {row['minutes']} min)"
        if row.get("error"):
            extra += f" (run {row['status']}: {row['error'][:120]})"
        lines.append(f"| {plant} | {experiment} | {setup} | {separation} | {row['track_end_nm']:.3f}{extra} | "
                     f"{row['sign']:.1f} | {'yes' if goals_met(experiment, row) else '**no**'} | {row['fallbacks']} | "
                     f"{row['growth_kn']:.2f} | {row['check']} |")
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--exp2-steps", type=int, default=None,
                        help="macro steps of Experiment 2 (default: the scenario's, the full voyage)")
    parser.add_argument("--plants", nargs="*", default=None,
                        help="only the plants whose label starts with one of these (default: all)")
    parser.add_argument("--out", type=Path, default=None, help="also write the table to this markdown file")
    args = parser.parse_args()
    logging.basicConfig(level=logging.ERROR)
    load = os.getloadavg()
    rows = []
    with tempfile.TemporaryDirectory() as results:
        for plant, experiments in SCENARIOS.items():
            if args.plants and not plant.startswith(tuple(args.plants)):
                continue
            for experiment, path in experiments.items():
                for setup, overrides in SETUPS.items():
                    if plant.startswith(SHIPPED_ONLY) and setup != "identified + observer":
                        continue
                    overrides = dict(overrides)
                    exp2_steps = {"simulation.steps": args.exp2_steps} if args.exp2_steps else {}
                    if experiment == "exp2":
                        overrides.update(exp2_steps)
                    if plant.startswith("S175 (force level") and setup == "KCS model":
                        path_used, overrides = OWN / f"{experiment}_s175_kcs_model.toml", (
                            exp2_steps if experiment == "exp2" else {})
                    else:
                        path_used = path
                    row = measure(path_used, overrides, results, experiment)
                    rows.append((plant, experiment, setup, row))
                    print(table([rows[-1]])[-1], flush=True)
    lines = table(rows)
    print()
    print("\n".join(lines))
    if args.out is not None:
        stamp = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
        header = [
            f"# Own-ship goals, measured (written by `python bench/bench_own_ship.py {' '.join(sys.argv[1:])}`)",
            "",
            f"Generated {stamp}; load average at the start {load[0]:.1f} (2-core machine shared with other work: "
            "the figures are the runs' outcomes, not times). Goals: separation >= R + R_i, within 0.2 nm of the "
            "track at the end, at most 10 sign changes of tau_r per 100 solves. Experiment 2 has no obstacle; its "
            "track figure is the distance from the navigation's reference at the last sample.",
            "",
        ]
        args.out.write_text("\n".join(header + lines) + "\n")


if __name__ == "__main__":
    main()
