"""Which participant is the ship and what steers it, read from a scenario's connections.

The plant is the participant whose outputs include the ship state (x, y, psi); analyses
and figures of :mod:`rhnc.cosim` find it, its steering and its demanded forces here.
"""

from __future__ import annotations

from orchestrator.analyses import driver_column
from orchestrator.errors import ToolchainError


def find_plant(cosim) -> str | None:
    """The participant whose outputs include the ship state (x, y, psi), or None."""
    for participant in cosim.participants:
        if {"x", "y", "psi"} <= set(participant.output_names):
            return participant.name
    return None


def plant_name(cosim) -> str:
    """As :func:`find_plant`, for analyses that need a ship: raises without one."""
    plant = find_plant(cosim)
    if plant is None:
        raise ToolchainError("no participant outputs the ship state x, y, psi")
    return plant


def tau_column(scenario, port: str) -> str | None:
    """Column of the output feeding a ``tau_u``/``tau_r`` input anywhere (the plant's, or an
    allocation's in front of an actuator-level plant), or None when nothing demands tau."""
    for connection in scenario.connections:
        if connection.target_port == port:
            return f"{connection.source}.{connection.source_port}"
    return None


def steering_column(frame, scenario, plant) -> tuple[str, str]:
    """What steers the plant: (column, kind) with kind ``"rudder"`` (radians) or ``"yaw moment"``.

    An actuator-level plant is steered by what drives its ``rudder_angle_cmd`` input (else
    its reported ``rudder_angle``); a plant that takes tau by what drives ``tau_r``.
    """
    try:
        return driver_column(scenario, plant, "rudder_angle_cmd"), "rudder"
    except ToolchainError:
        pass
    if f"{plant}.rudder_angle" in frame.columns:
        return f"{plant}.rudder_angle", "rudder"
    return driver_column(scenario, plant, "tau_r"), "yaw moment"


def own_radius_m(cosim) -> float:
    """The own hazard radius R [m]: the controller's setting, 0 without a controller."""
    for participant in cosim.participants:
        settings = getattr(getattr(participant, "controller", None), "settings", None)
        if settings is not None and hasattr(settings, "own_radius_m"):
            return float(settings.own_radius_m)
    return 0.0
