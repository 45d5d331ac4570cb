"""Files in the layouts the Copernicus services deliver: ERA5 single levels and CMEMS surface currents.

Nothing is downloaded here.  These writers produce files laid out exactly as the services
deliver them, so the readers (:func:`rhnc.weather.metocean_sources.from_netcdf`) are tested,
and the passages sailed, on that layout; ``docs/passages.md`` says how to obtain real ones.

ERA5 single levels (Copernicus Climate Data Store, NetCDF3 as ``cdsapi`` delivered it
up to 2024 and many archives hold it):

* dimensions ``time``, ``latitude``, ``longitude``; latitude from north to south,
  longitude from 0 to 360 on the 0.25 deg grid;
* ``time`` an int32 in ``hours since 1900-01-01 00:00:00.0`` (calendar gregorian);
* ``u10``, ``v10`` [m s**-1], ``swh`` [m], ``mwd`` [degree true, the direction the waves
  come from] packed as int16 with ``scale_factor`` and ``add_offset`` chosen per variable
  from its range, and ``_FillValue`` / ``missing_value`` -32767.

CMEMS global physics analysis and forecast (Copernicus Marine, product
GLOBAL_ANALYSISFORECAST_PHY_001_024, hourly surface currents ``uo``, ``vo``):

* dimensions ``time``, ``depth``, ``latitude``, ``longitude``; latitude south to north,
  longitude from -180 to 180 on the 1/12 deg grid, ``depth`` [m, positive down] with the
  first level at 0.494 m;
* ``time`` in ``hours since 1950-01-01``; ``uo``, ``vo`` [m s-1] float32 (deflated), NaN on land.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from orchestrator.geometry import wrap_longitude_deg

#: The int16 value ERA5 writes for a missing value.
ERA5_MISSING = -32767
ERA5_EPOCH = np.datetime64("1900-01-01T00:00:00")
CMEMS_EPOCH = np.datetime64("1950-01-01T00:00:00")
CMEMS_SURFACE_DEPTH_M = 0.494025

_ERA5_VARIABLES = {
    "u10": ("10 metre U wind component", "m s**-1", None),
    "v10": ("10 metre V wind component", "m s**-1", None),
    "swh": ("Significant height of combined wind waves and swell", "m", None),
    "mwd": ("Mean wave direction", "Degree true", None),
}


def era5_packing(values: np.ndarray) -> tuple[float, float]:
    """``(scale_factor, add_offset)`` as ERA5 chooses them: the range over the int16 span."""
    low, high = float(np.nanmin(values)), float(np.nanmax(values))
    offset = (high + low) / 2.0
    scale = (high - low) / (2 ** 16 - 4) if high > low else 1.0  # within +-32766, clear of the fill value
    return scale, offset


def _axis(ds, name: str, kind: str, values, **attributes: str) -> None:
    """The coordinate variable ``name`` of ``ds`` on its own dimension: its values and CF attributes
    (in the order given)."""
    variable = ds.createVariable(name, kind, (name,))
    for key, value in attributes.items():
        setattr(variable, key, value)
    variable[:] = values


def write_era5_single_levels(path, lat_deg, lon_deg, times, u10, v10, swh, mwd) -> Path:
    """Write an ERA5 single-levels file.

    Parameters
    ----------
    lat_deg, lon_deg : array_like
        Grid [deg], any order and convention: written north to south and 0 to 360.
    times : array_like of numpy.datetime64
        Whole hours.
    u10, v10, swh, mwd : ndarray (time, lat, lon)
        Values on ``lat_deg`` x ``lon_deg`` as given [m/s, m/s, m, deg from].
    """
    import netCDF4

    lat = np.asarray(lat_deg, dtype=float)
    lon = np.asarray(lon_deg, dtype=float) % 360.0
    order_lat = np.argsort(-lat)
    order_lon = np.argsort(lon)
    hours = (np.asarray(times, dtype="datetime64[s]") - ERA5_EPOCH) / np.timedelta64(1, "h")
    if np.any(hours != np.round(hours)):
        raise ValueError("ERA5 times are whole hours")
    path = Path(path)
    with netCDF4.Dataset(path, "w", format="NETCDF3_64BIT_OFFSET") as ds:
        ds.Conventions = "CF-1.6"
        ds.history = "written by rhnc.weather.copernicus_layouts in the ERA5 single-levels layout (synthetic values)"
        ds.createDimension("longitude", lon.size)
        ds.createDimension("latitude", lat.size)
        ds.createDimension("time", None)
        _axis(ds, "longitude", "f4", lon[order_lon], units="degrees_east", long_name="longitude")
        _axis(ds, "latitude", "f4", lat[order_lat], units="degrees_north", long_name="latitude")
        _axis(ds, "time", "i4", hours.astype(np.int32), units="hours since 1900-01-01 00:00:00.0", long_name="time",
              calendar="gregorian")
        for name, values in (("u10", u10), ("v10", v10), ("swh", swh), ("mwd", mwd)):
            values = np.asarray(values, dtype=float)[:, order_lat][:, :, order_lon]
            scale, offset = era5_packing(values)
            variable = ds.createVariable(name, "i2", ("time", "latitude", "longitude"), fill_value=ERA5_MISSING)
            variable.scale_factor, variable.add_offset = scale, offset
            variable.missing_value = np.int16(ERA5_MISSING)
            variable.long_name, variable.units = _ERA5_VARIABLES[name][:2]
            variable.set_auto_maskandscale(True)
            variable[:] = values
    return path


def write_cmems_currents(path, lat_deg, lon_deg, times, uo, vo, depths_m=(CMEMS_SURFACE_DEPTH_M,)) -> Path:
    """Write a CMEMS currents file.

    Parameters
    ----------
    lat_deg, lon_deg : array_like
        Grid [deg]: written south to north and from -180 to 180.
    times : array_like of numpy.datetime64
    uo, vo : ndarray (time, lat, lon) or (time, depth, lat, lon)
        Eastward and northward current [m/s]; NaN on land.  A 3-D array is the same at every depth.
    depths_m : sequence of float
        Depth levels [m, positive down].
    """
    import netCDF4

    lat = np.asarray(lat_deg, dtype=float)
    lon = wrap_longitude_deg(lon_deg)
    order_lat, order_lon = np.argsort(lat), np.argsort(lon)
    hours = (np.asarray(times, dtype="datetime64[s]") - CMEMS_EPOCH) / np.timedelta64(1, "h")
    depths = np.asarray(depths_m, dtype=float)
    path = Path(path)
    with netCDF4.Dataset(path, "w", format="NETCDF4") as ds:
        ds.Conventions = "CF-1.8"
        ds.title = "daily/hourly mean fields from Global Ocean Physics Analysis and Forecast (layout; synthetic values)"
        for name, size in (("time", None), ("depth", depths.size), ("latitude", lat.size), ("longitude", lon.size)):
            ds.createDimension(name, size)
        _axis(ds, "time", "f8", hours, units="hours since 1950-01-01", standard_name="time", calendar="gregorian")
        _axis(ds, "depth", "f4", depths, units="m", positive="down", standard_name="depth")
        _axis(ds, "latitude", "f4", lat[order_lat], units="degrees_north", standard_name="latitude")
        _axis(ds, "longitude", "f4", lon[order_lon], units="degrees_east", standard_name="longitude")
        for name, values, standard in (("uo", uo, "eastward_sea_water_velocity"),
                                       ("vo", vo, "northward_sea_water_velocity")):
            values = np.asarray(values, dtype=float)
            if values.ndim == 3:
                values = np.repeat(values[:, None], depths.size, axis=1)
            values = values[:, :, order_lat][:, :, :, order_lon]
            variable = ds.createVariable(name, "f4", ("time", "depth", "latitude", "longitude"),
                                         fill_value=np.float32(np.nan), zlib=True, complevel=4)
            variable.units, variable.standard_name = "m s-1", standard
            variable[:] = values
    return path
