"""Where a met-ocean field comes from: a scenario's ``[metocean]`` table, a generator or a NetCDF file.

The entry point ``metocean`` of the group ``rhnc_cosim.scenario_tables`` names this module:
the co-simulation master builds a scenario's field with :func:`from_scenario_table` and an
exported FMU reads its bundled file with :func:`from_netcdf`.

Reading (:func:`from_netcdf`): the five fields of :mod:`rhnc.weather.metocean` under their short
names (``u10``, ``v10``, ``swh``, ``uo``, ``vo``) or CF standard names, on a
``northing``/``easting`` grid in metres (what :meth:`rhnc.weather.metocean.MetOceanField.to_netcdf`
writes) or on a ``latitude``/``longitude`` grid projected to the local plane about an
origin.  A ``time`` or ``valid_time`` dimension is read whole: its CF-decoded dates become
seconds since ``start_time`` (an ISO 8601 date, the calendar time of the simulation's
t = 0), else since the file's ``time_origin`` attribute (written with the field), else
since the file's first time.  ``time_index`` takes one time step only (a static field).
"""

from __future__ import annotations

import logging
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from orchestrator.errors import ScenarioError
from orchestrator.geometry import EARTH_RADIUS_M, NM, local_north_east_m, wrap_longitude_deg
from rhnc.weather.metocean import MetOceanField
from rhnc.weather.metocean_grid import FIELDS, axis_node_count, check_grid_nodes
from rhnc.weather.metocean_netcdf import CF_NAMES, TIME_DIMS
from rhnc.weather.weather_generators import build_generated, checked_option

log = logging.getLogger(__name__)

#: Keys of a ``[metocean] file = ...`` table and their kinds (see rhnc.weather.weather_generators.checked_option).
_FILE_KEYS = {"origin_deg": "point", "resolution_nm": "number", "time_index": "integer", "start_time": "text",
              "currents_file": "text", "projection": "text"}
#: Projections of a latitude/longitude file onto the local plane (``projection`` key).
PROJECTIONS = ("equirectangular", "aeqd")


def from_scenario_table(table: Mapping[str, Any], scenario_dir: Path, where: str) -> MetOceanField:
    """Build the field a scenario's ``[metocean]`` table describes.

    ``generator = "<name>"`` with that generator's keys (registry and keys:
    :func:`rhnc.weather.weather_generators.list_generators`), or ``file = "path.nc"`` with the
    options of :func:`from_netcdf`.  Either may add ``hold_edges_nm``: the map grown by that
    distance beyond every edge, the edge's values held there
    (:meth:`rhnc.weather.metocean.MetOceanField.with_edges_held`).  Errors name ``where``
    (file and table) and the key.
    """
    table = dict(table)
    if "hold_edges_nm" in table:
        hold_nm = checked_option(table.pop("hold_edges_nm"), "number", f"{where}.hold_edges_nm")
        if hold_nm < 0.0:
            raise ScenarioError(f"{where}.hold_edges_nm: expected a distance of at least 0 nm, got {hold_nm:g}")
        return from_scenario_table(table, scenario_dir, where).with_edges_held(hold_nm * NM)
    if ("generator" in table) == ("file" in table):
        raise ScenarioError(f"{where}: give exactly one of 'generator' or 'file'")
    if "generator" in table:
        return build_generated(table.pop("generator"), table, where)
    file = table.pop("file")
    if not isinstance(file, str) or not file or "\0" in file:
        raise ScenarioError(f"{where}.file: expected the path of a NetCDF file, got {file!r}"[:300])
    file = Path(file)
    file = file if file.is_absolute() else scenario_dir / file
    if not file.is_file():
        raise ScenarioError(f"{where}.file: met-ocean file not found: {file}")
    for key in table:
        if key not in _FILE_KEYS:
            raise ScenarioError(f"{where}: unknown key '{key}' (valid: {', '.join(sorted(_FILE_KEYS))})")
        table[key] = checked_option(table[key], _FILE_KEYS[key], f"{where}.{key}")
    if table.get("projection", "equirectangular") not in PROJECTIONS:
        raise ScenarioError(f"{where}.projection: '{table['projection']}' is not valid (valid: {', '.join(PROJECTIONS)})")
    if table.get("projection") == "aeqd" and "origin_deg" not in table:
        raise ScenarioError(f"{where}.projection: 'aeqd' needs origin_deg, the centre of the plane")
    if "currents_file" in table:
        currents = Path(table["currents_file"])
        table["currents_file"] = currents = currents if currents.is_absolute() else scenario_dir / currents
        if not currents.is_file():
            raise ScenarioError(f"{where}.currents_file: currents file not found: {currents}")
    try:
        return from_netcdf(file, **table)
    except (ValueError, TypeError, KeyError) as exc:
        raise ScenarioError(f"{where}: {exc}") from exc


def from_netcdf(path, origin_deg=None, resolution_nm: float | None = None,
                time_index: int | None = None, start_time: str | None = None,
                currents_file=None, projection: str = "equirectangular") -> MetOceanField:
    """Load a NetCDF file with CF names (ERA5/CMEMS style), every time step of it, through xarray.

    Parameters
    ----------
    path : path-like
        The NetCDF file.
    origin_deg : (lat, lon), optional
        For a latitude/longitude grid: the point that becomes x = y = 0 of the local
        plane (default: the south-west corner of the data).
    resolution_nm : float, optional
        For a latitude/longitude grid: spacing of the local grid [nm] (default: the
        data's own spacing in latitude, in nm).
    time_index : int, optional
        Take only this time step (a static field).  Default: every time step.
    start_time : str, optional
        ISO 8601 calendar time of the simulation's t = 0 (default: the file's
        ``time_origin`` attribute, else its first time).
    currents_file : path-like, optional
        A second file with the current (``uo``, ``vo``, CMEMS layout: a ``depth`` dimension,
        of which the shallowest level is taken; NaN on land), on its own latitude/longitude
        grid and time axis: interpolated onto the first file's grid (bilinear, held at its
        edges) and times (linear, held before its first and after its last time).  Its
        current replaces the first file's.

    projection : str
        For a latitude/longitude grid: ``"equirectangular"`` (north and east proportional
        to latitude and longitude about the origin; the default, good near the origin) or
        ``"aeqd"``, pyproj's azimuthal equidistant plane about ``origin_deg``, the plane of a
        passage's chart (:mod:`rhnc.chart.projection`), so that weather, coastline and ship
        share one plane (over a 170 nm map the two differ by up to 9 nm at its far corner).
        The grid is then the largest rectangle of the plane inside the data, each node's
        values interpolated at its own latitude and longitude.

    Longitudes may run from 0 to 360 (ERA5) or from -180 to 180: with ``origin_deg`` they are
    shifted by whole turns to within half a turn of the origin before sorting, so a map
    across the Greenwich meridian is read whole from an ERA5 file.  ERA5's mean wave
    direction ``mwd`` is not read: the ship model takes the waves from the wind's direction
    (``models/KCS/readme.md``).

    Missing variables are an error, except the current, which defaults to zero
    (ERA5 carries no current) with a warning.  NaN (land in ocean products)
    becomes zero.
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"met-ocean file not found: {path}")
    if resolution_nm is not None and not resolution_nm > 0:
        raise ValueError(f"resolution_nm must be positive, got {resolution_nm}")
    ds, time_dim, times_s, zero = _read_dataset(path, time_index, start_time)
    arrays = {name: _find_variable(ds, name, path, quiet=currents_file is not None) for name in FIELDS}
    lead = (time_dim,) if time_dim else ()
    nt = (ds.sizes[time_dim],) if time_dim else ()
    keep = {"times_s": times_s, "start_time": zero}
    if "northing" in ds.dims and "easting" in ds.dims:
        x = ds["northing"].values.astype(float)
        y = ds["easting"].values.astype(float)
        fields = {name: _as_grid(arr, lead + ("northing", "easting"), nt + (x.size, y.size))
                  for name, arr in arrays.items()}
        return MetOceanField(x, y, fields, source=f"file: {path}", **keep)
    lat_name = "latitude" if "latitude" in ds.dims else "lat"
    lon_name = "longitude" if "longitude" in ds.dims else "lon"
    if lat_name not in ds.dims or lon_name not in ds.dims:
        raise ValueError(f"{path}: expected dimensions northing/easting [m] or latitude/longitude")
    lat = ds[lat_name].values.astype(float)
    lon = ds[lon_name].values.astype(float)
    if origin_deg is not None:
        lon = wrap_longitude_deg(lon, origin_deg[1])
    order_lat = np.argsort(lat)
    order_lon = np.argsort(lon)
    lat, lon = lat[order_lat], lon[order_lon]
    lat0, lon0 = origin_deg if origin_deg is not None else (lat[0], lon[0])
    north, east, plane = _plane_extent(lat, lon, lat0, lon0, projection)
    step = resolution_nm * NM if resolution_nm else float(np.radians(np.min(np.diff(lat))) * EARTH_RADIUS_M)
    x, y, node_lat, node_lon = _grid_nodes(north, east, step, nt, plane, lat, lon, lat0, lon0)
    from scipy.interpolate import RegularGridInterpolator

    fields = {}
    for name, arr in arrays.items():
        grid = _as_grid(arr, lead + (lat_name, lon_name), nt + (lat.size, lon.size))
        grid = grid[..., order_lat, :][..., order_lon]
        slices = grid if time_dim else grid[None]
        projected = np.stack([RegularGridInterpolator((lat, lon), s)((node_lat, node_lon)) for s in slices])
        fields[name] = projected if time_dim else projected[0]
    source = f"file: {path} (origin {lat0:.4f}N {lon0:.4f}E{', azimuthal equidistant' if plane else ''})"
    if currents_file is not None:
        fields.update(_currents_on_grid(Path(currents_file), (lat0, lon0), node_lat, node_lon, times_s, zero))
        source += f", currents: {currents_file}"
    return MetOceanField(x, y, fields, source=source, **keep)


def _read_dataset(path: Path, time_index, start_time):
    """The file's data, loaded: ``(dataset, time dimension or None, times [s] or None, zero time or None)``.

    ``time_index`` (or a time axis of one step) leaves a static field, without the time
    dimension; otherwise the times are sorted and become seconds since ``start_time`` (else
    the file's ``time_origin``, else its first time).  Any other dimension beside the grid's
    and the time's (a depth, a level) is cut to its first index.
    """
    import xarray as xr

    with xr.open_dataset(path) as ds:
        _check_size(ds, time_index)  # from the header, before the data are read
        ds = ds.load()
    time_dim = next((d for d in TIME_DIMS if d in ds.dims), None)
    times_s, zero = None, None
    if time_dim is not None and time_index is not None:
        if isinstance(time_index, bool) or not isinstance(time_index, int) or not (
                -ds.sizes[time_dim] <= time_index < ds.sizes[time_dim]):
            raise ValueError(f"time_index {time_index!r} is not one of the file's {ds.sizes[time_dim]} time steps")
        ds = ds.isel({time_dim: time_index})
        time_dim = None
    elif time_dim is not None and ds.sizes[time_dim] == 1:
        ds = ds.isel({time_dim: 0})
        time_dim = None
    elif time_dim is not None:
        ds = ds.sortby(time_dim)
        times_s, zero = _seconds(ds[time_dim].values, start_time or ds.attrs.get("time_origin"), path, time_dim)
    for extra in [d for d in ds.dims if d not in ("northing", "easting", "latitude", "longitude", "lat", "lon",
                                                  time_dim)]:
        ds = ds.isel({extra: 0})
    return ds, time_dim, times_s, zero


def _plane_extent(lat, lon, lat0, lon0, projection: str):
    """``(north, east, plane)``: the local plane's extent [m] of the (sorted) latitude/longitude axes.

    Equirectangular (``plane`` None): the axes' own north/east offsets from the origin.  ``"aeqd"``:
    the largest rectangle of pyproj's azimuthal equidistant plane about the origin that lies inside
    the data (``north``, ``east``: its two edges each), with the projection to map nodes back.
    """
    north, east = local_north_east_m(lat, lon, lat0, lon0)
    plane = None
    if projection == "aeqd":
        from rhnc.chart.projection import LocalProjection

        plane = LocalProjection(lat0, lon0)
        lat_edge = np.linspace(lat[0], lat[-1], 64)
        lon_edge = np.linspace(lon[0], lon[-1], 64)
        south, _ = plane.to_local(np.full(64, lat[0]), lon_edge)
        north_edge, _ = plane.to_local(np.full(64, lat[-1]), lon_edge)
        _, west = plane.to_local(lat_edge, np.full(64, lon[0]))
        _, east_edge = plane.to_local(lat_edge, np.full(64, lon[-1]))
        north = np.array([south.max(), north_edge.min()])  # the largest plane rectangle inside the data
        east = np.array([west.max(), east_edge.min()])
    return north, east, plane


def _grid_nodes(north, east, step: float, nt: tuple, plane, lat, lon, lat0, lon0):
    """``(x, y, node_lat, node_lon)``: the local grid's axes [m] over the extent, spaced no coarser than
    ``step`` [m], and each node's latitude and longitude [deg] (clipped to the data's)."""
    # cover the data's whole extent with a spacing no coarser than `step`
    nx = axis_node_count(north[-1] - north[0], step) + 1  # ceil, so one more node at most
    ny = axis_node_count(east[-1] - east[0], step) + 1
    check_grid_nodes(nx, ny, nt[0] if nt else 1)
    x = np.linspace(north[0], north[-1], int(np.ceil((north[-1] - north[0]) / step - 1e-9)) + 1)
    y = np.linspace(east[0], east[-1], int(np.ceil((east[-1] - east[0]) / step - 1e-9)) + 1)
    xx, yy = np.meshgrid(x, y, indexing="ij")
    if plane is not None:
        node_lat, node_lon = plane.to_geographic(xx, yy)
        node_lon = wrap_longitude_deg(node_lon, lon0)
    else:
        node_lat = lat0 + np.degrees(xx / EARTH_RADIUS_M)
        node_lon = lon0 + np.degrees(yy / (EARTH_RADIUS_M * np.cos(np.radians(lat0))))
    node_lat = np.clip(node_lat, lat[0], lat[-1])
    node_lon = np.clip(node_lon, lon[0], lon[-1])
    return x, y, node_lat, node_lon


def _currents_on_grid(path: Path, origin_deg, node_lat, node_lon, times_s, zero) -> dict[str, np.ndarray]:
    """``current_north``/``current_east`` of a CMEMS-layout file at the grid's nodes (their latitude and
    longitude [deg]) and the times ``times_s`` [s since ``zero``] (a static field when ``times_s`` is None)."""
    import xarray as xr
    from scipy.interpolate import RegularGridInterpolator

    with xr.open_dataset(path) as ds:
        _check_size(ds, None)
        ds = ds.load()
    for depth in ("depth", "deptht", "elevation"):
        if depth in ds.dims:
            ds = ds.sortby(depth).isel({depth: 0})
    lat_name = "latitude" if "latitude" in ds.dims else "lat"
    lon_name = "longitude" if "longitude" in ds.dims else "lon"
    if lat_name not in ds.dims or lon_name not in ds.dims:
        raise ValueError(f"{path}: expected dimensions latitude/longitude for the current")
    time_dim = next((d for d in TIME_DIMS if d in ds.dims), None)
    lat = ds[lat_name].values.astype(float)
    lon = wrap_longitude_deg(ds[lon_name].values.astype(float), origin_deg[1])
    order_lat, order_lon = np.argsort(lat), np.argsort(lon)
    lat, lon = lat[order_lat], lon[order_lon]
    if time_dim is not None and ds.sizes[time_dim] > 1:
        ds = ds.sortby(time_dim)
        own_s, _ = _seconds(ds[time_dim].values, zero, path, time_dim)
    else:
        own_s = None
        if time_dim is not None:
            ds = ds.isel({time_dim: 0})
            time_dim = None
    at = (np.clip(node_lat, lat[0], lat[-1]), np.clip(node_lon, lon[0], lon[-1]))
    result = {}
    for name in ("current_north", "current_east"):
        found = next((ds[c] for c in CF_NAMES[name] if c in ds.data_vars), None)
        if found is None:
            raise ValueError(f"{path}: no variable for {name} (looked for {', '.join(CF_NAMES[name])})")
        lead = (time_dim,) if time_dim else ()
        nt = (ds.sizes[time_dim],) if time_dim else ()
        grid = _as_grid(found, lead + (lat_name, lon_name), nt + (lat.size, lon.size))
        grid = grid[..., order_lat, :][..., order_lon]
        slices = grid if time_dim else grid[None]
        on_grid = np.stack([RegularGridInterpolator((lat, lon), s)(at) for s in slices])
        if own_s is None:
            values = on_grid[0]
            result[name] = values if times_s is None else np.broadcast_to(values, (len(times_s),) + values.shape).copy()
        elif times_s is None:
            raise ValueError(f"{path}: the current varies in time but the weather file is static: give the weather "
                             "file's times or a static currents file")
        else:
            result[name] = np.stack([_at_time(on_grid, own_s, t) for t in times_s])
    return result


def _at_time(slices: np.ndarray, times_s: np.ndarray, t: float) -> np.ndarray:
    """Linear in time between the two slices around ``t``, held before the first and after the last."""
    k = int(np.clip(np.searchsorted(times_s, t) - 1, 0, len(times_s) - 2))
    w = float(np.clip((t - times_s[k]) / (times_s[k + 1] - times_s[k]), 0.0, 1.0))
    return (1.0 - w) * slices[k] + w * slices[k + 1]


def _check_size(ds, time_index) -> None:
    """Refuse a file whose grid exceeds the met-ocean grid limit (its sizes, not its data)."""
    steps = 1 if time_index is not None else next((ds.sizes[d] for d in TIME_DIMS if d in ds.sizes), 1)
    spatial = [ds.sizes[d] for d in ds.sizes if d not in TIME_DIMS] + [1, 1]
    rest = 1
    for size in spatial[2:]:  # further dimensions (levels, ensemble members) are read too
        rest *= size
    check_grid_nodes(spatial[0], spatial[1] * rest, steps)


def _seconds(times, origin, path, time_dim) -> tuple[np.ndarray, str]:
    """Seconds [s] of CF-decoded ``times`` since ``origin`` (ISO 8601), else since the first
    time; and that zero as an ISO 8601 string."""
    if not np.issubdtype(np.asarray(times).dtype, np.datetime64):
        raise ValueError(f"{path}: the '{time_dim}' coordinate is not a CF time (no 'units = \"<unit> since "
                         "<date>\"' attribute); give time_index to read one time step")
    times = np.asarray(times).astype("datetime64[ns]")
    try:
        zero = np.datetime64(origin, "ns") if origin is not None else times[0]
    except ValueError as exc:
        raise ValueError(f"start_time '{origin}' is not an ISO 8601 date") from exc
    return (times - zero).astype("timedelta64[ns]").astype("int64") / 1e9, str(zero)


def _find_variable(ds, name, path, quiet: bool = False):
    for candidate in CF_NAMES[name]:
        if candidate in ds.data_vars:
            return ds[candidate]
    for var in ds.data_vars.values():
        if var.attrs.get("standard_name") in CF_NAMES[name]:
            return var
    if name.startswith("current"):
        if not quiet:  # a currents file gives it
            log.warning("%s: no %s variable (%s); assuming zero current", path, name, "/".join(CF_NAMES[name]))
        any_var = next(iter(ds.data_vars.values()))
        return any_var * 0.0
    raise ValueError(f"{path}: no variable for {name} (looked for {', '.join(CF_NAMES[name])})")


def _as_grid(arr, dims, shape) -> np.ndarray:
    values = arr.transpose(*dims).values.astype(float) if set(dims) <= set(arr.dims) else None
    if values is None or values.shape != tuple(shape):
        raise ValueError(f"variable {arr.name} must have dimensions {dims}")
    return np.nan_to_num(values, nan=0.0)
