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

from orchestrator.plugins import LazyModule
from orchestrator.participant import is_finite_number
from orchestrator.errors import ScenarioError
from orchestrator.scenario import read_toml

BATCH_TOP_KEYS = ("batch", "set", "grid", "monte_carlo", "situations", "acceptance", "report")
SITUATION_KEYS = ("files", "radius_nm", "origin_nm", "route_nm", "plant", "traffic")
BATCH_KEYS = ("name", "scenario", "description")
encounters = LazyModule("batch", "encounters")  # target placement, registered by the ship domain
MONTE_CARLO_KEYS = ("seed", "runs", "own_ship", "encounters", "obstacles", "targets_key", "obstacles_key",
                    "uniform", "normal", "choice", "scale")
OWN_SHIP_KEYS = ("start_nm", "course_deg", "speed_kn")
ENCOUNTER_KEYS = ("type", "cpa_nm", "tcpa_min", "speed_kn", "course_offset_deg", "radius_nm", "passing_side")
OBSTACLE_KEYS = ("count", "along_track_nm", "cross_track_nm", "radius_nm")
CRITERION_KEYS = ("name", "metric", "op", "value", "ref")
REPORT_KEYS = ("columns",)
OPERATORS = ("<", "<=", "==", "!=", ">=", ">")
DEFAULT_TARGETS_KEY = "participants.traffic.options.targets"
DEFAULT_OBSTACLES_KEY = "participants.traffic.options.static_obstacles"
#: Decimals kept of a drawn value: 1e-6 nm is 2 mm; keeps overrides readable and ids stable.
DRAW_DECIMALS = 6


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
    own_ship: encounters.ShipMotion | None
    encounters: tuple[EncounterSpec, ...]
    obstacles: ObstacleSpec | None
    targets_key: str
    obstacles_key: str
    uniform: dict[str, Range]
    normal: dict[str, tuple[float, float]]
    choice: dict[str, list]
    scale: dict[str, tuple[Range, Any]]  # key -> (factor, the base scenario's value)


@dataclass(frozen=True)
class SituationRun:
    """One traffic-situation file of ``[situations]``: its overrides and table parameters."""

    overrides: dict[str, Any]
    parameters: dict[str, Any]


@dataclass(frozen=True)
class Criterion:
    """``[[acceptance]]``: ``metric op value`` or ``metric op ref``, paths into summary.json."""

    name: str
    metric: str
    op: str
    value: Any = None
    ref: str | None = None

    def describe(self) -> str:
        return f"{self.metric} {self.op} {self.ref if self.ref is not None else json.dumps(self.value)}"


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
    _reject_unknown(data, BATCH_TOP_KEYS, where, "")
    batch = _table(data, "batch", where, "batch", required=True)
    _reject_unknown(batch, BATCH_KEYS, where, "batch.")
    name = batch.get("name", path.stem)
    if not isinstance(name, str) or not name or any(c in name for c in "/\\") or name.startswith("."):
        raise ScenarioError(f"{where}: 'batch.name' must be a non-empty string without slashes")
    if not isinstance(batch.get("scenario"), str):
        raise ScenarioError(f"{where}: 'batch.scenario' must name the base scenario file (relative to the batch file)")
    scenario = (path.parent / batch["scenario"]).resolve()
    if not scenario.is_file():
        raise ScenarioError(f"{where}: 'batch.scenario': scenario file not found: {scenario}")
    description = batch.get("description", "")
    if not isinstance(description, str):
        raise ScenarioError(f"{where}: 'batch.description' must be a string")
    fixed = _table(data, "set", where, "set", required=False)
    grid = _table(data, "grid", where, "grid", required=False)
    for key, values in grid.items():
        if not isinstance(values, list) or not values:
            raise ScenarioError(f"{where}: 'grid.\"{key}\"' must be a non-empty list of values")
        if len({_canonical(v) for v in values}) != len(values):
            raise ScenarioError(f"{where}: 'grid.\"{key}\"' lists a value twice")
    scenario_data, _ = read_toml(scenario, "scenario")
    monte_carlo = None
    if "monte_carlo" in data:
        monte_carlo = _monte_carlo(_table(data, "monte_carlo", where, "monte_carlo", True), where, scenario_data)
    situations: tuple[SituationRun, ...] = ()
    if "situations" in data:
        situations = _situations(_table(data, "situations", where, "situations", True), path, scenario_data)
    keys = [("set", k) for k in fixed] + [("grid", k) for k in grid] + (
        [("monte_carlo", k) for k in _drawn_keys(monte_carlo)] if monte_carlo else []) + (
        [("situations", k) for k in situations[0].overrides] if situations else [])
    _check_keys(keys, where)
    acceptance = parse_acceptance(data.get("acceptance", []), where)
    report = _table(data, "report", where, "report", required=False)
    _reject_unknown(report, REPORT_KEYS, where, "report.")
    columns = report.get("columns", [])
    if not isinstance(columns, list) or not all(isinstance(c, str) and c for c in columns):
        raise ScenarioError(f"{where}: 'report.columns' must be a list of dotted paths into summary.json")
    return BatchSpec(path=path.resolve(), name=name, scenario=scenario,
                     scenario_sha256=hashlib.sha256(scenario.read_bytes()).hexdigest(), fixed=fixed, grid=grid,
                     monte_carlo=monte_carlo, acceptance=acceptance, report_columns=tuple(columns),
                     description=description, situations=situations)


# -- expansion ------------------------------------------------------------------------------
def _expand(spec: BatchSpec) -> list[RunSpec]:
    keys = list(spec.grid)
    points = list(itertools.product(*(spec.grid[k] for k in keys))) or [()]
    draws = [_draw(spec.monte_carlo, i) for i in range(spec.monte_carlo.runs)] if spec.monte_carlo else [({}, {})]
    situations = [(s.overrides, s.parameters) for s in spec.situations] or [({}, {})]
    runs, seen = [], {}
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
    rng = np.random.default_rng([mc.seed, index])
    overrides: dict[str, Any] = {}
    parameters: dict[str, Any] = {"draw": index}
    if mc.encounters:
        targets = []
        for k, enc in enumerate(mc.encounters):
            kind = enc.types[int(rng.integers(len(enc.types)))]
            cpa, tcpa = enc.cpa_nm.draw(rng), enc.tcpa_min.draw(rng)
            speed, offset = enc.speed_kn.draw(rng), enc.course_offset_deg.draw(rng)
            side = enc.passing_side or encounters.PASSING_SIDES[int(rng.integers(2))]
            target = encounters.place_target(mc.own_ship, kind, cpa, tcpa, speed, offset, side)
            targets.append({"start_nm": _rounded(target.start_nm), "velocity_kn": _rounded(target.velocity_kn),
                            "radius_nm": _round(enc.radius_nm.draw(rng))})
            parameters.update({f"enc{k}.type": kind, f"enc{k}.cpa_nm": _round(cpa), f"enc{k}.tcpa_min": _round(tcpa),
                               f"enc{k}.speed_kn": _round(speed), f"enc{k}.passing_side": side})
        overrides[mc.targets_key] = targets
    if mc.obstacles is not None:
        obstacles = []
        count = int(rng.integers(mc.obstacles.count[0], mc.obstacles.count[1] + 1))
        heading = np.asarray(mc.own_ship.velocity_kn) / mc.own_ship.speed_kn
        starboard = np.array([-heading[1], heading[0]])
        for _ in range(count):
            along, cross = mc.obstacles.along_track_nm.draw(rng), mc.obstacles.cross_track_nm.draw(rng)
            center = np.asarray(mc.own_ship.start_nm) + along * heading + cross * starboard
            obstacles.append({"center_nm": _rounded(center), "radius_nm": _round(mc.obstacles.radius_nm.draw(rng))})
        overrides[mc.obstacles_key] = obstacles
        parameters["obstacles.count"] = count
    for key, span in mc.uniform.items():
        overrides[key] = parameters[key] = _round(span.draw(rng))
    for key, (mean, sd) in mc.normal.items():
        overrides[key] = parameters[key] = _round(float(rng.normal(mean, sd)))
    for key, options in mc.choice.items():
        overrides[key] = parameters[key] = options[int(rng.integers(len(options)))]
    for key, (factor_range, base) in mc.scale.items():
        factor = _round(factor_range.draw(rng))
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
            raise ScenarioError(f"{where}: '{table_a}.\"{a}\"' and '{table_b}.\"{b}\"' set the same scenario value")
    for table, key in keys:
        if not key or not all(key.split(".")):
            raise ScenarioError(f"{where}: '{table}.\"{key}\"' is not a dotted scenario key")


def _monte_carlo(table: dict, where: str, scenario_data: dict) -> MonteCarloSpec:
    _reject_unknown(table, MONTE_CARLO_KEYS, where, "monte_carlo.")
    seed = table.get("seed")
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise ScenarioError(f"{where}: 'monte_carlo.seed' must be a non-negative integer, got {seed!r}")
    runs = table.get("runs")
    if isinstance(runs, bool) or not isinstance(runs, int) or runs < 1:
        raise ScenarioError(f"{where}: 'monte_carlo.runs' must be a positive integer, got {runs!r}")
    own = None
    if "own_ship" in table:
        own_table = _table(table, "own_ship", where, "monte_carlo.own_ship", required=True)
        _reject_unknown(own_table, OWN_SHIP_KEYS, where, "monte_carlo.own_ship.")
        start = _pair(own_table, "start_nm", where, "monte_carlo.own_ship.")
        course = _number(own_table, "course_deg", where, "monte_carlo.own_ship.")
        speed = _number(own_table, "speed_kn", where, "monte_carlo.own_ship.", positive=True)
        own = encounters.ShipMotion.from_course(start, course, speed)
    entries = table.get("encounters", [])
    if not isinstance(entries, list) or not all(isinstance(e, dict) for e in entries):
        raise ScenarioError(f"{where}: 'monte_carlo.encounters' must be an array of tables ([[monte_carlo.encounters]])")
    encounter_specs = tuple(_encounter(e, where, f"monte_carlo.encounters[{k}].", own) for k, e in enumerate(entries))
    obstacles = None
    if "obstacles" in table:
        obstacles = _obstacles(_table(table, "obstacles", where, "monte_carlo.obstacles", True), where)
    if (encounter_specs or obstacles) and own is None:
        raise ScenarioError(f"{where}: 'monte_carlo.own_ship' (start_nm, course_deg, speed_kn) is needed to place "
                            f"encounters and obstacles")
    keys = {}
    for key in ("targets_key", "obstacles_key"):
        keys[key] = table.get(key, DEFAULT_TARGETS_KEY if key == "targets_key" else DEFAULT_OBSTACLES_KEY)
        if not isinstance(keys[key], str):
            raise ScenarioError(f"{where}: 'monte_carlo.{key}' must be a dotted scenario key")
    uniform = {k: _range(v, where, f'monte_carlo.uniform."{k}"')
               for k, v in _table(table, "uniform", where, "monte_carlo.uniform", False).items()}
    normal = {}
    for key, value in _table(table, "normal", where, "monte_carlo.normal", False).items():
        if not (isinstance(value, list) and len(value) == 2 and all(is_finite_number(v) for v in value) and value[1] >= 0):
            raise ScenarioError(f"{where}: 'monte_carlo.normal.\"{key}\"' must be [mean, standard deviation >= 0]")
        normal[key] = (float(value[0]), float(value[1]))
    choice = {}
    for key, value in _table(table, "choice", where, "monte_carlo.choice", False).items():
        if not isinstance(value, list) or not value:
            raise ScenarioError(f"{where}: 'monte_carlo.choice.\"{key}\"' must be a non-empty list of values")
        choice[key] = value
    scale = {}
    for key, value in _table(table, "scale", where, "monte_carlo.scale", False).items():
        base = _scenario_value(scenario_data, key)
        if base is None or not _numeric_tree(base):
            raise ScenarioError(f"{where}: 'monte_carlo.scale.\"{key}\"': the base scenario must set this key to a "
                                f"number or a list of numbers")
        scale[key] = (_range(value, where, f'monte_carlo.scale."{key}"'), base)
    return MonteCarloSpec(seed=seed, runs=runs, own_ship=own, encounters=encounter_specs, obstacles=obstacles,
                          uniform=uniform, normal=normal, choice=choice, scale=scale, **keys)


def _situations(table: dict, path: Path, scenario_data: dict) -> tuple[SituationRun, ...]:
    """``[situations]``: one run per maritime-schema traffic-situation file (DNV trafficgen).

    ``files`` is a folder (every ``*.json`` in it, sorted) or one file, relative to the batch
    file; each becomes the overrides of the ``scenario_overrides`` of the registered ``situations`` module.
    """
    situations = LazyModule("batch", "situations")
    load_traffic_situation, scenario_overrides = situations.load_traffic_situation, situations.scenario_overrides

    where, prefix = str(path), "situations."
    _reject_unknown(table, SITUATION_KEYS, where, prefix)
    files = table.get("files")
    if not isinstance(files, str) or not files:
        raise ScenarioError(f"{where}: '{prefix}files' must name a folder of traffic-situation JSON files or one file")
    location = (path.parent / files).resolve()
    if location.is_dir():
        found = sorted(location.glob("*.json"))
        if not found:
            raise ScenarioError(f"{where}: '{prefix}files': no *.json files in {location}")
    elif location.is_file():
        found = [location]
    else:
        raise ScenarioError(f"{where}: '{prefix}files': not found: {location}")
    radius = table.get("radius_nm")
    if not is_finite_number(radius) or radius < 0:
        raise ScenarioError(f"{where}: '{prefix}radius_nm' (each target's hazard radius R_i) must be a number >= 0, "
                            f"got {radius!r}")
    origin = _pair(table, "origin_nm", where, prefix) if "origin_nm" in table else (0.0, 0.0)
    route = table.get("route_nm", 15.0)
    if not is_finite_number(route) or route <= 0:
        raise ScenarioError(f"{where}: '{prefix}route_nm' must be a positive number, got {route!r}")
    names = {}
    for key in ("plant", "traffic"):
        names[key] = table.get(key, "ship" if key == "plant" else "traffic")
        if not isinstance(names[key], str) or not names[key]:
            raise ScenarioError(f"{where}: '{prefix}{key}' must name a participant of the base scenario")
    runs = []
    for file in found:
        situation = load_traffic_situation(file, origin)
        overrides = scenario_overrides(situation, scenario_data, float(radius), float(route), **names)
        parameters = {"situation": file.name, "situation.title": situation.title,
                      "situation.targets": len(situation.targets)}
        runs.append(SituationRun(overrides, parameters))
    return tuple(runs)


def _encounter(entry: dict, where: str, prefix: str, own) -> EncounterSpec:
    _reject_unknown(entry, ENCOUNTER_KEYS, where, prefix)
    types = entry.get("type")
    types = [types] if isinstance(types, str) else types
    if not isinstance(types, list) or not types or any(t not in encounters.ENCOUNTER_TYPES for t in types):
        raise ScenarioError(f"{where}: '{prefix}type' must be one of {', '.join(encounters.ENCOUNTER_TYPES)} "
                            f"or a list of them, got {entry.get('type')!r}")
    side = entry.get("passing_side")
    if side is not None and side not in encounters.PASSING_SIDES:
        raise ScenarioError(f"{where}: '{prefix}passing_side' must be one of {', '.join(encounters.PASSING_SIDES)} "
                            f"(default: drawn), got {side!r}")
    spans = {}
    for key, default in (("cpa_nm", None), ("tcpa_min", None), ("speed_kn", None),
                         ("course_offset_deg", 0.0), ("radius_nm", None)):
        if key not in entry and default is None:
            raise ScenarioError(f"{where}: missing key '{prefix}{key}' (a number or [low, high])")
        spans[key] = _range(entry.get(key, default), where, prefix + key)
    if spans["cpa_nm"].low < 0 or spans["tcpa_min"].low <= 0 or spans["speed_kn"].low <= 0 or spans["radius_nm"].low < 0:
        raise ScenarioError(f"{where}: '{prefix}': need cpa_nm >= 0, tcpa_min > 0, speed_kn > 0 and radius_nm >= 0")
    if own is not None and "overtaking" in types and spans["speed_kn"].high >= own.speed_kn:
        raise ScenarioError(f"{where}: '{prefix}speed_kn': an overtaken target must be slower than the own ship "
                            f"({own.speed_kn:g} kn)")
    return EncounterSpec(types=tuple(types), passing_side=side, **spans)


def _obstacles(table: dict, where: str) -> ObstacleSpec:
    prefix = "monte_carlo.obstacles."
    _reject_unknown(table, OBSTACLE_KEYS, where, prefix)
    count = table.get("count", 1)
    count = [count, count] if isinstance(count, int) and not isinstance(count, bool) else count
    if not (isinstance(count, list) and len(count) == 2 and all(isinstance(c, int) and not isinstance(c, bool)
                                                                 for c in count) and 0 <= count[0] <= count[1]):
        raise ScenarioError(f"{where}: '{prefix}count' must be an integer or [low, high] integers, 0 <= low <= high")
    spans = {}
    for key in ("along_track_nm", "cross_track_nm", "radius_nm"):
        if key not in table:
            raise ScenarioError(f"{where}: missing key '{prefix}{key}' (a number or [low, high])")
        spans[key] = _range(table[key], where, prefix + key)
    return ObstacleSpec(count=(count[0], count[1]), **spans)


def parse_acceptance(entries, where: str) -> tuple[Criterion, ...]:
    """``[[acceptance]]`` entries of a batch or scenario file, checked; errors name file and key."""
    if not isinstance(entries, list) or not all(isinstance(e, dict) for e in entries):
        raise ScenarioError(f"{where}: 'acceptance' must be an array of tables ([[acceptance]])")
    criteria, names = [], set()
    for k, entry in enumerate(entries):
        prefix = f"acceptance[{k}]."
        _reject_unknown(entry, CRITERION_KEYS, where, prefix)
        metric = entry.get("metric")
        if not isinstance(metric, str) or not metric:
            raise ScenarioError(f"{where}: '{prefix}metric' must be a dotted path into summary.json")
        op = entry.get("op")
        if op not in OPERATORS:
            raise ScenarioError(f"{where}: '{prefix}op' must be one of {' '.join(OPERATORS)}, got {op!r}")
        if ("value" in entry) == ("ref" in entry):
            raise ScenarioError(f"{where}: '{prefix}': give exactly one of 'value' (a literal) or 'ref' "
                                f"(figures of the summary joined by ' + ' / ' - ')")
        ref = entry.get("ref")
        if ref is not None and (not isinstance(ref, str) or not ref.strip()):
            raise ScenarioError(f"{where}: '{prefix}ref' must be a string such as \"a.b + c.d + 0.1\"")
        name = entry.get("name", metric)
        if not isinstance(name, str) or not name or name in names:
            raise ScenarioError(f"{where}: '{prefix}name' must be a unique non-empty string, got {name!r}")
        names.add(name)
        criteria.append(Criterion(name=name, metric=metric, op=op, value=entry.get("value"), ref=ref))
    return tuple(criteria)


def _scenario_value(data: dict, dotted: str):
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


def _range(value, where: str, key: str) -> Range:
    if is_finite_number(value):
        return Range(float(value), float(value))
    if isinstance(value, list) and len(value) == 2 and all(is_finite_number(v) for v in value) and value[0] <= value[1]:
        return Range(float(value[0]), float(value[1]))
    raise ScenarioError(f"{where}: '{key}' must be a number or [low, high] with low <= high, got {value!r}")


def _pair(table: dict, key: str, where: str, prefix: str) -> tuple[float, float]:
    value = table.get(key)
    if not (isinstance(value, list) and len(value) == 2 and all(is_finite_number(v) for v in value)):
        raise ScenarioError(f"{where}: '{prefix}{key}' must be [north, east] in nm, got {value!r}")
    return float(value[0]), float(value[1])


def _number(table: dict, key: str, where: str, prefix: str, positive: bool = False) -> float:
    value = table.get(key)
    if not is_finite_number(value) or (positive and value <= 0):
        kind = "a positive number" if positive else "a finite number"
        raise ScenarioError(f"{where}: '{prefix}{key}' must be {kind}, got {value!r}")
    return float(value)


def _table(data: dict, key: str, where: str, name: str, required: bool) -> dict:
    if key not in data:
        if required:
            raise ScenarioError(f"{where}: missing table [{name}]")
        return {}
    if not isinstance(data[key], dict):
        raise ScenarioError(f"{where}: '{name}' must be a table ([{name}])")
    return data[key]


def _reject_unknown(table: dict, allowed, where: str, prefix: str) -> None:
    for key in table:
        if key not in allowed:
            raise ScenarioError(f"{where}: unknown key '{prefix}{key}' (valid: {', '.join(allowed)})")

