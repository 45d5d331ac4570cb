"""The local plane of a passage: latitude/longitude to metres north and east of an origin, and back.

A passage is planned and sailed in a local plane, x north and y east in metres, as every
other scenario.  Geographic positions (ports, waypoints, coastline, no-go polygons, the
sailed track in the results) go through one projection: pyproj's **azimuthal equidistant**
projection on the WGS84 ellipsoid centred at the passage's origin (``+proj=aeqd``).  Distances
and bearings from the origin are true; elsewhere the scale error grows as the square of the
distance from it, about 0.1 % at 150 nm and 0.4 % at 300 nm, far below the clearance of a
passage's declared margins (a 1 nm clearance at 150 nm from the origin is off by under 2 m).
The projection's east axis is pyproj's x and its north axis pyproj's y; this module swaps
them into the plane's (north, east) order.  Longitudes may be given from -180 to 180 or from
0 to 360 (ERA5's convention): they are wrapped to within half a turn of the origin's.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from orchestrator.geometry import wrap_longitude_deg


@dataclass(frozen=True)
class LocalProjection:
    """Azimuthal equidistant plane centred at ``(origin_lat_deg, origin_lon_deg)``.

    Attributes
    ----------
    origin_lat_deg, origin_lon_deg : float
        Geographic origin of the plane [deg]: x = y = 0 there.
    """

    origin_lat_deg: float
    origin_lon_deg: float
    _forward: Any = field(init=False, repr=False, compare=False)
    _inverse: Any = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        if not (np.isfinite(self.origin_lat_deg) and -80.0 <= self.origin_lat_deg <= 80.0):
            raise ValueError(f"origin latitude must lie within 80 deg of the equator, got {self.origin_lat_deg!r}")
        if not (np.isfinite(self.origin_lon_deg) and -360.0 <= self.origin_lon_deg <= 360.0):
            raise ValueError(f"origin longitude must lie in [-360, 360] deg, got {self.origin_lon_deg!r}")
        from pyproj import Transformer

        plane = (f"+proj=aeqd +lat_0={self.origin_lat_deg!r} +lon_0={self.origin_lon_deg!r} "
                 "+datum=WGS84 +units=m")
        object.__setattr__(self, "_forward", Transformer.from_crs("EPSG:4326", plane, always_xy=True))
        object.__setattr__(self, "_inverse", Transformer.from_crs(plane, "EPSG:4326", always_xy=True))

    def to_local(self, lat_deg, lon_deg) -> tuple[np.ndarray, np.ndarray]:
        """North and east [m] of geographic positions [deg]."""
        lon = wrap_longitude_deg(lon_deg, self.origin_lon_deg)
        east, north = self._forward.transform(lon, np.asarray(lat_deg, dtype=float))
        return np.asarray(north, dtype=float), np.asarray(east, dtype=float)

    def to_geographic(self, north_m, east_m) -> tuple[np.ndarray, np.ndarray]:
        """Latitude and longitude [deg, longitude in -180..180] of plane positions [m]."""
        lon, lat = self._inverse.transform(np.asarray(east_m, dtype=float), np.asarray(north_m, dtype=float))
        return np.asarray(lat, dtype=float), wrap_longitude_deg(lon)
