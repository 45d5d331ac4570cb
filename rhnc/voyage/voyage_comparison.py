"""A voyage comparison that is fair by construction: the ``[voyage]`` table of a comparison file.

Comparing navigation systems by cost per nautical mile rewards whichever system sails
slower or further: fuel per hour grows with the cube of the speed through water, so a
system that loses half a knot looks "cheaper" without having routed anything.  This
extension of ``python -m orchestrator compare`` (see :mod:`orchestrator.compare`) removes
speed from the comparison:

* every run sails until it arrives within ``arrival_radius_nm`` of ``goal_nm`` (the step
  cap is raised to ``max_duration_h`` and the run stops on arrival); a run that still does
  not arrive is reported as such and left out of the headline;
* beside each system under test, an **equal-arrival baseline**: the ``equal_arrival``
  scenario (the straight or shortest obstacle-free route tracked by the same NMPC and
  plant, e.g. Offline-SPNC) with its reference speed chosen so that it crosses the arrival
  radius within ``ARRIVAL_TOLERANCE_S`` of the system (:mod:`rhnc.voyage.equal_arrival`);
* the **headline** is the total cost and CO2 of the passage against that baseline, at equal
  arrival time, never per nm sailed;
* the **available saving**: the optimal weather route and speed profile
  (:mod:`rhnc.routing.weather_routing` with :mod:`rhnc.routing.speed_profile`, over the same
  met-ocean field and energy model) against the straight route at constant speed, both
  arriving when the system arrived; each system's saving is reported as a share of it;
* the **sailed track at equal speed**: the system's track and the straight line costed by
  the routing model at one constant speed through water (the baseline's mean), which
  isolates the route from the speed;
* each run's mean speed through water; runs whose mean speeds differ by more than
  :data:`rhnc.voyage.voyage_comparison_tables.SPEED_SPREAD_LIMIT_PERCENT` without an equal-arrival baseline beside each are
  flagged in the table.

Tables, figures and the sweep summary are built in :mod:`rhnc.voyage.voyage_comparison_tables`.
"""

from __future__ import annotations

import copy
import json
import logging
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from orchestrator.compare import ScenarioRunner, Section
from orchestrator.errors import ScenarioError
from orchestrator.participant import is_finite_number
from orchestrator.scenario import load_scenario
from rhnc.voyage.equal_arrival import EqualArrival, match_arrival_time
from orchestrator.geometry import KNOT, NM
from rhnc.voyage.voyage_comparison_tables import evaluation_section, sweep_section
from rhnc.voyage.voyage_geometry import check_on_map, edge_hold_nm, geometry_overrides, refuse_conflicts
from rhnc.voyage.voyage_spec import (VOYAGE_KEYS, EqualArrivalSettings, OptimalRouteSettings, equal_arrival,
                                     optimal_route, plane_positions, point, positive, reject_unknown)

log = logging.getLogger(__name__)

#: The equal-arrival baseline is accepted when it crosses the arrival radius within this
#: time of the system [s] (the crossing instants are interpolated between samples; 2 s of
#: an 8 h passage at about 18 kn is worth about 0.007 % of its fuel).
ARRIVAL_TOLERANCE_S = 2.0

@dataclass(frozen=True)
class SailedVoyage:
    """What a co-simulated run did, read from its results folder (SI units, track in m)."""

    label: str
    status: str
    arrived: bool
    arrival_s: float | None
    cost_usd: float
    co2_t: float
    mean_speed_through_water_kn: float
    distance_nm: float
    made_good_nm: float
    track_m: np.ndarray = field(repr=False)
    folder: Path | None = None
    reason: str = ""

    @property
    def usable(self) -> bool:
        """Fit for the headline: the recorded voyage reaches the arrival radius.

        The totals are cut at the arrival sample, so a run that failed after it (say, the
        ship crossed the edge of the weather map in the step it arrived) still counts; it is
        flagged."""
        return self.arrived and self.arrival_s is not None


class VoyageComparison:
    """The ``[voyage]`` extension of a comparison file (see the module docstring)."""

    def __init__(self, path: Path, start_m, goal_m, arrival_radius_nm: float, max_duration_s: float,
                 equal_arrival: EqualArrivalSettings | None, optimal_route: OptimalRouteSettings | None,
                 run_scenarios: Mapping[str, Path]) -> None:
        self.path = path
        self.start_m = np.asarray(start_m, dtype=float)
        self.goal_m = np.asarray(goal_m, dtype=float)
        self.arrival_radius_nm = arrival_radius_nm
        self.max_duration_s = max_duration_s
        self.equal_arrival = equal_arrival
        self.optimal_route = optimal_route
        self.run_scenarios = dict(run_scenarios)
        #: published figures per run label (the comparison file's ``paper`` tables)
        self.published: dict[str, dict[str, Any]] = {}
        self.labels = tuple(run_scenarios)
        #: the passage's arrival time after departure [min] (None: each navigation keeps its own)
        self.arrival_time_min: float | None = None
        self._maps: dict[str, Any] = {}

    # -- construction --------------------------------------------------------------------
    @classmethod
    def from_table(cls, table: Mapping[str, Any], path: Path, spec: Mapping[str, Any]) -> "VoyageComparison":
        """Check ``[voyage]`` of the comparison file ``path``; errors name the key."""
        where = f"{path}: voyage"
        reject_unknown(table, VOYAGE_KEYS, where)
        table = plane_positions(table, path)
        start = point(table, "start_nm", where)
        goal = point(table, "goal_nm", where)
        radius = positive(table, "arrival_radius_nm", where, 0.5)
        max_hours = positive(table, "max_duration_h", where, 24.0)
        labels = tuple(run["label"] for run in spec["runs"])
        equal = None
        if "equal_arrival" in table:
            equal = equal_arrival(table["equal_arrival"], path, labels, spec.get("set", {}))
        optimal = None
        if "optimal_route" in table:
            optimal = optimal_route(table["optimal_route"], f"{where}.optimal_route")
        scenarios = {run["label"]: path.parent / run["scenario"] for run in spec["runs"]}
        comparison = cls(path, start * NM, goal * NM, radius, max_hours * 3600.0, equal, optimal, scenarios)
        comparison.published = {run["label"]: dict(run["paper"]) for run in spec["runs"] if "paper" in run}
        if "arrival_time_min" in table:
            comparison.arrival_time_min = positive(table, "arrival_time_min", where, 0.0)
        return comparison

    # -- the extension's hooks -------------------------------------------------------------
    def run_overrides(self, scenario: Path, overrides: Mapping[str, Any], where: str) -> dict[str, Any]:
        """Overrides that make a run sail until it arrives at this comparison's goal.

        Gives every participant the comparison's passage (:mod:`rhnc.voyage.voyage_geometry`:
        navigation, goal, the plant's initial state, a reference route, the arrival time),
        raises the step cap to ``max_duration_h``, stops on the goal participant's arrival,
        and has the voyage analysis cut its totals at arrival.  The scenario must have one
        ``goal`` participant; an override giving a geometry key another value, or a start or
        goal outside the met-ocean map, is refused.
        """
        where = f"{where}: {scenario.name}"
        loaded = load_scenario(scenario, dict(overrides))
        goals = [p for p in loaded.participants if p.type == "goal"]
        if len(goals) != 1:
            raise ScenarioError(f"{where}: a voyage comparison needs exactly one participant of type \"goal\"")
        goal = goals[0]
        hold = self._check_on_map(loaded, where)
        geometry = geometry_overrides(loaded, self.start_m, self.goal_m, self.arrival_time_min, where)
        refuse_conflicts(geometry, overrides, where)
        loaded = load_scenario(scenario, {**dict(overrides), **geometry})
        sim = loaded.simulation
        steps = int(math.ceil(self.max_duration_s / sim.dt_s))
        stop = [str(c) for c in sim.stop_when]
        arrival = f"{goal.name}.arrived > 0.5"
        analyses = list(loaded.outputs.analyses)
        result = {
            **geometry,
            "simulation.stop_when": stop + ([arrival] if arrival not in stop else []),
            f"participants.{goal.name}.options.arrival_radius_nm": self.arrival_radius_nm,
            "outputs.analyses": analyses + ([] if "voyage" in analyses else ["voyage"]),
            "outputs.options.voyage.goal_nm": [float(v) for v in self.goal_m / NM],
            "outputs.options.voyage.arrival_radius_nm": self.arrival_radius_nm,
        }
        if hold is not None and "metocean.hold_edges_nm" not in overrides:
            result["metocean.hold_edges_nm"] = hold
        equal = self.equal_arrival
        if equal is not None and equal.same_control and any(
                Path(scenario).resolve() == self.run_scenarios[label].resolve() for label in equal.systems
                if label in self.run_scenarios):
            self._same_control(loaded, {})  # its input error before any run
        # one way to give the length: keep the scenario's own key (steps or stop_s)
        if "simulation.steps" in overrides or _uses_steps(scenario):
            result["simulation.steps"] = steps
        else:
            result["simulation.stop_s"] = sim.start_s + steps * sim.dt_s
        return result

    def _check_on_map(self, loaded, where: str) -> float | None:
        """Refuse a start or goal outside the run's met-ocean map (each map built once); the
        band [nm] over which the run must hold the map's edges for the arrival circle
        (:func:`rhnc.voyage.voyage_geometry.edge_hold_nm`), None if it need not."""
        if loaded.metocean is None:
            return None
        from rhnc.weather.metocean_sources import from_scenario_table

        key = json.dumps([str(loaded.directory), loaded.metocean], sort_keys=True, default=str)
        if key not in self._maps:
            self._maps[key] = from_scenario_table(loaded.metocean, loaded.directory, f"{loaded.path}: metocean")
        check_on_map(self._maps[key], self.start_m, self.goal_m, where)
        return edge_hold_nm(self._maps[key], self.goal_m, self.arrival_radius_nm)

    def evaluate(self, reports: Mapping[str, Any], runner: ScenarioRunner, overrides: Mapping[str, Any],
                 out_dir: Path) -> Section:
        """Equal-arrival baselines, route costs and the tables for one set of runs."""
        systems = {label: read_voyage(label, report) for label, report in reports.items()}
        baselines: dict[str, EqualArrival] = {}
        if self.equal_arrival is not None:
            for label in self.equal_arrival.systems:
                if systems[label].usable:
                    baselines[label] = self._equal_arrival_baseline(systems[label], runner, overrides,
                                                                    reports[label])
        routes = self._route_costs(systems, baselines, overrides) if self._needs_routing() else {}
        section = evaluation_section(self, systems, baselines, routes, out_dir)
        section.flags.extend(unmet_criteria_flags(reports, baselines))
        if self.optimal_route is not None and self.equal_arrival is not None:
            try:
                section.summary["nominal"] = self.nominal_available_saving(overrides)
            except ValueError as exc:
                log.warning("%s: no available saving at the nominal speed: %s", self.path, exc)
        return section

    def nominal_speed_kn(self, overrides: Mapping[str, Any]) -> float | None:
        """The equal-arrival scenario's own reference speed [kn] (its ``speed_key`` value)."""
        from orchestrator.scenario import apply_override, read_toml

        data, _ = read_toml(self._equal.scenario, "scenario")
        for key, value in copy.deepcopy(dict(overrides)).items():
            apply_override(data, key, value, str(self._equal.scenario))
        node: Any = data
        for part in self._equal.speed_key.split("."):
            node = node.get(part) if isinstance(node, Mapping) else None
        return float(node) if is_finite_number(node) else None

    def nominal_available_saving(self, overrides: Mapping[str, Any]) -> dict[str, float]:
        """The weather's available saving, whatever any system did: the optimal route against the
        straight route, both arriving when the straight route sailed at the equal-arrival
        scenario's own reference speed (taken as speed through water) arrives."""
        from rhnc.ship.energy import EnergyParameters
        from rhnc.weather.metocean_sources import from_scenario_table
        from rhnc.routing.routing_problem import plane_point
        from rhnc.routing.weather_routing import RoutingProblem, optimal_route, straight_route

        speed_kn = self.nominal_speed_kn(overrides)
        loaded = load_scenario(self._equal.scenario, dict(overrides))
        if speed_kn is None or loaded.metocean is None:
            raise ValueError("the equal-arrival scenario has no reference speed or no [metocean] table")
        metocean = from_scenario_table(loaded.metocean, loaded.directory, f"{loaded.path}: metocean")
        settings = self._optimal
        problem = RoutingProblem(plane_point(self.start_m), plane_point(self.goal_m), metocean, energy=EnergyParameters(),
                                 resolution_nm=settings.resolution_nm, avoid=settings.avoid_m)
        straight = straight_route(problem, speed_mps=speed_kn * KNOT)
        optimal = optimal_route(problem, arrival_s=straight.arrival_s, speed_profile=True)
        return {"speed_kn": speed_kn, "arrival_min": straight.duration_s / 60.0,
                "straight_cost_usd": straight.cost_usd, "optimal_cost_usd": optimal.cost_usd,
                "available_cost_percent": 100.0 * (straight.cost_usd - optimal.cost_usd) / straight.cost_usd,
                "available_co2_percent": 100.0 * (straight.co2_t - optimal.co2_t) / straight.co2_t}

    def summarise_sweep(self, key: str, members: list[tuple[Any, Section]], out_dir: Path) -> Section:
        """The distribution, over a sweep's members, of each system's share of the available saving."""
        return sweep_section(key, members, out_dir)

    # -- baselines and route costs ------------------------------------------------------------
    @property
    def _equal(self) -> EqualArrivalSettings:
        """``[voyage.equal_arrival]``, for the steps its callers take only when it is given."""
        if self.equal_arrival is None:
            raise RuntimeError(f"{self.path}: an equal-arrival step without [voyage.equal_arrival]")
        return self.equal_arrival

    @property
    def _optimal(self) -> OptimalRouteSettings:
        """``[voyage.optimal_route]``, for the steps its callers take only when it is given."""
        if self.optimal_route is None:
            raise RuntimeError(f"{self.path}: an optimal-route step without [voyage.optimal_route]")
        return self.optimal_route

    @property
    def straight_distance_nm(self) -> float:
        return float(np.hypot(*(self.goal_m - self.start_m)) / NM)

    def _equal_arrival_baseline(self, system: SailedVoyage, runner: ScenarioRunner,
                                overrides: Mapping[str, Any], report) -> EqualArrival:
        settings = self._equal
        base = dict(overrides)
        if settings.same_control:
            base.update(self.control_overrides(report, overrides))
        base.update(self.run_overrides(settings.scenario, overrides, f"{self.path}: voyage.equal_arrival"))
        label = f"{system.label} equal-arrival baseline"

        def arrival_of(speed_kn: float):
            run = read_voyage(label, runner(settings.scenario, {**base, settings.speed_key: speed_kn}, label))
            return (run.arrival_s if run.usable else None), run

        target_s = system.arrival_s
        if target_s is None:  # its callers match usable voyages only, which arrived
            raise ValueError(f"{system.label} did not arrive: no arrival time to match")
        first = (self.straight_distance_nm - self.arrival_radius_nm) / (target_s / 3600.0)
        return match_arrival_time(arrival_of, target_s, ARRIVAL_TOLERANCE_S, first, settings.max_trials)

    def control_overrides(self, report, overrides: Mapping[str, Any]) -> dict[str, Any]:
        """Overrides giving the baseline's control participant the options of the system's,
        so that both sides sail with the same NMPC settings (an offset-free observer on one
        side only would be compared, not the navigation).  Nothing when either scenario has
        no single participant of type "control"."""
        scenario = report.summary.get("scenario")
        if not scenario:
            return {}
        return self._same_control(load_scenario(Path(scenario), dict(report.summary.get("overrides") or {})),
                                  overrides)

    def _same_control(self, system, baseline_overrides: Mapping[str, Any]) -> dict[str, Any]:
        """:meth:`control_overrides` for a system sailed from the loaded scenario ``system``.

        Raises ScenarioError when the control options name files (strings) and the two
        scenarios lie in different folders, where those names would point elsewhere.
        """
        where = f"{self.path}: voyage.equal_arrival.same_control"
        baseline = load_scenario(self._equal.scenario, dict(baseline_overrides))
        controls = [[p for p in loaded.participants if p.type == "control"] for loaded in (system, baseline)]
        if any(len(found) != 1 for found in controls):
            return {}
        (own,), (theirs,) = controls
        if system.path.resolve().parent != self._equal.scenario.resolve().parent and any(
                isinstance(value, str) for value in own.options.values()):
            raise ScenarioError(f"{where}: {system.path} and {self._equal.scenario} lie in different "
                                "folders and the control options name files; put them side by side or "
                                "set same_control = false")
        return {f"participants.{theirs.name}.options": copy.deepcopy(dict(own.options))}

    def _needs_routing(self) -> bool:
        return self.optimal_route is not None or self.equal_arrival is not None

    def _route_costs(self, systems, baselines, overrides) -> dict[str, dict[str, Any]]:
        """Per system: straight and optimal routes at its arrival time, track and line at equal speed."""
        from rhnc.ship.energy import EnergyParameters
        from rhnc.weather.metocean_sources import from_scenario_table

        scenario = self.equal_arrival.scenario if self.equal_arrival else self.run_scenarios[self.labels[0]]
        loaded = load_scenario(scenario, dict(overrides))
        if loaded.metocean is None:
            log.info("%s: no [metocean] table, no route costs", scenario)
            return {}
        from rhnc.routing.track_cost import constant_speed_times, densify
        from rhnc.routing.routing_problem import plane_point
        from rhnc.routing.weather_routing import RoutingProblem, cost_of_track, optimal_route, straight_route

        metocean = from_scenario_table(loaded.metocean, loaded.directory,
                                                     f"{loaded.path}: metocean")
        energy = EnergyParameters()
        settings = self.optimal_route or OptimalRouteSettings()
        problem = RoutingProblem(plane_point(self.start_m), plane_point(self.goal_m), metocean, energy=energy,
                                 resolution_nm=settings.resolution_nm, avoid=settings.avoid_m)
        # a track may end in the part of the arrival circle off the map: it is costed, as it
        # was sailed, with the edge's weather held there; the routes stay on the map
        hold_nm = edge_hold_nm(metocean, self.goal_m, self.arrival_radius_nm)
        track_field = metocean if hold_nm is None else metocean.with_edges_held(hold_nm * NM)
        costs: dict[str, dict[str, Any]] = {}
        for label, system in systems.items():
            if not system.usable:
                continue
            entry: dict[str, Any] = {}
            if self.optimal_route is not None:
                try:
                    entry["straight"] = straight_route(problem, arrival_s=system.arrival_s)
                    entry["optimal"] = optimal_route(problem, arrival_s=system.arrival_s, speed_profile=True)
                except ValueError as exc:   # e.g. no speed arrives then: reported, the comparison goes on
                    log.warning("%s: no optimal route at %s's arrival: %s", self.path, label, exc)
                    entry.pop("straight", None)
                    entry["routing_error"] = str(exc)
            equal = baselines.get(label)
            if equal is not None and equal.usable:
                # both at the baseline's measured mean speed through water, from the same departure
                speed = equal.at_target(lambda t: t.run.mean_speed_through_water_kn) * KNOT
                track = densify(_with_goal(system.track_m, self.goal_m), settings.resolution_nm * NM / 2.0)
                line = densify(np.vstack([self.start_m, self.goal_m]), settings.resolution_nm * NM / 2.0)
                entry["equal_speed_kn"] = speed / KNOT
                for name, points in (("track_at_equal_speed", track), ("line_at_equal_speed", line)):
                    entry[name] = cost_of_track(track_field, energy, points,
                                                constant_speed_times(track_field, points, speed))
            costs[label] = entry
        return costs


def read_voyage(label: str, report) -> SailedVoyage:
    """The voyage figures and the track (up to arrival) of a finished run."""
    figures = report.summary.get("analyses", {}).get("voyage", {})
    folder = Path(report.folder)
    series = folder / report.summary.get("timeseries", "timeseries.parquet")
    track = np.empty((0, 2))
    if series.is_file():
        frame = pd.read_parquet(series) if series.suffix == ".parquet" else pd.read_csv(series)
        plant = next((c[:-2] for c in frame.columns if c.endswith(".x") and f"{c[:-2]}.psi" in frame.columns), None)
        if plant is not None:
            track = frame[[f"{plant}.x", f"{plant}.y"]].to_numpy(dtype=float)
            if figures.get("arrival_time_min") is not None:
                track = track[frame["time_s"].to_numpy() <= figures["arrival_time_min"] * 60.0 + 1e-6]
    arrival_min = figures.get("arrival_time_min")
    return SailedVoyage(
        label=label, status=report.status, arrived=bool(figures.get("arrived", False)),
        arrival_s=float(arrival_min) * 60.0 if arrival_min is not None else None,
        cost_usd=_float(figures.get("cost_usd")), co2_t=_float(figures.get("co2_t")),
        mean_speed_through_water_kn=_float(figures.get("mean_speed_through_water_kn")),
        distance_nm=_float(figures.get("distance_nm")), made_good_nm=_float(figures.get("made_good_nm")),
        track_m=track, folder=folder, reason=report.reason or "")


def _with_goal(track_m: np.ndarray, goal_m: np.ndarray) -> np.ndarray:
    """The track with the last leg to the goal itself (arrival is counted at a radius)."""
    points = np.vstack([track_m, goal_m])
    keep = np.concatenate([[True], np.hypot(*np.diff(points, axis=0).T) > 1e-6])
    return points[keep]


def _uses_steps(scenario: Path) -> bool:
    from orchestrator.scenario import read_toml

    data, _ = read_toml(scenario, "scenario")
    return "steps" in data.get("simulation", {})


def _float(value) -> float:
    return float(value) if is_finite_number(value) else math.nan


def unmet_criteria_flags(reports: Mapping[str, Any], baselines: Mapping[str, EqualArrival]) -> list[str]:
    """One flag per system, and per baseline, whose runs missed their scenario's own acceptance
    criteria (a track that came closer to land than its declared clearance, say): the comparison
    still tabulates them, but never as if they were fine."""
    flags = [f"{label}: acceptance not met: {'; '.join(report.failed_criteria)}"
             for label, report in reports.items() if getattr(report, "failed_criteria", None)]
    for label, baseline in baselines.items():
        failed = sorted({criterion for trial in baseline.trials
                         for criterion in getattr(trial.run, "failed_criteria", None) or []})
        if failed:
            flags.append(f"{label} equal-arrival baseline: acceptance not met in some trials: {'; '.join(failed)}")
    return flags
