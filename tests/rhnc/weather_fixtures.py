"""Met-ocean fields for routing tests: uniform weather and circular storms on small maps."""

import numpy as np

from orchestrator.geometry import NM
from rhnc.weather.metocean import FIELDS, MetOceanField, fetch_limited_hs


def axis_nm(size_nm: float, resolution_nm: float) -> np.ndarray:
    return np.linspace(0.0, size_nm, int(round(size_nm / resolution_nm)) + 1) * NM


def storm_field(size_nm=20.0, resolution_nm=0.5, storms=(), base_wind_ms=5.0, wind_from_deg=45.0,
                current_ms=(0.0, 0.0)) -> MetOceanField:
    """Wind from ``wind_from_deg`` of ``base_wind_ms`` plus Gaussian storms.

    ``storms``: (north_nm, east_nm, radius_nm, extra wind speed m/s); Hs fetch-limited.
    """
    x = axis_nm(size_nm, resolution_nm)
    xx, yy = np.meshgrid(x, x, indexing="ij")
    speed = np.full(xx.shape, float(base_wind_ms))
    for north, east, radius, extra in storms:
        speed += extra * np.exp(-((xx - north * NM) ** 2 + (yy - east * NM) ** 2) / (2 * (radius * NM) ** 2))
    towards = np.radians(wind_from_deg) + np.pi
    return MetOceanField(x, x, {
        "wind_north": speed * np.cos(towards),
        "wind_east": speed * np.sin(towards),
        "hs": fetch_limited_hs(speed, 100e3),
        "current_north": np.full(xx.shape, current_ms[0]),
        "current_east": np.full(xx.shape, current_ms[1]),
    }, source="test storms")


def switched_field(before: MetOceanField, after: MetOceanField, switch_s: float,
                   ramp_s: float = 1.0) -> MetOceanField:
    """A time-varying field that is ``before`` until ``switch_s`` and ``after`` from
    ``switch_s + ramp_s`` on (linear in between), so a test knows when the weather is where."""
    times = np.array([0.0, switch_s, switch_s + ramp_s, switch_s + ramp_s + 1e6])
    fields = {name: np.stack([getattr(before, name), getattr(before, name), getattr(after, name),
                              getattr(after, name)]) for name in FIELDS}
    return MetOceanField(before.x, before.y, fields, times_s=times, source="test: switched")
