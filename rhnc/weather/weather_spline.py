"""The paper weather's wind speed grid: a bicubic spline through a lattice, kept once computed.

:func:`bicubic_grid` evaluates FITPACK's interpolating bicubic spline
(``scipy.interpolate.RectBivariateSpline``, ``kx = ky = 3``, ``s = 0``) through control values
on a lattice, at every node of the map's grid.  Importing ``scipy.interpolate`` takes some
0.15 s (it brings ``scipy.optimize`` and ``scipy.special``), far longer than the weather
itself, and every run of a scenario asks for the same grid: so the grid, once computed, is
kept in a per-user folder, ``<user cache>/rhnc-cosim/weather/`` (``platformdirs``;
``$RHNC_WEATHER_CACHE`` names another folder, ``off`` keeps nothing), as one ``.npy`` file
named after the inputs' exact bytes and scipy's version.  A later run with the same lattice
and grid reads back the very doubles FITPACK gave; a file that is missing, unreadable or
not of the grid's shape is computed again and rewritten.  Nothing else reads the folder:
delete it to clear it.
"""

from __future__ import annotations

import hashlib
import logging
import os
import secrets
from pathlib import Path

import numpy as np

log = logging.getLogger(__name__)

#: environment variable naming the folder of computed grids (``off``: keep none)
CACHE_ENV = "RHNC_WEATHER_CACHE"
#: bump when what a grid file holds changes, so that old files are not read
RECIPE_VERSION = "1"
_OFF = {"0", "off", "false", "no"}


def bicubic_grid(control_x, control_y, control, x, y) -> np.ndarray:
    """The interpolating bicubic spline through ``control`` (``len(control_x)`` by
    ``len(control_y)`` values on that lattice), at every node of the grid ``x`` by ``y``."""
    control_x, control_y, control, x, y = (np.ascontiguousarray(a, dtype=float)
                                           for a in (control_x, control_y, control, x, y))
    folder = cache_dir()
    path = None if folder is None else folder / f"bicubic-{_key(control_x, control_y, control, x, y)}.npy"
    if path is not None:
        kept = _read(path, (x.size, y.size))
        if kept is not None:
            return kept
    from scipy.interpolate import RectBivariateSpline

    grid = RectBivariateSpline(control_x, control_y, control, kx=3, ky=3)(x, y)
    if path is not None:
        _keep(path, grid)
    return grid


def cache_dir() -> Path | None:
    """Folder of the computed grids (see the module docstring); None when turned off."""
    override = os.environ.get(CACHE_ENV)
    if override and override.strip().lower() in _OFF:
        return None
    if override:
        return Path(override).expanduser()
    from platformdirs import user_cache_dir

    from orchestrator.fmu_sources import CACHE_NAME

    return Path(user_cache_dir(CACHE_NAME)) / "weather"


def _key(*arrays: np.ndarray) -> str:
    """SHA-256 prefix over the recipe, scipy's version and each array's shape and bytes."""
    import scipy  # the package alone: its version, not its modules

    digest = hashlib.sha256(f"bicubic {RECIPE_VERSION} scipy {scipy.__version__}".encode())
    for array in arrays:
        digest.update(repr(array.shape).encode())
        digest.update(array.astype("<f8", copy=False).tobytes())
    return digest.hexdigest()[:32]


def _read(path: Path, shape: tuple[int, int]) -> np.ndarray | None:
    try:
        grid = np.load(path, allow_pickle=False)
    except (OSError, ValueError) as exc:
        if path.exists():
            log.debug("weather grid %s unreadable (%s): computed again", path, exc)
        return None
    if grid.shape != shape or grid.dtype != np.float64:
        log.debug("weather grid %s is %s %s, not %s float64: computed again", path, grid.shape, grid.dtype, shape)
        return None
    return grid


def _keep(path: Path, grid: np.ndarray) -> None:
    """Write ``grid`` to ``path`` whole or not at all (a file of its own, then renamed)."""
    partial = path.with_name(f".{path.name}.{os.getpid()}-{secrets.token_hex(4)}.partial")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        with open(partial, "wb") as file:
            np.save(file, grid, allow_pickle=False)
        os.replace(partial, path)
    except OSError as exc:  # a read-only or full disk: the run goes on without keeping the grid
        log.debug("weather grid not kept in %s: %s", path.parent, exc)
        partial.unlink(missing_ok=True)
