"""The met-ocean grid's names and size limits: the five fields, map axes, node counts.

The bottom of the met-ocean modules: the field (:mod:`rhnc.weather.metocean`), its NetCDF files
(:mod:`rhnc.weather.metocean_netcdf`, :mod:`rhnc.weather.metocean_sources`) and the weather generators
(:mod:`rhnc.weather.weather_generators`) all size their grids here, before any array is allocated.
"""

from __future__ import annotations

import math

import numpy as np

from orchestrator.geometry import NM

#: The gridded quantities, in the order the FMU grid file and the NetCDF files hold them.
FIELDS = ("wind_north", "wind_east", "hs", "current_north", "current_east")

#: Most nodes along one axis of a met-ocean grid (100 nm at 0.05 nm).
MAX_AXIS_NODES = 2001
#: Most nodes of a met-ocean grid over space and time (five float64 fields of 32 MB each).
MAX_GRID_NODES = 4_000_000


def axis_node_count(span: float, step: float, what: str = "resolution_nm") -> int:
    """Nodes of an axis ``span`` long at spacing ``step`` (same units), refused beyond the limit.

    Checked before any array is allocated: a fine resolution over a wide map would otherwise
    ask for gigabytes.
    """
    count = span / step if step > 0 else math.inf
    if not math.isfinite(count) or count + 1 > MAX_AXIS_NODES:
        raise ValueError(f"{what} gives {count + 1:.3g} grid nodes along an axis, more than the limit of "
                         f"{MAX_AXIS_NODES} (a coarser resolution or a smaller map)")
    return int(round(count)) + 1


def check_grid_nodes(nx: int, ny: int, nt: int = 1) -> None:
    """Refuse a grid of more than :data:`MAX_GRID_NODES` nodes over space and time, before it is built."""
    if nx * ny * nt > MAX_GRID_NODES:
        raise ValueError(f"the met-ocean grid would hold {nx} x {ny} x {nt} time steps = {nx * ny * nt} nodes, "
                         f"more than the limit of {MAX_GRID_NODES}")


def map_axis(range_nm, resolution_nm) -> np.ndarray:
    """Evenly spaced nodes [m] over ``range_nm`` (start, stop) [nm] at ``resolution_nm`` [nm]."""
    start, stop = (float(v) for v in range_nm)
    if not (math.isfinite(start) and math.isfinite(stop)):
        raise ValueError(f"range {list(range_nm)} nm must be finite")
    if stop <= start:
        raise ValueError(f"range {list(range_nm)} nm must increase")
    if not resolution_nm > 0:
        raise ValueError("resolution_nm must be positive")
    count = axis_node_count(stop - start, resolution_nm)
    return np.linspace(start, stop, max(count, 2)) * NM


def data_extent(field) -> tuple[float, float, float, float]:
    """(x_min, x_max, y_min, y_max) [m] where ``field`` holds data: its ``data_extent``
    (a grid grown by held edge values, :meth:`rhnc.weather.metocean.MetOceanField.with_edges_held`,
    keeps its data's), else the extent of its axes ``x``, ``y``.

    Planners lay their grids over this extent: the held band around it lets a ship sail
    there, but it is no weather to plan on.
    """
    extent = getattr(field, "data_extent", None)
    x_min, x_max, y_min, y_max = (field.x[0], field.x[-1], field.y[0], field.y[-1]) if extent is None else extent
    return float(x_min), float(x_max), float(y_min), float(y_max)
