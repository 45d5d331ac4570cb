"""Tables, flags and figures of the fair voyage comparison (:mod:`rhnc.voyage.voyage_comparison`).

Three tables per comparison, written as CSV and appended to ``table.md``:

* ``voyage_runs``: every voyage side by side, the systems under test, their equal-arrival
  baselines (co-simulated) and the straight and optimal routes at each system's arrival
  time (costed by the routing model, not sailed): arrival, mean speed through water, speed
  made good, distance, totals and totals per nm made good;
* ``voyage_headline``: per system, the total cost and CO2 of the passage against its
  equal-arrival baseline, the saving available to a weather router at that arrival time,
  the system's share of it, and its sailed track against the straight line at the
  baseline's constant speed;
* flags: mean speeds that differ by more than the limit with no equal-arrival baseline
  beside each run, baselines that missed the arrival time, runs that did not arrive.

A sweep (one comparison per weather member) adds ``voyage_sweep`` (per member the
available saving first: at the nominal speed, then at each system's arrival; then each
system's saving and share), ``voyage_sweep_stats``
(the distribution of the share) and ``voyage_sweep.png``.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from orchestrator.compare import Section, markdown_table
from orchestrator.geometry import KNOT, NM

#: A run whose first sample lies further than this from the comparison's start is flagged [m].
START_TOLERANCE_M = 0.05 * NM
#: Runs whose mean speeds through water differ by more than this are not comparable
#: without an equal-arrival baseline [%].
SPEED_SPREAD_LIMIT_PERCENT = 0.5
#: Below this available saving [% of the straight route's cost] no share is given: a ratio
#: of two small numbers (docs/compare-format.md).
MIN_AVAILABLE_SAVING_PERCENT = 0.5


def evaluation_section(comparison, systems, baselines, routes, out_dir: Path) -> Section:
    """Build the tables and flags of one comparison (see the module docstring)."""
    runs = _runs_table(comparison, systems, baselines, routes)

    headline_rows, summary_systems = [], {}
    for label, system in systems.items():
        figures = _system_figures(system, baselines.get(label), routes.get(label, {}))
        summary_systems[label] = figures
        if system.usable:
            headline_rows.append(_headline_row(label, figures))
    headline = pd.DataFrame(headline_rows)

    flags = _flags(systems, baselines, routes, SPEED_SPREAD_LIMIT_PERCENT, getattr(comparison, "start_m", None))
    speeds = [s.mean_speed_through_water_kn for s in systems.values() if math.isfinite(s.mean_speed_through_water_kn)]
    spread = 100.0 * (max(speeds) / min(speeds) - 1.0) if len(speeds) > 1 and min(speeds) > 0 else 0.0
    markdown = ["## Voyages side by side", "",
                "Every run sails until it arrives within the arrival radius of the goal. Sailed: "
                "co-simulated with the plant and NMPC; costed: the routing model's cost of the route "
                "(not sailed). Per nm made good divides by the straight distance from the start to where "
                "the voyage ended.", "", markdown_table(runs), ""]
    if not headline.empty:
        markdown += ["## Headline: the passage at equal arrival time", "",
                     "Saving: the system's total against its equal-arrival baseline (positive: the system is "
                     "cheaper). Available: the optimal weather route against the straight route, both "
                     "arriving when the system arrived. Share: saving / available (none below "
                     f"{MIN_AVAILABLE_SAVING_PERCENT} % available). Track vs line: the sailed track against the "
                     "straight line, both costed at one constant speed through water, the baseline's mean "
                     "(positive: the track is dearer).", "", markdown_table(headline), ""]
    outcomes = _outcomes(systems, baselines)
    markdown += [f"**Outcome**: {line}" for line in outcomes] + ([""] if outcomes else [])
    markdown += [f"**FLAG**: {flag}" for flag in flags] + ([""] if flags else [])
    trials = _trial_rows(baselines)
    if trials:
        markdown += ["## Equal-arrival trials", "",
                     "Every run of each equal-arrival baseline's speed search, failed ones included.", "",
                     markdown_table(pd.DataFrame(trials)), ""]
    failed = {f"{row['baseline']} at {row['reference speed [kn]']:.4f} kn": f"{row['status']}: {row['reason']}"
              for row in trials if row["status"] != "finished"}
    tables = {"voyage_runs": runs}
    if not headline.empty:
        tables["voyage_headline"] = headline
    if trials:
        tables["voyage_trials"] = pd.DataFrame(trials)
    summary = {"systems": summary_systems, "speed_spread_percent": spread, "flags": flags, "outcomes": outcomes}
    return Section("\n".join(markdown), tables, summary, flags, failed)


def _runs_table(comparison, systems, baselines, routes) -> pd.DataFrame:
    """One row per voyage: each system sailed, its published figures, its baseline sailed, its routes costed."""
    straight_nm = comparison.straight_distance_nm
    rows = []
    for label, system in systems.items():
        rows.append(_voyage_row(label, "system (sailed)", system))
        if label in comparison.published:
            rows.append(_published_row(label, comparison.published[label]))
        equal = baselines.get(label)
        if equal is not None and equal.best is not None:
            best = equal.best.run
            row = _voyage_row(best.label, "equal-arrival baseline (sailed)", best)
            row["reference speed [kn]"] = equal.best.speed_kn
            rows.append(row)
        for kind in ("straight", "optimal"):
            if kind in routes.get(label, {}):
                rows.append(_route_row(f"{kind} route at {label}'s arrival", f"{kind} route (costed)",
                                       routes[label][kind], straight_nm))
    return pd.DataFrame(rows)


def _system_figures(system, equal, route) -> dict[str, Any]:
    """The summary's figures of one system: its own, against its equal-arrival baseline and its routes."""
    figures: dict[str, Any] = {"arrived": system.arrived, "arrival_min": _minutes(system.arrival_s),
                               "mean_speed_through_water_kn": system.mean_speed_through_water_kn,
                               "cost_usd": system.cost_usd, "co2_t": system.co2_t}
    if system.usable and equal is not None:
        figures["baseline_outcome"] = _baseline_outcome(equal)
    if system.usable and equal is not None and equal.usable:
        cost, co2 = equal.at_target(lambda t: t.run.cost_usd), equal.at_target(lambda t: t.run.co2_t)
        figures.update({
            "baseline_speed_kn": equal.at_target(lambda t: t.speed_kn),
            "baseline_arrival_min": _minutes(equal.at_target(lambda t: t.run.arrival_s)),
            "baseline_trials": len(equal.trials), "baseline_interpolated": equal.interpolated,
            "baseline_cost_usd": cost, "baseline_co2_t": co2,
            "saving_cost_percent": _saving(cost, system.cost_usd),
            "saving_co2_percent": _saving(co2, system.co2_t),
        })
    if "optimal" in route:
        figures["available_cost_percent"] = _saving(route["straight"].cost_usd, route["optimal"].cost_usd)
        figures["available_co2_percent"] = _saving(route["straight"].co2_t, route["optimal"].co2_t)
        for quantity in ("cost", "co2"):
            available = figures[f"available_{quantity}_percent"]
            saving = figures.get(f"saving_{quantity}_percent")
            share = None
            if saving is not None and available is not None and available >= MIN_AVAILABLE_SAVING_PERCENT:
                share = 100.0 * saving / available
            figures[f"share_{quantity}_percent"] = share
    if "track_at_equal_speed" in route:
        figures["track_vs_line_at_equal_speed_cost_percent"] = -_saving(
            route["line_at_equal_speed"]["cost_usd"], route["track_at_equal_speed"]["cost_usd"])
    return figures


def _baseline_outcome(equal) -> str:
    """How the equal-arrival search ended: ``matched``, ``interpolated``, ``cannot arrive``
    (no reference speed up to the fastest allowed arrives) or ``unmatched``."""
    if equal.matched:
        return "matched"
    if equal.interpolated:
        return "interpolated"
    return "cannot arrive" if equal.cannot_arrive else "unmatched"


def _outcomes(systems, baselines) -> list[str]:
    """A line for each system whose equal-arrival baseline arrives at no speed: the result
    of the comparison in that weather (no saving can be given), stated with its trials."""
    lines = []
    for label, equal in baselines.items():
        if label in systems and systems[label].usable and equal.cannot_arrive:
            speeds = ", ".join(f"{t.speed_kn:.2f}" for t in equal.trials)
            lines.append(f"{label} arrives at {systems[label].arrival_s / 60.0:.1f} min; its equal-arrival "
                         f"baseline arrives at no reference speed up to the fastest allowed, "
                         f"{equal.top_speed_kn:g} kn (trials at {speeds} kn): in this weather the baseline cannot "
                         "make the passage, so there is no saving at equal arrival time to give")
    return lines


def _trial_rows(baselines) -> list[dict[str, Any]]:
    """One row per run of every equal-arrival search, in the order they were sailed."""
    rows = []
    for label, equal in baselines.items():
        for number, trial in enumerate(equal.trials, start=1):
            run = trial.run
            rows.append({"baseline": f"{label} equal-arrival baseline", "trial": number,
                         "reference speed [kn]": trial.speed_kn,
                         "arrival [min]": _minutes(trial.arrival_s),
                         "status": getattr(run, "status", "finished"), "reason": getattr(run, "reason", "") or ""})
    return rows


def sweep_section(key: str, members: list[tuple[Any, Section]], out_dir: Path) -> Section:
    """Per-member table, distribution of each system's share, and a figure."""
    rows = []
    for value, section in members:
        row: dict[str, Any] = {key: value}
        nominal = section.summary.get("nominal", {})
        row["available cost saving at the nominal speed [%]"] = nominal.get("available_cost_percent")
        row["nominal arrival [min]"] = nominal.get("arrival_min")
        systems = section.summary.get("systems", {})
        for label, figures in systems.items():
            row[f"{label} available cost saving [%]"] = figures.get("available_cost_percent")
        for label, figures in systems.items():
            row[f"{label} arrived"] = figures.get("arrived")
            row[f"{label} arrival [min]"] = figures.get("arrival_min")
            for quantity, name in (("cost", "cost"), ("co2", "CO2")):
                saving = figures.get(f"saving_{quantity}_percent")
                available = figures.get(f"available_{quantity}_percent")
                row[f"{label} saving {name} [%]"] = saving
                row[f"{label} share {name} [%]"] = (
                    100.0 * saving / available if saving is not None and available is not None
                    and available >= MIN_AVAILABLE_SAVING_PERCENT else None)
        rows.append(row)
    table = pd.DataFrame(rows)
    labels = list(dict.fromkeys(label for _, s in members for label in s.summary.get("systems", {})))
    stats_rows: list[dict[str, Any]] = []
    summary: dict[str, dict[str, Any]] = {}  # system -> figure -> its statistics
    nominal = pd.to_numeric(table["available cost saving at the nominal speed [%]"], errors="coerce").dropna()
    stats_rows.append({"system": "(the weather)", "figure": "available cost saving at the nominal speed [%]",
                       **_distribution(nominal.to_numpy())})
    for label in labels:
        for quantity, column in (("available cost saving [%]", f"{label} available cost saving [%]"),
                                 ("saving cost [%]", f"{label} saving cost [%]"),
                                 ("share cost [%]", f"{label} share cost [%]")):
            values = pd.to_numeric(table.get(column), errors="coerce").dropna().to_numpy() \
                if column in table else np.array([])
            stats = _distribution(values)
            stats_rows.append({"system": label, "figure": quantity, **stats})
            summary.setdefault(label, {})[quantity] = stats
    for label in labels:
        arrived = table.get(f"{label} arrived")
        count = int(sum(bool(v) for v in arrived)) if arrived is not None else 0
        stats_rows.append({"system": label, "figure": "arrived", "count": count})
        summary.setdefault(label, {})["arrived"] = count
    stats_table = pd.DataFrame(stats_rows)
    _sweep_figure(key, table, labels, out_dir / "voyage_sweep.png")
    markdown = [f"## Per {key}: the available saving first, then each system's", "", markdown_table(table), "",
                "## Distribution over the members", "", markdown_table(stats_table), "",
                "Figure: voyage_sweep.png", ""]
    return Section("\n".join(markdown), {"voyage_sweep": table, "voyage_sweep_stats": stats_table},
                   {"distribution": summary, "members": len(members)})


def _voyage_row(label: str, kind: str, voyage) -> dict[str, Any]:
    hours = voyage.arrival_s / 3600.0 if voyage.arrival_s else math.nan
    made_good = voyage.made_good_nm
    return {
        "voyage": label, "kind": kind, "arrived": voyage.arrived,
        "arrival [min]": _minutes(voyage.arrival_s),
        "mean speed through water [kn]": voyage.mean_speed_through_water_kn,
        "speed made good [kn]": made_good / hours if hours and math.isfinite(hours) else None,
        "reference speed [kn]": None,
        "sailed [nm]": voyage.distance_nm, "made good [nm]": made_good,
        "cost [USD]": voyage.cost_usd, "CO2 [t]": voyage.co2_t,
        "cost per nm made good [USD]": voyage.cost_usd / made_good if made_good > 0 else None,
        "CO2 per nm made good [kg]": 1000.0 * voyage.co2_t / made_good if made_good > 0 else None,
    }


def _published_row(label: str, paper: dict[str, Any]) -> dict[str, Any]:
    """The published figures of a run, where the comparison file gives them."""
    minutes, made_good = paper.get("time_min"), paper.get("made_good_nm")
    co2 = paper.get("co2_t")
    return {
        "voyage": f"{label} (paper)", "kind": "published", "arrived": None, "arrival [min]": minutes,
        "mean speed through water [kn]": None,
        "speed made good [kn]": made_good / (minutes / 60.0) if made_good and minutes else None,
        "reference speed [kn]": None, "sailed [nm]": None, "made good [nm]": made_good,
        "cost [USD]": paper.get("cost_usd"), "CO2 [t]": co2,
        "cost per nm made good [USD]": paper.get("cost_per_made_good_nm_usd"),
        "CO2 per nm made good [kg]": paper.get("co2_per_made_good_nm_kg"),
    }


def _route_row(label: str, kind: str, route, made_good_nm: float) -> dict[str, Any]:
    mean_kn = float(route.speed_through_water_mps) / KNOT
    return {
        "voyage": label, "kind": kind, "arrived": True, "arrival [min]": route.duration_s / 60.0,
        "mean speed through water [kn]": mean_kn,
        "speed made good [kn]": made_good_nm / (route.duration_s / 3600.0),
        "reference speed [kn]": None,
        "sailed [nm]": route.distance_nm, "made good [nm]": made_good_nm,
        "cost [USD]": route.cost_usd, "CO2 [t]": route.co2_t,
        "cost per nm made good [USD]": route.cost_usd / made_good_nm,
        "CO2 per nm made good [kg]": 1000.0 * route.co2_t / made_good_nm,
    }


def _headline_row(label: str, f: dict[str, Any]) -> dict[str, Any]:
    return {
        "system": label, "arrival [min]": f["arrival_min"],
        "cost [USD]": f["cost_usd"], "baseline cost [USD]": f.get("baseline_cost_usd"),
        "saving cost [%]": f.get("saving_cost_percent"),
        "CO2 [t]": f["co2_t"], "baseline CO2 [t]": f.get("baseline_co2_t"),
        "saving CO2 [%]": f.get("saving_co2_percent"),
        "baseline": f.get("baseline_outcome"),
        "baseline speed [kn]": f.get("baseline_speed_kn"), "baseline arrival [min]": f.get("baseline_arrival_min"),
        "available cost [%]": f.get("available_cost_percent"), "available CO2 [%]": f.get("available_co2_percent"),
        "share cost [%]": f.get("share_cost_percent"), "share CO2 [%]": f.get("share_co2_percent"),
        "track vs line at equal speed, cost [%]": f.get("track_vs_line_at_equal_speed_cost_percent"),
    }


def _flags(systems, baselines, routes, limit_percent: float, start_m=None) -> list[str]:
    flags = []
    if start_m is not None:
        runs = list(systems.values()) + [e.best.run for e in baselines.values() if e.best is not None]
        for run in runs:
            if len(run.track_m) and np.hypot(*(run.track_m[0] - start_m)) > START_TOLERANCE_M:
                offset_nm = np.hypot(*(run.track_m[0] - start_m)) / NM
                flags.append(f"{run.label} started {offset_nm:.2f} nm from voyage.start_nm: not the same passage")
    speeds = {label: s.mean_speed_through_water_kn for label, s in systems.items()
              if math.isfinite(s.mean_speed_through_water_kn)}
    if len(speeds) > 1:
        slow, fast = min(speeds.values()), max(speeds.values())
        spread = 100.0 * (fast / slow - 1.0) if slow > 0 else math.inf
        unmatched = [label for label in speeds if label not in baselines or not baselines[label].usable]
        if spread > limit_percent and unmatched:
            listing = ", ".join(f"{label} {speed:.2f} kn" for label, speed in speeds.items())
            flags.append(f"mean speeds through water differ by {spread:.2f} % ({listing}) and "
                         f"{', '.join(unmatched)} {'has' if len(unmatched) == 1 else 'have'} no equal-arrival "
                         "baseline beside it: the differences between these runs mix speed with routing")
    for label, system in systems.items():
        if not system.arrived:
            why = f" (the run {system.status}: {system.reason})" if system.status != "finished" else ""
            flags.append(f"{label} did not arrive{why}: left out of the headline")
        elif system.status != "finished":
            flags.append(f"{label} arrived at {system.arrival_s / 60.0:.0f} min, then the run ended "
                         f"'{system.status}' ({system.reason}): its totals up to arrival are used")
    for label, entry in (routes or {}).items():
        if "routing_error" in entry:
            flags.append(f"no optimal route at {label}'s arrival time ({entry['routing_error']}): "
                         "no available saving or share for it")
    for label, equal in baselines.items():
        if equal.interpolated:
            early, late = equal.bracket
            flags.append(f"the equal-arrival baseline of {label} is read between two runs arriving "
                         f"{equal.target_s - early.arrival_s:.0f} s before and {late.arrival_s - equal.target_s:.0f} s "
                         f"after it (the arrival jumps with the reference speed there)")
        elif not equal.matched and not equal.cannot_arrive:  # that one is an outcome (_outcomes)
            best = equal.best
            miss = f"{abs(best.arrival_s - equal.target_s):.0f} s off" if best else "no trial arrived"
            flags.append(f"the equal-arrival baseline of {label} missed its arrival time by more than "
                         f"{equal.tolerance_s:g} s ({miss} after {len(equal.trials)} runs)")
    return flags


def _distribution(values: np.ndarray) -> dict[str, Any]:
    if values.size == 0:
        return {"count": 0, "min": None, "p25": None, "median": None, "p75": None, "max": None, "mean": None}
    return {"count": int(values.size), "min": float(values.min()), "p25": float(np.percentile(values, 25)),
            "median": float(np.median(values)), "p75": float(np.percentile(values, 75)),
            "max": float(values.max()), "mean": float(values.mean())}


def _sweep_figure(key: str, table: pd.DataFrame, labels, target: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (top, bottom) = plt.subplots(2, 1, figsize=(8, 6.5), sharex=True)
    members = np.arange(len(table))
    width = 0.8 / max(len(labels), 1)
    nominal = pd.to_numeric(table.get("available cost saving at the nominal speed [%]"), errors="coerce")
    if nominal is not None and nominal.notna().any():
        top.bar(members, nominal, 0.9, color="none", edgecolor="tab:green", label="available (nominal speed)")
    for i, label in enumerate(labels):
        available = pd.to_numeric(table.get(f"{label} available cost saving [%]"), errors="coerce")
        saving = pd.to_numeric(table.get(f"{label} saving cost [%]"), errors="coerce")
        share = pd.to_numeric(table.get(f"{label} share cost [%]"), errors="coerce")
        offset = (i - (len(labels) - 1) / 2) * width
        if available is not None:
            top.bar(members + offset, available, width, color="0.7", label=f"available ({label}'s arrival)")
        if saving is not None:
            top.plot(members + offset, saving, "o", label=f"{label} saving")
        if share is not None:
            bottom.plot(members + offset, share, "o", label=label)
        arrived = table.get(f"{label} arrived")
        if arrived is not None:
            missed = members[[not bool(v) for v in arrived]]
            top.plot(missed + offset, np.zeros(missed.size), "x", color="tab:red", label=f"{label} did not arrive")
    top.axhline(0.0, color="k", lw=0.5)
    top.set_ylabel("cost saving [%]")
    top.legend(fontsize=8)
    bottom.axhline(0.0, color="k", lw=0.5)
    bottom.axhline(100.0, color="k", lw=0.5, ls="--")
    bottom.set_ylabel("share of available [%]")
    bottom.set_xlabel(key)
    bottom.set_xticks(members, [str(v) for v in table[key]], fontsize=7)
    bottom.legend(fontsize=8)
    top.set_title("Available saving and each system's share, at equal arrival time")
    fig.tight_layout()
    fig.savefig(target, dpi=120)
    plt.close(fig)


def _saving(reference, value):
    if reference is None or value is None or not math.isfinite(reference) or not math.isfinite(value) or not reference:
        return None
    return 100.0 * (reference - value) / reference


def _minutes(seconds):
    return seconds / 60.0 if seconds is not None else None
