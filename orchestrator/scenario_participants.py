"""The ``[participants.<name>]`` tables of a scenario as pydantic models.

A table with ``fmu`` is an FMU participant (its parameters, port mapping, geodetic origin
and initial state), one with ``type`` a Python participant (a registered type or
``type = "python"`` with ``class``); :func:`participant_specs` checks every table and
returns the frozen :class:`~orchestrator.scenario_spec.ParticipantSpec` of each.  Options of
Python participants are checked by the participant type that reads them.
"""

from __future__ import annotations

from pathlib import Path

from typing import Annotated, Any

from pydantic import Field, PlainValidator, model_validator

from orchestrator.errors import ScenarioError
from orchestrator.scenario_spec import ParticipantSpec, ScenarioTable, VariableMapping, VectorMapping
from orchestrator.toml_input import (Positive, Table, Text, checked, fail, fail_whole, is_finite_number, one_of,
                                     shown, shown_text)

#: Earth models of a geodetic mapping: the WGS84 ellipsoid, or a sphere (``sphere_radius_m``)
EARTH_MODELS = ("wgs84", "sphere")
#: IUGG mean earth radius [m], the sphere's radius unless the mapping gives the plant's own
MEAN_EARTH_RADIUS_M = 6371008.8
FMI_VERSIONS = ("2.0", "3.0")
#: Largest ``every``: a participant steps at least once in this many macro steps (the step limit).
MAX_EVERY = 1_000_000


def _every(value: Any) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or not 1 <= value <= MAX_EVERY:
        raise fail(f"must be a positive integer (at most {MAX_EVERY}), got {shown(value)}")
    return value


def _class_path(value: Any) -> str:
    if not isinstance(value, str):
        raise fail("must name 'package.module:Class' for type = \"python\"")
    return value


Every = Annotated[int, PlainValidator(_every)]


def _given_as_table(data: Any, key: str) -> Any:
    """``data`` as it is, after refusing a ``key`` given as something other than a table (checked
    before the fields, whose own message for a dict would not name the key)."""
    if isinstance(data, dict) and key in data and not isinstance(data[key], dict):
        raise fail_whole(f"'{{prefix}}{key}' must be a table")
    return data


class PythonParticipantTable(ScenarioTable):
    """``[participants.<name>]`` of a Python participant: a registered type or ``type = "python"``."""

    type: Text
    class_path: Annotated[str, PlainValidator(_class_path)] | None = Field(default=None, alias="class")
    every: Every = 1
    options: dict[str, Any] = {}
    #: wall-time limit of one set-up or step call [s]; None: the simulation's
    step_timeout_s: Positive | None = None

    @model_validator(mode="before")
    @classmethod
    def _options_table(cls, data: Any) -> Any:
        return _given_as_table(data, "options")

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
    #: the surface the plant integrates its latitude and longitude on
    earth: Annotated[str, one_of(EARTH_MODELS)] = "wgs84"
    #: radius of the sphere [m] (only with earth = "sphere")
    sphere_radius_m: Positive | None = None

    @model_validator(mode="after")
    def _radius_with_sphere(self):
        if self.sphere_radius_m is not None and self.earth != "sphere":
            raise fail_whole("'{prefix}sphere_radius_m' needs earth = \"sphere\"")
        return self


class FmuParticipantTable(ScenarioTable):
    """``[participants.<name>]`` of an FMU: the model, its parameters and how its ports map."""

    fmu: Annotated[str, PlainValidator(lambda v: _fmu(v))]
    fmi_version: Annotated[str, one_of(FMI_VERSIONS)] = "2.0"
    every: Every = 1
    parameter_set: Text | None = None
    parameters: dict[str, Annotated[Any, PlainValidator(_parameter)]] = {}
    mapping: Table = {}
    geodetic: GeodeticTable | None = None
    initial: Table = {}
    #: wall-time limit of one set-up or step call [s]; None: the simulation's
    step_timeout_s: Positive | None = None

    @model_validator(mode="before")
    @classmethod
    def _parameters_table(cls, data: Any) -> Any:
        return _given_as_table(data, "parameters")


def _fmu(value: Any) -> str:
    if not isinstance(value, str) or not value:
        raise fail("must be a model name or a path to an .fmu")
    return value


MAPPING_FORMS = ("must be \"variable\", { variable = \"...\", scale = 1.0, ... } or a vector "
                 "{ speed = ..., direction = ... } / { north = ..., east = ... }")


def _mapping_entry(target: Any, where: str, at: tuple) -> VariableMapping | VectorMapping:
    """One ``mapping.<port>`` entry: a variable name, a variable table or a vector table."""
    if isinstance(target, str) and target:
        return VariableMapping(variable=target)
    if not isinstance(target, dict) or ("variable" not in target
                                        and not set(target) & {"speed", "direction", "north", "east"}):
        raise ScenarioError(f"{where}: '{_dotted(at)}' {MAPPING_FORMS}")
    if "variable" in target:
        return checked(VariableMapping, target, where, at)
    return checked(VectorMapping, target, where, at)


def _dotted(at: tuple) -> str:
    return ".".join(shown_text(part) for part in at)


def participant_specs(table: dict, where: str, directory: Path | None = None) -> tuple[ParticipantSpec, ...]:
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
            specs.append(_fmu_participant(name, checked(FmuParticipantTable, body, where, at), where, at, directory))
        elif "type" in body:
            model = checked(PythonParticipantTable, body, where, at)
            specs.append(ParticipantSpec(name=name, every=model.every, type=model.type, class_path=model.class_path,
                                         options=dict(model.options), step_timeout_s=model.step_timeout_s))
        else:
            raise ScenarioError(f"{where}: '{_dotted(at)}' needs either 'fmu' or 'type'")
    return tuple(specs)


def _earth(table: GeodeticTable | None) -> tuple[str, float | None]:
    """``(model, radius [m])`` of a geodetic table: ``("wgs84", None)`` or ``("sphere", R)``."""
    if table is None or table.earth == "wgs84":
        return ("wgs84", None)
    return ("sphere", float(table.sphere_radius_m or MEAN_EARTH_RADIUS_M))


def _fmu_participant(name: str, model: FmuParticipantTable, where: str, at: tuple,
                     directory: Path | None = None) -> ParticipantSpec:
    from orchestrator.plant_ports import INITIAL_KEYS, port_table

    mapping = {port: _mapping_entry(target, where, at + ("mapping", port)) for port, target in model.mapping.items()}
    initial = {}
    table = dict(model.initial)
    in_plane = port_table().geographic_initial
    if in_plane is not None:  # the domain's geographic keys (a position in latitude and longitude)
        table = in_plane(table, Path(where).parent if directory is None else directory,
                         f"{where}: {_dotted(at + ('initial',))}")
    for key, value in table.items():
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
                           geodetic_earth=_earth(model.geodetic),
                           fmi_version=model.fmi_version, initial=initial,
                           step_timeout_s=model.step_timeout_s)
