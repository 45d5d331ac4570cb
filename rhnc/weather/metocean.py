"""Met-ocean fields over the map and in time: one data source per scenario for the FMU and the planner.

The field lives on a regular grid in a local plane, x north and y east in metres, and
optionally on a time axis ``times_s`` [s on the simulation clock: t = 0 is the moment the
scenario's clock reads 0, the departure of every shipped scenario].  Five gridded
quantities are kept:

=================  =========  ==============================================
name               unit       meaning
=================  =========  ==============================================
``wind_north``     m/s        wind velocity towards north (10 m)
``wind_east``      m/s        wind velocity towards east (10 m)
``hs``             m          significant wave height
``current_north``  m/s        surface current towards north
``current_east``   m/s        surface current towards east
=================  =========  ==============================================

Interpolation (:meth:`MetOceanField.sample`): bilinear in space within each time step,
then linear in time between the two time steps around ``t_s``, held constant before the
first and after the last time.  A static field has a single time step and ignores time.
The MetOcean FMU evaluates the same formula at its own simulation time, so FMU and planner
agree to rounding (``models/MetOcean/readme.md``).

Sources (:mod:`rhnc.weather.metocean_sources`, what a scenario's ``[metocean]`` table names)
-------------------------------------------------------------------------------------
* generators (:mod:`rhnc.weather.weather_generators`, one registry, ``[metocean] generator =
  "<name>"``): the paper's synthetic weather and the storm sets of ``docs/weather.md``;
* ``from_netcdf``: a NetCDF file with CF names as ERA5 and CMEMS write them, every time
  step of it (written again by :meth:`MetOceanField.to_netcdf`, :mod:`rhnc.weather.metocean_netcdf`).

This module knows none of its sources: they build the field, it only holds and samples it.

The environment FMU reads the same grid through ``write_fmu_grid`` (binary format
``MOGRID2``, described in ``models/MetOcean/readme.md``).
"""

from __future__ import annotations

import math
import struct
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from orchestrator.geometry import NM
from rhnc.weather.metocean_grid import FIELDS
from rhnc.weather.metocean_netcdf import to_dataset, write_netcdf

GRAVITY = 9.81  #: m/s^2

#: Magic of the FMU grid file with a time axis (the FMU still reads the static MOGRID1).
FMU_GRID_MAGIC = b"MOGRID2\n"


class MetOceanField:
    """Gridded met-ocean quantities on a regular local grid (x north, y east, metres), in time.

    Parameters
    ----------
    x, y : ndarray
        Strictly increasing, evenly spaced node coordinates [m] (north, east).
    fields : mapping
        One array per name in :data:`FIELDS`: (nx, ny) for a static field, or
        (nt, nx, ny) with one slice per entry of ``times_s``.
    source : str
        Human-readable provenance, written into results.
    times_s : array_like, optional
        Strictly increasing times [s, simulation clock] of the slices; omitted: a static
        field (one slice, valid at all times).
    start_time : str, optional
        Calendar time (ISO 8601) of t = 0, kept so that NetCDF round trips keep dates.
    data_extent : (x_min, x_max, y_min, y_max), optional
        Where the values are data [m]; omitted: the whole grid (a grid grown by held edge
        values, :meth:`with_edges_held`, passes its data's extent on).
    """

    def __init__(self, x: np.ndarray, y: np.ndarray, fields: Mapping[str, np.ndarray], source: str = "",
                 times_s=None, start_time: str | None = None,
                 data_extent: tuple[float, float, float, float] | None = None):
        self.x = np.asarray(x, dtype=float)
        self.y = np.asarray(y, dtype=float)
        for axis_name, axis in (("x (north)", self.x), ("y (east)", self.y)):
            if axis.ndim != 1 or axis.size < 2:
                raise ValueError(f"met-ocean grid axis {axis_name} needs at least 2 nodes")
            steps = np.diff(axis)
            if np.any(steps <= 0) or not np.allclose(steps, steps[0], rtol=1e-6, atol=1e-6):
                raise ValueError(f"met-ocean grid axis {axis_name} must be evenly spaced and increasing")
        self.times_s = np.array([0.0]) if times_s is None else np.asarray(times_s, dtype=float).reshape(-1)
        if self.times_s.size < 1 or not np.all(np.isfinite(self.times_s)) or np.any(np.diff(self.times_s) <= 0):
            raise ValueError("met-ocean times must be finite and strictly increasing")
        shape = (self.times_s.size, self.x.size, self.y.size)
        self._fields = {}
        for name in FIELDS:
            values = np.asarray(fields[name], dtype=float)
            if values.ndim == 2 and times_s is None:
                values = values[None]
            if values.shape != shape:
                raise ValueError(f"met-ocean field {name} has shape {values.shape}, grid is "
                                 f"{shape if times_s is not None else shape[1:]} (times, north, east)")
            if not np.all(np.isfinite(values)):
                raise ValueError(f"met-ocean field {name} holds NaN or infinite values")
            self._fields[name] = values
        self.source = source
        self.start_time = start_time
        #: (x_min, x_max, y_min, y_max) [m] of the data: the grid's own extent, except where
        #: :meth:`with_edges_held` grew the grid by held values, which are not data.
        self.data_extent: tuple[float, float, float, float] = self.extent if data_extent is None else data_extent

    # -- gridded quantities -------------------------------------------------------
    def _grid(self, name: str) -> np.ndarray:
        """(nx, ny) for a static field, (nt, nx, ny) for a time-varying one."""
        values = self._fields[name]
        return values if self.is_time_varying else values[0]

    wind_north = property(lambda self: self._grid("wind_north"))
    wind_east = property(lambda self: self._grid("wind_east"))
    hs = property(lambda self: self._grid("hs"))
    current_north = property(lambda self: self._grid("current_north"))
    current_east = property(lambda self: self._grid("current_east"))

    @property
    def is_time_varying(self) -> bool:
        """True when the field has more than one time step."""
        return self.times_s.size > 1

    @property
    def wind_speed(self) -> np.ndarray:
        """Wind speed [m/s] at the nodes (per time step when time-varying)."""
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

    def with_edges_held(self, margin_m: float) -> "MetOceanField":
        """This field on a grid grown by at least ``margin_m`` [m] beyond every edge, whole
        grid steps, the edge's values held there (the field on the original grid unchanged).

        A ship's arrival circle about a goal on the edge lies partly off the map; holding
        the edge's weather over that band lets it sail there (nearest-edge values, not
        data).
        """
        if not (np.isfinite(margin_m) and margin_m >= 0.0):
            raise ValueError(f"the margin to hold the edges over must be a non-negative distance, got {margin_m}")
        nx, ny = int(math.ceil(margin_m / self.dx - 1e-9)), int(math.ceil(margin_m / self.dy - 1e-9))
        if nx == 0 and ny == 0:
            return self
        x = np.concatenate([self.x[0] - self.dx * np.arange(nx, 0, -1), self.x, self.x[-1] + self.dx * np.arange(1, nx + 1)])
        y = np.concatenate([self.y[0] - self.dy * np.arange(ny, 0, -1), self.y, self.y[-1] + self.dy * np.arange(1, ny + 1)])
        fields = {name: np.pad(values, ((0, 0), (nx, nx), (ny, ny)), mode="edge") for name, values in self._fields.items()}
        if not self.is_time_varying:
            fields = {name: values[0] for name, values in fields.items()}
        return MetOceanField(x, y, fields, source=f"{self.source} (edge values held {margin_m / NM:g} nm beyond)",
                             times_s=self.times_s if self.is_time_varying else None, start_time=self.start_time,
                             data_extent=self.data_extent)

    # -- interpolation --------------------------------------------------------------
    def time_weights(self, t_s) -> tuple[np.ndarray, np.ndarray]:
        """Slice index k and weight w [-] so that a value at ``t_s`` is (1 - w) F[k] + w F[k + 1].

        ``t_s`` [s] is held at the first time before it and at the last time after it;
        exactly at a node time the weight is 0 (or 1 at the last node), so node values
        are returned exactly.  A static field gives k = 0, w = 0.
        """
        t = np.asarray(t_s, dtype=float)
        if not self.is_time_varying:
            return np.zeros(t.shape, dtype=int), np.zeros(t.shape)
        if not np.all(np.isfinite(t)):
            raise ValueError("met-ocean sample time must be finite")
        times = self.times_s
        held = np.clip(t, times[0], times[-1])
        k = np.clip(np.searchsorted(times, held, side="right") - 1, 0, times.size - 2)
        w = (held - times[k]) / (times[k + 1] - times[k])
        return k, w

    def sample(self, x, y, t_s=None) -> dict[str, np.ndarray]:
        """Interpolate every field at points (x, y) [m] and times ``t_s`` [s].

        Bilinear in space in each time step, linear in time between the two time steps
        around ``t_s`` (see :meth:`time_weights`).  ``t_s`` is a scalar or an array
        broadcasting with ``x``; a static field ignores it, a time-varying field needs it.
        Returns the five gridded fields plus ``wind_speed`` and ``wind_direction``
        computed from the interpolated wind components (as the FMU does).

        Raises
        ------
        ValueError
            If a point lies outside the grid (no extrapolation), or a time-varying field
            is sampled without a time.
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
        if self.is_time_varying and t_s is None:
            raise ValueError(f"the met-ocean field varies in time ({self.times_s.size} steps): "
                             "sample it at a time t_s")
        fx = np.clip((x - self.x[0]) / self.dx, 0.0, self.x.size - 1.0)
        fy = np.clip((y - self.y[0]) / self.dy, 0.0, self.y.size - 1.0)
        i = np.minimum(np.floor(fx).astype(int), self.x.size - 2)
        j = np.minimum(np.floor(fy).astype(int), self.y.size - 2)
        tx = fx - i
        ty = fy - j

        out = {}
        if not self.is_time_varying:
            for name, stack in self._fields.items():
                out[name] = bilinear(stack[0], i, j, tx, ty)
        else:
            k, w = self.time_weights(t_s)
            k, w, i, j, tx, ty = np.broadcast_arrays(k, w, i, j, tx, ty)
            for name, stack in self._fields.items():
                out[name] = between(bilinear(stack, i, j, tx, ty, k), bilinear(stack, i, j, tx, ty, k + 1), w)
        out["wind_speed"] = np.hypot(out["wind_north"], out["wind_east"])
        out["wind_direction"] = wind_from_direction(out["wind_north"], out["wind_east"])
        return out

    def snapshot(self, t_s: float) -> "MetOceanField":
        """The static field at time ``t_s`` [s], linear between time steps (for static planners)."""
        if not self.is_time_varying:
            return self
        k_array, w_array = self.time_weights(float(t_s))
        k, w = int(k_array), float(w_array)
        fields = {name: between(stack[k], stack[k + 1], w) for name, stack in self._fields.items()}
        return MetOceanField(self.x, self.y, fields, source=f"{self.source} at t = {float(t_s):g} s",
                             data_extent=self.data_extent)

    # -- writers -------------------------------------------------------------------
    def to_dataset(self):
        """The field as an ``xarray.Dataset`` with CF-style names and attributes."""
        return to_dataset(self)

    def to_netcdf(self, path) -> Path:
        """Write the field as NetCDF (read again, every time step, by :func:`rhnc.weather.metocean_sources.from_netcdf`)."""
        return write_netcdf(self, path)

    def write_fmu_files(self, work_dir) -> dict[str, str]:
        """Write what the environment FMU reads into ``work_dir``: ``{placeholder: path}``.

        The co-simulation master substitutes each path for its placeholder in FMU
        parameters (``grid_file = "metocean.grid"``).
        """
        return {"metocean.grid": str(self.write_fmu_grid(Path(work_dir) / "metocean.grid"))}

    def write_fmu_grid(self, path) -> Path:
        """Write the binary grid the MetOcean FMU reads (``MOGRID2``, models/MetOcean/readme.md).

        Header: magic, int32 nx, ny, nt, float64 x0, dx, y0, dy [m]; then the nt times
        [s]; then per time step the five fields of nx * ny float64 (row-major [i * ny + j]).
        """
        path = Path(path)
        nt = self.times_s.size
        header = FMU_GRID_MAGIC + struct.pack("<iii", self.x.size, self.y.size, nt)
        header += struct.pack("<dddd", self.x[0], self.dx, self.y[0], self.dy)
        header += np.ascontiguousarray(self.times_s, dtype="<f8").tobytes()
        body = b"".join(np.ascontiguousarray(self._fields[name][k], dtype="<f8").tobytes()
                        for k in range(nt) for name in FIELDS)
        tmp = path.with_suffix(path.suffix + ".tmp")
        tmp.write_bytes(header + body)
        tmp.replace(path)
        return path


def bilinear(grid, i, j, tx, ty, k=None):
    """Bilinear sample of ``grid`` (nx, ny) in cell (i, j) at fractions (tx, ty) [-].

    ``tx`` runs along x (north) from node i to i + 1, ``ty`` along y (east) from j to j + 1;
    the index and fraction arrays broadcast (one sample per element).  With ``k``, ``grid``
    is a stack (nt, nx, ny) sampled in its slices ``k``.  The MetOcean FMU's C code
    evaluates the same four terms in the same order.
    """
    def node(di, dj):
        return grid[i + di, j + dj] if k is None else grid[k, i + di, j + dj]

    return ((1 - tx) * (1 - ty) * node(0, 0) + tx * (1 - ty) * node(1, 0)
            + (1 - tx) * ty * node(0, 1) + tx * ty * node(1, 1))


def between(before, after, w):
    """Linear in time: ``before`` at weight 0, ``after`` at weight 1."""
    return (1 - w) * before + w * after


def wind_from_direction(wind_north, wind_east):
    """Meteorological direction [rad in [0, 2 pi)] the wind comes from."""
    return np.mod(np.arctan2(-np.asarray(wind_east), -np.asarray(wind_north)), 2 * np.pi)


def fetch_limited_hs(wind_speed, fetch_m: float):
    """Significant wave height [m] for a wind speed [m/s] over a fetch [m].

    Fetch-limited JONSWAP growth, ``g Hs / U^2 = 0.0016 (g F / U^2)^(1/2)``, capped at the
    fully developed Pierson-Moskowitz sea, ``Hs = 0.21 U^2 / g``.
    """
    u = np.asarray(wind_speed, dtype=float)
    limited = 0.0016 * u * np.sqrt(fetch_m / GRAVITY)
    developed = 0.21 * u**2 / GRAVITY
    return np.minimum(limited, developed)
