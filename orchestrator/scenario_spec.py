"""What a loaded scenario is: one declaration per table, read by :mod:`orchestrator.scenario_model`.

A table the file states as it is used (a port mapping, ``[outputs]``) is its own frozen
pydantic model, the same object checks the file and is kept in the loaded scenario; a part
the loader derives (the time grid from ``stop_s`` or ``steps``, a participant from its FMU or
Python table, connections and stop conditions from their strings) is a frozen dataclass.
The file format is documented in ``docs/scenario-format.md``;
:func:`orchestrator.scenario.load_scenario` reads a file into these.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Annotated, Any

from pydantic import PlainValidator, model_validator

from orchestrator.toml_input import Finite, Text, TomlTable, fail, fail_whole, is_finite_number, one_of, shown, shown_text

GEODETIC_ROLES = ("latitude", "longitude")
DIRECTION_SENSES = ("towards", "from")
OUTPUT_FORMATS = ("parquet", "csv")
CONNECTIONS_HINT = " ('connections' must come before the first [table] of the file)"


class ScenarioTable(TomlTable):
    """A table of a scenario file: a key that belongs at the top gets a hint (a TOML key after a
    ``[table]`` header lands in that table)."""

    key_hints = {"connections": CONNECTIONS_HINT}


def _scale(value: Any) -> float:
    if not is_finite_number(value):
        raise fail(f"must be a finite number, got {shown(value)}")
    if value == 0:
        raise fail("must not be zero")
    return float(value)


class VariableMapping(ScenarioTable):
    """A port bound to an FMU variable: ``canonical = scale * fmu_value + offset``.

    ``mapping.<port> = "variable"`` or ``{ variable = ..., ... }``.  Without ``scale`` and
    ``offset`` the conversion follows from the unit the FMU declares for the variable (or
    ``unit``, for a variable that declares none); ``geodetic`` marks a latitude or longitude
    projected to north/east metres; ``start`` names the FMU parameter holding the port's
    initial value (see :mod:`orchestrator.port_mapping`).
    """

    variable: Annotated[str, PlainValidator(lambda v: _variable(v))]
    scale: Annotated[float, PlainValidator(_scale)] | None = None
    offset: Finite | None = None
    unit: Text | None = None
    geodetic: Annotated[str, one_of(GEODETIC_ROLES)] | None = None
    start: Text | None = None


def _variable(value: Any) -> str:
    if not isinstance(value, str) or not value:
        raise fail("must be an FMU variable name")
    return value


class VectorMapping(ScenarioTable):
    """A vector input (``current``, ``wind``) the FMU takes as speed + direction or north + east.

    ``mapping.<port> = { speed = ..., direction = ... }`` or ``{ north = ..., east = ... }``.
    ``direction_is`` says whether the direction is where the flow goes (``towards``: a
    current's set) or where it comes from (``from``: a wind); ``units`` may state the unit
    of a part (``speed``, ``direction``, ``north``, ``east``) the FMU declares none for.
    """

    speed: Text | None = None
    direction: Text | None = None
    direction_is: Annotated[str, one_of(DIRECTION_SENSES)] = "towards"
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
    #: earth model of the geodetic mapping: ("wgs84", None) or ("sphere", radius [m])
    geodetic_earth: tuple[str, float | None] = ("wgs84", None)
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


def _names(value: Any) -> tuple[str, ...]:
    if not isinstance(value, list) or not all(isinstance(v, str) and v for v in value):
        raise fail("must be a list of names")
    return tuple(value)


class OutputSpec(ScenarioTable):
    """``[outputs]``: file format, analyses, figures and the analyses' options (keyword options
    per analysis, from ``[outputs.options.<analysis>]``)."""

    format: Annotated[str, one_of(OUTPUT_FORMATS)] = "parquet"
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


def _analysis_options(value: Any) -> dict:
    if not isinstance(value, dict):
        raise fail("must be a table of [outputs.options.<analysis>] tables")
    for name, values in value.items():
        if not isinstance(values, dict):
            raise fail(f"entry '{shown_text(name)}' must be a table")
    return value


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
