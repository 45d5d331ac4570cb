"""Batch files: a base scenario plus grids, Monte Carlo draws and acceptance criteria, expanded into runs.

The format is documented in the README (section "Batches"); ``batches/*.toml`` are
commented examples.  Every error
names the batch file and the key and says what would be valid.  Each run is a set of
dotted-key overrides of the base scenario (see :func:`orchestrator.scenario.load_scenario`);
its id hashes the base scenario's bytes and the canonical JSON of its overrides, so the
same run always lands in the same folder.
"""

from __future__ import annotations

import hashlib
import itertools
import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from orchestrator.acceptance import Criterion, parse_acceptance
from orchestrator.batch_model import (DEFAULT_OBSTACLES_KEY, DEFAULT_TARGETS_KEY, MAX_RUNS, BatchFile, BatchTable,
                                      EncounterSpec, MonteCarloSpec, ObstacleSpec, Range, ReportTable,
                                      SituationsTable, monte_carlo_spec, run_count)
from orchestrator.errors import ScenarioError
from orchestrator.plugins import LazyModule
from orchestrator.toml_input import checked, default_folder_name, read_toml, shown_text

__all__ = ["BatchSpec", "Criterion", "DEFAULT_OBSTACLES_KEY", "DEFAULT_TARGETS_KEY", "EncounterSpec", "MAX_RUNS",
           "MonteCarloSpec", "ObstacleSpec", "Range", "RunSpec", "SituationRun", "load_batch", "parse_acceptance",
           "run_id"]
encounters = LazyModule("batch", "encounters")  # target placement, registered by the ship domain
#: Decimals kept of a drawn value: 1e-6 nm is 2 mm; keeps overrides readable and ids stable.
DRAW_DECIMALS = 6


@dataclass(frozen=True)
class SituationRun:
    """One traffic-situation file of ``[situations]``: its overrides and table parameters."""

    overrides: dict[str, Any]
    parameters: dict[str, Any]


@dataclass(frozen=True)
class RunSpec:
    """One run of a batch: its id, overrides and the parameters shown in the table."""

    run_id: str
    index: int
    overrides: dict[str, Any]
    parameters: dict[str, Any]


@dataclass(frozen=True)
class BatchSpec:
    """A loaded, checked batch file."""

    path: Path
    name: str
    scenario: Path
    scenario_sha256: str
    fixed: dict[str, Any]
    grid: dict[str, list]
    monte_carlo: MonteCarloSpec | None
    acceptance: tuple[Criterion, ...]
    report_columns: tuple[str, ...]
    description: str = ""
    situations: tuple[SituationRun, ...] = ()
    report_series: tuple[str, ...] = ()
    search: dict | None = None  # the raw [search] table (orchestrator.search_spec checks it)
    _runs: list = field(default_factory=list, repr=False, compare=False)

    def runs(self) -> list[RunSpec]:
        """Every run: the grid's cartesian product, each point with every Monte Carlo draw."""
        if not self._runs:
            self._runs.extend(_expand(self))
        return list(self._runs)


def run_id(scenario_sha256: str, overrides: dict[str, Any]) -> str:
    """Stable id of a run: 12 hex digits of the hash of the base scenario and the overrides."""
    canonical = json.dumps({"scenario_sha256": scenario_sha256, "overrides": overrides},
                           sort_keys=True, separators=(",", ":"), default=str)
    return hashlib.sha256(canonical.encode()).hexdigest()[:12]


def load_batch(path) -> BatchSpec:
    """Read and check a batch file.

    Parameters
    ----------
    path : path-like
        The batch TOML file; ``batch.scenario`` resolves against its folder.

    Raises
    ------
    ScenarioError
        For a missing file, a TOML error, an unknown key, a wrong type or value; the
        message names the batch file and the key.
    """
    path = Path(path)
    data, _ = read_toml(path, "batch")
    where = str(path)
    top = checked(BatchFile, data, where)
    batch = checked(BatchTable, top.batch, where, ("batch",))
    name = batch.name or default_folder_name(path.stem, "batch.name", where)
    scenario = (path.parent / batch.scenario).resolve()
    if not scenario.is_file():
        raise ScenarioError(f"{where}: 'batch.scenario': scenario file not found: {scenario}")
    fixed = top.set or {}
    grid = top.grid or {}
    for key, values in grid.items():
        if not isinstance(values, list) or not values:
            raise ScenarioError(f"{where}: 'grid.\"{shown_text(key)}\"' must be a non-empty list of values")
        if len({_canonical(v) for v in values}) != len(values):
            raise ScenarioError(f"{where}: 'grid.\"{shown_text(key)}\"' lists a value twice")
    scenario_data, _ = read_toml(scenario, "scenario")
    monte_carlo = monte_carlo_spec(top.monte_carlo, where, scenario_data) if top.monte_carlo is not None else None
    situations: tuple[SituationRun, ...] = ()
    if top.situations is not None:
        situations = _situations(top.situations, path, scenario_data)
    total = run_count(grid, len(situations), monte_carlo.runs if monte_carlo else 1)
    if total > MAX_RUNS:
        raise ScenarioError(f"{where}: the batch expands to {total} runs ([grid] x [situations] x "
                            f"'monte_carlo.runs'), more than the limit of {MAX_RUNS}")
    keys = [("set", k) for k in fixed] + [("grid", k) for k in grid] + (
        [("monte_carlo", k) for k in _drawn_keys(monte_carlo)] if monte_carlo else []) + (
        [("situations", k) for k in situations[0].overrides] if situations else [])
    _check_keys(keys, where)
    acceptance = parse_acceptance(top.acceptance, where)
    report = checked(ReportTable, top.report or {}, where, ("report",))
    return BatchSpec(path=path.resolve(), name=name, scenario=scenario,
                     scenario_sha256=hashlib.sha256(scenario.read_bytes()).hexdigest(), fixed=fixed, grid=grid,
                     monte_carlo=monte_carlo, acceptance=acceptance, report_columns=report.columns,
                     description=batch.description, situations=situations, report_series=report.series,
                     search=top.search)


# -- expansion ------------------------------------------------------------------------------
def _expand(spec: BatchSpec) -> list[RunSpec]:
    keys = list(spec.grid)
    points = list(itertools.product(*(spec.grid[k] for k in keys))) or [()]
    draws = [_draw(spec.monte_carlo, i) for i in range(spec.monte_carlo.runs)] if spec.monte_carlo else [({}, {})]
    situations = [(s.overrides, s.parameters) for s in spec.situations] or [({}, {})]
    runs: list[RunSpec] = []
    seen: dict[str, int] = {}  # run id -> index of the run that has it
    for point, (situation_overrides, situation_parameters), (draw_overrides, draw_parameters) in itertools.product(
            points, situations, draws):
        overrides = {**spec.fixed, **dict(zip(keys, point)), **situation_overrides, **draw_overrides}
        parameters = {**dict(zip(keys, point)), **situation_parameters, **draw_parameters}
        # two situation files may hold the same geometry (Imazu's problems 5 and 8): the
        # file's name keeps their runs apart
        hashed = {**overrides, "<situation>": situation_parameters["situation"]} if situation_parameters else overrides
        identifier = run_id(spec.scenario_sha256, hashed)
        if identifier in seen:
            raise ScenarioError(f"{spec.path}: runs {seen[identifier]} and {len(runs)} are identical "
                                f"(same overrides); vary the grid or the draws")
        seen[identifier] = len(runs)
        runs.append(RunSpec(identifier, len(runs), overrides, parameters))
    return runs


def _draw(mc: MonteCarloSpec, index: int) -> tuple[dict, dict]:
    """Overrides and table parameters of draw ``index``: its own stream, so draws never shift."""
    overrides, parameters = draw_overrides(mc, RandomChoices(np.random.default_rng([mc.seed, index])))
    return overrides, {"draw": index, **parameters}


class RandomChoices:
    """The values of a Monte Carlo draw, from one seeded NumPy stream (uniform, as declared)."""

    def __init__(self, rng: np.random.Generator) -> None:
        self.rng = rng

    def number(self, name: str, span: Range) -> float:
        return span.draw(self.rng)

    def index(self, name: str, options: list | tuple) -> int:
        return int(self.rng.integers(len(options)))

    def integer(self, name: str, low: int, high: int) -> int:
        return int(self.rng.integers(low, high + 1))

    def normal(self, name: str, mean: float, sd: float) -> float:
        return float(self.rng.normal(mean, sd))


def draw_overrides(mc: MonteCarloSpec, choices) -> tuple[dict, dict]:
    """Overrides and table parameters of one point of the ``[monte_carlo]`` space.

    ``choices`` picks every value, by the parameter's table name: :class:`RandomChoices`
    draws them (a batch), an optimiser suggests them (a search, :mod:`orchestrator.search`).
    """
    overrides: dict[str, Any] = {}
    parameters: dict[str, Any] = {}
    if mc.encounters:
        targets = []
        used = mc.encounters
        if mc.encounter_count is not None:
            count = choices.integer("encounters.count", *mc.encounter_count)
            used = mc.encounters[:count]
            parameters["encounters.count"] = count
        for k, enc in enumerate(used):
            kind = enc.types[choices.index(f"enc{k}.type", enc.types)]
            cpa, tcpa = choices.number(f"enc{k}.cpa_nm", enc.cpa_nm), choices.number(f"enc{k}.tcpa_min", enc.tcpa_min)
            speed = choices.number(f"enc{k}.speed_kn", enc.speed_kn)
            offset = choices.number(f"enc{k}.course_offset_deg", enc.course_offset_deg)
            side = enc.passing_side or encounters.PASSING_SIDES[choices.index(f"enc{k}.passing_side",
                                                                             encounters.PASSING_SIDES)]
            target = encounters.place_target(mc.own_ship, kind, cpa, tcpa, speed, offset, side)
            targets.append({"start_nm": _rounded(target.start_nm), "velocity_kn": _rounded(target.velocity_kn),
                            "radius_nm": _round(choices.number(f"enc{k}.radius_nm", enc.radius_nm))})
            parameters.update({f"enc{k}.type": kind, f"enc{k}.cpa_nm": _round(cpa), f"enc{k}.tcpa_min": _round(tcpa),
                               f"enc{k}.speed_kn": _round(speed), f"enc{k}.passing_side": side})
        overrides[mc.targets_key] = targets
    if mc.obstacles is not None:
        obstacles = []
        count = choices.integer("obstacles.count", *mc.obstacles.count)
        own_ship = mc.own_ship
        assert own_ship is not None  # obstacles are placed along the own ship's track (required on reading)
        heading = np.asarray(own_ship.velocity_kn) / own_ship.speed_kn
        starboard = np.array([-heading[1], heading[0]])
        for j in range(count):
            along = choices.number(f"obs{j}.along_track_nm", mc.obstacles.along_track_nm)
            cross = choices.number(f"obs{j}.cross_track_nm", mc.obstacles.cross_track_nm)
            center = np.asarray(own_ship.start_nm) + along * heading + cross * starboard
            obstacles.append({"center_nm": _rounded(center),
                              "radius_nm": _round(choices.number(f"obs{j}.radius_nm", mc.obstacles.radius_nm))})
        overrides[mc.obstacles_key] = obstacles
        parameters["obstacles.count"] = count
    for key, span in mc.uniform.items():
        overrides[key] = parameters[key] = _round(choices.number(key, span))
    for key, (mean, sd) in mc.normal.items():
        overrides[key] = parameters[key] = _round(choices.normal(key, mean, sd))
    for key, options in mc.choice.items():
        overrides[key] = parameters[key] = options[choices.index(key, options)]
    for key, (factor_range, base) in mc.scale.items():
        factor = _round(choices.number(f"{key} (scale)", factor_range))
        overrides[key] = _scaled(base, factor)
        parameters[f"{key} (scale)"] = factor
    return overrides, parameters


def _scaled(value, factor: float):
    if isinstance(value, list):
        return [_scaled(v, factor) for v in value]
    return _round(value * factor)


def _round(value: float) -> float:
    return round(float(value), DRAW_DECIMALS) + 0.0  # + 0.0: no negative zero in the JSON


def _rounded(values) -> list[float]:
    return [_round(v) for v in values]


def _canonical(value) -> str:
    return json.dumps(value, sort_keys=True, default=str)


# -- parsing --------------------------------------------------------------------------------
def _drawn_keys(mc: MonteCarloSpec) -> list[str]:
    keys = ([mc.targets_key] if mc.encounters else []) + ([mc.obstacles_key] if mc.obstacles else [])
    return keys + list(mc.uniform) + list(mc.normal) + list(mc.choice) + list(mc.scale)


def _check_keys(keys: list[tuple[str, str]], where: str) -> None:
    """Each scenario key varies in one place only, and no key lies inside another."""
    for (table_a, a), (table_b, b) in itertools.combinations(keys, 2):
        if a == b or a.startswith(b + ".") or b.startswith(a + "."):
            raise ScenarioError(f"{where}: '{table_a}.\"{shown_text(a)}\"' and '{table_b}.\"{shown_text(b)}\"' set the "
                                "same scenario value")
    for table, key in keys:
        if not key or not all(key.split(".")):
            raise ScenarioError(f"{where}: '{table}.\"{shown_text(key)}\"' is not a dotted scenario key")


def _situations(table: dict, path: Path, scenario_data: dict) -> tuple[SituationRun, ...]:
    """``[situations]``: one run per maritime-schema traffic-situation file (DNV trafficgen).

    ``files`` is a folder (every ``*.json`` in it, sorted) or one file, relative to the batch
    file; each becomes the overrides of the ``scenario_overrides`` of the registered ``situations`` module.
    """
    situations = LazyModule("batch", "situations")
    load_traffic_situation, scenario_overrides = situations.load_traffic_situation, situations.scenario_overrides

    where = str(path)
    model = checked(SituationsTable, table, where, ("situations",))
    location = (path.parent / model.files).resolve()
    if location.is_dir():
        found = sorted(location.glob("*.json"))
        if not found:
            raise ScenarioError(f"{where}: 'situations.files': no *.json files in {location}")
    elif location.is_file():
        found = [location]
    else:
        raise ScenarioError(f"{where}: 'situations.files': not found: {location}")
    origin, radius, route = model.origin_nm, model.radius_nm, model.route_nm
    names = {"plant": model.plant, "traffic": model.traffic}
    runs = []
    for file in found:
        situation = load_traffic_situation(file, origin)
        overrides = scenario_overrides(situation, scenario_data, float(radius), float(route), **names)
        parameters = {"situation": file.name, "situation.title": situation.title,
                      "situation.targets": len(situation.targets)}
        runs.append(SituationRun(overrides, parameters))
    return tuple(runs)
