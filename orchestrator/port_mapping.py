"""Bindings between an FMU's variables and the ports a scenario connects.

A scenario maps canonical plant ports (:mod:`orchestrator.plant_ports`) onto the variables
of a vendor's FMU.  Each binding converts values both ways:

- a *scalar* binding, ``canonical = scale * fmu_value + offset``: the scale and offset are
  given in the mapping, or follow from the unit the FMU declares for the variable (or the
  mapping's ``unit``), converted to the port's SI unit;
- a *geodetic* binding: latitude and longitude projected to local north/east metres about
  the scenario's origin (transverse Mercator on WGS84 or a sphere, see :class:`GeodeticBinding`);
- a *vector* binding: a current or wind the FMU takes as speed and direction ("set",
  towards; or "from") or as north/east components, fed from the canonical ports.

Mistakes are refused before a run with one line naming the port, the FMU variable and
the units involved: a declared unit of another dimension than the port's, a mapping ``unit``
that contradicts the unit the FMU declares, an angle port
bound to a variable that declares no unit and has no scale, one FMU variable feeding two
ports.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Mapping
from typing import TYPE_CHECKING

from orchestrator.errors import FmuError, ScenarioError
from orchestrator.geometry import DEG, wrap_angle
from orchestrator.plant_ports import ANGULAR_RATE, INITIAL_KEYS, PLANT_PORTS, VECTOR_PORTS, WRAPPED_OUTPUTS
from orchestrator.scenario import ParticipantSpec, VariableMapping, VectorMapping
from orchestrator.units import SiUnit, UnitParseError, declared_unit, describe_dimension, resolve_unit

if TYPE_CHECKING:
    from fmpy.model_description import ScalarVariable

log = logging.getLogger(__name__)

#: Type names of real variables: FMI 2.0 ``Real``, FMI 3.0 ``Float64``/``Float32``.
REAL_TYPES = ("Real", "Float64", "Float32")


class ScalarBinding:
    """One port, one FMU variable: ``canonical = scale * fmu + offset``."""

    def __init__(self, port: str, variable: str, scale: float, offset: float, wrap: bool = False) -> None:
        self.ports = (port,)
        self.variables = (variable,)
        self.scale, self.offset, self.wrap = scale, offset, wrap

    def to_canonical(self, values: Mapping[str, float]) -> dict[str, float]:
        value = self.scale * values[self.variables[0]] + self.offset
        return {self.ports[0]: float(wrap_angle(value)) if self.wrap else value}

    def to_fmu(self, canonical: Mapping[str, float]) -> dict[str, float]:
        return {self.variables[0]: (canonical[self.ports[0]] - self.offset) / self.scale}


class GeodeticBinding:
    """Ports ``x`` (north) and ``y`` (east) [m] from an FMU's latitude and longitude.

    The projection is a transverse Mercator on the plant's earth model (the WGS84 ellipsoid,
    or a sphere of the given radius for a plant that integrates its position on one) whose
    central meridian and origin are the scenario's origin (scale 1 on that meridian): it is conformal, so
    headings and turning circles keep their shape, and its scale error stays below 5e-4
    within 100 nm east or west of the origin.  (An azimuthal equidistant projection keeps
    distances from the origin exact instead, but distorts angles away from it.)  Grid north
    departs from true north by the meridian convergence, about Δlon·sin(lat): 0.1 deg at
    10 nm from the origin in mid latitudes.
    """

    def __init__(self, variables: tuple[str, str], to_degrees: tuple[tuple[float, float], tuple[float, float]],
                 origin_deg: tuple[float, float], earth: tuple[str, float | None] = ("wgs84", None)) -> None:
        from pyproj import Transformer

        self.ports = ("x", "y")
        self.variables = variables
        self.to_degrees = to_degrees
        lat0, lon0 = origin_deg
        model, radius = earth
        if model == "sphere":
            if radius is None:
                raise ValueError("a spherical earth needs its radius")
            surface = f"+R={float(radius)!r}"
            geographic = f"+proj=longlat {surface} +no_defs +type=crs"
        else:
            surface, geographic = "+ellps=WGS84", "EPSG:4326"
        projection = f"+proj=tmerc +lat_0={lat0!r} +lon_0={lon0!r} +k=1 +x_0=0 +y_0=0 {surface} +units=m +no_defs +type=crs"
        self._forward = Transformer.from_crs(geographic, projection, always_xy=True)

    def to_canonical(self, values: Mapping[str, float]) -> dict[str, float]:
        (lat_scale, lat_offset), (lon_scale, lon_offset) = self.to_degrees
        lat = lat_scale * values[self.variables[0]] + lat_offset
        lon = lon_scale * values[self.variables[1]] + lon_offset
        east, north = self._forward.transform(lon, lat)
        return {"x": float(north), "y": float(east)}

    def latitude_longitude(self, north_m: float, east_m: float) -> tuple[float, float]:
        """Latitude and longitude [deg] of a point ``north_m``, ``east_m`` of the origin."""
        from pyproj.enums import TransformDirection

        lon, lat = self._forward.transform(east_m, north_m, direction=TransformDirection.INVERSE)
        return float(lat), float(lon)


class VectorBinding:
    """A velocity the canonical ports give in one form and the FMU takes in another.

    Forms: ``cartesian`` (north, east components) or ``polar_towards``/``polar_from``
    (speed and the direction the flow goes to, "set", or comes from), directions
    clockwise from north.  A port left unconnected counts as zero.
    """

    def __init__(self, ports: tuple[str, str], canonical_form: str, variables: tuple[str, str], fmu_form: str,
                 conversions: tuple[tuple[float, float], tuple[float, float]]) -> None:
        self.ports, self.canonical_form = ports, canonical_form
        self.variables, self.fmu_form, self.conversions = variables, fmu_form, conversions

    def to_fmu(self, canonical: Mapping[str, float]) -> dict[str, float]:
        first, second = (canonical.get(port, 0.0) for port in self.ports)
        if self.canonical_form == "cartesian":
            speed, towards = math.hypot(first, second), math.atan2(second, first)
        else:  # polar_from
            speed, towards = first, second + math.pi
        if self.fmu_form == "cartesian":
            values = (speed * math.cos(towards), speed * math.sin(towards))
        else:
            direction = towards + (math.pi if self.fmu_form == "polar_from" else 0.0)
            values = (speed, math.fmod(direction, 2.0 * math.pi) % (2.0 * math.pi))
        return {variable: (value - offset) / scale
                for variable, value, (scale, offset) in zip(self.variables, values, self.conversions)}


def _fail(where: str, message: str) -> ScenarioError:
    return ScenarioError(f"{where}: {message}")


def scalar_conversion(port: str, entry: VariableMapping, variable, model_description, where: str) -> tuple[float, float]:
    """``(scale, offset)`` taking the FMU variable's values to the port's SI values.

    An explicit ``scale``/``offset`` wins; otherwise the mapping's ``unit`` or the unit the
    FMU declares is converted to the canonical port's SI unit.  Refuses a unit of another
    dimension than the port's, and an angle port without unit and without scale.
    """
    spec = PLANT_PORTS.get(port)
    declared = declared_unit(variable, model_description)
    unit_name = entry.unit or declared
    si = None
    if unit_name is not None:
        try:
            si = resolve_unit(unit_name, model_description)
        except UnitParseError as exc:
            raise _fail(where, f"FMU variable '{variable.name}': {exc}") from None
    if entry.unit is not None and declared is not None and si is not None and entry.unit != declared:
        _check_same_unit(entry.unit, si, declared, variable.name, model_description, where)
    if spec is not None:
        if si is not None and spec.revolutions and si.dimension == ANGULAR_RATE:
            # rpm, rad/s: 2 pi rad per revolution
            si = SiUnit(si.name, si.factor / (2.0 * math.pi), si.offset / (2.0 * math.pi), spec.dimension)
        if si is not None and si.dimension != spec.dimension:
            raise _fail(where, f"port '{port}' is in {spec.si_unit} but FMU variable '{variable.name}' is in "
                               f"'{unit_name}' ({describe_dimension(si.dimension)}): not convertible")
        if si is None and spec.is_angle and entry.scale is None:
            raise _fail(where, f"port '{port}' is an angle ({spec.si_unit}) and FMU variable '{variable.name}' "
                               "declares no unit: give its unit (unit = \"deg\") or a scale")
    converts = si if spec is not None else None  # the declared unit, where the port has one to convert to
    if entry.scale is not None:
        scale = entry.scale
        if converts is not None and not math.isclose(scale, converts.factor, rel_tol=1e-6):
            log.warning("%s: scale %g differs from the factor %g of the declared unit '%s' of '%s'",
                        where, scale, converts.factor, unit_name, variable.name)
    else:
        scale = converts.factor if converts is not None else 1.0
    if entry.offset is not None:
        offset = entry.offset
    else:
        offset = converts.offset if converts is not None and entry.scale is None else 0.0
    return scale, offset


def _check_same_unit(given: str, given_si: SiUnit, declared: str, variable: str, model_description,
                     where: str) -> None:
    """Refuse a mapping ``unit`` that means something else than the unit the FMU declares.

    The FMU's declaration describes what it computes; a mapping that states another unit
    (m/s on a variable in knots, rad on one in degrees) would scale every value by the
    ratio of the two without a word.  Another name for the same unit (``knot`` for ``kn``)
    is accepted.
    """
    try:
        own = resolve_unit(declared, model_description)
    except UnitParseError:
        return  # the FMU's own name is unreadable: the mapping's unit is what we have
    same = (given_si.dimension == own.dimension and math.isclose(given_si.factor, own.factor, rel_tol=1e-9)
            and math.isclose(given_si.offset, own.offset, rel_tol=1e-9, abs_tol=1e-12))
    if not same:
        raise _fail(where, f"unit '{given}' contradicts the unit '{declared}' that the FMU declares for variable "
                           f"'{variable}'; remove unit (the declared one is used) or fix the FMU's modelDescription")


def _degree_conversion(entry: VariableMapping, variable, model_description, where: str) -> tuple[float, float]:
    """``(scale, offset)`` from a latitude/longitude variable to degrees."""
    scale, offset = scalar_conversion("psi", entry, variable, model_description, where)  # an angle, in rad
    return scale / DEG, offset / DEG


def bind_ports(spec: ParticipantSpec, variables: Mapping[str, ScalarVariable], model_description, where: str,
               fmu_name: str) -> tuple[list, list]:
    """Input and output bindings of an FMU participant (mapped ports, then unmapped variables).

    Raises
    ------
    FmuError
        A mapped variable the FMU lacks, a wrong causality or type.
    ScenarioError
        A unit mismatch, an angle without unit, one variable feeding two ports, an
        incomplete geodetic or vector mapping.
    """
    inputs: list[ScalarBinding | VectorBinding | GeodeticBinding] = []
    outputs: list[ScalarBinding | VectorBinding | GeodeticBinding] = []
    used: dict[str, str] = {}  # FMU variable -> the port it feeds

    def take(port: str, name: str, causality: str | None):
        key = f"{where}.mapping.{port}"
        variable = variables.get(name)
        if variable is None:
            raise FmuError(f"{key}: FMU {fmu_name} has no variable '{name}'")
        if variable.causality not in ("input", "output"):
            raise FmuError(f"{key}: variable '{name}' has causality '{variable.causality}'; "
                           "only inputs and outputs can be mapped")
        if causality is not None and variable.causality != causality:
            raise FmuError(f"{key}: '{port}' is a plant {causality} but FMU variable '{name}' is an {variable.causality}")
        if variable.type not in REAL_TYPES:
            raise FmuError(f"{key}: variable '{name}' is not Real")
        if name in used:
            raise ScenarioError(f"{key}: FMU variable '{name}' already feeds port '{used[name]}'; "
                                "one variable may feed one port")
        used[name] = port
        return variable

    geodetic = {port: entry for port, entry in spec.mapping.items()
                if isinstance(entry, VariableMapping) and entry.geodetic is not None}
    for port, entry in spec.mapping.items():
        key = f"{where}.mapping.{port}"
        if isinstance(entry, VectorMapping):
            inputs.append(_vector_binding(port, entry, take, model_description, key))
            continue
        expected = PLANT_PORTS[port].causality if port in PLANT_PORTS else None
        variable = take(port, entry.variable, expected)
        if port in geodetic:
            continue
        scale, offset = scalar_conversion(port, entry, variable, model_description, key)
        binding = ScalarBinding(port, entry.variable, scale, offset,
                                wrap=variable.causality == "output" and port in WRAPPED_OUTPUTS)
        (inputs if variable.causality == "input" else outputs).append(binding)
    if geodetic:
        outputs.append(_geodetic_binding(spec, geodetic, variables, model_description, where))
    bound_ports = set()
    for bound in inputs + outputs:
        for port in bound.ports:
            if port in bound_ports:
                raise ScenarioError(f"{where}.mapping: port '{port}' is mapped twice (directly and in a vector)")
            bound_ports.add(port)
    for variable in model_description.modelVariables:
        if variable.name in used or variable.type not in REAL_TYPES or variable.name in bound_ports:
            continue
        if variable.causality not in ("input", "output"):
            continue
        entry = VariableMapping(variable=variable.name)
        scale, offset = scalar_conversion(variable.name, entry, variable, model_description,
                                          f"{where}: FMU variable '{variable.name}'")
        binding = ScalarBinding(variable.name, variable.name, scale, offset,
                                wrap=variable.causality == "output" and variable.name in WRAPPED_OUTPUTS)
        (inputs if variable.causality == "input" else outputs).append(binding)
    return inputs, outputs


def _vector_binding(name: str, entry: VectorMapping, take, model_description, key: str) -> VectorBinding:
    if name not in VECTOR_PORTS:
        raise ScenarioError(f"{key}: '{name}' is not a vector input (valid: {', '.join(VECTOR_PORTS)})")
    canonical_form, *ports = VECTOR_PORTS[name]
    parts: tuple[tuple[str, str | None, str], ...]
    if entry.speed is not None:
        fmu_form = f"polar_{entry.direction_is}"
        parts = (("speed", entry.speed, "wind_speed"), ("direction", entry.direction, "wind_direction"))
    else:
        fmu_form = "cartesian"
        parts = (("north", entry.north, "current_north"), ("east", entry.east, "current_east"))

    def bind(role: str, variable_name: str | None, like: str) -> tuple[str, tuple[float, float]]:
        if variable_name is None:   # VectorMapping holds both parts of its form
            raise ScenarioError(f"{key}: no '{role}' variable")
        variable = take(f"{name}.{role}", variable_name, "input")
        sub = VariableMapping(variable=variable_name, unit=entry.units.get(role))
        return variable_name, scalar_conversion(like, sub, variable, model_description, f"{key}.{role}")

    (first, first_conversion), (second, second_conversion) = (bind(*part) for part in parts)
    return VectorBinding(tuple(ports), canonical_form, (first, second), fmu_form,
                         (first_conversion, second_conversion))


def _geodetic_binding(spec: ParticipantSpec, geodetic: dict, variables, model_description, where: str):
    roles = {entry.geodetic: port for port, entry in geodetic.items()}
    if roles.get("latitude") != "x" or roles.get("longitude") != "y" or len(geodetic) != 2:
        raise ScenarioError(f"{where}.mapping: geodetic positions need x = {{ variable = ..., geodetic = \"latitude\" }}"
                            " and y = { variable = ..., geodetic = \"longitude\" }")
    if spec.geodetic_origin_deg is None:
        raise ScenarioError(f"{where}.geodetic: give origin_deg = [lat, lon] for the geodetic mapping of x and y")
    north, east = (_degree_conversion(geodetic[port], variables[geodetic[port].variable], model_description,
                                      f"{where}.mapping.{port}") for port in ("x", "y"))
    return GeodeticBinding((geodetic["x"].variable, geodetic["y"].variable), (north, east), spec.geodetic_origin_deg,
                           spec.geodetic_earth)


def initial_start_values(spec: ParticipantSpec, outputs: list, variables: Mapping[str, ScalarVariable], model_description,
                         where: str) -> dict[str, float]:
    """FMU start values (parameter name -> value) of the ``[initial]`` table.

    Each canonical value is taken through the same mapping as the port it initialises
    into the FMU's start parameter: the mapping entry's ``start``, else a parameter named
    ``<port>0`` (the built-in models' convention).
    """
    canonical: dict[str, float] = {}
    for key, value in spec.initial.items():
        port, factor = INITIAL_KEYS[key]
        if port in canonical:
            raise ScenarioError(f"{where}.initial.{key}: '{port}' is already given")
        canonical[port] = value * factor
    starts: dict[str, float] = {}
    geodetic = next((b for b in outputs if isinstance(b, GeodeticBinding)), None)
    for port, value in canonical.items():
        entry = spec.mapping.get(port)
        entry = entry if isinstance(entry, VariableMapping) else VariableMapping(variable=port)
        name = entry.start or f"{port}0"
        parameter = variables.get(name)
        key = f"{where}.initial: '{port}'"
        if parameter is None or parameter.causality != "parameter":
            raise ScenarioError(f"{key} has no start parameter in the FMU (give start = \"...\" in mapping.{port})")
        if geodetic is not None and port in ("x", "y"):
            continue
        scale, offset = scalar_conversion(port, entry, parameter, model_description, key)
        starts[name] = (value - offset) / scale
    if geodetic is not None and ({"x", "y"} & set(canonical)):
        degrees = geodetic.latitude_longitude(canonical.get("x", 0.0), canonical.get("y", 0.0))
        for port, value in zip(("x", "y"), degrees):
            entry = spec.mapping[port]
            assert isinstance(entry, VariableMapping)  # a geodetic x, y maps to one variable (checked on reading)
            parameter = variables[entry.start or f"{port}0"]
            scale, offset = _degree_conversion(entry, parameter, model_description, f"{where}.initial: '{port}'")
            starts[parameter.name] = (value - offset) / scale
    for name in starts:
        if name in spec.parameters:
            raise ScenarioError(f"{where}.parameters.{name}: the initial state is already given in [initial]")
    return starts
