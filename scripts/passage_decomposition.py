"""Split each passage's saving against its sea-route baseline into where it comes from.

    python scripts/passage_decomposition.py [--results results]   # writes docs/passages-decomposition.md

Read from the latest comparison of each passage (``python -m orchestrator compare
scenarios/passages/<name>_compare.toml``): RHNC's run and the baseline trial that arrived
nearest RHNC's arrival, their sailed tracks cut at the arrival, and the weather each run met
(its ``metocean.nc``).  With the energy model the voyage analysis costs every run with
(:mod:`rhnc.ship.energy`), each sailed path is also costed at one constant speed through
water ``V``: in calm water (no wind, waves or current), and in the weather and current the run
met (times as :func:`rhnc.routing.track_cost.constant_speed_times`).  ``V_B``, ``V_R``: the one
speed on which the baseline's path, RHNC's path, arrives when the run arrived; ``L`` the
sailed lengths; ``e(path, V)`` what the weather and current add per nm at ``V``; ``C`` the
sailed cost.  The saving ``C_B - C_R`` is exactly the sum of five parts:

* track length, calm: ``calm(L_B, V_B) - calm(L_R, V_R)`` (the shorter track alone);
* track length, in the weather: ``(e(B, V_B) - e(B, V_R)) L_B + e(R, V_R) (L_B - L_R)``
  (the longer track sailed faster through its weather, and its extra miles);
* weather on the path at equal speed: ``(e(B, V_R) - e(R, V_R)) L_B`` (the route's choice of
  where to meet the weather: what routing round it wins);
* RHNC's speed profile and closed loop: ``one(R, V_R) - C_R`` (RHNC's sailed speeds against
  one speed on its own path);
* the baseline's closed loop: ``C_B - one(B, V_B)`` (its sailed speeds against the one speed).

Each part is given in per cent of the baseline's sailed cost (and CO2); the running cost per
hour is the same for both at equal arrival.  Beside them, ``e`` on each path at RHNC's speed:
how much weather there is on the passage to route round.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
import pandas as pd

from orchestrator.geometry import NM
from rhnc.routing.routing_problem import RoutingProblem, costed_route
from rhnc.routing.track_cost import constant_speed_times, densify
from rhnc.ship.energy import EnergyParameters, brake_power, cost_rate, emission_rate
from rhnc.weather.metocean_sources import from_netcdf

ROOT = Path(__file__).resolve().parent.parent
PASSAGES_DIR = ROOT / "scenarios" / "passages"
PASSAGES = ("biscay_crossing", "ligurian_crossing", "cyclades_islands", "gibraltar_strait")
#: Where the one speed through water that arrives on time is looked for [m/s].
ONE_SPEED_BRACKET_MPS = (2.0, 20.0)
PARTS = ("track length, calm", "track length, in the weather", "weather on the path at equal speed",
         "RHNC speed profile and closed loop", "baseline closed loop")


def latest(folder: Path) -> Path | None:
    runs = sorted(p for p in folder.glob("*") if p.is_dir() and not p.name.startswith(".")) if folder.is_dir() else []
    return runs[-1] if runs else None


def sailed_path(run: Path) -> tuple[np.ndarray, float, dict]:
    """The run's track (n, 2) [m] cut at its arrival, the arrival time [s] and its voyage analysis."""
    voyage = json.loads((run / "summary.json").read_text())["analyses"]["voyage"]
    arrival_s = 60.0 * voyage["arrival_time_min"]
    frame = pd.read_parquet(run / "timeseries.parquet", columns=["time_s", "ship.x", "ship.y"])
    t = frame["time_s"].to_numpy(dtype=float)
    x, y = frame["ship.x"].to_numpy(dtype=float), frame["ship.y"].to_numpy(dtype=float)
    before = t < arrival_s
    end = [np.interp(arrival_s, t, x), np.interp(arrival_s, t, y)]
    return np.vstack([np.stack([x[before], y[before]], axis=1), end]), arrival_s, voyage


def calm_cost(length_m: float, speed_mps: float, energy: EnergyParameters) -> tuple[float, float]:
    """Cost [USD] and CO2 [t] of ``length_m`` at ``speed_mps`` in calm water (no wind, waves or current)."""
    power = brake_power(speed_mps, 0.0, 0.0, 0.0, 0.0, energy)
    hours = length_m / speed_mps / 3600.0
    return float(cost_rate(power, energy)) * hours, float(emission_rate(power, energy)) * hours / 1000.0


class SailedPath:
    """A run's sailed path in the weather the run met, costed at one speed through water."""

    def __init__(self, run: Path, energy: EnergyParameters) -> None:
        path, self.arrival_s, voyage = sailed_path(run)
        self.sailed = (voyage["cost_usd"], voyage["co2_t"])
        self.energy = energy
        self.length_m = float(np.sum(np.hypot(*np.diff(path, axis=0).T)))
        metocean = from_netcdf(run / "metocean.nc")
        self.problem = RoutingProblem(tuple(path[0]), tuple(path[-1]), metocean, energy, resolution_nm=0.5)
        self.path = path
        self.points = densify(path, self.problem.resolution_nm * NM / 2.0)

    def late_s(self, speed_mps: float) -> float:
        """Arrival at one speed through water against the run's [s] (inf where a head current stops it)."""
        try:
            return constant_speed_times(self.problem.metocean, self.points, speed_mps)[-1] - self.arrival_s
        except ValueError:
            return float("inf")

    def on_time_speed_mps(self) -> float:
        """The one speed through water that arrives when the run arrived."""
        from scipy.optimize import brentq

        return float(brentq(self.late_s, *ONE_SPEED_BRACKET_MPS, xtol=1e-6, rtol=1e-10))

    def one_speed(self, speed_mps: float) -> tuple[float, float]:
        """Cost [USD] and CO2 [t] of the path in the weather at ``speed_mps`` through water."""
        route = costed_route(self.problem, self.path, speed_mps, "sailed path")
        return route.cost_usd, route.co2_t

    def weather_per_nm(self, speed_mps: float) -> tuple[float, float]:
        """What the weather (and current) adds per nm at ``speed_mps``: cost [USD/nm] and CO2 [t/nm]."""
        weather, calm = self.one_speed(speed_mps), calm_cost(self.length_m, speed_mps, self.energy)
        return tuple((w - c) / (self.length_m / NM) for w, c in zip(weather, calm))


def decompose(baseline: SailedPath, rhnc: SailedPath) -> dict:
    """The saving and its parts [per cent of the baseline's sailed cost, and of its CO2].

    With V the one speed through water on time and e(path, V) the weather's cost per nm:
    calm track length ``calm(L_B, V_B) - calm(L_R, V_R)``; the track length in the weather
    ``(e(B, V_B) - e(B, V_R)) L_B + e(R, V_R) (L_B - L_R)`` (the longer track sailed faster
    through the same weather, and its extra miles); the weather on the path at equal speed
    ``(e(B, V_R) - e(R, V_R)) L_B``; RHNC's speed profile and closed loop ``one_R - C_R``; the
    baseline's closed loop ``C_B - one_B``.  They add up to ``C_B - C_R``.
    """
    v_b, v_r = baseline.on_time_speed_mps(), rhnc.on_time_speed_mps()
    l_b, l_r = baseline.length_m / NM, rhnc.length_m / NM
    one_b, one_r = baseline.one_speed(v_b), rhnc.one_speed(v_r)
    calm_b, calm_r = calm_cost(baseline.length_m, v_b, baseline.energy), calm_cost(rhnc.length_m, v_r, rhnc.energy)
    e_b_own, e_b_at_r, e_r = baseline.weather_per_nm(v_b), baseline.weather_per_nm(v_r), rhnc.weather_per_nm(v_r)
    out = {"speed_kn": (v_r * 3600.0 / NM, v_b * 3600.0 / NM), "length_nm": (l_r, l_b),
           "arrival_min": (rhnc.arrival_s / 60.0, baseline.arrival_s / 60.0)}
    for k, what in enumerate(("cost", "co2")):
        b_sailed, r_sailed = baseline.sailed[k], rhnc.sailed[k]
        parts = (calm_b[k] - calm_r[k],
                 (e_b_own[k] - e_b_at_r[k]) * l_b + e_r[k] * (l_b - l_r),
                 (e_b_at_r[k] - e_r[k]) * l_b,
                 one_r[k] - r_sailed,
                 b_sailed - one_b[k])
        out[what] = {"saving": 100.0 * (b_sailed - r_sailed) / b_sailed,
                     **{name: 100.0 * part / b_sailed for name, part in zip(PARTS, parts)},
                     "weather per nm, RHNC / baseline path": (e_r[k], e_b_at_r[k]),
                     "residual": 100.0 * (b_sailed - r_sailed - sum(parts)) / b_sailed}
    return out


def available_saving(name: str, rhnc: SailedPath) -> dict:
    """What the routing itself expects to win on the passage, in its own model (open loop): its
    optimal route (and least-fuel speed profile) against the shortest clear route at one speed,
    all from RHNC's start to where it arrived, at RHNC's arrival time, on the chart, at the
    resolution RHNC's navigation searched with [per cent of the shortest route's cost, CO2]."""
    import dataclasses
    import tomllib

    from rhnc.chart.chart import load_chart
    from rhnc.routing.routing_problem import straight_route
    from rhnc.routing.weather_routing import optimal_route

    scenario = tomllib.loads((PASSAGES_DIR / f"{name}.toml").read_text())
    options = scenario["participants"]["nav"]["options"]
    problem = dataclasses.replace(rhnc.problem, resolution_nm=options.get("resolution_nm", 0.5),
                                  keep_out=load_chart(PASSAGES_DIR / options["chart"]))
    shortest = straight_route(problem, arrival_s=rhnc.arrival_s)
    routed = optimal_route(problem, arrival_s=rhnc.arrival_s)
    profiled = optimal_route(problem, arrival_s=rhnc.arrival_s, speed_profile=True)
    return {"shortest_nm": shortest.distance_nm, "routed_nm": routed.distance_nm,
            **{f"{label} {what}": 100.0 * (1.0 - getattr(route, field) / getattr(shortest, field))
               for label, route in (("route", routed), ("route and speed", profiled))
               for what, field in (("cost", "cost_usd"), ("co2", "co2_t"))}}


def nearest_trial(folder: Path, arrival_min: float) -> Path | None:
    """The baseline trial that arrived nearest ``arrival_min`` (None: none arrived)."""
    best, gap = None, float("inf")
    for summary in sorted((folder / "runs" / "RHNC_equal-arrival_baseline").glob("*/summary.json")):
        voyage = json.loads(summary.read_text())["analyses"]["voyage"]
        if voyage.get("arrived") and abs(voyage["arrival_time_min"] - arrival_min) < gap:
            best, gap = summary.parent, abs(voyage["arrival_time_min"] - arrival_min)
    return best


def passage_lines(results: Path, name: str) -> tuple[list[str], list[str], str]:
    """The passage's cost and CO2 rows, the runs used, and its row of the routing's own available saving."""
    folder = latest(results / f"passage_{name}")
    if folder is None:
        return [f"| {name} | not compared yet |"], [], f"| {name} | not compared yet |"
    summary = json.loads((folder / "summary.json").read_text())
    energy = EnergyParameters()
    rhnc = SailedPath(folder / summary["runs"]["RHNC"], energy)
    available = available_saving(name, rhnc)
    available_row = (f"| {name} | {rhnc.arrival_s / 60.0:.2f} | {available['shortest_nm']:.2f} | "
                     f"{available['routed_nm']:.2f} | " + " | ".join(
                         f"{available[key]:.2f}" for key in ("route cost", "route co2", "route and speed cost",
                                                             "route and speed co2")) + " |")
    trial = nearest_trial(folder, summary["voyage"]["systems"]["RHNC"]["arrival_min"])
    used = f"- {name}: {folder.relative_to(results.parent)}"
    if trial is None:
        return [f"| {name} | the baseline arrived in no trial: no saving to split |"], [used], available_row
    split = decompose(SailedPath(trial, energy), rhnc)
    rows = []
    for what, unit in (("cost", "USD"), ("co2", "kg")):
        part = split[what]
        scale = 1.0 if what == "cost" else 1000.0
        per_nm = " / ".join(f"{value * scale:.1f}" for value in part["weather per nm, RHNC / baseline path"])
        rows.append(f"| {name} | {what} | {split['arrival_min'][0]:.2f} / {split['arrival_min'][1]:.2f} | "
                    f"{split['length_nm'][0]:.2f} / {split['length_nm'][1]:.2f} | "
                    f"{split['speed_kn'][0]:.2f} / {split['speed_kn'][1]:.2f} | {part['saving']:.2f} | "
                    + " | ".join(f"{part[key]:.2f}" for key in PARTS) + f" | {per_nm} {unit}/nm |")
    return rows, [f"{used}, baseline trial {trial.name}"], available_row


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--results", default=str(ROOT / "results"))
    results = Path(parser.parse_args(argv).results).resolve()
    lines = ["# Real passages: where the saving comes from", "",
             "Written by `scripts/passage_decomposition.py` (its docstring gives the method) from the latest "
             "comparison of each passage, the same as [passages-results.md](passages-results.md). Every part is in "
             "per cent of the baseline's sailed cost (or CO2); the five parts add up to the saving. The saving here "
             "is against the baseline trial that arrived nearest RHNC (the comparison's own figure may be read "
             "between two trials). *One speed on time*: the one speed through water on which each path arrives "
             "when its run did. *Weather per nm*: what wind, waves and current add per nm on each path at RHNC's "
             "one speed.", "",
             "| passage | of | arrival RHNC / baseline [min] | sailed RHNC / baseline [nm] | "
             "one speed on time RHNC / baseline [kn] | saving [%] | "
             + " [%] | ".join(PARTS) + " [%] | weather per nm, RHNC / baseline path |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    sources, available = [], []
    for name in PASSAGES:
        rows, used, available_row = passage_lines(results, name)
        lines += rows
        sources += used
        available.append(available_row)
    lines += ["", "What the routing expects to win in its own model (open loop, no NMPC): its optimal route at one "
              "speed, and with its least-fuel speed profile, against the shortest clear route at one speed, all "
              "from RHNC's start to where RHNC arrived and at RHNC's arrival time, on the chart, at the search "
              "resolution of RHNC's navigation; in per cent of the shortest route's cost (CO2). Where it is "
              "near zero there is nothing in the weather to route round at that arrival time.", "",
              "| passage | arrival [min] | shortest clear route [nm] | routed [nm] | route, cost [%] | "
              "route, CO2 [%] | route and speed, cost [%] | route and speed, CO2 [%] |",
              "|---|---|---|---|---|---|---|---|"] + available
    lines += ["", "Runs used:", ""] + sources + [""]
    out = ROOT / "docs" / "passages-decomposition.md"
    out.write_text("\n".join(lines))
    print("\n".join(lines))


if __name__ == "__main__":
    main()
