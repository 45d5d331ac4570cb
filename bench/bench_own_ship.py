"""Bring your own ship: Experiments 2, 3a and 3b on the third-party S175 FMU, side by side
with the KCS prediction model (not the plant's) and with the model `identify` fitted on it.

Prints, per run: minimum separation against R + R_i, cross-track error at the end (3a/3b),
the NMPC's tau_r sign changes per 100 solves, solver fallbacks, solves with the collision
clearance relaxed, the model check; for Experiment 2 the distance made good, the distance
left to the goal and the ship's distance from the navigation's reference (RMS / max).

    python bench/bench_own_ship.py [--exp2-steps 480]

The identified model is `scenarios/own_ship/S175_identified.toml`, written by
    python -m orchestrator identify scenarios/own_ship/exp3a_s175_kcs_model.toml \\
        --tau-u-max-N 8e5 --tau-r-max-Nm 1.65e8 --out scenarios/own_ship/S175_identified.toml
"""

from __future__ import annotations

import argparse
import logging
import re
import tempfile
from pathlib import Path

import numpy as np
import pandas as pd

from orchestrator.geometry import NM

REPO = Path(__file__).resolve().parents[1]
OWN = REPO / "scenarios" / "own_ship"


def reference_error_m(frame: pd.DataFrame) -> np.ndarray:
    """Distance [m] of the ship from the navigation's reference at every sample."""
    from rhnc.control_participant import interpolate_reference

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


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--exp2-steps", type=int, default=480, help="macro steps of Experiment 2 (480: full)")
    args = parser.parse_args()
    logging.basicConfig(level=logging.ERROR)
    from orchestrator.run import run_scenario

    print("| run | NMPC model | min separation - (R + R_i) [m] | cross-track at end [nm] | tau_r sign changes / 100 solves "
          "| fallbacks | relaxed clearance | model check |")
    print("|---|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as results:
        exp2 = {}
        for experiment in ("exp3a", "exp3b", "exp2"):
            for model in ("kcs_model", "identified"):
                path = OWN / f"{experiment}_s175_{model}.toml"
                overrides = {"simulation.steps": args.exp2_steps} if experiment == "exp2" else None
                report = run_scenario(path, results, progress=False, overrides=overrides)
                ctrl = report.summary["participants"]["ctrl"]
                encounter = report.summary["analyses"].get("encounter", {})
                clearance = encounter.get("min_clearance_nm")
                separation = "-" if clearance is None else f"{clearance * NM:+.1f}"
                track = f"{encounter['cross_track_end_nm']:.3f}" if "cross_track_end_nm" in encounter else "-"
                label = "KCS (default)" if model == "kcs_model" else "identified S175"
                print(f"| {experiment} | {label} | {separation} | {track} | "
                      f"{ctrl['tau_r_sign_changes_per_100_solves']:.1f} | {ctrl['fallback_count']} | "
                      f"{ctrl['relaxed_clearance_steps']} | {ctrl['model_check']['check']} |")
                if experiment == "exp2":
                    frame = pd.read_parquet(report.folder / "timeseries.parquet")
                    error = reference_error_m(frame)
                    voyage = report.summary["analyses"]["voyage"]
                    left = np.hypot(frame["ship.x"].iloc[-1] - 100 * NM, frame["ship.y"].iloc[-1] - 100 * NM) / NM
                    exp2[model] = (voyage["made_good_nm"], left, np.sqrt(np.mean(error ** 2)), error.max(),
                                   report.summary["simulation"]["steps_done"])
    print()
    print("| Experiment 2 on the S175 | made good [nm] | left to goal [nm] | distance from reference RMS / max [m] | steps |")
    print("|---|---|---|---|---|")
    for model, (made_good, left, rms, worst, steps) in exp2.items():
        print(f"| {model} | {made_good:.1f} | {left:.2f} | {rms:.0f} / {worst:.0f} | {steps} |")


if __name__ == "__main__":
    main()
