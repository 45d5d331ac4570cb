"""Rerun the README's scenarios: regenerate ``docs/figures/*.png`` and ``docs/readme_numbers.json``.

Every number the README quotes for the manoeuvring trials and Experiments 1-4 comes from
one fresh run here, with the command that reproduces it.  Run from the repository root:

    python scripts/reproduce_readme.py                      # everything (a few minutes)
    python scripts/reproduce_readme.py --only exp3a_static  # some experiments; the others'
                                                            # numbers in the JSON are kept

Wall-clock figures (NMPC solve times) are recorded under ``measured_on_this_machine`` and
depend on the machine and its load; every other number is a property of the model and
the scenario.  ``tests/test_readme_numbers.py`` reruns the cheap experiments and checks
them against the committed JSON within the tolerances in :data:`TOLERANCES`.
"""

from __future__ import annotations

import argparse
import datetime as dt
import json
import logging
import math
import shutil
import sys
import tempfile
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

log = logging.getLogger("reproduce_readme")

NUMBERS_FILE = REPO / "docs" / "readme_numbers.json"
FIGURES_DIR = REPO / "docs" / "figures"

#: Tolerances of the fresh-run check: (relative, absolute) per kind of number.  Runs are
#: deterministic on one machine; across machines, libraries or BLAS builds the solver's
#: last digits differ and a control step may move, hence the margins.
TOLERANCES = {
    "geometry_L": (0.01, 0.0),          # turning circle in ship lengths
    "angle_deg": (0.0, 0.2),            # zig-zag overshoots
    "distance_nm": (0.0, 0.01),         # separations, cross-track errors
    "force": (0.01, 0.0),               # max |tau_u| [MN], |tau_r| [MN m]
    "time_s": (0.0, 20.0),              # one control interval
    "count": (0.0, 0.0),                # fallbacks
}


@dataclass
class Experiment:
    """One README experiment: how to run it, what to keep of it."""

    name: str
    command: str
    run: Callable[[Path], tuple[Path, dict]]  # results root -> (result folder, summary)
    numbers: Callable[[Path, dict], dict]
    figures: dict[str, str] = field(default_factory=dict)  # file in the result folder -> docs/figures name
    cheap: bool = False  # rerun by the test


def _run(scenario: str) -> Callable[[Path], tuple[Path, dict]]:
    def run(results: Path):
        from orchestrator.run import run_scenario

        report = run_scenario(REPO / "scenarios" / scenario, results, progress=False)
        if not report.ok:
            raise RuntimeError(f"{scenario}: {report.status}: {report.reason}")
        return report.folder, report.summary

    return run


def _plan(scenario: str):
    def run(results: Path):
        from rhnc.navigation.offline_planning import run_offline_planning

        folder = run_offline_planning(REPO / "scenarios" / scenario, results)
        return folder, json.loads((folder / "summary.json").read_text())

    return run


def _compare(comparison: str):
    def run(results: Path):
        from orchestrator.compare import run_comparison

        folder = run_comparison(REPO / "scenarios" / comparison, results, progress=False)
        summary = json.loads((folder / "summary.json").read_text())
        if summary["status"] != "finished":
            raise RuntimeError(f"{comparison}: {summary['failed_runs']}")
        return folder, summary

    return run


# -- numbers ---------------------------------------------------------------------------------
def _turning(_folder, summary):
    figures = summary["analyses"]["turning_circle"]
    return {key: round(figures[key], 3) for key in ("advance_L", "transfer_L", "tactical_diameter_L",
                                                      "steady_diameter_L")}


def _zigzag(_folder, summary):
    figures = summary["analyses"]["zigzag"]
    return {key: round(value, 2) for key, value in figures.items()
            if key.endswith("_deg") and isinstance(value, (int, float))}


def _exp1(_folder, summary):
    keys = ("path_length_nm", "final_goal_distance_nm", "sum_ec_usd_h", "sum_em_kg_h", "sum_u")
    return {row["case"]: {key: round(row[key], 3) for key in keys} for row in summary["cases"]}


def _controller(summary, name="ctrl"):
    ctrl = summary["participants"][name]
    return {"fallback_count": ctrl["fallback_count"], "solver_failures": ctrl["failure_count"]}, {
        "solve_time_median_ms": round(1e3 * ctrl["solve_time_median_s"], 1),
        "solve_time_max_ms": round(1e3 * ctrl["solve_time_max_s"], 1)}


def _encounter(summary):
    encounter = summary["analyses"]["encounter"]
    return {
        "min_distance_nm": [round(o["min_distance_nm"], 3) for o in encounter["obstacles"]],
        "required_nm": [round(o["required_nm"], 3) for o in encounter["obstacles"]],
        "tau_u_max_abs_MN": round(encounter["tau_u_max_abs"] / 1e6, 3),
        "tau_r_max_abs_MNm": round(encounter["tau_r_max_abs"] / 1e6, 1),
        "cross_track_end_nm": round(encounter["cross_track_end_nm"], 3),
        "back_on_track_s": encounter["back_on_track_s"],
    }


def _exp3(_folder, summary):
    counts, timing = _controller(summary)
    return {**_encounter(summary), **counts, "measured_on_this_machine": timing}


def _exp4(folder, summary):
    counts, timing = _controller(summary)
    encounter = _encounter(summary)
    transitions = [{"time_min": round(t["time"] / 60.0, 1), "obstacle": t["kind"],
                    "range_nm": round(t["range_m"] / 1852.0, 2), "state": t["state"]}
                   for t in summary["participants"]["nav"]["et_transitions"]]
    return {"et_transitions": transitions,
            "min_distance_nm": encounter["min_distance_nm"], "required_nm": encounter["required_nm"],
            "goal_distance_end_nm": round(final_goal_distance_m(folder, summary) / 1852.0, 2), **counts,
            "measured_on_this_machine": timing}


def final_goal_distance_m(folder: Path, summary: dict) -> float:
    """Distance [m] from the ship's position in the last recorded row to the goal monitor's goal.

    Not the monitor's own output in that row: a participant's output is what it computed at
    its last step, from the position one macro step earlier, so the last row holds the
    distance of the step before the end.
    """
    import pandas as pd

    from orchestrator.scenario import load_scenario

    scenario = load_scenario(summary["scenario"])
    goal = next(spec for spec in scenario.participants if spec.type == "goal")
    north_nm, east_nm = goal.options["goal_nm"]
    x, y = (next(f"{c.source}.{c.source_port}" for c in scenario.connections
                 if (c.target, c.target_port) == (goal.name, port)) for port in ("x", "y"))
    frame = pd.read_parquet(folder / "timeseries.parquet", columns=[x, y])
    return float(math.hypot(frame[x].iloc[-1] - north_nm * 1852.0, frame[y].iloc[-1] - east_nm * 1852.0))


def _exp2(folder, summary):
    numbers = {"table": summary["table"]}
    for label, relative in summary["runs"].items():
        run_summary = json.loads((folder / relative / "summary.json").read_text())
        counts, timing = _controller(run_summary)
        numbers[label] = {"voyage": {k: _round(v, 4) for k, v in run_summary["analyses"]["voyage"].items()
                                     if isinstance(v, (int, float, str)) or v is None},
                          **counts, "measured_on_this_machine": timing}
    return numbers


def _json_safe(value):
    """NaN (a figure the paper does not give) as null: the file stays strict JSON."""
    if isinstance(value, float) and value != value:
        return None
    if isinstance(value, dict):
        return {k: _json_safe(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_json_safe(v) for v in value]
    return value


def _round(value, digits):
    return round(value, digits) if isinstance(value, float) else value


EXPERIMENTS = [
    Experiment("turning_circle", "python -m orchestrator run scenarios/turning_circle.toml",
               _run("turning_circle.toml"), _turning, {"turning_circle.png": "turning_circle.png"}, cheap=True),
    Experiment("zigzag_10_10", "python -m orchestrator run scenarios/zigzag_10_10.toml",
               _run("zigzag_10_10.toml"), _zigzag, {"zigzag.png": "zigzag.png"}, cheap=True),
    Experiment("exp1_cost_vs_emission", "python -m orchestrator plan scenarios/exp1_cost_vs_emission.toml",
               _plan("exp1_cost_vs_emission.toml"), _exp1,
               {"figure8_paths.png": "exp1_figure8_paths.png", "figure9_field_energy.png": "exp1_figure9_field_energy.png"}),
    Experiment("exp2_table3", "python -m orchestrator compare scenarios/exp2_table3.toml",
               _compare("exp2_table3.toml"), _exp2,
               {"figure10_fields_and_track.png": "exp2_figure10_fields_and_track.png",
                "figure11_controls.png": "exp2_figure11_controls.png",
                "figure12_baseline_track.png": "exp2_figure12_baseline_track.png", "tracks.png": "exp2_tracks.png"}),
    Experiment("exp3a_static", "python -m orchestrator run scenarios/exp3a_static.toml",
               _run("exp3a_static.toml"), _exp3,
               {"track.png": "exp3a_static_track.png", "controls.png": "exp3a_static_controls.png"}, cheap=True),
    Experiment("exp3b_head_on", "python -m orchestrator run scenarios/exp3b_head_on.toml",
               _run("exp3b_head_on.toml"), _exp3,
               {"track.png": "exp3b_head_on_track.png", "controls.png": "exp3b_head_on_controls.png"}, cheap=True),
    Experiment("exp4_full", "python -m orchestrator run scenarios/exp4_full.toml",
               _run("exp4_full.toml"), _exp4,
               {"navigation_fields.png": "exp4_figure17_fields_and_track.png", "track.png": "exp4_full_track.png",
                "controls.png": "exp4_full_controls.png"}),
    Experiment("exp4_close_pass_variant", "python -m orchestrator run scenarios/exp4_close_pass_variant.toml",
               _run("exp4_close_pass_variant.toml"), _exp4,
               {"navigation_fields.png": "exp4_close_pass_variant_fields.png",
                "track.png": "exp4_close_pass_variant_track.png"}),
    Experiment("exp4_head_on_variant", "python -m orchestrator run scenarios/exp4_head_on_variant.toml",
               _run("exp4_head_on_variant.toml"), _exp4,
               {"track.png": "exp4_head_on_variant_track.png", "controls.png": "exp4_head_on_variant_controls.png"}),
]


def reproduce(names, results: Path, figures_dir: Path | None) -> dict[str, Any]:
    """Run the named experiments into ``results``; copy their figures; return their numbers."""
    out = {}
    for experiment in EXPERIMENTS:
        if experiment.name not in names:
            continue
        log.info("running %s: %s", experiment.name, experiment.command)
        folder, summary = experiment.run(results)
        out[experiment.name] = {"command": experiment.command, **experiment.numbers(folder, summary)}
        if figures_dir is not None:
            figures_dir.mkdir(parents=True, exist_ok=True)
            for source, target in experiment.figures.items():
                shutil.copyfile(folder / source, figures_dir / target)
    return out


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", nargs="+", choices=[e.name for e in EXPERIMENTS], help="experiments to rerun")
    parser.add_argument("--numbers", type=Path, default=NUMBERS_FILE, help="JSON to update")
    parser.add_argument("--figures", type=Path, default=FIGURES_DIR, help="folder of the README's figures")
    parser.add_argument("--results", type=Path, default=None, help="keep the runs here (default: a temp folder)")
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    names = args.only or [e.name for e in EXPERIMENTS]
    with tempfile.TemporaryDirectory(prefix="readme-runs-") as tmp:
        fresh = reproduce(names, args.results or Path(tmp), args.figures)
    numbers = json.loads(args.numbers.read_text()) if args.numbers.is_file() else {}
    numbers.setdefault("experiments", {}).update(fresh)
    numbers["regenerated_utc"] = dt.datetime.now(dt.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")
    numbers["command"] = "python scripts/reproduce_readme.py"
    args.numbers.parent.mkdir(parents=True, exist_ok=True)
    args.numbers.write_text(json.dumps(_json_safe(numbers), indent=2, allow_nan=False) + "\n")
    print(f"{len(fresh)} experiments rerun; numbers in {args.numbers}, figures in {args.figures}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
