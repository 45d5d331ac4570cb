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

from pydantic import PlainValidator, model_validator

from orchestrator.errors import ScenarioError
from orchestrator.scenario_participants import participant_specs
from orchestrator.scenario_spec import Connection, OutputSpec, ScenarioTable, SimulationSpec, StopCondition
from orchestrator.toml_input import (FolderName, Positive, PositiveInt, check_distances_nm, checked,
                                     default_folder_name, fail, fail_whole, is_finite_number, one_of, shown,
                                     shown_text)

#: Exchange orders: participants due at a communication point step one after another, each
#: seeing the outputs of those before it ("gauss-seidel"), or all from the values published
#: before the point ("jacobi", as masters that step FMUs in parallel do, e.g. libcosim).
EXCHANGE_ORDERS = ("gauss-seidel", "jacobi")
STOP_OPERATORS = ("<=", ">=", "<", ">")
#: Most macro steps of one run: a run records every step (an hour at 5 ms, 11.5 days at 1 s).
MAX_STEPS = 1_000_000
#: Largest start or stop time [s] (about 317 years): keeps time arithmetic far from overflow.
MAX_TIME_S = 1e10
#: Shortest macro step [s].
MIN_DT_S = 1e-6


def _time(value: Any) -> float:
    if not is_finite_number(value):
        raise fail(f"must be a finite number, got {shown(value)}")
    if abs(value) > MAX_TIME_S:
        raise fail(f"must lie within +-{MAX_TIME_S:g} s, got {shown(value)}")
    return float(value)


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


def _positive_time(value: Any) -> float:
    number = _time(value)
    if number <= 0:
        raise fail(f"must be positive, got {shown(value)}")
    if number < MIN_DT_S:
        raise fail(f"must be at least {MIN_DT_S:g} s, got {shown(value)}")
    return number


class SimulationTable(ScenarioTable):
    """``[simulation]``: the time grid and when the run ends."""

    name: FolderName | None = None
    start_s: Time = 0.0
    stop_s: Time | None = None
    steps: PositiveInt | None = None
    dt_s: Annotated[float, PlainValidator(_positive_time)]
    stop_when: Annotated[tuple[StopCondition, ...], PlainValidator(_stop_conditions)] = ()
    exchange: Annotated[str, one_of(EXCHANGE_ORDERS)] = "gauss-seidel"
    #: wall-time limit of one participant call (set-up or step) [s]
    step_timeout_s: Positive = SimulationSpec.step_timeout_s

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
        if self.steps is None:
            assert self.stop_s is not None  # the validator asks for exactly one of stop_s and steps
            stop = self.stop_s
        else:
            stop = self.start_s + self.steps * self.dt_s
        return SimulationSpec(name=self.name or default_name, start_s=self.start_s, stop_s=stop, dt_s=self.dt_s,
                              stop_when=self.stop_when, exchange=self.exchange,
                              step_timeout_s=self.step_timeout_s)


# -- the whole file ------------------------------------------------------------------------------
def build_scenario_parts(data: dict, where: str, default_name: str, directory=None):
    """Check a parsed scenario; return its simulation, participants, connections, metocean, outputs.

    Raises
    ------
    ScenarioError
        The first problem, naming ``where`` (the file) and the dotted key.
    """
    top = checked(ScenarioFile, data, where)
    table = checked(SimulationTable, top.simulation, where, ("simulation",))
    simulation = table.spec(table.name or default_folder_name(default_name, "simulation.name", where))
    participants = participant_specs(top.participants, where, directory)
    for spec in participants:
        check_distances_nm(spec.options, where, f"participants.{spec.name}.options")
    check_distances_nm(top.metocean or {}, where, "metocean")
    connections = _connections(top.connections, participants, where)
    outputs = checked(OutputSpec, top.outputs or {}, where, ("outputs",))
    return simulation, participants, connections, top.metocean, outputs, top.acceptance


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
