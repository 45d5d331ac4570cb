"""The canonical plant ports: causality, SI unit and the initial-condition keys.

This small table is the only ship knowledge the FMU mapping needs.  Every canonical port
carries SI values on the co-simulation bus; a mapped FMU variable is converted to (and from)
the port's unit by :mod:`orchestrator.port_mapping`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

#: Order of the exponents of a dimension: the seven SI base units and the radian, as in the
#: ``BaseUnit`` element of an FMI 2.0 modelDescription.
BASE_UNITS = ("kg", "m", "s", "A", "K", "mol", "cd", "rad")


def dimension(**exponents: int) -> tuple[int, ...]:
    """Exponent vector over :data:`BASE_UNITS`, e.g. ``dimension(m=1, s=-1)`` for a speed."""
    return tuple(int(exponents.get(unit, 0)) for unit in BASE_UNITS)


LENGTH = dimension(m=1)
SPEED = dimension(m=1, s=-1)
ANGLE = dimension(rad=1)
ANGULAR_RATE = dimension(rad=1, s=-1)
FORCE = dimension(kg=1, m=1, s=-2)
MOMENT = dimension(kg=1, m=2, s=-2)
POWER = dimension(kg=1, m=2, s=-3)
#: revolutions per second: a frequency; a unit of angle per time (pint's ``rpm``, ``rad/s``)
#: is accepted for it and divided by 2 pi rad per revolution
FREQUENCY = dimension(s=-1)


@dataclass(frozen=True)
class PlantPort:
    """One canonical port of a ship plant.

    Attributes
    ----------
    causality : str
        ``output`` (the plant reports it) or ``input`` (the plant takes it).
    dimension : tuple of int
        Exponents over :data:`BASE_UNITS`; the port's value is in the SI unit of it.
    si_unit : str
        That unit's name, for messages.
    revolutions : bool
        A rate of revolutions (1/s): a unit of angle per time (``rpm``, ``rad/s``) is
        converted at 2 pi rad per revolution.
    """

    causality: str
    dimension: tuple[int, ...]
    si_unit: str
    revolutions: bool = False

    @property
    def is_angle(self) -> bool:
        """Angles and angular rates: a mapping must say their unit (degrees are common)."""
        return self.dimension[BASE_UNITS.index("rad")] != 0


PLANT_PORTS: dict[str, PlantPort] = {
    "x": PlantPort("output", LENGTH, "m"),
    "y": PlantPort("output", LENGTH, "m"),
    "psi": PlantPort("output", ANGLE, "rad"),
    "u": PlantPort("output", SPEED, "m/s"),
    "v": PlantPort("output", SPEED, "m/s"),
    "r": PlantPort("output", ANGULAR_RATE, "rad/s"),
    "sog": PlantPort("output", SPEED, "m/s"),
    "cog": PlantPort("output", ANGLE, "rad"),
    "tau_u": PlantPort("input", FORCE, "N"),
    "tau_r": PlantPort("input", MOMENT, "N.m"),
    "current_north": PlantPort("input", SPEED, "m/s"),
    "current_east": PlantPort("input", SPEED, "m/s"),
    "wind_speed": PlantPort("input", SPEED, "m/s"),
    "wind_direction": PlantPort("input", ANGLE, "rad"),
    "hs": PlantPort("input", LENGTH, "m"),
    # actuator level (a plant steered by rudder and propeller, e.g. KCSMMG behind an allocation)
    "rudder_angle_cmd": PlantPort("input", ANGLE, "rad"),
    "propeller_rps_cmd": PlantPort("input", FREQUENCY, "1/s", revolutions=True),
    "rudder_angle": PlantPort("output", ANGLE, "rad"),
    "propeller_rps": PlantPort("output", FREQUENCY, "1/s", revolutions=True),
    "thrust": PlantPort("output", FORCE, "N"),
    "delivered_power": PlantPort("output", POWER, "W"),
}

#: The ports of an actuator-level plant that an allocation participant drives and reads.
ACTUATOR_INPUTS = ("rudder_angle_cmd", "propeller_rps_cmd")
ACTUATOR_OUTPUTS = ("rudder_angle", "propeller_rps")

#: Output angles reported in (-pi, pi] whatever range the FMU uses (compass 0-360 deg).
WRAPPED_OUTPUTS = ("psi", "cog")

#: Vector inputs an FMU may take in another form than the canonical ports give them:
#: name -> (form of the canonical ports, first port, second port).  ``cartesian``: north and
#: east components of a velocity; ``polar_from``: a speed and the direction it comes from
#: (meteorological wind), clockwise from north.
VECTOR_PORTS = {
    "current": ("cartesian", "current_north", "current_east"),
    "wind": ("polar_from", "wind_speed", "wind_direction"),
}

KNOT = 1852.0 / 3600.0
NM = 1852.0
DEG = math.pi / 180.0

#: ``[participants.<plant>.initial]`` keys: the canonical port they set and the factor
#: to the port's SI unit.
INITIAL_KEYS = {
    "x_m": ("x", 1.0), "x_nm": ("x", NM),
    "y_m": ("y", 1.0), "y_nm": ("y", NM),
    "psi_rad": ("psi", 1.0), "psi_deg": ("psi", DEG),
    "u_mps": ("u", 1.0), "u_kn": ("u", KNOT),
    "v_mps": ("v", 1.0), "v_kn": ("v", KNOT),
    "r_rad_s": ("r", 1.0), "r_deg_s": ("r", DEG), "r_deg_min": ("r", DEG / 60.0),
    "rudder_angle_rad": ("rudder_angle", 1.0), "rudder_angle_deg": ("rudder_angle", DEG),
    "propeller_rps": ("propeller_rps", 1.0), "propeller_rpm": ("propeller_rps", 1.0 / 60.0),
}
