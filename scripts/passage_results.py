"""Tabulate the real passages from their latest comparisons into docs/passages-results.md.

    python -m orchestrator compare scenarios/passages/biscay_crossing_compare.toml
    python -m orchestrator compare scenarios/passages/ligurian_crossing_compare.toml
    python -m orchestrator compare scenarios/passages/cyclades_islands_compare.toml
    python -m orchestrator compare scenarios/passages/gibraltar_strait_compare.toml
    python -m orchestrator run scenarios/passages/gibraltar_strait_traffic.toml
    python scripts/passage_results.py [--results results]

Nothing is typed by hand: every figure is read from the comparisons' and runs' summary.json;
the README's passage lines (between the ``passages-summary`` markers) come from the same runs.
A passage not yet compared is listed as such.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from orchestrator.marked_blocks import replace_between

ROOT = Path(__file__).resolve().parent.parent
PASSAGES = ("biscay_crossing", "ligurian_crossing", "cyclades_islands", "gibraltar_strait")


def latest(folder: Path) -> Path | None:
    runs = sorted(p for p in folder.glob("*") if p.is_dir() and not p.name.startswith(".")) if folder.is_dir() else []
    return runs[-1] if runs else None


def clearance_of(run_folder: Path) -> dict:
    summary = json.loads((run_folder / "summary.json").read_text())
    return summary.get("analyses", {}).get("clearance", {})


def fmt(value, digits=2) -> str:
    return "-" if value is None else f"{value:,.{digits}f}"


def passage_figures(results: Path, name: str) -> dict | None:
    """The figures of a passage's latest comparison (None: not compared yet)."""
    folder = latest(results / f"passage_{name}")
    if folder is None:
        return None
    summary = json.loads((folder / "summary.json").read_text())
    system = summary["voyage"]["systems"]["RHNC"]
    rhnc = clearance_of(folder / summary["runs"]["RHNC"])
    trials = sorted((folder / "runs" / "RHNC_equal-arrival_baseline").glob("*/summary.json"))
    trial_summaries = [json.loads(t.read_text()) for t in trials]
    baseline = [t.get("analyses", {}).get("clearance", {}) for t in trial_summaries]
    rhnc_nm = json.loads((folder / summary["runs"]["RHNC"] / "summary.json").read_text())["analyses"]["voyage"].get(
        "distance_nm")
    arrival_s = (system.get("baseline_arrival_min") or 0.0) * 60.0
    nearest = min(trial_summaries, default=None, key=lambda t: abs(
        (t["participants"].get("goal", {}).get("arrival_time_s") or float("inf")) - arrival_s))
    arrived = nearest is not None and nearest["participants"].get("goal", {}).get("arrival_time_s") is not None
    # a baseline that never arrived sailed no passage to set beside RHNC's
    baseline_nm = nearest["analyses"]["voyage"].get("distance_nm") if arrived else None
    # what the distance alone would save at equal arrival time: at one constant speed through
    # calm water brake power grows as the cube of speed, so the energy of d nm in time t as d³/t²
    distance_alone = 100.0 * (1.0 - (rhnc_nm / baseline_nm) ** 3) if rhnc_nm and baseline_nm else None
    return {"folder": folder.relative_to(results.parent), "system": system, "rhnc": rhnc, "rhnc_nm": rhnc_nm,
            "baseline_nm": baseline_nm, "distance_alone": distance_alone,
            "baseline_min": min((b.get("min_clearance_nm", float("inf")) for b in baseline), default=None),
            "baseline_kept": all(b.get("kept", False) for b in baseline) if baseline else None}


def passage_row(results: Path, name: str) -> str:
    f = passage_figures(results, name)
    if f is None:
        return f"| {name} | not compared yet | | | | | | | | | | | |"
    system, rhnc = f["system"], f["rhnc"]
    return (f"| {name} | {fmt(system.get('arrival_min'), 1)} | {baseline_outcome(system)} | "
            f"{fmt(system.get('cost_usd'), 0)} | "
            f"{fmt(system.get('baseline_cost_usd'), 0)} | {fmt(system.get('saving_cost_percent'))} | "
            f"{fmt(system.get('saving_co2_percent'))} | {fmt(f['rhnc_nm'], 1)} / {fmt(f['baseline_nm'], 1)} | "
            f"{fmt(f['distance_alone'], 1)} | "
            f"{fmt(system.get('baseline_speed_kn'))} | {fmt(rhnc.get('min_clearance_nm'), 3)} / "
            f"{fmt(rhnc.get('required_clearance_nm'), 1)} ({'kept' if rhnc.get('kept') else 'NOT kept'}) | "
            f"{fmt(f['baseline_min'], 3)} ({'kept' if f['baseline_kept'] else 'NOT kept'}) | {f['folder']} |")


#: The README's passage lines lie between these markers.
README_BEGIN, README_END = "<!-- passages-summary:begin -->", "<!-- passages-summary:end -->"
KINDS = {"biscay_crossing": "open sea, a gale", "ligurian_crossing": "open sea, Beaufort 6",
         "cyclades_islands": "among islands", "gibraltar_strait": "a strait"}


def readme_lines(results: Path) -> list[str]:
    """One line per passage for the README, from the same comparisons as the table."""
    lines = []
    for name in PASSAGES:
        f = passage_figures(results, name)
        if f is None:
            lines.append(f"- `{name}` ({KINDS[name]}): not compared yet.")
            continue
        system, rhnc = f["system"], f["rhnc"]
        kept = "kept" if rhnc.get("kept") else "NOT kept"
        head = (f"- `{name}` ({KINDS[name]}): RHNC arrives at {fmt(system.get('arrival_min'), 1)} min, "
                f"{fmt(rhnc.get('min_clearance_nm'), 3)} nm from land and no-go areas ({kept}, "
                f"{fmt(rhnc.get('required_clearance_nm'), 1)} nm declared); ")
        outcome = baseline_outcome(system)
        if outcome == "cannot arrive":
            lines.append(head + "the sea-route baseline arrives at no speed up to 30 kn in this weather: "
                                "no saving to give.")
        elif system.get("saving_cost_percent") is None:
            lines.append(head + "no equal-arrival baseline was matched: no saving given.")
        else:
            lines.append(head + f"against the sea route at equal arrival time it saves "
                                f"{fmt(system.get('saving_cost_percent'))} % of cost and "
                                f"{fmt(system.get('saving_co2_percent'))} % of CO2 (the shorter track alone: "
                                f"{fmt(f['distance_alone'], 1)} %); the baseline's clearance "
                                f"{fmt(f['baseline_min'], 3)} nm ({'kept' if f['baseline_kept'] else 'NOT kept'}).")
    return lines


def write_readme_block(readme: Path, block: str) -> None:
    text = replace_between(readme.read_text(), README_BEGIN, README_END, block)
    if text is None:
        raise SystemExit(f"{readme}: no {README_BEGIN} ... {README_END} markers to write the passages between")
    readme.write_text(text)


def baseline_outcome(system: dict) -> str:
    """How the equal-arrival search ended (comparisons before ``baseline_outcome`` existed: from
    whether the baseline was read between two trials)."""
    if "baseline_outcome" in system:
        return system["baseline_outcome"]
    if "baseline_interpolated" in system:
        return "interpolated" if system["baseline_interpolated"] else "matched"
    return "-"


def stalled_baseline_lines(results: Path, name: str) -> list[str]:
    """For a passage whose baseline never arrived: how far each trial got, and in what weather."""
    import numpy as np
    import pandas as pd

    folder = latest(results / f"passage_{name}")
    if folder is None:
        return []
    import tomllib

    from rhnc.ship.ship_model import load_parameter_set
    from rhnc.voyage.voyage_spec import plane_positions

    compare = ROOT / "scenarios" / "passages" / f"{name}_compare.toml"
    voyage = plane_positions(tomllib.loads(compare.read_text())["voyage"], compare)  # goal_deg into goal_nm
    goal = np.array(voyage["goal_nm"], dtype=float)
    lines = []
    tau_u_max = load_parameter_set("default").tau_u_max  # the baselines' plant: the KCS's default set
    for trial in sorted((folder / "runs" / "RHNC_equal-arrival_baseline").glob("*/summary.json")):
        summary = json.loads(trial.read_text())
        if summary["participants"].get("goal", {}).get("arrival_time_s") is not None:
            return []  # a trial arrived: nothing stalled
        frame = pd.read_parquet(trial.parent / "timeseries.parquet")
        distance = np.hypot(frame["ship.x"] / 1852.0 - goal[0], frame["ship.y"] / 1852.0 - goal[1])
        off_bow = np.degrees(np.abs(np.angle(np.exp(1j * (frame["env.wind_direction"] - frame["ship.psi"])))))
        lines.append(f"- reference {frame['route.reference[0,4]'].iloc[0] / 0.514444:.2f} kn: made good "
                     f"{distance.iloc[0] - distance.iloc[-1]:.1f} nm of {distance.iloc[0]:.1f} in "
                     f"{frame['time_s'].iloc[-1] / 3600.0:.1f} h (least {distance.min():.1f} nm from the goal); at the "
                     f"ship, median Hs {frame['env.hs'].median():.1f} m, wind {frame['env.wind_speed'].median():.1f} m/s "
                     f"from {np.median(off_bow):.0f} deg off the bow, speed through water "
                     f"{frame['ship.u'].median() / 0.514444:.1f} kn; surge force within 1 % of the plant's bound "
                     f"({tau_u_max / 1e6:.1f} MN) in {100.0 * np.mean(frame['ctrl.tau_u'] >= 0.99 * tau_u_max):.0f} % "
                     f"of the samples")
    if not lines:
        return []
    return ["", f"{name}: the sea-route baseline arrived in no trial ({folder.relative_to(results.parent)}):", ""] + lines


def traffic_lines(results: Path) -> list[str]:
    folder = latest(results / "gibraltar_strait_traffic")
    if folder is None:
        return ["The strait with traffic has not been run yet."]
    summary = json.loads((folder / "summary.json").read_text())
    encounter = summary.get("analyses", {}).get("encounter", {})
    clearance = summary.get("analyses", {}).get("clearance", {})
    criteria = summary.get("acceptance", {}).get("criteria", [])
    met = sum(c.get("passed", False) for c in criteria)
    lines = [f"The strait with traffic (`gibraltar_strait_traffic.toml`, {folder.relative_to(results.parent)}): "
             f"separation margin to the target {fmt(encounter.get('min_clearance_nm'))} nm (R + R_i kept when >= 0), "
             f"land and no-go clearance {fmt(clearance.get('min_clearance_nm'))} nm of "
             f"{fmt(clearance.get('required_clearance_nm'), 1)}; acceptance {met}/{len(criteria)} criteria met:"]
    lines += [f"- {c['name']}: {'met' if c.get('passed') else 'NOT met'} ({c.get('criterion')}, value {c.get('value')})"
              for c in criteria]
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--results", default=str(ROOT / "results"))
    results = Path(parser.parse_args().results).resolve()
    lines = ["# Real passages: results", "",
             "Written by `scripts/passage_results.py` from the latest comparison of each passage "
             "(`python -m orchestrator compare scenarios/passages/<name>_compare.toml`); see "
             "[passages.md](passages.md) for what each passage is and how it is measured.", "",
             "RHNC (routing navigation on the chart) against the sea-route baseline (Offline-SPNC along "
             "searoute's route), the baseline's speed matched to RHNC's arrival. Saving: positive when RHNC "
             "is cheaper. Clearance: least distance of the sailed track to land and no-go areas along its "
             "chords, against the declared clearance; the baseline's is the least over its speed trials. "
             "Sailed: the distance along each track (the baseline's trial nearest the matched arrival): the "
             "sea-route network's detours make the baseline sail farther and so faster, which is most of "
             "the saving where the two distances differ. Distance alone: the saving the shorter track "
             "alone would give at equal arrival time, if brake power grew as the cube of speed (calm "
             "water, one constant speed: energy as distance³ / time²): 1 - (RHNC / baseline)³; a "
             "saving near it is the sea route's detour, not the weather.", "",
             "Baseline: how the search for the baseline's speed ended: matched (a trial arrives within 2 s "
             "of RHNC), interpolated (read between two trials around it), cannot arrive (no trial arrives, "
             "up to the fastest speed the search may try: no saving can be given).", "",
             "| passage | arrival [min] | baseline | RHNC cost [USD] | baseline cost [USD] | saving cost [%] | saving CO2 [%] "
             "| sailed RHNC / baseline [nm] | distance alone [%] | baseline speed [kn] "
             "| RHNC clearance [nm] / declared | baseline clearance [nm] | comparison |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    lines += [passage_row(results, name) for name in PASSAGES]
    flags, outcomes = [], []
    for name in PASSAGES:
        folder = latest(results / f"passage_{name}")
        if folder is not None:
            summary = json.loads((folder / "summary.json").read_text())
            flags += [f"- {name}: {flag}" for flag in summary.get("flags", [])]
            outcomes += [f"- {name}: {line}" for line in summary.get("voyage", {}).get("outcomes", [])]
    if outcomes:
        lines += ["", "Outcomes of the comparisons:", ""] + outcomes
    if flags:
        lines += ["", "Flags of the comparisons:", ""] + flags
    for name in PASSAGES:
        lines += stalled_baseline_lines(results, name)
    lines += [""] + traffic_lines(results) + [""]
    out = ROOT / "docs" / "passages-results.md"
    out.write_text("\n".join(lines))
    print("\n".join(lines))
    summary = readme_lines(results)
    write_readme_block(ROOT / "README.md", "\n".join(summary))
    print("\n".join(summary))


if __name__ == "__main__":
    main()
