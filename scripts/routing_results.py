"""Write docs/routing-results.md from the latest fair voyage comparisons in results/.

Every figure in the document comes from the comparisons' own output files (or, for the
paper's figures, from the ``paper`` tables of ``scenarios/exp2_table3.toml`` and the
project's energy model); nothing is typed by hand.  Run the comparisons first:

    python -m orchestrator compare scenarios/exp2_table3.toml
    python -m orchestrator compare scenarios/weather/storm_off_route.toml
    python -m orchestrator compare scenarios/weather/cyclone.toml
    python -m orchestrator compare scenarios/weather/moving_storm.toml
    python -m orchestrator compare scenarios/weather/storm_set.toml
    python -m orchestrator compare scenarios/weather/storm_set_routing.toml
    python scripts/routing_results.py [--results results] [--out docs/routing-results.md]

It also rewrites the README's routing table and storm-set findings (between the
``routing-summary`` markers), so the README quotes exactly these runs.  The fixed routing
weather sets go to ``docs/routing-sets.md`` and the README's ``routing-sets`` block, alone
with ``--sets-only``; run them first:

    python -m orchestrator compare scenarios/weather/routing_set_ne.toml
    python -m orchestrator compare scenarios/weather/routing_set_sw.toml
    python -m orchestrator compare scenarios/weather/routing_set_w.toml
    python scripts/routing_results.py --sets-only
"""

from __future__ import annotations

import argparse
import json
import shutil
import tomllib
from pathlib import Path

import numpy as np
import pandas as pd

from orchestrator.marked_blocks import replace_between

REPO = Path(__file__).resolve().parents[1]
#: (comparison name, the weather in words, comparison file)
WEATHERS = (
    ("exp2_table3", "paper_default: the paper-style storm on the direct route", "scenarios/exp2_table3.toml"),
    ("weather_storm_off_route", "storm_off_route: a gale centred off the direct route",
     "scenarios/weather/storm_off_route.toml"),
    ("weather_cyclone", "cyclone: a rotating storm with its sea state", "scenarios/weather/cyclone.toml"),
    ("weather_moving_storm", "moving_storm: the rotating storm crossing the route (time-varying)",
     "scenarios/weather/moving_storm.toml"),
)
#: (comparison name, navigation method in words, comparison file) of the storm-set sweeps
SWEEPS = (
    ("weather_storm_set", "the paper's navigation (RHNC)", "scenarios/weather/storm_set.toml"),
    ("weather_storm_set_routing", "the routing navigation method (RHNC routing)",
     "scenarios/weather/storm_set_routing.toml"),
)
#: (comparison name, the set in words, comparison file) of the fixed routing weather sets (docs/routing-sets.md)
ROUTING_SETS = (
    ("weather_routing_set_ne", "heading north-east, 100 x 100 nm", "scenarios/weather/routing_set_ne.toml"),
    ("weather_routing_set_sw", "heading south-south-west, 140 x 90 nm", "scenarios/weather/routing_set_sw.toml"),
    ("weather_routing_set_w", "heading west, 80 x 150 nm", "scenarios/weather/routing_set_w.toml"),
)
#: the system measured on the routing sets
ROUTING_SET_SYSTEM = "RHNC routing"
#: the goal over every weather set: median share, least share where >= 0.5 % is available
SET_GOAL_MEDIAN_PERCENT, SET_GOAL_LEAST_PERCENT = 90.0, 75.0
HEADLINE = ["system", "arrival [min]", "cost [USD]", "baseline cost [USD]", "saving cost [%]", "saving CO2 [%]",
            "baseline speed [kn]", "available cost [%]", "available CO2 [%]", "share cost [%]",
            "track vs line at equal speed, cost [%]"]
RUNS = ["voyage", "arrival [min]", "mean speed through water [kn]", "speed made good [kn]", "sailed [nm]",
        "cost [USD]", "CO2 [t]", "cost per nm made good [USD]", "CO2 per nm made good [kg]"]


def latest(results: Path, name: str) -> Path | None:
    """The newest published folder of comparison ``name`` (run ids sort by time)."""
    folder = results / name
    runs = sorted(p for p in folder.iterdir() if p.is_dir() and not p.name.startswith(".")) if folder.is_dir() else []
    return runs[-1] if runs else None


_NOMINAL: dict[str, dict] = {}


def nominal_saving(comparison: Path, overrides: dict) -> dict:
    """:meth:`VoyageComparison.nominal_available_saving` of a sweep member (cached by its weather)."""
    from orchestrator.compare import load_comparison, load_extensions

    weather = json.dumps(overrides, sort_keys=True)
    if weather not in _NOMINAL:
        extension = load_extensions(load_comparison(comparison), comparison)["voyage"]
        _NOMINAL[weather] = extension.nominal_available_saving(overrides)
    return _NOMINAL[weather]


def sweep_members(results: Path, name: str, path: Path, out_dir: Path):
    """The sweep's members tabulated by the current code (:func:`sweep_section`).

    Members are gathered from every folder of the sweep, published or unfinished (a hidden
    staging folder keeps the members it completed), the newest folder winning for a member
    run twice; so a sweep may be split over processes, or stopped and its members kept.
    Returns (section, folders used, members, all published) or None.
    """
    from orchestrator.compare import Section
    from rhnc.voyage.voyage_comparison_tables import sweep_section

    folder = results / name
    if not folder.is_dir():
        return None
    sources = sorted((p for p in folder.iterdir() if p.is_dir()), key=lambda p: p.name.lstrip("."))
    by_member, used, key = {}, {}, None
    for source in sources:   # oldest first: newer folders overwrite a member
        for member in source.glob("members/*/summary.json"):
            key, _, value = member.parent.name.partition("=")
            summary = json.loads(member.read_text())
            voyage = summary.get("voyage", {})
            if "nominal" not in voyage:   # written before the comparison computed it: same code, here,
                cached = member.parent / "nominal.json"   # kept beside the member's summary
                if not cached.is_file():
                    cached.write_text(json.dumps(nominal_saving(path, summary["overrides"]), indent=2) + "\n")
                voyage["nominal"] = json.loads(cached.read_text())
            by_member[int(value)] = (source, Section(summary=voyage))
    if not by_member:
        return None
    for source, _ in by_member.values():
        used[source.name] = not source.name.startswith(".")
    members = [(value, section) for value, (_, section) in sorted(by_member.items())]
    return sweep_section(key, members, out_dir), used, len(members), all(used.values())


def fmt(value, digits=2) -> str:
    if value is None or (isinstance(value, float) and value != value):
        return "-"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, float) and value.is_integer() and abs(value) < 1e4 and digits == 0:
        return str(int(value))
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    if isinstance(value, (float, np.floating)):
        return f"{value:,.{digits}f}"
    return str(value)


def table(frame: pd.DataFrame, columns) -> str:
    columns = [c for c in columns if c in frame.columns]
    lines = ["| " + " | ".join(columns) + " |", "|" + "|".join("---" for _ in columns) + "|"]
    for _, row in frame[columns].iterrows():
        lines.append("| " + " | ".join(fmt(row[c]) for c in columns) + " |")
    return "\n".join(lines)


def paper_speed_effect() -> dict:
    """The paper's Table 3 speeds made good, and what that speed difference alone is worth
    per nm in calm water by this project's energy model."""
    from rhnc.ship.energy import EnergyParameters, brake_power, cost_rate, emission_rate
    from orchestrator.geometry import KNOT

    spec = tomllib.loads((REPO / "scenarios" / "exp2_table3.toml").read_text())
    paper = {run["label"]: run["paper"] for run in spec["runs"] if "paper" in run}
    rhnc, spnc = paper["RHNC"], paper["Offline-SPNC"]
    speeds = {label: p["made_good_nm"] / (p["time_min"] / 60.0) for label, p in paper.items()}
    energy = EnergyParameters()

    def per_nm(speed_kn):
        power = brake_power(speed_kn * KNOT, 0.0, 0.0, 0.0, 0.0, energy)
        return float(cost_rate(power, energy)) / speed_kn, float(emission_rate(power, energy)) / speed_kn

    (cost_r, co2_r), (cost_s, co2_s) = per_nm(speeds["RHNC"]), per_nm(speeds["Offline-SPNC"])
    return {
        "rhnc_kn": speeds["RHNC"], "spnc_kn": speeds["Offline-SPNC"], "rhnc": rhnc, "spnc": spnc,
        "paper_cost_per_nm_percent": 100.0 * (rhnc["cost_per_made_good_nm_usd"]
                                              / spnc["cost_per_made_good_nm_usd"] - 1),
        "paper_co2_per_nm_percent": 100.0 * (rhnc["co2_per_made_good_nm_kg"] / spnc["co2_per_made_good_nm_kg"] - 1),
        "speed_cost_per_nm_percent": 100.0 * (cost_r / cost_s - 1),
        "speed_co2_per_nm_percent": 100.0 * (co2_r / co2_s - 1),
    }


def summary_text(rows: list[dict], sweeps: dict, effect: dict) -> list[str]:
    """The findings in sentences, every figure taken from the tables below."""
    lines = ["## Summary", "", "Savings are against the equal-arrival baseline; negative: the system is dearer.", ""]
    for weather in dict.fromkeys(row["weather"] for row in rows):
        parts = []
        for row in (r for r in rows if r["weather"] == weather):
            saving, co2 = row.get("saving cost [%]"), row.get("saving CO2 [%]")
            if saving is None or saving != saving:
                continue
            share = row.get("share cost [%]")
            share_text = f", {share:.0f} % of it" if share is not None and share == share else ""
            parts.append(f"{row['system']} saves {saving:+.2f} % of cost and {co2:+.2f} % of CO2 against its "
                         f"equal-arrival baseline (arrival {row['arrival [min]']:.0f} min; available "
                         f"{row['available cost [%]']:.2f} %{share_text})")
        if parts:
            lines.append(f"- **{weather}**: " + "; ".join(parts) + ".")
    for method, (section, done) in sweeps.items():
        stats = section.tables["voyage_sweep_stats"].set_index(["system", "figure"])
        nominal = stats.loc[("(the weather)", "available cost saving at the nominal speed [%]")]
        systems = [label for label in dict.fromkeys(stats.index.get_level_values(0)) if label != "(the weather)"]
        text = (f"- **{method}** ({done} members): the weather offers a median "
                f"{nominal['median']:.2f} % (largest {nominal['max']:.2f} %) at the nominal speed")
        for label in systems:
            arrived = int(stats.loc[(label, "arrived"), "count"])
            saving = stats.loc[(label, "saving cost [%]")]
            shares = int(stats.loc[(label, "share cost [%]"), "count"])
            text += (f"; {label} arrived in {arrived}, and there saved a median {saving['median']:+.2f} % "
                     f"(quartiles {saving['p25']:+.2f} to {saving['p75']:+.2f} %, worst {saving['min']:+.2f} %) "
                     f"against its equal-arrival baseline; a share is defined (at least 0.5 % available) in "
                     f"{shares}")
            share = stats.loc[(label, "share cost [%]")]
            if shares:
                met = (share["median"] >= SET_GOAL_MEDIAN_PERCENT and share["min"] >= SET_GOAL_LEAST_PERCENT
                       and saving["min"] >= GOAL_WORST_PERCENT and arrived == done)
                text += (f", median share {share['median']:.0f} %, least {share['min']:.0f} % (goal: median >= "
                         f"{SET_GOAL_MEDIAN_PERCENT:.0f} %, each >= {SET_GOAL_LEAST_PERCENT:.0f} %, never more than "
                         f"{-GOAL_WORST_PERCENT:.1f} % dearer: {'met' if met else 'not met'})")
        lines.append(text + ".")
    lines += [f"- **The paper's Table 3**: its RHNC made good {effect['rhnc_kn']:.1f} kn, its Offline-SPNC "
              f"{effect['spnc_kn']:.1f} kn; that speed difference alone is worth "
              f"{effect['speed_cost_per_nm_percent']:+.2f} % cost and {effect['speed_co2_per_nm_percent']:+.2f} % "
              f"CO2 per nm by our energy model in calm water, of the {effect['paper_cost_per_nm_percent']:+.2f} % "
              f"and {effect['paper_co2_per_nm_percent']:+.2f} % it reports.", ""]
    return lines


README_BEGIN, README_END = "<!-- routing-summary:begin -->", "<!-- routing-summary:end -->"
SETS_BEGIN, SETS_END = "<!-- routing-sets:begin -->", "<!-- routing-sets:end -->"
#: (label in the comparisons, words in the README)
README_SYSTEMS = (("RHNC", "RHNC, paper's method"), ("RHNC routing", "RHNC, routing method"))
#: the goal of the routing navigation over the storm set
GOAL_SHARE_PERCENT, GOAL_WORST_PERCENT = 80.0, -0.5


def storm_set_findings(section, label: str) -> dict:
    """Per-member figures of ``label`` over a sweep: savings, shares at two thresholds, worst."""
    members = section.tables["voyage_sweep"]
    key = members.columns[0]
    saving = members[f"{label} saving cost [%]"].astype(float)
    available = members[f"{label} available cost saving [%]"].astype(float)
    arrived = saving.notna()
    share = 100.0 * saving / available

    def median_share(threshold):
        picked = arrived & (available >= threshold)
        return (float(np.median(share[picked])) if picked.any() else float("nan")), int(picked.sum())

    worst = int(saving[arrived].idxmin())
    return {"members": len(members), "arrived": int(arrived.sum()),
            "median": float(saving[arrived].median()), "p25": float(saving[arrived].quantile(0.25)),
            "p75": float(saving[arrived].quantile(0.75)), "share_05": median_share(0.5),
            "share_01": median_share(0.1), "worst": float(saving[worst]), "worst_member": members[key][worst],
            "dearer": int((saving[arrived] < GOAL_WORST_PERCENT).sum())}


def readme_block(rows: list[dict], sweeps: dict) -> str:
    """The README's routing table and storm-set findings, from the same runs as the document."""
    lines = ["| weather (start (0, 0), goal (100, 100) nm) | system | arrival [min] | saving vs equal-arrival "
             "baseline, cost / CO2 | available saving | share |", "|---|---|---|---|---|---|"]
    for weather in dict.fromkeys(row["weather"] for row in rows):
        for label, words in README_SYSTEMS:
            row = next((r for r in rows if r["weather"] == weather and r["system"] == label), None)
            if row is None:
                continue
            if row.get("arrived") is False:
                lines.append(f"| `{weather}` | {words} | did not arrive (mean "
                             f"{row['mean speed through water [kn]']:.1f} kn through water) | - | - | - |")
                continue
            saving = row.get("saving cost [%]")
            if saving is None or saving != saving:
                lines.append(f"| `{weather}` | {words} | {fmt(row.get('arrival [min]'))} | no baseline | "
                             f"{fmt(row.get('available cost [%]'))} % | - |")
                continue
            share = row.get("share cost [%]")
            lines.append(f"| `{weather}` | {words} | {row['arrival [min]']:.1f} | {saving:+.2f} % / "
                         f"{row['saving CO2 [%]']:+.2f} % | {row['available cost [%]']:.2f} % | "
                         f"{'-' if share is None or share != share else f'{share:.0f} %'} |")
    routing = next((section for method, (section, _) in sweeps.items() if "routing" in method), None)
    paper = next((section for method, (section, _) in sweeps.items() if "routing" not in method), None)
    if routing is not None:
        r = storm_set_findings(routing, "RHNC routing")
        met = r["share_05"][0] >= GOAL_SHARE_PERCENT and r["dearer"] == 0 and r["arrived"] == r["members"]
        lines += ["", f"Over the {r['members']} drawn gales of the storm set, co-simulated at equal arrival time, "
                  f"the routing navigation arrived in {r['arrived']} and saved a median {r['median']:+.2f} % "
                  f"(quartiles {r['p25']:+.2f} to {r['p75']:+.2f} %); of the available saving it captured a median "
                  f"{r['share_05'][0]:.0f} % over the {r['share_05'][1]} members offering at least 0.5 % and "
                  f"{r['share_01'][0]:.0f} % over the {r['share_01'][1]} offering at least 0.1 %; its worst member "
                  f"(member {r['worst_member']}) is {r['worst']:+.2f} %, and {r['dearer']} members are more than "
                  f"0.5 % dearer than the line."]
        if paper is not None:
            q = storm_set_findings(paper, "RHNC")
            lines[-1] += (f" The paper's method in the same set arrived in {q['arrived']}; there it saved a "
                          f"median {q['median']:+.2f} % (worst {q['worst']:+.2f} %), and {q['dearer']} of those "
                          f"{q['arrived']} are more than 0.5 % dearer.")
        lines += ["", f"**Goal** (a median share of at least {GOAL_SHARE_PERCENT:.0f} % over the members offering at "
                  "least 0.5 %, never more than 0.5 % dearer than the equal-arrival line, over the storm set): "
                  + ("**met**." if met else "**not met**.")]
    return "\n".join(lines)


def write_readme_block(readme: Path, block: str, begin: str = README_BEGIN, end: str = README_END) -> None:
    text = replace_between(readme.read_text(), begin, end, block)
    if text is None:
        raise SystemExit(f"{readme}: no {begin} ... {end} markers to write the routing summary between")
    readme.write_text(text)


def sailed_track(run: Path) -> tuple[np.ndarray, np.ndarray] | None:
    """(points [m], times [s]) of a finished run up to its arrival, the last point where the
    ship crossed the arrival radius (interpolated); None if it did not arrive."""
    summary = json.loads((run / "summary.json").read_text())
    arrival_min = summary.get("analyses", {}).get("voyage", {}).get("arrival_time_min")
    if arrival_min is None:
        return None
    frame = pd.read_parquet(run / summary.get("timeseries", "timeseries.parquet"))
    plant = next(c[:-2] for c in frame.columns if c.endswith(".x") and f"{c[:-2]}.psi" in frame.columns)
    time = frame["time_s"].to_numpy(dtype=float)
    points = frame[[f"{plant}.x", f"{plant}.y"]].to_numpy(dtype=float)
    arrival_s = float(arrival_min) * 60.0
    before = time < arrival_s - 1e-6
    end = np.array([np.interp(arrival_s, time, points[:, 0]), np.interp(arrival_s, time, points[:, 1])])
    return np.vstack([points[before], end]), np.concatenate([time[before], [arrival_s]])


_RECOST_FIELDS: dict[str, object] = {}


def recosted_saving(member: Path, comparison: Path, overrides: dict, label: str = ROUTING_SET_SYSTEM) -> dict:
    """The system's saving re-costed by the routing model: its track as sailed (positions and
    times, up to the arrival radius) against the equal-arrival baseline's track as sailed (the
    trial arriving closest to it), both costed by :func:`rhnc.routing.track_cost.cost_of_track`
    in the member's field, the same model and field as the available saving; so the share
    compares like with like (the co-simulated saving uses the plant's own power)."""
    from orchestrator.compare import load_comparison, load_extensions
    from orchestrator.geometry import NM
    from orchestrator.scenario import load_scenario
    from rhnc.routing.track_cost import cost_of_track
    from rhnc.ship.energy import EnergyParameters
    from rhnc.voyage.voyage_geometry import edge_hold_nm
    from rhnc.weather.metocean_sources import from_scenario_table

    voyage = load_extensions(load_comparison(comparison), comparison)["voyage"]
    key = json.dumps(overrides, sort_keys=True)
    if key not in _RECOST_FIELDS:
        loaded = load_scenario(voyage.equal_arrival.scenario, dict(overrides))
        field = from_scenario_table(loaded.metocean, loaded.directory, f"{loaded.path}: metocean")
        hold = edge_hold_nm(field, voyage.goal_m, voyage.arrival_radius_nm)
        _RECOST_FIELDS[key] = field if hold is None else field.with_edges_held(hold * NM)
    field = _RECOST_FIELDS[key]
    runs = member / "runs"
    system_runs = sorted((runs / label.replace(" ", "_")).glob("*/summary.json"))
    system = sailed_track(system_runs[-1].parent) if system_runs else None
    if system is None:
        return {}
    trials = [t for t in (sailed_track(s.parent) for s in (runs / f"{label} equal-arrival baseline".replace(" ", "_"))
                          .glob("*/summary.json")) if t is not None]
    if not trials:
        return {}
    baseline = min(trials, key=lambda t: abs(t[1][-1] - system[1][-1]))
    energy = EnergyParameters()
    sailed = cost_of_track(field, energy, *system)["cost_usd"]
    line = cost_of_track(field, energy, *baseline)["cost_usd"]
    return {"saving_percent": 100.0 * (line - sailed) / line, "arrival_gap_s": float(system[1][-1] - baseline[1][-1])}


def routing_set_members(section, name: str, folders: list[Path], label: str = ROUTING_SET_SYSTEM,
                        comparison: Path | None = None) -> pd.DataFrame:
    """One row per member of a routing set: its kind of weather, what it offers, the system's
    saving and share, and every failed run or trial of the member by name."""
    from rhnc.weather.routing_weather_set import KINDS

    members = section.tables["voyage_sweep"]
    key = members.columns[0]
    failed: dict[int, list[str]] = {}
    recosted: dict[int, dict] = {}
    for folder in folders:   # oldest first, as the members were gathered
        for summary in folder.glob("members/*/summary.json"):
            member = int(summary.parent.name.partition("=")[2])
            content = json.loads(summary.read_text())
            runs = content.get("failed_runs") or {}
            failed[member] = [f"{run}: {reason}" for run, reason in runs.items()]
            if comparison is not None:
                recosted[member] = recosted_saving(summary.parent, comparison, content["overrides"], label)
    rows = []
    for _, row in members.iterrows():
        member = int(row[key])
        saving = row.get(f"{label} saving cost [%]")
        rows.append({
            "member": member, "weather": KINDS[member % len(KINDS)],
            "available at the nominal speed [%]": row.get("available cost saving at the nominal speed [%]"),
            "arrived": bool(row.get(f"{label} arrived")),
            "arrival [min]": row.get(f"{label} arrival [min]"),
            "available at its arrival [%]": row.get(f"{label} available cost saving [%]"),
            "saving vs equal-arrival line [%]": saving,
            "share [%]": row.get(f"{label} share cost [%]"),
            "saving re-costed [%]": recosted.get(member, {}).get("saving_percent"),
            "share re-costed [%]": _share(recosted.get(member, {}).get("saving_percent"),
                                          row.get(f"{label} available cost saving [%]")),
            "more than 0.5 % dearer": (None if saving is None or saving != saving
                                       else bool(saving < GOAL_WORST_PERCENT)),
            "failed runs and trials": "; ".join(failed.get(member, [])) or "none",
        })
    return pd.DataFrame(rows)


def percent(value, spec: str = ".0f") -> str:
    """``value`` [%] as text, ``-`` when undefined."""
    return "-" if value is None or value != value else f"{value:{spec}} %"


def _share(saving, available):
    """saving / available [%] where at least the threshold is available, else None."""
    from rhnc.voyage.voyage_comparison_tables import MIN_AVAILABLE_SAVING_PERCENT

    if saving is None or available is None or saving != saving or available != available:
        return None
    return 100.0 * saving / available if available >= MIN_AVAILABLE_SAVING_PERCENT else None


def routing_set_verdict(members: pd.DataFrame, planned: int) -> dict:
    """The goal's figures over one set: median share (members offering >= 0.5 %), least share,
    worst saving, members dearer than the line by more than 0.5 %, failures."""
    share = pd.to_numeric(members["share [%]"], errors="coerce").dropna()
    saving = pd.to_numeric(members["saving vs equal-arrival line [%]"], errors="coerce").dropna()
    failures = int((members["failed runs and trials"] != "none").sum())
    verdict = {"members": len(members), "planned": planned, "arrived": int(members["arrived"].sum()),
               "with_share": int(share.size), "median_share": float(share.median()) if share.size else float("nan"),
               "least_share": float(share.min()) if share.size else float("nan"),
               "worst_saving": float(saving.min()) if saving.size else float("nan"),
               "dearer": int((saving < GOAL_WORST_PERCENT).sum()), "failed_members": failures}
    recosted = pd.to_numeric(members.get("share re-costed [%]", pd.Series(dtype=float)), errors="coerce").dropna()
    verdict["median_share_recosted"] = float(recosted.median()) if recosted.size else float("nan")
    verdict["least_share_recosted"] = float(recosted.min()) if recosted.size else float("nan")
    verdict["met"] = bool(verdict["members"] == planned and verdict["arrived"] == planned and failures == 0
                          and verdict["dearer"] == 0 and (not share.size or (
                              verdict["median_share"] >= SET_GOAL_MEDIAN_PERCENT
                              and verdict["least_share"] >= SET_GOAL_LEAST_PERCENT)))
    return verdict


def routing_sets_document(results: Path, out: Path, figures: Path) -> tuple[list[str], list[str]]:
    """docs/routing-sets.md and the README's block: each fixed routing set, member by member,
    against the goal (median share >= 90 %, each >= 75 % where >= 0.5 % is available, never
    more than 0.5 % dearer than the equal-arrival line, no failed run or trial)."""
    lines = ["# The fixed routing weather sets, measured at equal arrival time", "",
             "Generated by `python scripts/routing_results.py --sets-only` (or without the option, with "
             "[routing-results.md](routing-results.md)) from the comparisons below. The sets (seed 2611: gales, "
             "moving gales and current jets about the route, three headings, three map sizes; "
             "[weather.md](weather.md)) were fixed before any routing result on them was seen. Each member is "
             "one fair comparison ([compare-format.md](compare-format.md)): the routing navigation (RHNC routing) "
             "sails the passage, Offline-SPNC's straight line is co-simulated at the speed that arrives with it "
             "(the equal-arrival line), and the optimal route and speed profile for that arrival time are costed "
             "by the routing model. Available: the optimum against the straight route at constant speed. Share: "
             "saving against the equal-arrival line / available, where at least 0.5 % is available. "
             "Re-costed: the same saving with both voyages' tracks as sailed (positions and times, up to the "
             "arrival radius) costed by the routing model in the member's field (`cost_of_track`), the model and "
             "field of the available saving; the co-simulated saving uses the plant's own power. A share above "
             "100 % means the sailed voyage beat the equal-arrival line by more than the routing model's optimum "
             "beats the straight route: there the optimum (a graph search with refinement and a speed profile) falls "
             "short of the true optimum, and the share overstates what was captured of the true available saving.",
             "",
             f"Goal, per set: a median share of at least {SET_GOAL_MEDIAN_PERCENT:.0f} %, at least "
             f"{SET_GOAL_LEAST_PERCENT:.0f} % in every member offering 0.5 % or more, no member more than "
             f"{-GOAL_WORST_PERCENT:.1f} % dearer than the equal-arrival line, every run and trial finished.", ""]
    summary = ["| set | members run | arrived | members offering >= 0.5 % | median share | least share | "
               "median / least share re-costed | worst saving vs line | more than 0.5 % dearer | "
               "members with a failed run or trial | goal |",
               "|---|---|---|---|---|---|---|---|---|---|---|"]
    readme = list(summary)
    body = []
    for name, words, path in ROUTING_SETS:
        spec = tomllib.loads((REPO / path).read_text())
        low, high = spec["sweep"]["range"]
        planned = int(high) - int(low) + 1
        found = sweep_members(results, name, REPO / path, figures)
        body += [f"## {words}", ""]
        if found is None:
            body += [f"No results yet: `python -m orchestrator compare {path}`.", ""]
            row = f"| {words} | 0 of {planned} | - | - | - | - | - | - | - | - | not measured |"
            summary.append(row)
            readme.append(row)
            continue
        section, used, done, finished = found
        folders = sorted((results / name / folder for folder in used), key=lambda p: p.name.lstrip("."))
        members = routing_set_members(section, name, folders, comparison=REPO / path)
        v = routing_set_verdict(members, planned)
        (figures / "voyage_sweep.png").replace(figures / f"{out.stem}_{name}_share.png")
        state = "" if finished else " The comparison had not published its folder (stopped, or still running); the members it had finished are kept."
        body += [f"`python -m orchestrator compare {path}` ({done} of {planned} members; results "
                 + ", ".join(f"`{folder}`" for folder in used) + f").{state}", "",
                 table(members, list(members.columns)), "",
                 f"![shares](figures/{out.stem}_{name}_share.png)", ""]
        row = (f"| {words} | {v['members']} of {planned} | {v['arrived']} | {v['with_share']} | "
               f"{percent(v['median_share'])} | {percent(v['least_share'])} | "
               f"{percent(v['median_share_recosted'])} / {percent(v['least_share_recosted'])} | "
               f"{percent(v['worst_saving'], '+.2f')} | "
               f"{v['dearer']} | {v['failed_members']} | "
               + ("met" if v["met"] else "not met" if v["members"] == planned else "incomplete") + " |")
        summary.append(row)
        readme.append(row)
    lines += ["## Summary", ""] + summary + [""] + body
    return lines, readme


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--results", default=str(REPO / "results"))
    parser.add_argument("--out", default=str(REPO / "docs" / "routing-results.md"))
    parser.add_argument("--readme", default=str(REPO / "README.md"), help="README whose routing summary is rewritten "
                                                                       "('' to leave it)")
    parser.add_argument("--note", default="", help="a caveat printed under the title (e.g. which runs predate a "
                                                   "model change)")
    parser.add_argument("--sets-only", action="store_true", help="write only docs/routing-sets.md and the README's "
                                                                      "routing-sets block")
    args = parser.parse_args()
    results, out = Path(args.results), Path(args.out)
    figures = out.parent / "figures"
    figures.mkdir(parents=True, exist_ok=True)
    sets_out = out.parent / "routing-sets.md"
    set_lines, set_readme = routing_sets_document(results, sets_out, figures)
    sets_out.write_text("\n".join(set_lines) + "\n")
    print(f"wrote {sets_out}")
    if args.readme:
        write_readme_block(Path(args.readme), "\n".join(set_readme), SETS_BEGIN, SETS_END)
        print(f"rewrote the routing-sets summary in {args.readme}")
    if args.sets_only:
        return

    lines = ["# Routing savings, measured at equal arrival time", "",
             "Generated by `python scripts/routing_results.py` from the comparisons below (format: "
             "[compare-format.md](compare-format.md)); rerun them and the script to regenerate. Every run sails "
             "(0, 0) -> (100, 100) nm (the routing sets: the passage of their [voyage] table) until it arrives "
             "within 0.5 nm of the goal. Beside each system: its "
             "equal-arrival baseline (Offline-SPNC's straight line, co-simulated with the same plant and NMPC, its "
             "reference speed searched until it crosses the arrival radius within 2 s of the system) and the optimal weather route at "
             "the same arrival time (costed by the routing model; route and speed profile decided together since "
             "the routing sets were added). Saving: against the baseline, positive when the "
             "system is cheaper. Available: optimal route and speed against the straight route at constant speed. "
             "Share: saving / available. The fixed routing weather sets (gales, moving gales and current jets, three "
             "headings and map sizes): [routing-sets.md](routing-sets.md).", ""]
    summary_rows, sections, speed_spreads = [], [], {}
    for name, words, path in WEATHERS:
        folder = latest(results, name)
        if folder is None:
            sections += [f"### {words}", "", f"No results yet: `python -m orchestrator compare {path}`.", ""]
            continue
        headline = pd.read_csv(folder / "voyage_headline.csv")
        runs = pd.read_csv(folder / "voyage_runs.csv")
        summary = json.loads((folder / "summary.json").read_text())
        speed_spreads[name] = summary.get("voyage", {}).get("speed_spread_percent")
        for _, row in headline.iterrows():
            summary_rows.append({"weather": words.split(":")[0], **row.to_dict()})
        for label, sailed in summary.get("voyage", {}).get("systems", {}).items():
            if not sailed.get("arrived"):   # listed in the README as not arrived, with its mean speed
                summary_rows.append({"weather": words.split(":")[0], "system": label, "arrived": False,
                                     "mean speed through water [kn]": sailed.get("mean_speed_through_water_kn")})
        shutil.copyfile(folder / "tracks.png", figures / f"{out.stem}_{name}_tracks.png")
        sections += [f"### {words}", "", f"`python -m orchestrator compare {path}` (results `{folder.name}`)", "",
                     table(runs, RUNS), "", table(headline, HEADLINE), ""]
        sections += [f"**FLAG**: {flag}" for flag in summary.get("flags", [])]
        sections += ["", f"![tracks](figures/{out.stem}_{name}_tracks.png)", ""]
    sailed_rows = [row for row in summary_rows if row.get("arrived") is not False]
    if sailed_rows:
        lines += ["## Headline: each weather, each system, at equal arrival time", "",
                  table(pd.DataFrame(sailed_rows), ["weather"] + HEADLINE), ""]
    lines += ["## Per weather", ""] + sections

    lines += ["## The drawn storm set: each navigation's share of the available saving", ""]
    sweep_facts: dict = {}
    for name, method, path in SWEEPS:
        found = sweep_members(results, name, REPO / path, figures)
        lines += [f"### {method}", ""]
        if found is None:
            lines += [f"No results yet: `python -m orchestrator compare {path}`.", ""]
            continue
        section, used, done, finished = found
        sweep_facts[method] = (section, done)
        (figures / "voyage_sweep.png").replace(figures / f"{out.stem}_{name}_share.png")
        state = "" if finished else " Some members come from a sweep stopped before it published its folder."
        folders = ", ".join(f"`{folder}`" for folder in used)
        lines += [f"`python -m orchestrator compare {path}` ({done} members; results {folders}).{state} One fair "
                  "comparison per member; per member the saving available to a weather router first (at the "
                  "nominal speed, then at the system's arrival time), then the system's saving against its "
                  "equal-arrival baseline and its share.", "",
                  "Distribution over the members:", "", table(section.tables["voyage_sweep_stats"],
                                                              list(section.tables["voyage_sweep_stats"].columns)), "",
                  f"![storm set](figures/{out.stem}_{name}_share.png)", "", "Per member:", "",
                  table(section.tables["voyage_sweep"], list(section.tables["voyage_sweep"].columns)), ""]

    effect = paper_speed_effect()
    lines += ["## How the paper's Table 3 mixes speed into routing", "",
              f"The paper's RHNC made good {effect['rhnc_kn']:.1f} kn ({effect['rhnc']['made_good_nm']} nm in "
              f"{effect['rhnc']['time_min']} min) against its Offline-SPNC's {effect['spnc_kn']:.1f} kn "
              f"({effect['spnc']['made_good_nm']} nm in {effect['spnc']['time_min']} min), and reports "
              f"{effect['paper_cost_per_nm_percent']:+.2f} % cost and {effect['paper_co2_per_nm_percent']:+.2f} % "
              "CO2 per nm. By this project's energy model, in calm water, sailing "
              f"{effect['rhnc_kn']:.1f} instead of {effect['spnc_kn']:.1f} kn alone changes the cost per nm by "
              f"{effect['speed_cost_per_nm_percent']:+.2f} % and the CO2 per nm by "
              f"{effect['speed_co2_per_nm_percent']:+.2f} %, with no routing at all: part of the published saving "
              "is the slower passage. A comparison at equal arrival time removes that part.", ""]
    if "exp2_table3" in speed_spreads and speed_spreads["exp2_table3"] is not None:
        lines += [f"In our default-weather run the systems' mean speeds through water differ by up to "
                  f"{speed_spreads['exp2_table3']:.2f} %; the per-nm columns of the Table 3 comparison carry the "
                  "same mix, which is why the headline above is taken against the equal-arrival baseline.", ""]
    lines[4:4] = summary_text(sailed_rows, sweep_facts, effect)
    if args.note:
        lines[2:2] = [f"**Note.** {args.note}", ""]
    out.write_text("\n".join(lines) + "\n")
    print(f"wrote {out}")
    if args.readme:
        write_readme_block(Path(args.readme), readme_block(summary_rows, sweep_facts))
        print(f"rewrote the routing summary in {args.readme}")


if __name__ == "__main__":
    main()
