"""Scenario loading: TOML into frozen dataclasses, every error naming the file and the key.

The format is documented in ``docs/scenario-format.md``.
"""

from __future__ import annotations

import hashlib
import json
import math
import tomllib
from dataclasses import dataclass, field
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from orchestrator.participant import is_finite_number
from orchestrator.errors import ScenarioError

TOP_LEVEL_KEYS = ("connections", "simulation", "metocean", "participants", "outputs", "acceptance")
SIMULATION_KEYS = ("name", "start_s", "stop_s", "steps", "dt_s", "stop_when", "exchange", "step_timeout_s")
#: Exchange orders: participants due at a communication point step one after another, each
#: seeing the outputs of those before it ("gauss-seidel"), or all from the values published
#: before the point ("jacobi", as masters that step FMUs in parallel do, e.g. libcosim).
EXCHANGE_ORDERS = ("gauss-seidel", "jacobi")
STOP_OPERATORS = ("<=", ">=", "<", ">")
FMU_PARTICIPANT_KEYS = ("fmu", "fmi_version", "every", "parameter_set", "parameters", "mapping", "geodetic",
                        "initial", "step_timeout_s")
MAPPING_KEYS = ("variable", "scale", "offset", "unit", "geodetic", "start")
VECTOR_MAPPING_KEYS = ("speed", "direction", "direction_is", "north", "east", "units")
GEODETIC_ROLES = ("latitude", "longitude")
DIRECTION_SENSES = ("towards", "from")
FMI_VERSIONS = ("2.0", "3.0")
PYTHON_PARTICIPANT_KEYS = ("type", "class", "every", "options", "step_timeout_s")
OUTPUT_KEYS = ("format", "analyses", "figures", "options")
OUTPUT_FORMATS = ("parquet", "csv")


@dataclass(frozen=True)
class VariableMapping:
    """A port bound to an FMU variable: ``canonical = scale * fmu_value + offset``.

    Without ``scale`` and ``offset`` the conversion follows from the unit the FMU declares
    for the variable (or ``unit``, for a variable that declares none); ``geodetic`` marks a
    latitude or longitude projected to north/east metres; ``start`` names the FMU parameter
    holding the port's initial value (see :mod:`orchestrator.port_mapping`).
    """

    variable: str
    scale: float | None = None
    offset: float | None = None
    unit: str | None = None
    geodetic: str | None = None
    start: str | None = None


@dataclass(frozen=True)
class VectorMapping:
    """A vector input (``current``, ``wind``) the FMU takes as speed + direction or north + east.

    ``direction_is`` says whether the direction is where the flow goes (``towards``: a
    current's set) or where it comes from (``from``: a wind); ``units`` may state the unit
    of a part (``speed``, ``direction``, ``north``, ``east``) the FMU declares none for.
    """

    speed: str | None = None
    direction: str | None = None
    direction_is: str = "towards"
    north: str | None = None
    east: str | None = None
    units: dict[str, str] = field(default_factory=dict)


@dataclass(frozen=True)
class ParticipantSpec:
    """One ``[participants.<name>]`` table."""

    name: str
    every: int
    fmu: str | None = None
    parameter_set: str | None = None
    parameters: dict[str, Any] = field(default_factory=dict)
    mapping: dict[str, VariableMapping | VectorMapping] = field(default_factory=dict)
    geodetic_origin_deg: tuple[float, float] | None = None
    initial: dict[str, float] = field(default_factory=dict)
    fmi_version: str = "2.0"   # of a built-in model; an FMU file's own description decides
    type: str | None = None
    class_path: str | None = None
    options: dict[str, Any] = field(default_factory=dict)
    #: wall-time limit of one set-up or step call [s]; None: the simulation's
    step_timeout_s: float | None = None

    @property
    def is_fmu(self) -> bool:
        return self.fmu is not None


@dataclass(frozen=True)
class Connection:
    """``source.port -> target.port``."""

    source: str
    source_port: str
    target: str
    target_port: str

    def __str__(self) -> str:
        return f"{self.source}.{self.source_port} -> {self.target}.{self.target_port}"


@dataclass(frozen=True)
class StopCondition:
    """``participant.port <op> value``: the run ends (finished) once it holds."""

    participant: str
    port: str
    operator: str
    value: float

    def holds(self, observed: float) -> bool:
        return {"<": observed < self.value, "<=": observed <= self.value,
                ">": observed > self.value, ">=": observed >= self.value}[self.operator]

    def __str__(self) -> str:
        return f"{self.participant}.{self.port} {self.operator} {self.value:g}"


@dataclass(frozen=True)
class SimulationSpec:
    name: str
    start_s: float
    stop_s: float
    dt_s: float
    stop_when: tuple[StopCondition, ...] = ()
    exchange: str = "gauss-seidel"
    #: wall-time limit of one participant call (set-up or step) [s] (orchestrator.time_limits)
    step_timeout_s: float = 300.0

    @property
    def steps(self) -> int:
        """Number of macro steps."""
        return int(round((self.stop_s - self.start_s) / self.dt_s))


@dataclass(frozen=True)
class OutputSpec:
    format: str = "parquet"
    analyses: tuple[str, ...] = ()
    figures: tuple[str, ...] = ("track",)
    #: keyword options per analysis, from ``[outputs.options.<analysis>]``
    options: dict[str, dict[str, Any]] = field(default_factory=dict)


@dataclass(frozen=True)
class Scenario:
    """A loaded, checked scenario."""

    path: Path
    simulation: SimulationSpec
    participants: tuple[ParticipantSpec, ...]
    connections: tuple[Connection, ...]
    metocean: dict[str, Any] | None
    outputs: OutputSpec
    sha256: str
    #: ``[[acceptance]]`` criteria checked on the run's summary.json after the run
    acceptance: tuple = ()

    @property
    def directory(self) -> Path:
        return self.path.parent

    def participant(self, name: str) -> ParticipantSpec:
        for spec in self.participants:
            if spec.name == name:
                return spec
        raise KeyError(name)


def load_scenario(path, overrides: Mapping[str, Any] | None = None) -> Scenario:
    """Read and check a scenario file.

    Parameters
    ----------
    path : path-like
        The scenario TOML file; relative paths inside it resolve against its folder.
    overrides : mapping, optional
        Values replacing (or adding) keys of the file before it is checked, by dotted
        path: ``{"participants.nav.options.k2": 0.0, "simulation.dt_s": 60.0}``.  The
        batch runner varies scenarios this way.  The scenario hash covers them.

    Raises
    ------
    ScenarioError
        For a missing file, a TOML syntax error, an unknown key, a wrong type or an
        inconsistent value; the message names the file and the key.
    """
    path = Path(path)
    data, raw = read_toml(path, "scenario")
    if overrides:
        for dotted, value in overrides.items():
            apply_override(data, dotted, value, str(path))
        raw = raw + b"\n# overrides\n" + json.dumps(dict(overrides), sort_keys=True, default=str).encode()
    where = str(path)
    _refuse_other_file_kinds(data, where)
    _reject_unknown(data, TOP_LEVEL_KEYS, where, "")
    simulation = _simulation(_table(data, "simulation", where, required=True), path)
    participants = _participants(_table(data, "participants", where, required=True), where)
    connections = _connections(data.get("connections", []), participants, where)
    metocean = data.get("metocean")
    if metocean is not None and not isinstance(metocean, dict):
        raise ScenarioError(f"{where}: 'metocean' must be a table")
    outputs = _outputs(_table(data, "outputs", where, required=False), where)
    from orchestrator.batch_spec import parse_acceptance  # batch files share the format

    acceptance = parse_acceptance(data.get("acceptance", []), where)
    return Scenario(
        path=path.resolve(),
        simulation=simulation,
        participants=participants,
        connections=connections,
        metocean=metocean,
        outputs=outputs,
        sha256=hashlib.sha256(raw).hexdigest(),
        acceptance=acceptance,
    )


def read_toml(path: Path, kind: str) -> tuple[dict, bytes]:
    """Parse a TOML input file; return its data and raw bytes.

    Every file the toolchain reads (scenario, batch, comparison, offline planning) comes in
    here, so a missing or malformed one always reads ``<path>: <kind> file not found`` or
    ``<path>: not valid TOML: <where the parser stopped>``.
    """
    path = Path(path)
    if not path.is_file():
        raise ScenarioError(f"{path}: {kind} file not found")
    raw = path.read_bytes()
    try:
        return tomllib.loads(raw.decode("utf-8")), raw
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise ScenarioError(f"{path}: not valid TOML: {exc}") from exc


def apply_override(data: dict, dotted: str, value: Any, where: str) -> None:
    """Set ``data[a][b][c] = value`` for ``dotted = "a.b.c"``, creating missing tables.

    A path running through a value that is not a table is an error naming it.
    """
    keys = dotted.split(".")
    if not all(keys):
        raise ScenarioError(f"{where}: override '{dotted}' is not a dotted key path")
    node = data
    for depth, key in enumerate(keys[:-1]):
        child = node.setdefault(key, {})
        if not isinstance(child, dict):
            raise ScenarioError(
                f"{where}: override '{dotted}': '{'.'.join(keys[:depth + 1])}' is a value, not a table"
            )
        node = child
    node[keys[-1]] = value


def _table(data: dict, key: str, where: str, required: bool) -> dict:
    if key not in data:
        if required:
            raise ScenarioError(f"{where}: missing table [{key}]")
        return {}
    value = data[key]
    if not isinstance(value, dict):
        raise ScenarioError(f"{where}: '{key}' must be a table ([{key}])")
    return value


#: Top-level keys that mark the other input files, their kind and the subcommand that reads them.
OTHER_FILE_KINDS = (("batch", "a batch file", "batch"), ("runs", "a comparison file", "compare"),
                    ("planner", "an offline planning file", "plan"), ("cases", "an offline planning file", "plan"))


def _refuse_other_file_kinds(data: dict, where: str) -> None:
    """A batch, comparison or planning file given where a scenario is read: name the right command."""
    if "participants" in data or "simulation" in data:
        return
    for key, kind, command in OTHER_FILE_KINDS:
        if key in data:
            raise ScenarioError(f"{where}: {kind} (it has '{key}'), not a scenario: "
                                f"use 'python -m orchestrator {command} {where}'")


def _reject_unknown(table: dict, allowed, where: str, prefix: str) -> None:
    for key in table:
        if key not in allowed:
            hint = ""
            if key == "connections":
                hint = " ('connections' must come before the first [table] of the file)"
            raise ScenarioError(
                f"{where}: unknown key '{prefix}{key}'{hint} (valid: {', '.join(allowed)})"
            )


def _number(table: dict, key: str, where: str, prefix: str, default=None, positive=False) -> float:
    if key not in table:
        if default is None:
            raise ScenarioError(f"{where}: missing key '{prefix}{key}'")
        return default
    value = table[key]
    if not is_finite_number(value):
        raise ScenarioError(f"{where}: '{prefix}{key}' must be a finite number, got {value!r}")
    if positive and value <= 0:
        raise ScenarioError(f"{where}: '{prefix}{key}' must be positive, got {value!r}")
    return float(value)


def _simulation(table: dict, path: Path) -> SimulationSpec:
    where, prefix = str(path), "simulation."
    _reject_unknown(table, SIMULATION_KEYS, where, prefix)
    name = table.get("name", path.stem)
    if not isinstance(name, str) or not name or any(c in name for c in "/\\"):
        raise ScenarioError(f"{where}: 'simulation.name' must be a non-empty string without slashes")
    start = _number(table, "start_s", where, prefix, default=0.0)
    dt = _number(table, "dt_s", where, prefix, positive=True)
    if ("stop_s" in table) == ("steps" in table):
        raise ScenarioError(f"{where}: give exactly one of 'simulation.stop_s' or 'simulation.steps'")
    if "steps" in table:
        steps = table["steps"]
        if isinstance(steps, bool) or not isinstance(steps, int) or steps < 1:
            raise ScenarioError(f"{where}: 'simulation.steps' must be a positive integer, got {steps!r}")
        stop = start + steps * dt
    else:
        stop = _number(table, "stop_s", where, prefix)
        count = (stop - start) / dt
        if count < 1 - 1e-9 or abs(count - round(count)) > 1e-9 * max(1.0, count):
            raise ScenarioError(
                f"{where}: 'simulation.stop_s' - 'start_s' must be a positive whole number of 'dt_s' steps"
            )
    exchange = table.get("exchange", "gauss-seidel")
    if exchange not in EXCHANGE_ORDERS:
        raise ScenarioError(f"{where}: 'simulation.exchange' must be one of {', '.join(EXCHANGE_ORDERS)}, "
                            f"got {exchange!r}")
    timeout = _number(table, "step_timeout_s", where, prefix, default=SimulationSpec.step_timeout_s, positive=True)
    return SimulationSpec(name=name, start_s=start, stop_s=stop, dt_s=dt,
                          stop_when=_stop_conditions(table.get("stop_when", []), where), exchange=exchange,
                          step_timeout_s=timeout)


def _stop_conditions(entries, where: str) -> tuple[StopCondition, ...]:
    if isinstance(entries, str):
        entries = [entries]
    if not isinstance(entries, list):
        raise ScenarioError(f"{where}: 'simulation.stop_when' must be a condition string or a list of them")
    conditions = []
    for entry in entries:
        parsed = None
        if isinstance(entry, str):
            for operator in STOP_OPERATORS:
                left, found, right = entry.partition(operator)
                if found:
                    participant, dot, port = left.strip().partition(".")
                    try:
                        value = float(right)
                    except ValueError:
                        break
                    if dot and participant and port and math.isfinite(value):
                        parsed = StopCondition(participant, port, operator, value)
                    break
        if parsed is None:
            raise ScenarioError(
                f"{where}: 'simulation.stop_when' entry {entry!r} must read \"participant.port < number\" "
                f"(operators {', '.join(STOP_OPERATORS)})")
        conditions.append(parsed)
    return tuple(conditions)


def _participants(table: dict, where: str) -> tuple[ParticipantSpec, ...]:
    if not table:
        raise ScenarioError(f"{where}: [participants] declares no participant")
    specs = []
    for name, body in table.items():
        prefix = f"participants.{name}."
        if not isinstance(body, dict):
            raise ScenarioError(f"{where}: 'participants.{name}' must be a table")
        if not name.isidentifier():
            raise ScenarioError(f"{where}: participant name '{name}' must be an identifier")
        every = body.get("every", 1)
        if isinstance(every, bool) or not isinstance(every, int) or every < 1:
            raise ScenarioError(f"{where}: '{prefix}every' must be a positive integer, got {every!r}")
        if "fmu" in body:
            _reject_unknown(body, FMU_PARTICIPANT_KEYS, where, prefix)
            specs.append(_fmu_participant(name, body, every, where, prefix))
        elif "type" in body:
            _reject_unknown(body, PYTHON_PARTICIPANT_KEYS, where, prefix)
            kind = body["type"]
            class_path = body.get("class")
            if kind == "python" and not isinstance(class_path, str):
                raise ScenarioError(f"{where}: '{prefix}class' must name 'package.module:Class' for type = \"python\"")
            if kind != "python" and class_path is not None:
                raise ScenarioError(f"{where}: '{prefix}class' is only for type = \"python\"")
            options = body.get("options", {})
            if not isinstance(options, dict):
                raise ScenarioError(f"{where}: '{prefix}options' must be a table")
            specs.append(ParticipantSpec(name=name, every=every, type=kind, class_path=class_path, options=options,
                                         step_timeout_s=_participant_timeout(body, where, prefix)))
        else:
            raise ScenarioError(f"{where}: 'participants.{name}' needs either 'fmu' or 'type'")
    return tuple(specs)


def _fmu_participant(name: str, body: dict, every: int, where: str, prefix: str) -> ParticipantSpec:
    fmu = body["fmu"]
    if not isinstance(fmu, str) or not fmu:
        raise ScenarioError(f"{where}: '{prefix}fmu' must be a model name or a path to an .fmu")
    fmi_version = body.get("fmi_version", "2.0")
    if fmi_version not in FMI_VERSIONS:
        raise ScenarioError(f"{where}: '{prefix}fmi_version' must be one of {', '.join(FMI_VERSIONS)}, got {fmi_version!r}")
    parameter_set = body.get("parameter_set")
    if parameter_set is not None and not isinstance(parameter_set, str):
        raise ScenarioError(f"{where}: '{prefix}parameter_set' must be a string")
    parameters = body.get("parameters", {})
    if not isinstance(parameters, dict):
        raise ScenarioError(f"{where}: '{prefix}parameters' must be a table")
    for key, value in parameters.items():
        if not isinstance(value, (int, float, bool, str)):
            raise ScenarioError(f"{where}: '{prefix}parameters.{key}' must be a number, boolean or string")
    mapping_table = body.get("mapping", {})
    if not isinstance(mapping_table, dict):
        raise ScenarioError(f"{where}: '{prefix}mapping' must be a table")
    mapping = {port: _mapping_entry(target, where, f"{prefix}mapping.{port}")
               for port, target in mapping_table.items()}
    origin = None
    geodetic = body.get("geodetic")
    if geodetic is not None:
        if not isinstance(geodetic, dict):
            raise ScenarioError(f"{where}: '{prefix}geodetic' must be a table with origin_deg = [lat, lon]")
        _reject_unknown(geodetic, ("origin_deg",), where, prefix + "geodetic.")
        value = geodetic.get("origin_deg")
        if (not isinstance(value, list) or len(value) != 2 or not all(is_finite_number(v) for v in value)
                or not -90.0 < value[0] < 90.0 or not -180.0 <= value[1] <= 180.0):
            raise ScenarioError(f"{where}: '{prefix}geodetic.origin_deg' must be [latitude, longitude] in degrees")
        origin = (float(value[0]), float(value[1]))
    initial = body.get("initial", {})
    if not isinstance(initial, dict):
        raise ScenarioError(f"{where}: '{prefix}initial' must be a table")
    from orchestrator.plant_ports import INITIAL_KEYS

    _reject_unknown(initial, INITIAL_KEYS, where, prefix + "initial.")
    for key, value in initial.items():
        if not is_finite_number(value):
            raise ScenarioError(f"{where}: '{prefix}initial.{key}' must be a finite number, got {value!r}")
    return ParticipantSpec(name=name, every=every, fmu=fmu, parameter_set=parameter_set,
                           parameters=parameters, mapping=mapping, geodetic_origin_deg=origin,
                           fmi_version=fmi_version, step_timeout_s=_participant_timeout(body, where, prefix),
                           initial={k: float(v) for k, v in initial.items()})


def _participant_timeout(body: dict, where: str, prefix: str) -> float | None:
    """A participant's own ``step_timeout_s`` [s], or None for the simulation's."""
    if "step_timeout_s" not in body:
        return None
    return _number(body, "step_timeout_s", where, prefix, positive=True)


def _mapping_entry(target, where: str, key: str) -> VariableMapping | VectorMapping:
    """One ``mapping.<port>`` entry: a variable name, a variable table or a vector table."""
    if isinstance(target, str):
        return VariableMapping(target)
    if not isinstance(target, dict):
        raise ScenarioError(f"{where}: '{key}' must be a variable name or a table")
    if "variable" not in target and not set(target) & {"speed", "direction", "north", "east"}:
        raise ScenarioError(f"{where}: '{key}' must be \"variable\", {{ variable = \"...\", scale = 1.0, ... }} "
                            "or a vector { speed = ..., direction = ... } / { north = ..., east = ... }")
    if "variable" not in target:
        _reject_unknown(target, VECTOR_MAPPING_KEYS, where, key + ".")
        polar = "speed" in target or "direction" in target
        cartesian = "north" in target or "east" in target
        names = ("speed", "direction") if polar else ("north", "east")
        if polar == cartesian or not all(isinstance(target.get(n), str) for n in names):
            raise ScenarioError(f"{where}: '{key}' needs variable = \"...\", or a vector: speed and direction, "
                                "or north and east")
        sense = target.get("direction_is", "towards")
        if sense not in DIRECTION_SENSES:
            raise ScenarioError(f"{where}: '{key}.direction_is' must be one of {', '.join(DIRECTION_SENSES)}")
        units = target.get("units", {})
        if not isinstance(units, dict) or not all(k in names and isinstance(v, str) for k, v in units.items()):
            raise ScenarioError(f"{where}: '{key}.units' must map {' and '.join(names)} to unit names")
        return VectorMapping(speed=target.get("speed"), direction=target.get("direction"), direction_is=sense,
                             north=target.get("north"), east=target.get("east"), units=dict(units))
    _reject_unknown(target, MAPPING_KEYS, where, key + ".")
    if not isinstance(target["variable"], str) or not target["variable"]:
        raise ScenarioError(f"{where}: '{key}.variable' must be an FMU variable name")
    scale = _number(target, "scale", where, key + ".") if "scale" in target else None
    if scale == 0:
        raise ScenarioError(f"{where}: '{key}.scale' must not be zero")
    offset = _number(target, "offset", where, key + ".") if "offset" in target else None
    for text in ("unit", "start"):
        if text in target and (not isinstance(target[text], str) or not target[text]):
            raise ScenarioError(f"{where}: '{key}.{text}' must be a non-empty string")
    role = target.get("geodetic")
    if role is not None and role not in GEODETIC_ROLES:
        raise ScenarioError(f"{where}: '{key}.geodetic' must be one of {', '.join(GEODETIC_ROLES)}, got {role!r}")
    return VariableMapping(target["variable"], scale, offset, target.get("unit"), role, target.get("start"))


def _connections(entries, participants, where: str) -> tuple[Connection, ...]:
    if not isinstance(entries, list):
        raise ScenarioError(f"{where}: 'connections' must be a list of \"a.port -> b.port\" strings")
    names = {spec.name for spec in participants}
    result = []
    for entry in entries:
        if not isinstance(entry, str) or entry.count("->") != 1:
            raise ScenarioError(f"{where}: connection {entry!r} must read \"source.port -> target.port\"")
        ends = []
        for end in (part.strip() for part in entry.split("->")):
            participant, dot, port = end.partition(".")
            if not dot or not participant or not port:
                raise ScenarioError(f"{where}: connection {entry!r}: '{end}' must read participant.port")
            if participant not in names:
                raise ScenarioError(
                    f"{where}: connection {entry!r}: no participant '{participant}' (declared: {', '.join(sorted(names))})"
                )
            ends.append((participant, port))
        connection = Connection(ends[0][0], ends[0][1], ends[1][0], ends[1][1])
        if any((c.target, c.target_port) == (connection.target, connection.target_port) for c in result):
            raise ScenarioError(f"{where}: connection {entry!r}: {connection.target}.{connection.target_port} is already driven")
        result.append(connection)
    return tuple(result)


def _outputs(table: dict, where: str) -> OutputSpec:
    _reject_unknown(table, OUTPUT_KEYS, where, "outputs.")
    fmt = table.get("format", "parquet")
    if fmt not in OUTPUT_FORMATS:
        raise ScenarioError(f"{where}: 'outputs.format' must be one of {', '.join(OUTPUT_FORMATS)}, got {fmt!r}")
    lists = {}
    for key, default in (("analyses", ()), ("figures", ("track",))):
        value = table.get(key, list(default))
        if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
            raise ScenarioError(f"{where}: 'outputs.{key}' must be a list of names")
        lists[key] = tuple(value)
    options = table.get("options", {})
    if not isinstance(options, dict):
        raise ScenarioError(f"{where}: 'outputs.options' must be a table of [outputs.options.<analysis>] tables")
    for name, values in options.items():
        if name not in lists["analyses"]:
            raise ScenarioError(f"{where}: 'outputs.options.{name}' is for an analysis not listed in 'outputs.analyses'")
        if not isinstance(values, dict):
            raise ScenarioError(f"{where}: 'outputs.options.{name}' must be a table")
    return OutputSpec(format=fmt, options=options, **lists)
