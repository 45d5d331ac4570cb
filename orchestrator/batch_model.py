"""The tables of a batch file as pydantic models, and the Monte Carlo draws they describe.

Unknown keys are forbidden, numbers must be finite, and the number of runs a file asks for
is bounded (:data:`MAX_RUNS`) before any run is expanded.  Tables keyed by dotted scenario
keys (``[set]``, ``[grid]``, ``[monte_carlo.uniform]`` ...) are checked key by key so that a
message quotes the key as the file does: ``'grid."simulation.dt_s"'``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Annotated, Any

import numpy as np
from pydantic import PlainValidator, model_validator
from pydantic_core import PydanticCustomError

from orchestrator.errors import ScenarioError
from orchestrator.plugins import LazyModule
from orchestrator.toml_input import (Finite, FolderName, NonNegative, NonNegativeInt, PairNm, Positive, Table, Text,
                                     TomlTable, checked, fail, fail_whole, is_finite_number, shown, shown_text)

encounters = LazyModule("batch", "encounters")  # target placement, registered by the ship domain
DEFAULT_TARGETS_KEY = "participants.traffic.options.targets"
DEFAULT_OBSTACLES_KEY = "participants.traffic.options.static_obstacles"
#: Most runs one batch file may expand to (grid points x situations x draws).
MAX_RUNS = 100_000


@dataclass(frozen=True)
class Range:
    """A value drawn uniformly in ``[low, high]`` (``low == high``: a constant)."""

    low: float
    high: float

    def draw(self, rng: np.random.Generator) -> float:
        return float(rng.uniform(self.low, self.high)) if self.high > self.low else self.low


@dataclass(frozen=True)
class EncounterSpec:
    """One ``[[monte_carlo.encounters]]`` entry: one target ship in every run."""

    types: tuple[str, ...]
    cpa_nm: Range
    tcpa_min: Range
    speed_kn: Range
    course_offset_deg: Range
    radius_nm: Range
    passing_side: str | None  # None: drawn


@dataclass(frozen=True)
class ObstacleSpec:
    """``[monte_carlo.obstacles]``: circles placed relative to the own ship's initial track."""

    count: tuple[int, int]
    along_track_nm: Range
    cross_track_nm: Range
    radius_nm: Range


@dataclass(frozen=True)
class MonteCarloSpec:
    seed: int
    runs: int
    own_ship: encounters.ShipMotion | None  # type: ignore[name-defined]  # the domain's type, reached through the plug-in registry
    encounters: tuple[EncounterSpec, ...]
    encounter_count: tuple[int, int] | None  # None: every entry of ``encounters`` in every run
    obstacles: ObstacleSpec | None
    targets_key: str
    obstacles_key: str
    uniform: dict[str, Range]
    normal: dict[str, tuple[float, float]]
    choice: dict[str, list]
    scale: dict[str, tuple[Range, Any]]  # key -> (factor, the base scenario's value)


def range_of(value: Any) -> Range:
    """A number or ``[low, high]`` with ``low <= high`` as a :class:`Range`."""
    if is_finite_number(value):
        return Range(float(value), float(value))
    if isinstance(value, list) and len(value) == 2 and all(is_finite_number(v) for v in value) and value[0] <= value[1]:
        return Range(float(value[0]), float(value[1]))
    raise fail(f"must be a number or [low, high] with low <= high, got {shown(value)}")


Spread = Annotated[Range, PlainValidator(range_of)]


def _runs(value: Any) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or not 1 <= value <= MAX_RUNS:
        raise fail(f"must be a positive integer (at most {MAX_RUNS}), got {shown(value)}")
    return value


def _scenario_path(value: Any) -> str:
    if not isinstance(value, str) or not value or "\0" in value:
        raise fail("must name the base scenario file (relative to the batch file)")
    return value


class BatchTable(TomlTable):
    """``[batch]``: the name of the results folder and the base scenario."""

    name: FolderName | None = None
    scenario: Annotated[str, PlainValidator(_scenario_path)] | None = None
    description: Annotated[str, PlainValidator(lambda v: _string(v))] = ""

    @model_validator(mode="after")
    def _needs_scenario(self):
        if self.scenario is None:
            raise fail_whole("'{prefix}scenario' must name the base scenario file (relative to the batch file)")
        return self


def _string(value: Any) -> str:
    if not isinstance(value, str):
        raise fail("must be a string")
    return value


class OwnShipTable(TomlTable):
    """``[monte_carlo.own_ship]``: the own ship's straight initial track that encounters are placed on."""

    start_nm: PairNm
    course_deg: Finite
    speed_kn: Positive

    def motion(self) -> encounters.ShipMotion:  # type: ignore[name-defined]  # the domain's type, reached through the plug-in registry
        return encounters.ShipMotion.from_course(self.start_nm, self.course_deg, self.speed_kn)


def _types(value: Any) -> tuple[str, ...]:
    types = [value] if isinstance(value, str) else value
    if not isinstance(types, list) or not types or any(t not in encounters.ENCOUNTER_TYPES for t in types):
        raise fail(f"must be one of {', '.join(encounters.ENCOUNTER_TYPES)} or a list of them, got {shown(value)}")
    return tuple(types)


def _side(value: Any) -> str:
    if value not in encounters.PASSING_SIDES:
        raise fail(f"must be one of {', '.join(encounters.PASSING_SIDES)} (default: drawn), got {shown(value)}")
    return value


class EncounterTable(TomlTable):
    """One ``[[monte_carlo.encounters]]`` table."""

    type: Annotated[tuple[str, ...], PlainValidator(_types)]
    cpa_nm: Spread
    tcpa_min: Spread
    speed_kn: Spread
    course_offset_deg: Spread = Range(0.0, 0.0)
    radius_nm: Spread
    passing_side: Annotated[str, PlainValidator(_side)] | None = None

    @model_validator(mode="after")
    def _signs(self):
        if self.cpa_nm.low < 0 or self.tcpa_min.low <= 0 or self.speed_kn.low <= 0 or self.radius_nm.low < 0:
            raise fail_whole("'{prefix}': need cpa_nm >= 0, tcpa_min > 0, speed_kn > 0 and radius_nm >= 0")
        return self

    def spec(self, own: encounters.ShipMotion | None, where: str, key: str) -> EncounterSpec:  # type: ignore[name-defined]  # the domain's type, reached through the plug-in registry
        if own is not None and "overtaking" in self.type and self.speed_kn.high >= own.speed_kn:
            raise ScenarioError(f"{where}: '{key}.speed_kn': an overtaken target must be slower than the own ship "
                                f"({own.speed_kn:g} kn)")
        return EncounterSpec(types=self.type, cpa_nm=self.cpa_nm, tcpa_min=self.tcpa_min, speed_kn=self.speed_kn,
                             course_offset_deg=self.course_offset_deg, radius_nm=self.radius_nm,
                             passing_side=self.passing_side)


def _count(value: Any) -> tuple[int, int]:
    count = [value, value] if isinstance(value, int) and not isinstance(value, bool) else value
    integers = isinstance(count, list) and len(count) == 2 and all(
        isinstance(c, int) and not isinstance(c, bool) for c in count)
    if not (integers and 0 <= count[0] <= count[1] <= 10_000):
        raise fail("must be an integer or [low, high] integers, 0 <= low <= high <= 10000")
    return count[0], count[1]


class ObstacleTable(TomlTable):
    """``[monte_carlo.obstacles]``."""

    count: Annotated[tuple[int, int], PlainValidator(_count)] = (1, 1)
    along_track_nm: Spread
    cross_track_nm: Spread
    radius_nm: Spread

    def spec(self) -> ObstacleSpec:
        return ObstacleSpec(count=self.count, along_track_nm=self.along_track_nm, cross_track_nm=self.cross_track_nm,
                            radius_nm=self.radius_nm)


def _dotted_key(value: Any) -> str:
    if not isinstance(value, str) or not value or not all(value.split(".")):
        raise fail("must be a dotted scenario key")
    return value


class MonteCarloTable(TomlTable):
    """``[monte_carlo]``: seeded draws of encounters, obstacles and any scenario key."""

    seed: NonNegativeInt
    runs: Annotated[int, PlainValidator(_runs)]
    own_ship: OwnShipTable | None = None
    encounters: Annotated[list, PlainValidator(lambda v: _array_of_tables(v))] = []
    encounter_count: Annotated[tuple[int, int], PlainValidator(_count)] | None = None
    obstacles: ObstacleTable | None = None
    targets_key: Annotated[str, PlainValidator(_dotted_key)] = DEFAULT_TARGETS_KEY
    obstacles_key: Annotated[str, PlainValidator(_dotted_key)] = DEFAULT_OBSTACLES_KEY
    uniform: Table = {}
    normal: Table = {}
    choice: Table = {}
    scale: Table = {}

    @model_validator(mode="after")
    def _own_ship_for_placements(self):
        if (self.encounters or self.obstacles) and self.own_ship is None:
            raise fail_whole("'{prefix}own_ship' (start_nm, course_deg, speed_kn) is needed to place encounters "
                             "and obstacles")
        if self.encounter_count is not None and not 1 <= self.encounter_count[0] <= self.encounter_count[1] <= len(
                self.encounters):
            raise fail_whole(f"'{{prefix}}encounter_count' must be [low, high] with 1 <= low <= high <= "
                             f"{len(self.encounters)} (the number of [[monte_carlo.encounters]] entries), got "
                             f"{list(self.encounter_count)}")
        return self


def _array_of_tables(value: Any) -> list:
    if not isinstance(value, list) or not all(isinstance(e, dict) for e in value):
        raise fail("must be an array of tables ([[monte_carlo.encounters]])")
    return value


def monte_carlo_spec(table: Any, where: str, scenario_data: dict) -> MonteCarloSpec:
    """``[monte_carlo]`` checked into a :class:`MonteCarloSpec`."""
    model = checked(MonteCarloTable, table, where, ("monte_carlo",))
    own = model.own_ship.motion() if model.own_ship else None
    specs = []
    for k, entry in enumerate(model.encounters):
        encounter = checked(EncounterTable, entry, where, ("monte_carlo", "encounters", k))
        specs.append(encounter.spec(own, where, f"monte_carlo.encounters[{k}]"))
    obstacles = model.obstacles.spec() if model.obstacles is not None else None
    uniform = {key: _keyed(range_of, value, where, f'monte_carlo.uniform."{key}"')
               for key, value in model.uniform.items()}
    normal = {}
    for key, value in model.normal.items():
        if not (isinstance(value, list) and len(value) == 2 and all(is_finite_number(v) for v in value)
                and value[1] >= 0):
            raise ScenarioError(f"{where}: 'monte_carlo.normal.\"{shown_text(key)}\"' must be "
                                "[mean, standard deviation >= 0]")
        normal[key] = (float(value[0]), float(value[1]))
    choice = {}
    for key, value in model.choice.items():
        if not isinstance(value, list) or not value:
            raise ScenarioError(f"{where}: 'monte_carlo.choice.\"{shown_text(key)}\"' must be a non-empty list of "
                                "values")
        choice[key] = value
    scale = {}
    for key, value in model.scale.items():
        base = scenario_value(scenario_data, key)
        if base is None or not _numeric_tree(base):
            raise ScenarioError(f"{where}: 'monte_carlo.scale.\"{shown_text(key)}\"': the base scenario must set "
                                "this key to a number or a list of numbers")
        scale[key] = (_keyed(range_of, value, where, f'monte_carlo.scale."{key}"'), base)
    return MonteCarloSpec(seed=model.seed, runs=model.runs, own_ship=own, encounters=tuple(specs),
                          encounter_count=model.encounter_count,
                          obstacles=obstacles, targets_key=model.targets_key, obstacles_key=model.obstacles_key,
                          uniform=uniform, normal=normal, choice=choice, scale=scale)


def _keyed(check, value: Any, where: str, key: str):
    try:
        return check(value)
    except PydanticCustomError as exc:  # a field check's failure, raised outside a model
        raise ScenarioError(f"{where}: '{shown_text(key)}' {exc.message()}") from None


class SituationsTable(TomlTable):
    """``[situations]``: a folder (or one file) of traffic-situation JSON files, one run each."""

    files: Annotated[str, PlainValidator(lambda v: _files(v))]
    radius_nm: Annotated[float, PlainValidator(lambda v: _radius(v))]
    origin_nm: PairNm = (0.0, 0.0)
    route_nm: Positive = 15.0
    plant: Text = "ship"
    traffic: Text = "traffic"


def _files(value: Any) -> str:
    if not isinstance(value, str) or not value or "\0" in value:
        raise fail("must name a folder of traffic-situation JSON files or one file")
    return value


def _radius(value: Any) -> float:
    if not is_finite_number(value) or value < 0:
        raise fail(f"(each target's hazard radius R_i) must be a number >= 0, got {shown(value)}")
    return float(value)


class ReportTable(TomlTable):
    """``[report]``: extra columns of the batch table, and the time series the HTML report draws per run."""

    columns: Annotated[tuple[str, ...], PlainValidator(lambda v: _columns(v))] = ()
    series: Annotated[tuple[str, ...], PlainValidator(lambda v: _series(v))] = ()


def _columns(value: Any) -> tuple[str, ...]:
    if not isinstance(value, list) or not all(isinstance(c, str) and c for c in value):
        raise fail("must be a list of dotted paths into summary.json")
    return tuple(value)


def _series(value: Any) -> tuple[str, ...]:
    if not isinstance(value, list) or not all(isinstance(c, str) and c for c in value):
        raise fail("must be a list of time-series columns (\"<participant>.<port>\", e.g. \"ship.u\")")
    return tuple(value)


class BatchFile(TomlTable):
    """The top level of a batch file."""

    batch: Any = None
    set: Any = None
    grid: Any = None
    monte_carlo: Any = None
    situations: Any = None
    acceptance: Any = []
    report: Any = None
    search: Any = None  # read by orchestrator.search_spec

    @model_validator(mode="after")
    def _tables(self):
        if self.batch is None:
            raise fail_whole("missing table [batch]")
        for name in ("batch", "set", "grid", "monte_carlo", "situations", "report", "search"):
            value = getattr(self, name)
            if value is not None and not isinstance(value, dict):
                raise fail_whole(f"'{name}' must be a table ([{name}])")
        return self


def scenario_value(data: dict, dotted: str):
    """The value at a dotted key of a parsed scenario, or None."""
    node = data
    for key in dotted.split("."):
        if not isinstance(node, dict) or key not in node:
            return None
        node = node[key]
    return node


def _numeric_tree(value) -> bool:
    if isinstance(value, list):
        return bool(value) and all(_numeric_tree(v) for v in value)
    return is_finite_number(value)


def run_count(grid: dict[str, list], situations: int, draws: int) -> int:
    """Runs a batch expands to, computed without expanding it."""
    return math.prod(len(values) for values in grid.values()) * max(situations, 1) * max(draws, 1)


__all__ = ["BatchFile", "BatchTable", "EncounterSpec", "MAX_RUNS", "MonteCarloSpec", "NonNegative", "ObstacleSpec",
           "Range", "ReportTable", "SituationsTable", "monte_carlo_spec", "range_of", "run_count", "scenario_value"]
