"""Met-ocean NetCDF: the CF names as ERA5 and CMEMS write them, and the writer of every time step.

The names serve both ways: :func:`rhnc.weather.metocean_sources.from_netcdf` reads the five fields
under them (short names or CF standard names), and the writer below writes them.  The
writer takes any field object (grid ``x``, ``y``, ``times_s``, ``start_time``, ``source``
and the five gridded quantities of :data:`rhnc.weather.metocean_grid.FIELDS`) and imports no field
class, so that the field can offer ``to_netcdf`` without its readers importing it back.

Writing (:func:`to_dataset`, :func:`write_netcdf`): a static field without a time
dimension (as before time was supported); a time-varying one with a ``time`` coordinate in
seconds since its ``time_origin``, so that a round trip returns the same ``times_s``.
:func:`write_netcdf` writes the same file through netCDF4 directly: every run writes its
field, and going through xarray cost half a second of processor time per run (importing
and setting it up), the netCDF4 library alone some 20 ms.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from rhnc.weather.metocean_grid import FIELDS

#: CF variable names (ERA5/CMEMS short names first, then standard_name) per field.
CF_NAMES = {
    "wind_north": ("v10", "northward_wind"),
    "wind_east": ("u10", "eastward_wind"),
    "hs": ("swh", "VHM0", "sea_surface_wave_significant_height"),
    "current_north": ("vo", "northward_sea_water_velocity"),
    "current_east": ("uo", "eastward_sea_water_velocity"),
}
_OUTPUT_NAMES = {"wind_north": "v10", "wind_east": "u10", "hs": "swh",
                 "current_north": "vo", "current_east": "uo"}
_STANDARD_NAMES = {"wind_north": "northward_wind", "wind_east": "eastward_wind",
                   "hs": "sea_surface_wave_significant_height",
                   "current_north": "northward_sea_water_velocity",
                   "current_east": "eastward_sea_water_velocity"}
TIME_DIMS = ("time", "valid_time")
#: Calendar time written for t = 0 when a time-varying field carries no start_time.
DEFAULT_TIME_ORIGIN = "1970-01-01T00:00:00"


def to_dataset(field):
    """The field as an ``xarray.Dataset`` with CF-style names and attributes."""
    import xarray as xr

    coords = {
        "northing": ("northing", field.x, {"standard_name": "projection_y_coordinate", "units": "m",
                                           "long_name": "distance north of the map origin"}),
        "easting": ("easting", field.y, {"standard_name": "projection_x_coordinate", "units": "m",
                                         "long_name": "distance east of the map origin"}),
    }
    attrs = {"Conventions": "CF-1.8", "source": field.source, "title": "RHNC met-ocean field"}
    dims: tuple[str, ...] = ("northing", "easting")
    if field.is_time_varying:
        origin = np.datetime64(field.start_time or DEFAULT_TIME_ORIGIN, "ns")
        offsets = np.round(field.times_s * 1e9).astype("int64").astype("timedelta64[ns]")
        coords["time"] = ("time", origin + offsets, {"standard_name": "time"})
        attrs["time_origin"] = str(origin.astype("datetime64[s]"))
        dims = ("time",) + dims
    units = {"hs": "m"}
    data = {
        _OUTPUT_NAMES[name]: (dims, getattr(field, name),
                              {"standard_name": _STANDARD_NAMES[name], "units": units.get(name, "m s-1")})
        for name in FIELDS
    }
    dataset = xr.Dataset(data, coords=coords, attrs=attrs)
    if field.is_time_varying:
        dataset["time"].encoding.update({"units": f"seconds since {attrs['time_origin']}", "dtype": "float64"})
    return dataset


def write_netcdf(field, path) -> Path:
    """Write ``field`` as NetCDF-4 with the names, attributes and time encoding of :func:`to_dataset`."""
    import netCDF4

    path = Path(path)
    dims: tuple[str, ...] = ("northing", "easting")
    with netCDF4.Dataset(path, "w", format="NETCDF4") as dataset:
        dataset.setncatts({"Conventions": "CF-1.8", "source": field.source, "title": "RHNC met-ocean field"})
        for name, values, long_name, standard_name in (
                ("northing", field.x, "distance north of the map origin", "projection_y_coordinate"),
                ("easting", field.y, "distance east of the map origin", "projection_x_coordinate")):
            dataset.createDimension(name, values.size)
            variable = dataset.createVariable(name, "f8", (name,))
            variable.setncatts({"standard_name": standard_name, "units": "m", "long_name": long_name})
            variable[:] = values
        if field.is_time_varying:
            origin = np.datetime64(field.start_time or DEFAULT_TIME_ORIGIN, "ns")
            origin_text = str(origin.astype("datetime64[s]"))
            dataset.setncattr("time_origin", origin_text)
            dataset.createDimension("time", field.times_s.size)
            variable = dataset.createVariable("time", "f8", ("time",))
            variable.setncatts({"standard_name": "time", "units": f"seconds since {origin_text}",
                                "calendar": "proleptic_gregorian"})
            variable[:] = np.round(field.times_s * 1e9) / 1e9
            dims = ("time",) + dims
        units = {"hs": "m"}
        for name in FIELDS:
            variable = dataset.createVariable(_OUTPUT_NAMES[name], "f8", dims, fill_value=np.nan)
            variable.setncatts({"standard_name": _STANDARD_NAMES[name], "units": units.get(name, "m s-1")})
            variable[:] = getattr(field, name)
    return path
