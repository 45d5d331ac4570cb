"""The tables of a scenario file as pydantic models, and the checks between them.

Each model forbids unknown keys, takes numbers only when finite and refuses what would
allocate without bound (a step count over :data:`MAX_STEPS`, times beyond
:data:`MAX_TIME_S`); :func:`build_scenario_parts` turns a parsed file into the frozen specs of
:mod:`orchestrator.scenario_spec`.  Every problem is one line naming the file and the dotted
key (:func:`orchestrator.toml_input.checked`).  Participant options and the ``[metocean]``
table are checked by the participant type and the weather source that read them.
"""

from __future__ import annotations

import math
from typing import Annotated, Any

from pydantic import Field, PlainValidator, model_validator

from orchestrator.errors import ScenarioError
from orchestrator.scenario_spec import (Connection, OutputSpec, ParticipantSpec, SimulationSpec, StopCondition,
                                        VariableMapping, VectorMapping)
from orchestrator.toml_input import (Finite, FolderName, PositiveInt, Text, TomlTable, checked, fail, fail_whole,
                                     is_finite_number, shown, shown_text)

#: Exchange orders: participants due at a communication point step one after another, each
#: seeing the outputs of those before it ("gauss-seidel"), or all from the values published
#: before the point ("jacobi", as masters that step FMUs in parallel do, e.g. libcosim).
EXCHANGE_ORDERS = ("gauss-seidel", "jacobi")
STOP_OPERATORS = ("<=", ">=", "<", ">")
GEODETIC_ROLES = ("latitude", "longitude")
DIRECTION_SENSES = ("towards", "from")
FMI_VERSIONS = ("2.0", "3.0")
OUTPUT_FORMATS = ("parquet", "csv")
#: Most macro steps of one run: a run records every step (an hour at 5 ms, 11.5 days at 1 s).
MAX_STEPS = 1_000_000
#: Largest start or stop time [s] (about 317 years): keeps time arithmetic far from overflow.
MAX_TIME_S = 1e10
#: Shortest macro step [s].
MIN_DT_S = 1e-6
CONNECTIONS_HINT = " ('connections' must come before the first [table] of the file)"


def _one_of(choices: tuple[str, ...]):
    def check(value: Any) -> str:
        if not isinstance(value, str) or value not in choices:
            raise fail(f"must be one of {', '.join(choices)}, got {shown(value)}")
        return value
    return PlainValidator(check)


def _time(value: Any) -> float:
    if not is_finite_number(value):
        raise fail(f"must be a finite number, got {shown(value)}")
    if abs(value) > MAX_TIME_S:
        raise fail(f"must lie within +-{MAX_TIME_S:g} s, got {shown(value)}")
    return float(value)


def _every(value: Any) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or not 1 <= value <= MAX_STEPS:
        raise fail(f"must be a positive integer (at most {MAX_STEPS}), got {shown(value)}")
    return value


def _names(value: Any) -> tuple[str, ...]:
    if not isinstance(value, list) or not all(isinstance(v, str) and v for v in value):
        raise fail("must be a list of names")
    return tuple(value)


def _stop_conditions(entries: Any) -> tuple[StopCondition, ...]:
    if isinstance(entries, str):
        entries = [entries]
    if not isinstance(entries, list):
        raise fail("must be a condition string or a list of them")
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
            raise fail(f"entry {shown(entry)} must read \"participant.port < number\" "
                       f"(operators {', '.join(STOP_OPERATORS)})")
        conditions.append(parsed)
    return tuple(conditions)


Time = Annotated[float, PlainValidator(_time)]
Every = Annotated[int, PlainValidator(_every)]


class ScenarioTable(TomlTable):
    key_hints = {"connections": CONNECTIONS_HINT}


class ScenarioFile(ScenarioTable):
    """The top level: which tables a scenario has."""

    connections: Any = []
    simulation: Any = None
    metocean: Any = None
    participants: Any = None
    outputs: Any = None
    acceptance: Any = []

    @model_validator(mode="after")
    def _required(self):
        for table in ("simulation", "participants"):
            value = getattr(self, table)
            if value is None:
                raise fail_whole(f"missing table [{table}]")
            if not isinstance(value, dict):
                raise fail_whole(f"'{table}' must be a table ([{table}])")
        for table in ("metocean", "outputs"):
            if getattr(self, table) is not None and not isinstance(getattr(self, table), dict):
                raise fail_whole(f"'{table}' must be a table ([{table}])")
        return self


class SimulationTable(ScenarioTable):
    """``[simulation]``: the time grid and when the run ends."""

    name: FolderName | None = None
    start_s: Time = 0.0
    stop_s: Time | None = None
    steps: PositiveInt | None = None
    dt_s: Annotated[float, PlainValidator(lambda v: _positive_time(v))]
    stop_when: Annotated[tuple[StopCondition, ...], PlainValidator(_stop_conditions)] = ()
    exchange: Annotated[str, _one_of(EXCHANGE_ORDERS)] = "gauss-seidel"

    @model_validator(mode="after")
    def _time_grid(self):
        if (self.stop_s is None) == (self.steps is None):
            raise fail_whole("give exactly one of '{prefix}stop_s' or '{prefix}steps'")
        if self.steps is not None:
            count = self.steps
            if count > MAX_STEPS:
                raise fail_whole(f"'{{prefix}}steps' = {shown(count)} is more than the limit of {MAX_STEPS} "
                                 "macro steps")
        else:
            count = (self.stop_s - self.start_s) / self.dt_s  # finite: times and dt_s are bounded
            if count < 1 - 1e-9 or abs(count - round(count)) > 1e-9 * max(1.0, count):
                raise fail_whole("'{prefix}stop_s' - 'start_s' must be a positive whole number of 'dt_s' steps")
        if count > MAX_STEPS:
            raise fail_whole(self._too_many(count))
        return self

    def _too_many(self, count: float) -> str:
        return (f"'{{prefix}}dt_s' = {self.dt_s:g} s gives {count:.3g} macro steps, more than the limit of "
                f"{MAX_STEPS}")

    def spec(self, default_name: str) -> SimulationSpec:
        stop = self.stop_s if self.steps is None else self.start_s + self.steps * self.dt_s
        return SimulationSpec(name=self.name or default_name, start_s=self.start_s, stop_s=stop, dt_s=self.dt_s,
                              stop_when=self.stop_when, exchange=self.exchange)


def _positive_time(value: Any) -> float:
    number = _time(value)
    if number <= 0:
        raise fail(f"must be positive, got {shown(value)}")
    if number < MIN_DT_S:
        raise fail(f"must be at least {MIN_DT_S:g} s, got {shown(value)}")
    return number


def _class_path(value: Any) -> str:
    if not isinstance(value, str):
        raise fail("must name 'package.module:Class' for type = \"python\"")
    return value


class PythonParticipantTable(ScenarioTable):
    """``[participants.<name>]`` of a Python participant: a registered type or ``type = "python"``."""

    type: Text
    class_path: Annotated[str, PlainValidator(_class_path)] | None = Field(default=None, alias="class")
    every: Every = 1
    options: dict[str, Any] = {}

    @model_validator(mode="before")
    @classmethod
    def _options_table(cls, data: Any) -> Any:
        if isinstance(data, dict) and "options" in data and not isinstance(data["options"], dict):
            raise fail_whole("'{prefix}options' must be a table")
        return data

    @model_validator(mode="after")
    def _class_for_python(self):
        if self.type == "python" and self.class_path is None:
            raise fail_whole("'{prefix}class' must name 'package.module:Class' for type = \"python\"")
        if self.type != "python" and self.class_path is not None:
            raise fail_whole("'{prefix}class' is only for type = \"python\"")
        return self


def _parameter(value: Any) -> Any:
    if isinstance(value, (bool, str)):
        return value
    if not is_finite_number(value):
        raise fail(f"must be a finite number, boolean or string, got {shown(value)}")
    return value


def _origin(value: Any) -> tuple[float, float]:
    if (not isinstance(value, list) or len(value) != 2 or not all(is_finite_number(v) for v in value)
            or not -90.0 < value[0] < 90.0 or not -180.0 <= value[1] <= 180.0):
        raise fail(f"must be [latitude, longitude] in degrees, got {shown(value)}")
    return float(value[0]), float(value[1])


class GeodeticTable(ScenarioTable):
    origin_deg: Annotated[tuple[float, float], PlainValidator(_origin)]


def _table_of(value: Any) -> dict:
    if not isinstance(value, dict):
        raise fail("must be a table")
    return value


class FmuParticipantTable(ScenarioTable):
    """``[participants.<name>]`` of an FMU: the model, its parameters and how its ports map."""

    fmu: Annotated[str, PlainValidator(lambda v: _fmu(v))]
    fmi_version: Annotated[str, _one_of(FMI_VERSIONS)] = "2.0"
    every: Every = 1
    parameter_set: Text | None = None
    parameters: dict[str, Annotated[Any, PlainValidator(_parameter)]] = {}
    mapping: Annotated[dict, PlainValidator(_table_of)] = {}
    geodetic: GeodeticTable | None = None
    initial: Annotated[dict, PlainValidator(_table_of)] = {}

    @model_validator(mode="before")
    @classmethod
    def _parameters_table(cls, data: Any) -> Any:
        if isinstance(data, dict) and "parameters" in data and not isinstance(data["parameters"], dict):
            raise fail_whole("'{prefix}parameters' must be a table")
        return data


def _fmu(value: Any) -> str:
    if not isinstance(value, str) or not value:
        raise fail("must be a model name or a path to an .fmu")
    return value


def _scale(value: Any) -> float:
    if not is_finite_number(value):
        raise fail(f"must be a finite number, got {shown(value)}")
    if value == 0:
        raise fail("must not be zero")
    return float(value)


class VariableTable(ScenarioTable):
    """``mapping.<port> = { variable = ..., ... }``: one FMU variable."""

    variable: Annotated[str, PlainValidator(lambda v: _variable(v))]
    scale: Annotated[float, PlainValidator(_scale)] | None = None
    offset: Finite | None = None
    unit: Text | None = None
    geodetic: Annotated[str, _one_of(GEODETIC_ROLES)] | None = None
    start: Text | None = None

    def spec(self) -> VariableMapping:
        return VariableMapping(self.variable, self.scale, self.offset, self.unit, self.geodetic, self.start)


def _variable(value: Any) -> str:
    if not isinstance(value, str) or not value:
        raise fail("must be an FMU variable name")
    return value


class VectorTable(ScenarioTable):
    """``mapping.<port> = { speed = ..., direction = ... }`` or ``{ north = ..., east = ... }``."""

    speed: Text | None = None
    direction: Text | None = None
    direction_is: Annotated[str, _one_of(DIRECTION_SENSES)] = "towards"
    north: Text | None = None
    east: Text | None = None
    units: dict[str, Any] = {}

    @model_validator(mode="after")
    def _one_form(self):
        polar = self.speed is not None or self.direction is not None
        cartesian = self.north is not None or self.east is not None
        names = ("speed", "direction") if polar else ("north", "east")
        if polar == cartesian or not all(getattr(self, n) is not None for n in names):
            raise fail_whole("'{key}' needs variable = \"...\", or a vector: speed and direction, or north and east")
        if not all(k in names and isinstance(v, str) for k, v in self.units.items()):
            raise fail_whole(f"'{{prefix}}units' must map {' and '.join(names)} to unit names")
        return self

    def spec(self) -> VectorMapping:
        return VectorMapping(speed=self.speed, direction=self.direction, direction_is=self.direction_is,
                             north=self.north, east=self.east, units=dict(self.units))


MAPPING_FORMS = ("must be \"variable\", { variable = \"...\", scale = 1.0, ... } or a vector "
                 "{ speed = ..., direction = ... } / { north = ..., east = ... }")


def _mapping_entry(target: Any, where: str, at: tuple) -> VariableMapping | VectorMapping:
    """One ``mapping.<port>`` entry: a variable name, a variable table or a vector table."""
    if isinstance(target, str) and target:
        return VariableMapping(target)
    if not isinstance(target, dict) or ("variable" not in target
                                        and not set(target) & {"speed", "direction", "north", "east"}):
        raise ScenarioError(f"{where}: '{_dotted(at)}' {MAPPING_FORMS}")
    if "variable" in target:
        return checked(VariableTable, target, where, at).spec()
    return checked(VectorTable, target, where, at).spec()


def _dotted(at: tuple) -> str:
    return ".".join(shown_text(part) for part in at)


class OutputsTable(ScenarioTable):
    """``[outputs]``: file format, analyses, figures and the analyses' options."""

    format: Annotated[str, _one_of(OUTPUT_FORMATS)] = "parquet"
    analyses: Annotated[tuple[str, ...], PlainValidator(_names)] = ()
    figures: Annotated[tuple[str, ...], PlainValidator(_names)] = ("track",)
    options: Annotated[dict, PlainValidator(lambda v: _analysis_options(v))] = {}

    @model_validator(mode="after")
    def _options_for_listed(self):
        for name in self.options:
            if name not in self.analyses:
                raise fail_whole(f"'{{prefix}}options.{shown_text(name)}' is for an analysis not listed in "
                                 "'{prefix}analyses'")
        return self

    def spec(self) -> OutputSpec:
        return OutputSpec(format=self.format, analyses=self.analyses, figures=self.figures, options=self.options)


def _analysis_options(value: Any) -> dict:
    if not isinstance(value, dict):
        raise fail("must be a table of [outputs.options.<analysis>] tables")
    for name, values in value.items():
        if not isinstance(values, dict):
            raise fail(f"entry '{shown_text(name)}' must be a table")
    return value


# -- the whole file ------------------------------------------------------------------------------
def build_scenario_parts(data: dict, where: str, default_name: str):
    """Check a parsed scenario; return its simulation, participants, connections, metocean, outputs.

    Raises
    ------
    ScenarioError
        The first problem, naming ``where`` (the file) and the dotted key.
    """
    top = checked(ScenarioFile, data, where)
    simulation = checked(SimulationTable, top.simulation, where, ("simulation",)).spec(default_name)
    participants = _participants(top.participants, where)
    connections = _connections(top.connections, participants, where)
    outputs = checked(OutputsTable, top.outputs or {}, where, ("outputs",)).spec()
    return simulation, participants, connections, top.metocean, outputs, top.acceptance


def _participants(table: dict, where: str) -> tuple[ParticipantSpec, ...]:
    if not table:
        raise ScenarioError(f"{where}: [participants] declares no participant")
    specs = []
    for name, body in table.items():
        at = ("participants", name)
        if not isinstance(body, dict):
            raise ScenarioError(f"{where}: '{_dotted(at)}' must be a table")
        if not name.isidentifier() or len(name) > 64:
            raise ScenarioError(f"{where}: participant name '{shown_text(name)}' must be an identifier "
                                f"(at most 64 characters)")
        if "fmu" in body:
            specs.append(_fmu_participant(name, checked(FmuParticipantTable, body, where, at), where, at))
        elif "type" in body:
            model = checked(PythonParticipantTable, body, where, at)
            specs.append(ParticipantSpec(name=name, every=model.every, type=model.type, class_path=model.class_path,
                                         options=dict(model.options)))
        else:
            raise ScenarioError(f"{where}: '{_dotted(at)}' needs either 'fmu' or 'type'")
    return tuple(specs)


def _fmu_participant(name: str, model: FmuParticipantTable, where: str, at: tuple) -> ParticipantSpec:
    from orchestrator.plant_ports import INITIAL_KEYS

    mapping = {port: _mapping_entry(target, where, at + ("mapping", port)) for port, target in model.mapping.items()}
    initial = {}
    for key, value in model.initial.items():
        if key not in INITIAL_KEYS:
            raise ScenarioError(f"{where}: unknown key '{_dotted(at + ('initial', key))}' "
                                f"(valid: {', '.join(INITIAL_KEYS)})")
        if not is_finite_number(value):
            raise ScenarioError(f"{where}: '{_dotted(at + ('initial', key))}' must be a finite number, "
                                f"got {shown(value)}")
        initial[key] = float(value)
    return ParticipantSpec(name=name, every=model.every, fmu=model.fmu, parameter_set=model.parameter_set,
                           parameters=dict(model.parameters), mapping=mapping,
                           geodetic_origin_deg=model.geodetic.origin_deg if model.geodetic else None,
                           fmi_version=model.fmi_version, initial=initial)


def _connections(entries: Any, participants, where: str) -> tuple[Connection, ...]:
    if not isinstance(entries, list):
        raise ScenarioError(f"{where}: 'connections' must be a list of \"a.port -> b.port\" strings")
    names = {spec.name for spec in participants}
    result = []
    for entry in entries:
        if not isinstance(entry, str) or entry.count("->") != 1:
            raise ScenarioError(f"{where}: connection {shown(entry)} must read \"source.port -> target.port\"")
        ends = []
        for end in (part.strip() for part in entry.split("->")):
            participant, dot, port = end.partition(".")
            if not dot or not participant or not port:
                raise ScenarioError(f"{where}: connection {shown(entry)}: '{shown_text(end)}' must read "
                                    "participant.port")
            if participant not in names:
                raise ScenarioError(f"{where}: connection {shown(entry)}: no participant '{shown_text(participant)}' "
                                    f"(declared: {', '.join(sorted(names))})")
            ends.append((participant, port))
        connection = Connection(ends[0][0], ends[0][1], ends[1][0], ends[1][1])
        if any((c.target, c.target_port) == (connection.target, connection.target_port) for c in result):
            raise ScenarioError(f"{where}: connection {shown(entry)}: {connection.target}."
                                f"{shown_text(connection.target_port)} is already driven")
        result.append(connection)
    return tuple(result)
