"""How far apart within their arrival minute a system and its equal-arrival baseline arrive.

The fair comparison matches the baseline's arrival to the system's in whole macro steps
(1 min): the runs stop in the step in which the ship comes within the arrival radius.
Within that minute the two may arrive up to a minute apart, 0.2 % of an 8 h passage, and
at fixed distance a ship arriving 0.2 % later sails about 0.2 % slower and burns about
0.4 % less fuel per nm: a difference of the same order as the savings compared.

This script interpolates, from each run's time series, the instant the ship crosses the
arrival radius (linear in the goal distance between the two steps around it), and prints
per member of a comparison folder (or of a single comparison) the two arrivals, their
difference, and an estimate of what the difference is worth: the calm-water shadow price
of time at the baseline's speed (:func:`rhnc.navigation.route_navigation.calm_water_time_price_usd_h`,
what an hour less at sea costs in extra fuel) times the difference, in percent of the
baseline's cost.  Positive: the system arrived earlier and paid for it.  It is an estimate
beside the measured saving, not a correction of it.

Run: ``python scripts/arrival_offsets.py results/weather_storm_set_routing/<run> [...] [--system "RHNC routing"]``
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
import pandas as pd

from rhnc.ship.energy import EnergyParameters
from orchestrator.geometry import KNOT, NM
from rhnc.navigation.route_navigation import calm_water_time_price_usd_h


def crossing_s(timeseries: Path, radius_nm: float) -> float:
    """Interpolated time [s] the ship first comes within ``radius_nm`` of the goal (NaN if never)."""
    frame = pd.read_parquet(timeseries, columns=["time_s", "goal.goal_distance_m"])
    time, distance = frame["time_s"].to_numpy(), frame["goal.goal_distance_m"].to_numpy()
    inside = np.flatnonzero(distance <= radius_nm * NM)
    if inside.size == 0 or inside[0] == 0:
        return float("nan")
    k = inside[0]
    fraction = (distance[k - 1] - radius_nm * NM) / (distance[k - 1] - distance[k])
    return float(time[k - 1] + fraction * (time[k] - time[k - 1]))


def member_rows(folder: Path, system: str, radius_nm: float):
    """One row per comparison (``folder`` itself, or each of its ``members/*``)."""
    comparisons = sorted(folder.glob("members/*/summary.json")) or [folder / "summary.json"]
    energy = EnergyParameters()
    for summary_path in comparisons:
        summary = json.loads(summary_path.read_text())
        facts = summary.get("voyage", {}).get("systems", {}).get(system)
        if not facts or not facts.get("arrived"):
            continue
        runs = summary_path.parent / "runs"
        label = system.replace(" ", "_")
        own = sorted((runs / label).glob("*/timeseries.parquet"))
        baseline = sorted((runs / f"{label}_equal-arrival_baseline").glob("*/timeseries.parquet"))
        if not own or not baseline:
            continue
        arrival, baseline_arrival = crossing_s(own[-1], radius_nm), crossing_s(baseline[-1], radius_nm)
        price = calm_water_time_price_usd_h(facts["baseline_speed_kn"] * KNOT, energy)
        worth = price * (baseline_arrival - arrival) / 3600.0 / facts["baseline_cost_usd"] * 100.0
        yield {"comparison": summary_path.parent.name, "arrival [min]": arrival / 60.0,
               "baseline arrival [min]": baseline_arrival / 60.0,
               "baseline later by [s]": baseline_arrival - arrival,
               "saving cost [%]": facts["saving_cost_percent"],
               "worth of the difference [% of cost]": worth,
               "available cost [%]": facts["available_cost_percent"]}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folders", nargs="+", type=Path)
    parser.add_argument("--system", default="RHNC routing")
    parser.add_argument("--radius-nm", type=float, default=0.5)
    args = parser.parse_args()
    rows = [row for folder in args.folders for row in member_rows(folder, args.system, args.radius_nm)]
    if not rows:
        print("no arrived runs of", args.system)
        return
    frame = pd.DataFrame(rows)
    print(frame.to_string(index=False, float_format=lambda v: f"{v:.2f}"))
    print(f"median difference {frame['baseline later by [s]'].median():.0f} s, worth a median "
          f"{frame['worth of the difference [% of cost]'].median():.2f} % of the cost")


if __name__ == "__main__":
    main()
