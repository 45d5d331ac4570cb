"""Encounter geometry: place a target ship so that it meets the own ship at a chosen CPA and TCPA.

Coordinates follow the scenarios: ``x`` north, ``y`` east, in nautical miles; courses in
degrees clockwise from north; speeds in knots (nm/h).  Both ships sail straight at
constant velocity; with the relative position ``r(t) = r0 + w t`` (target minus own ship,
``w`` the relative velocity) the time of closest approach is ``TCPA = -r0.w / |w|^2`` and
the closest approach ``CPA = |r(TCPA)|``.  Placing the target is the inverse: choose its
velocity from the encounter type, then ``r0 = CPA n - w TCPA`` with ``n`` the unit normal of
``w`` on the chosen passing side.

Encounter types (own ship is the give-way or overtaking vessel in the COLREG sense):

``head_on``
    Target on a (nearly) reciprocal course, ``course = own + 180 deg + offset``.
``crossing``
    Target crossing from starboard to port ahead, ``course = own - 90 deg + offset``.
``crossing_port``
    Target crossing from port to starboard ahead, ``course = own + 90 deg + offset``.
``overtaking``
    Own ship overtakes a slower target on a similar course, ``course = own + offset``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

ENCOUNTER_TYPES = ("head_on", "crossing", "crossing_port", "overtaking")
PASSING_SIDES = ("port", "starboard")

#: Course of the target relative to the own ship's course [deg], before the drawn offset.
RELATIVE_COURSE_DEG = {"head_on": 180.0, "crossing": -90.0, "crossing_port": 90.0, "overtaking": 0.0}


@dataclass(frozen=True)
class ShipMotion:
    """A ship sailing straight: start position [nm] (north, east) and velocity [kn] (north, east)."""

    start_nm: tuple[float, float]
    velocity_kn: tuple[float, float]

    @classmethod
    def from_course(cls, start_nm, course_deg: float, speed_kn: float) -> "ShipMotion":
        """Straight motion from a start [nm], course [deg from north] and speed [kn]."""
        course = math.radians(course_deg)
        return cls((float(start_nm[0]), float(start_nm[1])),
                   (speed_kn * math.cos(course), speed_kn * math.sin(course)))

    @property
    def speed_kn(self) -> float:
        return math.hypot(*self.velocity_kn)

    @property
    def course_deg(self) -> float:
        return math.degrees(math.atan2(self.velocity_kn[1], self.velocity_kn[0])) % 360.0


def cpa_tcpa(own: ShipMotion, target: ShipMotion) -> tuple[float, float]:
    """Closest point of approach of two straight motions.

    Returns
    -------
    cpa_nm : float
        Distance at the closest approach [nm].
    tcpa_min : float
        Time of the closest approach after the start [min]; negative when the ships are
        already opening, ``inf`` when their relative velocity is zero.
    """
    r0 = np.subtract(target.start_nm, own.start_nm)
    w = np.subtract(target.velocity_kn, own.velocity_kn)
    w2 = float(w @ w)
    if w2 == 0.0:
        return float(np.hypot(*r0)), math.inf
    tcpa_h = -float(r0 @ w) / w2
    return float(np.hypot(*(r0 + w * tcpa_h))), tcpa_h * 60.0


def place_target(own: ShipMotion, encounter: str, cpa_nm: float, tcpa_min: float, speed_kn: float,
                 course_offset_deg: float = 0.0, passing_side: str = "port") -> ShipMotion:
    """The target's straight motion meeting ``own`` at the requested CPA and TCPA.

    Parameters
    ----------
    own : ShipMotion
        The own ship's initial position [nm] and velocity [kn].
    encounter : str
        One of :data:`ENCOUNTER_TYPES`.
    cpa_nm : float
        Distance at the closest approach [nm], >= 0.
    tcpa_min : float
        Time to the closest approach [min], > 0.
    speed_kn : float
        The target's speed [kn], > 0 (below the own ship's speed for ``overtaking``).
    course_offset_deg : float
        Deviation from the type's nominal relative course [deg].
    passing_side : {"port", "starboard"}
        Side of the own ship's heading the target is on at the CPA (``"port"`` for the
        COLREG port-to-port head-on passing).

    Raises
    ------
    ValueError
        For an unknown type, a non-positive TCPA or speed, or a zero relative velocity.
    """
    if encounter not in RELATIVE_COURSE_DEG:
        raise ValueError(f"unknown encounter type {encounter!r} (valid: {', '.join(ENCOUNTER_TYPES)})")
    if passing_side not in PASSING_SIDES:
        raise ValueError(f"passing_side must be one of {', '.join(PASSING_SIDES)}, got {passing_side!r}")
    if not tcpa_min > 0 or not cpa_nm >= 0 or not speed_kn > 0:
        raise ValueError(f"need tcpa_min > 0, cpa_nm >= 0 and speed_kn > 0, got {tcpa_min}, {cpa_nm}, {speed_kn}")
    course = own.course_deg + RELATIVE_COURSE_DEG[encounter] + course_offset_deg
    velocity = ShipMotion.from_course((0.0, 0.0), course, speed_kn).velocity_kn
    w = np.subtract(velocity, own.velocity_kn)
    relative_speed = float(np.hypot(*w))
    if relative_speed < 1e-9:
        raise ValueError(f"{encounter}: the target at {speed_kn} kn keeps station with the own ship; no CPA")
    normal = np.array([-w[1], w[0]]) / relative_speed
    heading = np.asarray(own.velocity_kn) / max(own.speed_kn, 1e-12)
    to_starboard = heading[0] * normal[1] - heading[1] * normal[0] > 0  # heading x normal, x north, y east
    if to_starboard != (passing_side == "starboard"):
        normal = -normal
    r0 = cpa_nm * normal - w * (tcpa_min / 60.0)
    start = np.add(own.start_nm, r0)
    return ShipMotion((float(start[0]), float(start[1])), (float(velocity[0]), float(velocity[1])))
