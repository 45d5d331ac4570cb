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
from orchestrator.geometry import NM, local_north_east_m
from rhnc.weather.metocean import MetOceanField
from rhnc.weather.metocean_grid import FIELDS, axis_node_count, check_grid_nodes
from rhnc.weather.metocean_netcdf import CF_NAMES, TIME_DIMS
from rhnc.weather.weather_generators import build_generated, checked_option

log = logging.getLogger(__name__)

#: Keys of a ``[metocean] file = ...`` table and their kinds (see rhnc.weather.weather_generators.checked_option).
_FILE_KEYS = {"origin_deg": "point", "resolution_nm": "number", "time_index": "integer", "start_time": "text"}


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
    try:
        return from_netcdf(file, **table)
    except (ValueError, TypeError, KeyError) as exc:
        raise ScenarioError(f"{where}: {exc}") from exc


def from_netcdf(path, origin_deg=None, resolution_nm: float | None = None,
                time_index: int | None = None, start_time: str | None = None) -> MetOceanField:
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

    Missing variables are an error, except the current, which defaults to zero
    (ERA5 carries no current) with a warning.  NaN (land in ocean products)
    becomes zero.
    """
    import xarray as xr

    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"met-ocean file not found: {path}")
    if resolution_nm is not None and not resolution_nm > 0:
        raise ValueError(f"resolution_nm must be positive, got {resolution_nm}")
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
    arrays = {name: _find_variable(ds, name, path) for name in FIELDS}
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
    order_lat = np.argsort(lat)
    order_lon = np.argsort(lon)
    lat, lon = lat[order_lat], lon[order_lon]
    lat0, lon0 = origin_deg if origin_deg is not None else (lat[0], lon[0])
    north, east = local_north_east_m(lat, lon, lat0, lon0)
    step = resolution_nm * NM if resolution_nm else float(np.min(np.diff(north)))
    # cover the data's whole extent with a spacing no coarser than `step`
    nx = axis_node_count(north[-1] - north[0], step) + 1  # ceil, so one more node at most
    ny = axis_node_count(east[-1] - east[0], step) + 1
    check_grid_nodes(nx, ny, nt[0] if nt else 1)
    x = np.linspace(north[0], north[-1], int(np.ceil((north[-1] - north[0]) / step - 1e-9)) + 1)
    y = np.linspace(east[0], east[-1], int(np.ceil((east[-1] - east[0]) / step - 1e-9)) + 1)
    from scipy.interpolate import RegularGridInterpolator

    xx, yy = np.meshgrid(x, y, indexing="ij")
    fields = {}
    for name, arr in arrays.items():
        grid = _as_grid(arr, lead + (lat_name, lon_name), nt + (lat.size, lon.size))
        grid = grid[..., order_lat, :][..., order_lon]
        slices = grid if time_dim else grid[None]
        projected = np.stack([RegularGridInterpolator((north, east), s)((xx, yy)) for s in slices])
        fields[name] = projected if time_dim else projected[0]
    return MetOceanField(x, y, fields, source=f"file: {path} (origin {lat0:.4f}N {lon0:.4f}E)", **keep)


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


def _find_variable(ds, name, path):
    for candidate in CF_NAMES[name]:
        if candidate in ds.data_vars:
            return ds[candidate]
    for var in ds.data_vars.values():
        if var.attrs.get("standard_name") in CF_NAMES[name]:
            return var
    if name.startswith("current"):
        log.warning("%s: no %s variable (%s); assuming zero current", path, name, "/".join(CF_NAMES[name]))
        any_var = next(iter(ds.data_vars.values()))
        return any_var * 0.0
    raise ValueError(f"{path}: no variable for {name} (looked for {', '.join(CF_NAMES[name])})")


def _as_grid(arr, dims, shape) -> np.ndarray:
    values = arr.transpose(*dims).values.astype(float) if set(dims) <= set(arr.dims) else None
    if values is None or values.shape != tuple(shape):
        raise ValueError(f"variable {arr.name} must have dimensions {dims}")
    return np.nan_to_num(values, nan=0.0)
