"""The ship's canonical plant ports: the port table the co-simulation master maps FMUs onto.

Registered in the entry-point group ``rhnc_cosim.port_tables``
(:mod:`orchestrator.plant_ports`): the 3-DOF state and its over-ground motion as outputs,
surge force, yaw moment and the weather as inputs, and the initial-condition keys of
``[participants.<plant>.initial]`` in metres or nautical miles, radians or degrees,
m/s or knots.
"""

from __future__ import annotations

from orchestrator.geometry import DEG, KNOT, NM
from orchestrator.plant_ports import (ANGLE, ANGULAR_RATE, FORCE, FREQUENCY, LENGTH, MOMENT, POWER, SPEED, PlantPort,
                                      PortTable)
from rhnc.chart.positions import initial_in_plane

PORTS: dict[str, PlantPort] = {
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


#: ``[initial]`` may give the start in latitude and longitude (``start_deg``) with a chart
SHIP_PORTS = PortTable(PORTS, WRAPPED_OUTPUTS, VECTOR_PORTS, INITIAL_KEYS, geographic_initial=initial_in_plane)
