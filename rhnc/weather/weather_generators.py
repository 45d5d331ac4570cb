"""Synthetic met-ocean generators, registered in one table and selected by ``[metocean] generator``.

Every generator builds a :class:`rhnc.weather.metocean.MetOceanField` over a map (keys
``x_range_nm``, ``y_range_nm``, ``resolution_nm``), with the sea state from the wind by the
fetch-limited relation (:func:`rhnc.weather.metocean.fetch_limited_hs`, key ``fetch_km``) and a
uniform current (``current_kn`` towards ``current_towards_deg``).  What each one models,
its formula, its parameters and why they have the values they have: ``docs/weather.md``.

=================  ====================================================================
``paper_default``  the paper's weather: spline wind through control points, one direction
``storm_off_route``  a Gaussian gale over a background wind, centred off the direct route
``cyclone``        a Holland (1980) vortex with inflow, static unless ``translation_kn > 0``
``moving_storm``   the same vortex crossing the direct route, hourly steps over 24 h
``storm_set``      member k of a seeded set of gales drawn over position, size, strength
                   and wind direction (:func:`storm_set_member`)
``current_jet``    a band of current parallel to a route (:mod:`rhnc.weather.routing_weather_set`)
``routing_set``    member k of a seeded set of gales, moving gales and current jets about
                   any route and map (:mod:`rhnc.weather.routing_weather_set`)
=================  ====================================================================

Keys are checked against the generator's table before it runs: an unknown key or a value
of the wrong type is a one-line :class:`orchestrator.errors.ScenarioError` naming the key.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from orchestrator.errors import ScenarioError
from orchestrator.participant import is_finite_number
from orchestrator.geometry import KNOT, NM
from rhnc.weather.metocean import MetOceanField, fetch_limited_hs
from rhnc.weather.metocean_grid import check_grid_nodes, map_axis
from rhnc.weather.routing_weather_set import current_jet, routing_set_member
from rhnc.weather.weather_spline import bicubic_grid

#: Draws of the storm set, fixed on 2026-11-22 before any routing result (docs/weather.md).
STORM_SET_DRAWS = {
    "along_route": (0.25, 0.75),      # fraction of the route from start to goal, uniform
    "cross_route_nm": (-30.0, 30.0),  # offset to the left (+) or right (-) of the route, uniform
    "radius_nm": (10.0, 30.0),        # Gaussian radius, uniform
    "peak_wind_ms": (15.0, 28.0),     # wind speed at the centre, uniform
    "background_wind_ms": (4.0, 10.0),  # wind far from the storm, uniform
    "wind_from_deg": (0.0, 360.0),    # direction the wind comes from, uniform
}
#: Default wind-speed control points [m/s] of the paper-style weather, a 5 x 5 lattice
#: spanning the map (rows: north from south to north, columns: east from west to east).
#: A band of strong wind across the middle of the direct (0,0)->(100,100) nm route, calm
#: water in the north-west and south-east corners.
DEFAULT_WIND_CONTROL_POINTS = (
    (8.0, 9.0, 10.0, 8.0, 6.0),
    (9.0, 12.0, 14.0, 11.0, 7.0),
    (7.0, 13.0, 18.0, 14.0, 9.0),
    (6.0, 10.0, 15.0, 12.0, 8.0),
    (5.0, 7.0, 10.0, 9.0, 7.0),
)
#: Most time steps of a moving storm's field.
MAX_TIME_STEPS = 1000
#: Members of the documented storm set (the batch runs 0 .. STORM_SET_SIZE - 1).
STORM_SET_SIZE = 30


# -- the generators -----------------------------------------------------------------------
def paper_default(x_range_nm=(0.0, 100.0), y_range_nm=(0.0, 100.0), resolution_nm: float = 1.0,
                  wind_control_points_ms=DEFAULT_WIND_CONTROL_POINTS, wind_from_deg: float = 45.0,
                  fetch_km: float = 100.0, current_kn: float = 0.5,
                  current_towards_deg: float = 135.0) -> MetOceanField:
    """The paper's synthetic weather (its Section 6.1.1).

    Parameters
    ----------
    x_range_nm, y_range_nm : (float, float)
        Map extent north and east [nm].
    resolution_nm : float
        Grid spacing [nm].
    wind_control_points_ms : 2-D sequence
        Wind speed [m/s] at an evenly spaced lattice of control points spanning the
        map (rows south to north, columns west to east), at least 4 x 4 for the
        bicubic spline.
    wind_from_deg : float
        Direction the wind comes from [deg, clockwise from north], uniform.
    fetch_km : float
        Fetch for the fetch-limited wave height [km].
    current_kn, current_towards_deg : float
        Uniform current speed [kn] and the direction it sets towards [deg].
    """
    control = np.asarray(wind_control_points_ms, dtype=float)
    if control.ndim != 2 or min(control.shape) < 4:
        raise ValueError("wind_control_points_ms needs a 2-D lattice of at least 4 x 4 values")
    x, y = map_axis(x_range_nm, resolution_nm), map_axis(y_range_nm, resolution_nm)
    cx = np.linspace(x[0], x[-1], control.shape[0])
    cy = np.linspace(y[0], y[-1], control.shape[1])
    speed = np.clip(bicubic_grid(cx, cy, control, x, y), 0.0, None)
    towards = np.radians(wind_from_deg) + np.pi
    fields = _with_sea_and_current(speed, speed * np.cos(towards), speed * np.sin(towards), fetch_km,
                                   current_kn, current_towards_deg)
    return MetOceanField(x, y, fields, source="generated: paper_default")


def storm_off_route(x_range_nm=(0.0, 100.0), y_range_nm=(0.0, 100.0), resolution_nm: float = 1.0,
                    centre_nm=(60.0, 40.0), radius_nm: float = 20.0, peak_wind_ms: float = 22.0,
                    background_wind_ms: float = 7.0, wind_from_deg: float = 45.0, fetch_km: float = 100.0,
                    current_kn: float = 0.5, current_towards_deg: float = 135.0,
                    source: str = "generated: storm_off_route") -> MetOceanField:
    """A gale area: a Gaussian wind-speed bump over a background wind of one direction.

    ``U(p) = U_b + (U_p - U_b) exp(-|p - c|^2 / (2 R^2))`` from ``wind_from_deg``.

    Parameters
    ----------
    centre_nm : (float, float)
        Storm centre c, north and east [nm].
    radius_nm : float
        R [nm]: at R from the centre the excess over the background is exp(-1/2) = 61 %.
    peak_wind_ms, background_wind_ms : float
        U_p at the centre and U_b far from it [m/s].
    wind_from_deg : float
        Direction the wind comes from everywhere [deg, clockwise from north].
    Other parameters as :func:`paper_default`.
    """
    _require_positive(radius_nm=radius_nm)
    _require_non_negative(peak_wind_ms=peak_wind_ms, background_wind_ms=background_wind_ms)
    x, y = map_axis(x_range_nm, resolution_nm), map_axis(y_range_nm, resolution_nm)
    dx = x[:, None] - centre_nm[0] * NM
    dy = y[None, :] - centre_nm[1] * NM
    radius = radius_nm * NM
    speed = background_wind_ms + (peak_wind_ms - background_wind_ms) * np.exp(-(dx**2 + dy**2) / (2 * radius**2))
    towards = np.radians(wind_from_deg) + np.pi
    fields = _with_sea_and_current(speed, speed * np.cos(towards), speed * np.sin(towards), fetch_km,
                                   current_kn, current_towards_deg)
    return MetOceanField(x, y, fields, source=source)


def cyclone(x_range_nm=(0.0, 100.0), y_range_nm=(0.0, 100.0), resolution_nm: float = 1.0,
            centre_nm=(60.0, 40.0), max_wind_ms: float = 25.0, radius_max_wind_nm: float = 15.0,
            holland_b: float = 1.5, inflow_deg: float = 20.0, hemisphere: str = "north",
            translation_kn: float = 0.0, heading_deg: float = 0.0, duration_h: float = 24.0,
            time_step_h: float = 1.0, fetch_km: float = 100.0, current_kn: float = 0.5,
            current_towards_deg: float = 135.0, source: str = "generated: cyclone") -> MetOceanField:
    """A rotating storm: Holland (1980) wind profile, cyclonic rotation with inflow, optionally moving.

    Wind speed at distance r from the centre (Holland's profile without the Coriolis
    term, so that it peaks at exactly ``max_wind_ms``):
    ``V(r) = V_m sqrt((R_m / r)^B exp(1 - (R_m / r)^B))``.  The wind blows along the
    circle, counter-clockwise seen from above in the northern hemisphere (clockwise in
    the southern), turned towards the centre by the inflow angle.  With
    ``translation_kn > 0`` the centre moves from ``centre_nm`` at t = 0 towards
    ``heading_deg``, and the field has a time step every ``time_step_h`` hours until
    ``duration_h``; linear interpolation in time between them.

    Parameters
    ----------
    centre_nm : (float, float)
        Centre at t = 0, north and east [nm].
    max_wind_ms : float
        V_m, the maximum wind speed [m/s].
    radius_max_wind_nm : float
        R_m, the radius of maximum wind [nm].
    holland_b : float
        Holland's shape parameter B (1 to 2.5: larger is more peaked).
    inflow_deg : float
        Angle [deg] by which the wind is turned from the tangent towards the centre.
    hemisphere : {"north", "south"}
        Sense of rotation.
    translation_kn, heading_deg : float
        Speed [kn] and direction [deg, clockwise from north] of the centre's motion.
    duration_h, time_step_h : float
        Span and spacing [h] of the time steps of a moving storm.
    Other parameters as :func:`paper_default`.
    """
    _require_positive(max_wind_ms=max_wind_ms, radius_max_wind_nm=radius_max_wind_nm, holland_b=holland_b,
                      duration_h=duration_h, time_step_h=time_step_h)
    _require_non_negative(translation_kn=translation_kn)
    if hemisphere not in ("north", "south"):
        raise ValueError(f"hemisphere '{hemisphere}' is not valid (valid: north, south)")
    if not 0.0 <= inflow_deg < 90.0:
        raise ValueError(f"inflow_deg must lie in [0, 90), got {inflow_deg}")
    x, y = map_axis(x_range_nm, resolution_nm), map_axis(y_range_nm, resolution_nm)
    if translation_kn > 0:
        if time_step_h > duration_h:
            raise ValueError(f"time_step_h {time_step_h} is longer than duration_h {duration_h}")
        steps = duration_h / time_step_h
        if not steps < MAX_TIME_STEPS:
            raise ValueError(f"duration_h / time_step_h gives {steps + 1:.3g} time steps, more than the limit of "
                             f"{MAX_TIME_STEPS}")
        count = int(math.floor(steps + 1e-9)) + 1
        check_grid_nodes(x.size, y.size, count)
        times_s = np.arange(count) * time_step_h * 3600.0
    else:
        times_s = np.array([0.0])
    heading = math.radians(heading_deg)
    sense = 1.0 if hemisphere == "north" else -1.0
    cos_in, sin_in = math.cos(math.radians(inflow_deg)), math.sin(math.radians(inflow_deg))
    speeds, north, east = [], [], []
    for t_s in times_s:
        moved_nm = translation_kn * t_s / 3600.0
        dx = x[:, None] - (centre_nm[0] + moved_nm * math.cos(heading)) * NM
        dy = y[None, :] - (centre_nm[1] + moved_nm * math.sin(heading)) * NM
        r = np.maximum(np.hypot(dx, dy), 1.0)
        speed = holland_wind_speed(r, max_wind_ms, radius_max_wind_nm * NM, holland_b)
        # tangent (counter-clockwise for sense = +1) and outward radial unit vectors
        speeds.append(speed)
        north.append(speed * (sense * cos_in * dy / r - sin_in * dx / r))
        east.append(speed * (-sense * cos_in * dx / r - sin_in * dy / r))
    fields = _with_sea_and_current(np.stack(speeds), np.stack(north), np.stack(east), fetch_km, current_kn,
                                   current_towards_deg)
    if times_s.size == 1:
        return MetOceanField(x, y, {name: values[0] for name, values in fields.items()}, source=source)
    return MetOceanField(x, y, fields, source=source, times_s=times_s)


def moving_storm(**options) -> MetOceanField:
    """:func:`cyclone` with the defaults of the moving storm (``docs/weather.md``): it starts
    28 nm south-east of the direct (0,0)->(100,100) nm route and moves north-west at 8 kn, so
    that its centre crosses the route at (50, 50) nm 3.5 h after departure."""
    settings = {"centre_nm": (30.0, 70.0), "translation_kn": 8.0, "heading_deg": 315.0,
                "source": "generated: moving_storm", **options}
    return cyclone(**settings)


def storm_set_member(seed: int, member: int, route_start_nm=(0.0, 0.0),
                     route_goal_nm=(100.0, 100.0)) -> dict[str, Any]:
    """The storm parameters of member ``member`` of the set drawn from ``seed``.

    Each member draws from its own stream, ``numpy.random.default_rng([seed, member])``,
    in the order of :data:`STORM_SET_DRAWS`: member k depends on the seed and k alone.
    The centre is placed at a drawn fraction of the straight route and a drawn offset
    across it (positive: to the left looking from start to goal).

    Returns
    -------
    dict
        Keyword arguments of :func:`storm_off_route`: ``centre_nm``, ``radius_nm``,
        ``peak_wind_ms``, ``background_wind_ms``, ``wind_from_deg``.
    """
    rng = np.random.default_rng([int(seed), int(member)])
    draw = {name: float(rng.uniform(low, high)) for name, (low, high) in STORM_SET_DRAWS.items()}
    start = np.asarray(route_start_nm, dtype=float)
    along = np.asarray(route_goal_nm, dtype=float) - start
    length = float(np.hypot(*along))
    if not length > 0:
        raise ValueError("route_start_nm and route_goal_nm must differ")
    left = np.array([-along[1], along[0]]) / length  # (north, east) to the left of the route
    centre = start + draw["along_route"] * along + draw["cross_route_nm"] * left
    return {"centre_nm": (round(float(centre[0]), 6), round(float(centre[1]), 6)),
            **{name: round(draw[name], 6) for name in ("radius_nm", "peak_wind_ms", "background_wind_ms",
                                                       "wind_from_deg")}}


def storm_set(seed: int = 2026, member: int = 0, route_start_nm=(0.0, 0.0), route_goal_nm=(100.0, 100.0),
              **options) -> MetOceanField:
    """Member ``member`` of the seeded storm set: :func:`storm_off_route` with drawn parameters."""
    if member < 0 or seed < 0:
        raise ValueError(f"seed and member must not be negative, got seed {seed}, member {member}")
    storm = storm_set_member(seed, member, route_start_nm, route_goal_nm)
    described = ", ".join(f"{name} {value}" for name, value in storm.items())
    return storm_off_route(**options, **storm, source=f"generated: storm_set seed {seed} member {member} ({described})")


def holland_wind_speed(r_m, max_wind_ms: float, radius_max_wind_m: float, holland_b: float) -> np.ndarray:
    """Holland (1980) profile without Coriolis: V_m sqrt((R_m/r)^B exp(1 - (R_m/r)^B)) [m/s].

    Evaluated in logarithms so that it tends to 0 at the centre without overflow.
    """
    a_log = holland_b * np.log(radius_max_wind_m / np.asarray(r_m, dtype=float))
    return max_wind_ms * np.exp(0.5 * (a_log + 1.0 - np.exp(a_log)))


# -- the registry ---------------------------------------------------------------------------
@dataclass(frozen=True)
class Generator:
    """One registered generator: its builder, a one-line summary and its keys -> kinds.

    Kinds: ``number`` (int or float), ``integer``, ``boolean``, ``point`` ([north, east] numbers),
    ``lattice`` (2-D list of numbers), ``text``.
    """

    build: Callable[..., MetOceanField]
    summary: str
    keys: Mapping[str, str]


_MAP_KEYS = {"x_range_nm": "point", "y_range_nm": "point", "resolution_nm": "number"}
_SEA_KEYS = {"fetch_km": "number", "current_kn": "number", "current_towards_deg": "number"}
_CYCLONE_KEYS = {"centre_nm": "point", "max_wind_ms": "number", "radius_max_wind_nm": "number",
                 "holland_b": "number", "inflow_deg": "number", "hemisphere": "text", "translation_kn": "number",
                 "heading_deg": "number", "duration_h": "number", "time_step_h": "number"}

GENERATORS: dict[str, Generator] = {
    "paper_default": Generator(paper_default, "the paper's weather: spline wind through a 5 x 5 lattice, from 045",
                               {**_MAP_KEYS, "wind_control_points_ms": "lattice", "wind_from_deg": "number",
                                **_SEA_KEYS}),
    "storm_off_route": Generator(storm_off_route, "a Gaussian gale 14 nm off the direct route, from 045",
                                 {**_MAP_KEYS, "centre_nm": "point", "radius_nm": "number",
                                  "peak_wind_ms": "number", "background_wind_ms": "number",
                                  "wind_from_deg": "number", **_SEA_KEYS}),
    "cyclone": Generator(cyclone, "a Holland (1980) vortex with inflow, moving when translation_kn > 0",
                         {**_MAP_KEYS, **_CYCLONE_KEYS, **_SEA_KEYS}),
    "moving_storm": Generator(moving_storm, "the Holland vortex crossing the direct route at 8 kn, 24 h hourly",
                              {**_MAP_KEYS, **_CYCLONE_KEYS, **_SEA_KEYS}),
    "storm_set": Generator(storm_set, "member k of 30 seeded gales drawn over position, size, strength, direction",
                           {**_MAP_KEYS, "seed": "integer", "member": "integer", "route_start_nm": "point",
                            "route_goal_nm": "point", **_SEA_KEYS}),
}


def routing_set(seed: int = 2611, member: int = 0, route_start_nm=(0.0, 0.0), route_goal_nm=(100.0, 100.0),
                x_range_nm=(0.0, 100.0), y_range_nm=(0.0, 100.0), resolution_nm: float = 1.0,
                fetch_km: float = 100.0) -> MetOceanField:
    """Member ``member`` of the routing set (:mod:`rhnc.weather.routing_weather_set`) over the given map:
    a gale (:func:`storm_off_route`), a moving gale (:func:`cyclone`) or a current jet, without
    the uniform current of the other generators."""
    kind, arguments = routing_set_member(seed, member, route_start_nm, route_goal_nm)
    described = ", ".join(f"{name} {value}" for name, value in arguments.items()
                          if name not in ("route_start_nm", "route_goal_nm"))
    source = f"generated: routing_set seed {seed} member {member}: {kind} ({described})"
    grid = {"x_range_nm": x_range_nm, "y_range_nm": y_range_nm, "resolution_nm": resolution_nm,
            "fetch_km": fetch_km, "source": source}
    if kind == "gale":
        return storm_off_route(**grid, **arguments, current_kn=0.0)
    if kind == "moving gale":
        return cyclone(**grid, **arguments, current_kn=0.0)
    return current_jet(**grid, **arguments)


GENERATORS["current_jet"] = Generator(
    current_jet, "a Gaussian band of current parallel to the route, under a uniform wind",
    {**_MAP_KEYS, "route_start_nm": "point", "route_goal_nm": "point", "offset_nm": "number", "width_nm": "number",
     "peak_kn": "number", "towards_goal": "boolean", "background_wind_ms": "number", "wind_from_deg": "number",
     "fetch_km": "number"})
GENERATORS["routing_set"] = Generator(
    routing_set, "member k of a seeded set of gales, moving gales and current jets about any route",
    {**_MAP_KEYS, "seed": "integer", "member": "integer", "route_start_nm": "point", "route_goal_nm": "point",
     "fetch_km": "number"})


def list_generators() -> dict[str, str]:
    """Registered generator names and their one-line summaries."""
    return {name: generator.summary for name, generator in GENERATORS.items()}


def build_generated(name: Any, options: Mapping[str, Any], where: str) -> MetOceanField:
    """Check ``options`` against generator ``name``'s keys and build its field.

    Raises
    ------
    ScenarioError
        One line naming ``where`` and the key: an unknown generator or key, a value of
        the wrong kind, or a value the generator refuses.
    """
    generator = GENERATORS.get(name) if isinstance(name, str) else None
    if generator is None:
        raise ScenarioError(f"{where}.generator: unknown generator '{name}' (valid: {', '.join(GENERATORS)})")
    arguments = {}
    for key, value in options.items():
        if key not in generator.keys:
            raise ScenarioError(f"{where}: unknown key '{key}' for generator '{name}' "
                                f"(valid: {', '.join(sorted(generator.keys))})")
        arguments[key] = checked_option(value, generator.keys[key], f"{where}.{key}")
    try:
        return generator.build(**arguments)
    except (ValueError, TypeError) as exc:
        raise ScenarioError(f"{where}: {exc}") from exc


def checked_option(value: Any, kind: str, where: str) -> Any:
    """``value`` as the kind of :class:`Generator` (number, integer, point, lattice, text).

    Raises
    ------
    ScenarioError
        ``<where>: expected ...`` when the value is not of that kind.
    """
    if kind == "number":
        if not is_finite_number(value):
            raise ScenarioError(f"{where}: expected a number, got {value!r}")
        return float(value)
    if kind == "boolean":
        if not isinstance(value, bool):
            raise ScenarioError(f"{where}: expected true or false, got {value!r}")
        return value
    if kind == "integer":
        if isinstance(value, bool) or not isinstance(value, int):
            raise ScenarioError(f"{where}: expected an integer, got {value!r}")
        return value
    if kind == "point":
        if not isinstance(value, (list, tuple)) or len(value) != 2 or not all(is_finite_number(v) for v in value):
            raise ScenarioError(f"{where}: expected two numbers [a, b], got {value!r}")
        return (float(value[0]), float(value[1]))
    if kind == "lattice":
        if (not isinstance(value, (list, tuple)) or not value
                or not all(isinstance(row, (list, tuple)) and all(is_finite_number(v) for v in row) for row in value)):
            raise ScenarioError(f"{where}: expected a 2-D list of numbers, got {value!r}")
        return value
    if not isinstance(value, str):
        raise ScenarioError(f"{where}: expected a string, got {value!r}")
    return value


def _with_sea_and_current(wind_speed, wind_north, wind_east, fetch_km: float, current_kn: float,
                          current_towards_deg: float) -> dict[str, np.ndarray]:
    """The five fields from the wind: Hs by the fetch-limited relation from the wind speed
    [m/s] over ``fetch_km``, and a uniform current."""
    _require_positive(fetch_km=fetch_km)
    set_rad = np.radians(current_towards_deg)
    current = current_kn * KNOT
    shape = np.shape(wind_speed)
    return {
        "wind_north": wind_north,
        "wind_east": wind_east,
        "hs": fetch_limited_hs(wind_speed, fetch_km * 1000.0),
        "current_north": np.full(shape, current * np.cos(set_rad)),
        "current_east": np.full(shape, current * np.sin(set_rad)),
    }


def _require_positive(**values: float) -> None:
    for name, value in values.items():
        if not value > 0:
            raise ValueError(f"{name} must be positive, got {value}")


def _require_non_negative(**values: float) -> None:
    for name, value in values.items():
        if not value >= 0:
            raise ValueError(f"{name} must not be negative, got {value}")
