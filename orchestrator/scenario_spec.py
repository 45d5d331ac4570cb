"""What a loaded scenario is: frozen dataclasses, built by :mod:`orchestrator.scenario_model`.

The file format is documented in ``docs/scenario-format.md``; :func:`orchestrator.scenario.load_scenario`
reads a file into these.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any


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
