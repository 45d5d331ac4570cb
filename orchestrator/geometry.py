"""Units and plane geometry every layer shares: nautical mile, knot, degree, angle wrap, projection,
the nearest point of a segment.

Scenarios place ships in a local plane: ``x`` north, ``y`` east [m], angles clockwise from
north [rad].  Options and reports speak nautical miles and knots; these are the only
definitions of those units in the toolchain (the ship domain imports them from here).
"""

from __future__ import annotations

import math

import numpy as np

NM = 1852.0  #: metres per nautical mile
KNOT = NM / 3600.0  #: m/s per knot (nautical mile per hour)
DEG = math.pi / 180.0  #: radians per degree
EARTH_RADIUS_M = 6_371_000.0  #: mean radius of the Earth [m], for the local projection


def wrap_angle(angle, half_turn: float = np.pi):
    """Wrap angles to (-half_turn, half_turn]: radians by default, degrees with
    ``half_turn = 180`` (numpy; arrays element-wise)."""
    if type(angle) is float:  # a plain number, as a port's value every step: no array round trip
        return np.float64(wrap_float(angle, half_turn))
    wrapped = np.mod(np.asarray(angle, dtype=float) + half_turn, 2.0 * half_turn) - half_turn
    return np.where(wrapped == -half_turn, half_turn, wrapped)


def wrap_float(angle: float, half_turn: float = math.pi) -> float:
    """:func:`wrap_angle` of one Python float, as a Python float (the same value, no numpy)."""
    # Python's float % is numpy's np.mod to the bit (fmod, then the divisor's sign)
    scalar = (angle + half_turn) % (2.0 * half_turn) - half_turn
    return half_turn if scalar == -half_turn else scalar


def wrap_deg(angle_deg):
    """Wrap angles [deg] to (-180, 180]."""
    return wrap_angle(angle_deg, 180.0)


def wrap_longitude_deg(lon_deg, reference_lon_deg: float = 0.0) -> np.ndarray:
    """Longitudes [deg] shifted by whole turns into ``[reference - 180, reference + 180)``
    (a grid read from 0-360 degrees placed about the scenario's meridian)."""
    lon = np.asarray(lon_deg, dtype=float)
    return (lon - reference_lon_deg + 180.0) % 360.0 - 180.0 + reference_lon_deg


def local_north_east_m(lat_deg, lon_deg, lat0_deg: float, lon0_deg: float) -> tuple[np.ndarray, np.ndarray]:
    """Equirectangular projection about ``(lat0_deg, lon0_deg)``: north and east [m].

    Good to a fraction of a percent over a few hundred nautical miles away from the poles;
    the distances of gridded met-ocean data.  (Traffic situations, placed across larger
    areas, use pyproj's azimuthal equidistant projection instead.)
    """
    north = np.radians(np.asarray(lat_deg, dtype=float) - lat0_deg) * EARTH_RADIUS_M
    east = np.radians(np.asarray(lon_deg, dtype=float) - lon0_deg) * EARTH_RADIUS_M * np.cos(np.radians(lat0_deg))
    return north, east


def nearest_on_segments(points, a, b) -> tuple[np.ndarray, np.ndarray]:
    """The point of each segment a-b nearest to ``points``, and its distance [m].

    ``points``, ``a`` and ``b`` are plane positions (..., 2) [m] broadcast against each other:
    one point against many segments, many points against one segment, or point by segment.
    A segment of zero length is its start point.  Returns the nearest points (..., 2) [m] and
    their distances (...) [m].
    """
    points = np.asarray(points, dtype=float)
    a = np.asarray(a, dtype=float)
    along = np.asarray(b, dtype=float) - a
    length2 = np.sum(along * along, axis=-1)
    projected = np.sum((points - a) * along, axis=-1)
    share = np.divide(projected, length2, out=np.zeros(np.broadcast_shapes(projected.shape, length2.shape)),
                      where=length2 > 0)
    nearest = a + np.clip(share, 0.0, 1.0)[..., None] * along
    offset = points - nearest
    return nearest, np.asarray(np.hypot(offset[..., 0], offset[..., 1]))
