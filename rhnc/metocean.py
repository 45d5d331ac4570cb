"""Met-ocean fields over the map: one data source per scenario for the FMU and the planner.

The field lives on a regular grid in a local plane, x north and y east in metres
(spec section 0).  Five gridded quantities are kept, all interpolated bilinearly:

=================  =========  ==============================================
name               unit       meaning
=================  =========  ==============================================
``wind_north``     m/s        wind velocity towards north (10 m)
``wind_east``      m/s        wind velocity towards east (10 m)
``hs``             m          significant wave height
``current_north``  m/s        surface current towards north
``current_east``   m/s        surface current towards east
=================  =========  ==============================================

Sources
-------
* ``generate_paper_default``: the paper's synthetic weather (Section 6.1.1, spec section
  2): wind speed by a bicubic spline through control points, a constant wind direction,
  Hs from the fetch-limited JONSWAP relation capped at the fully developed
  Pierson-Moskowitz value, and a constant current.
* ``from_netcdf``: a NetCDF file with CF names as ERA5 and CMEMS write them (``u10``,
  ``v10``, ``swh``, ``uo``, ``vo``, or their ``standard_name``), on either a
  ``northing``/``easting`` grid in metres (what ``to_netcdf`` writes) or a
  ``latitude``/``longitude`` grid, projected to the local plane about an origin.

The environment FMU reads the same grid through ``write_fmu_grid`` (binary format in
``models/MetOcean/readme.md``), so FMU and planner see identical values.
"""

from __future__ import annotations

import logging
import struct
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from orchestrator.errors import ScenarioError

log = logging.getLogger(__name__)

NM = 1852.0  #: metres per nautical mile
KNOT = NM / 3600.0  #: m/s per knot
GRAVITY = 9.81  #: m/s^2
EARTH_RADIUS = 6_371_000.0  #: m, mean radius for the local projection

FIELDS = ("wind_north", "wind_east", "hs", "current_north", "current_east")

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


class MetOceanField:
    """Gridded met-ocean quantities on a regular local grid (x north, y east, metres).

    Parameters
    ----------
    x, y : ndarray
        Strictly increasing, evenly spaced node coordinates [m] (north, east).
    fields : mapping
        One (nx, ny) array per name in :data:`FIELDS`.
    source : str
        Human-readable provenance, written into results.
    """

    def __init__(self, x: np.ndarray, y: np.ndarray, fields: Mapping[str, np.ndarray], source: str = ""):
        self.x = np.asarray(x, dtype=float)
        self.y = np.asarray(y, dtype=float)
        for axis_name, axis in (("x (north)", self.x), ("y (east)", self.y)):
            if axis.ndim != 1 or axis.size < 2:
                raise ValueError(f"met-ocean grid axis {axis_name} needs at least 2 nodes")
            steps = np.diff(axis)
            if np.any(steps <= 0) or not np.allclose(steps, steps[0], rtol=1e-6, atol=1e-6):
                raise ValueError(f"met-ocean grid axis {axis_name} must be evenly spaced and increasing")
        shape = (self.x.size, self.y.size)
        self._fields = {}
        for name in FIELDS:
            values = np.asarray(fields[name], dtype=float)
            if values.shape != shape:
                raise ValueError(f"met-ocean field {name} has shape {values.shape}, grid is {shape}")
            if not np.all(np.isfinite(values)):
                raise ValueError(f"met-ocean field {name} holds NaN or infinite values")
            self._fields[name] = values
        self.source = source

    # -- gridded quantities -------------------------------------------------------
    wind_north = property(lambda self: self._fields["wind_north"])
    wind_east = property(lambda self: self._fields["wind_east"])
    hs = property(lambda self: self._fields["hs"])
    current_north = property(lambda self: self._fields["current_north"])
    current_east = property(lambda self: self._fields["current_east"])

    @property
    def wind_speed(self) -> np.ndarray:
        """Wind speed [m/s] at the nodes."""
        return np.hypot(self.wind_north, self.wind_east)

    @property
    def wind_direction(self) -> np.ndarray:
        """Direction the wind comes from [rad, clockwise from north] at the nodes."""
        return wind_from_direction(self.wind_north, self.wind_east)

    @property
    def dx(self) -> float:
        return float(self.x[1] - self.x[0])

    @property
    def dy(self) -> float:
        return float(self.y[1] - self.y[0])

    @property
    def extent(self) -> tuple[float, float, float, float]:
        """(x_min, x_max, y_min, y_max) [m]."""
        return float(self.x[0]), float(self.x[-1]), float(self.y[0]), float(self.y[-1])

    def contains(self, x, y, tolerance: float = 1e-6) -> np.ndarray:
        """True where (x, y) [m] lies on the grid (within ``tolerance`` metres)."""
        x_min, x_max, y_min, y_max = self.extent
        x = np.asarray(x, dtype=float)
        y = np.asarray(y, dtype=float)
        return ((x >= x_min - tolerance) & (x <= x_max + tolerance)
                & (y >= y_min - tolerance) & (y <= y_max + tolerance))

    # -- interpolation --------------------------------------------------------------
    def sample(self, x, y) -> dict[str, np.ndarray]:
        """Bilinear interpolation of every field at points (x, y) [m].

        Returns the five gridded fields plus ``wind_speed`` and ``wind_direction``
        computed from the interpolated wind components (as the FMU does).

        Raises
        ------
        ValueError
            If a point lies outside the grid (no extrapolation).
        """
        x = np.asarray(x, dtype=float)
        y = np.asarray(y, dtype=float)
        inside = self.contains(x, y)
        if not np.all(inside):
            bad = np.argwhere(~np.atleast_1d(inside))[0][0]
            px, py = np.atleast_1d(x)[bad] if x.ndim else x, np.atleast_1d(y)[bad] if y.ndim else y
            x_min, x_max, y_min, y_max = self.extent
            raise ValueError(
                f"point x={float(px):.1f} m, y={float(py):.1f} m lies outside the met-ocean grid "
                f"(x {x_min:.1f}..{x_max:.1f} m, y {y_min:.1f}..{y_max:.1f} m)"
            )
        fx = np.clip((x - self.x[0]) / self.dx, 0.0, self.x.size - 1.0)
        fy = np.clip((y - self.y[0]) / self.dy, 0.0, self.y.size - 1.0)
        i = np.minimum(np.floor(fx).astype(int), self.x.size - 2)
        j = np.minimum(np.floor(fy).astype(int), self.y.size - 2)
        tx = fx - i
        ty = fy - j
        out = {}
        for name, grid in self._fields.items():
            out[name] = ((1 - tx) * (1 - ty) * grid[i, j] + tx * (1 - ty) * grid[i + 1, j]
                         + (1 - tx) * ty * grid[i, j + 1] + tx * ty * grid[i + 1, j + 1])
        out["wind_speed"] = np.hypot(out["wind_north"], out["wind_east"])
        out["wind_direction"] = wind_from_direction(out["wind_north"], out["wind_east"])
        return out

    # -- sources ---------------------------------------------------------------------
    @classmethod
    def generate_paper_default(
        cls,
        x_range_nm=(0.0, 100.0),
        y_range_nm=(0.0, 100.0),
        resolution_nm: float = 1.0,
        wind_control_points_ms=DEFAULT_WIND_CONTROL_POINTS,
        wind_from_deg: float = 45.0,
        fetch_km: float = 100.0,
        current_kn: float = 0.5,
        current_towards_deg: float = 135.0,
    ) -> "MetOceanField":
        """The paper's synthetic weather (Section 6.1.1; spec section 2).

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
        from scipy.interpolate import RectBivariateSpline

        control = np.asarray(wind_control_points_ms, dtype=float)
        if control.ndim != 2 or min(control.shape) < 4:
            raise ValueError("wind_control_points_ms needs a 2-D lattice of at least 4 x 4 values")
        if resolution_nm <= 0:
            raise ValueError("resolution_nm must be positive")
        x = _axis(x_range_nm, resolution_nm)
        y = _axis(y_range_nm, resolution_nm)
        cx = np.linspace(x[0], x[-1], control.shape[0])
        cy = np.linspace(y[0], y[-1], control.shape[1])
        speed = np.clip(RectBivariateSpline(cx, cy, control, kx=3, ky=3)(x, y), 0.0, None)
        towards = np.radians(wind_from_deg) + np.pi
        hs = fetch_limited_hs(speed, fetch_km * 1000.0)
        current = current_kn * KNOT
        set_rad = np.radians(current_towards_deg)
        shape = speed.shape
        fields = {
            "wind_north": speed * np.cos(towards),
            "wind_east": speed * np.sin(towards),
            "hs": hs,
            "current_north": np.full(shape, current * np.cos(set_rad)),
            "current_east": np.full(shape, current * np.sin(set_rad)),
        }
        return cls(x, y, fields, source="generated: paper_default")

    @classmethod
    def from_netcdf(cls, path, origin_deg=None, resolution_nm: float | None = None,
                    time_index: int = 0) -> "MetOceanField":
        """Load a NetCDF file with CF names (ERA5/CMEMS style) through xarray.

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
        time_index : int
            Which time to take when the data have a ``time`` dimension.

        Missing variables are an error, except the current, which defaults to zero
        (ERA5 carries no current) with a warning.  NaN (land in ocean products)
        becomes zero.
        """
        import xarray as xr

        path = Path(path)
        if not path.is_file():
            raise FileNotFoundError(f"met-ocean file not found: {path}")
        with xr.open_dataset(path) as ds:
            ds = ds.load()
        for time_dim in ("time", "valid_time"):
            if time_dim in ds.dims:
                ds = ds.isel({time_dim: time_index})
        for extra in [d for d in ds.dims if d not in ("northing", "easting", "latitude", "longitude", "lat", "lon")]:
            ds = ds.isel({extra: 0})
        arrays = {name: _find_variable(ds, name, path) for name in FIELDS}
        if "northing" in ds.dims and "easting" in ds.dims:
            x = ds["northing"].values.astype(float)
            y = ds["easting"].values.astype(float)
            fields = {name: _as_grid(arr, ("northing", "easting"), x.size, y.size)
                      for name, arr in arrays.items()}
            return cls(x, y, fields, source=f"file: {path}")
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
        north = np.radians(lat - lat0) * EARTH_RADIUS
        east = np.radians(lon - lon0) * EARTH_RADIUS * np.cos(np.radians(lat0))
        step = resolution_nm * NM if resolution_nm else float(np.min(np.diff(north)))
        # cover the data's whole extent with a spacing no coarser than `step`
        x = np.linspace(north[0], north[-1], int(np.ceil((north[-1] - north[0]) / step - 1e-9)) + 1)
        y = np.linspace(east[0], east[-1], int(np.ceil((east[-1] - east[0]) / step - 1e-9)) + 1)
        from scipy.interpolate import RegularGridInterpolator

        xx, yy = np.meshgrid(x, y, indexing="ij")
        fields = {}
        for name, arr in arrays.items():
            grid = _as_grid(arr, (lat_name, lon_name), lat.size, lon.size)[np.ix_(order_lat, order_lon)]
            fields[name] = RegularGridInterpolator((north, east), grid)((xx, yy))
        return cls(x, y, fields, source=f"file: {path} (origin {lat0:.4f}N {lon0:.4f}E)")

    @classmethod
    def from_scenario_table(cls, table: Mapping[str, Any], scenario_dir: Path, where: str) -> "MetOceanField":
        """Build the field a scenario's ``[metocean]`` table describes.

        ``generator = "paper_default"`` with the keyword options of
        :meth:`generate_paper_default`, or ``file = "path.nc"`` with the options of
        :meth:`from_netcdf`.  Errors name ``where`` (file and table) and the key.
        """
        table = dict(table)
        if ("generator" in table) == ("file" in table):
            raise ScenarioError(f"{where}: give exactly one of 'generator' or 'file'")
        if "generator" in table:
            generator = table.pop("generator")
            if generator != "paper_default":
                raise ScenarioError(f"{where}.generator: unknown generator '{generator}' (valid: paper_default)")
            builder, allowed = cls.generate_paper_default, _GENERATOR_KEYS
        else:
            file = Path(table.pop("file"))
            file = file if file.is_absolute() else scenario_dir / file
            if not file.is_file():
                raise ScenarioError(f"{where}.file: met-ocean file not found: {file}")
            if "origin_deg" in table:
                table["origin_deg"] = tuple(table["origin_deg"])

            def builder(**options):
                return cls.from_netcdf(file, **options)

            allowed = _FILE_KEYS
        for key in table:
            if key not in allowed:
                raise ScenarioError(f"{where}: unknown key '{key}' (valid: {', '.join(sorted(allowed))})")
        try:
            return builder(**table)
        except (ValueError, TypeError, KeyError) as exc:
            raise ScenarioError(f"{where}: {exc}") from exc

    # -- writers -------------------------------------------------------------------
    def to_dataset(self):
        """The field as an ``xarray.Dataset`` with CF-style names and attributes."""
        import xarray as xr

        coords = {
            "northing": ("northing", self.x, {"standard_name": "projection_y_coordinate", "units": "m",
                                              "long_name": "distance north of the map origin"}),
            "easting": ("easting", self.y, {"standard_name": "projection_x_coordinate", "units": "m",
                                            "long_name": "distance east of the map origin"}),
        }
        units = {"hs": "m"}
        data = {
            _OUTPUT_NAMES[name]: (("northing", "easting"), self._fields[name],
                                  {"standard_name": _STANDARD_NAMES[name], "units": units.get(name, "m s-1")})
            for name in FIELDS
        }
        return xr.Dataset(data, coords=coords, attrs={"Conventions": "CF-1.8", "source": self.source,
                                                      "title": "RHNC met-ocean field"})

    def to_netcdf(self, path) -> Path:
        """Write the field as NetCDF (readable again by :meth:`from_netcdf`)."""
        path = Path(path)
        self.to_dataset().to_netcdf(path, engine="netcdf4")
        return path

    def write_fmu_grid(self, path) -> Path:
        """Write the binary grid the MetOcean FMU reads (format: models/MetOcean/readme.md)."""
        path = Path(path)
        header = b"MOGRID1\n" + struct.pack("<ii", self.x.size, self.y.size)
        header += struct.pack("<dddd", self.x[0], self.dx, self.y[0], self.dy)
        body = b"".join(np.ascontiguousarray(self._fields[name], dtype="<f8").tobytes() for name in FIELDS)
        tmp = path.with_suffix(path.suffix + ".tmp")
        tmp.write_bytes(header + body)
        tmp.replace(path)
        return path


_GENERATOR_KEYS = ("x_range_nm", "y_range_nm", "resolution_nm", "wind_control_points_ms",
                   "wind_from_deg", "fetch_km", "current_kn", "current_towards_deg")
_FILE_KEYS = ("origin_deg", "resolution_nm", "time_index")


def wind_from_direction(wind_north, wind_east):
    """Meteorological direction [rad in [0, 2 pi)] the wind comes from."""
    return np.mod(np.arctan2(-np.asarray(wind_east), -np.asarray(wind_north)), 2 * np.pi)


def fetch_limited_hs(wind_speed, fetch_m: float):
    """Significant wave height [m] for a wind speed [m/s] over a fetch [m].

    Fetch-limited JONSWAP growth, ``g Hs / U^2 = 0.0016 (g F / U^2)^(1/2)``, capped at the
    fully developed Pierson-Moskowitz sea, ``Hs = 0.21 U^2 / g`` (spec section 2).
    """
    u = np.asarray(wind_speed, dtype=float)
    limited = 0.0016 * u * np.sqrt(fetch_m / GRAVITY)
    developed = 0.21 * u**2 / GRAVITY
    return np.minimum(limited, developed)


def _axis(range_nm, resolution_nm) -> np.ndarray:
    start, stop = (float(v) for v in range_nm)
    if stop <= start:
        raise ValueError(f"range {list(range_nm)} nm must increase")
    count = int(round((stop - start) / resolution_nm)) + 1
    return np.linspace(start, stop, max(count, 2)) * NM


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


def _as_grid(arr, dims, n0, n1) -> np.ndarray:
    values = arr.transpose(*dims).values.astype(float) if set(dims) <= set(arr.dims) else None
    if values is None or values.shape != (n0, n1):
        raise ValueError(f"variable {arr.name} must have dimensions {dims}")
    return np.nan_to_num(values, nan=0.0)
