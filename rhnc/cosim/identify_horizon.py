"""The prediction horizon ``identify`` chooses the model for: the scenario's NMPC's.

The identification keeps the model class that predicts the held-out manoeuvre best over the
time the NMPC predicts with it (:class:`rhnc.ship.identification.Horizon`); that time is the
``horizon_steps`` times the control interval of the scenario's ``control`` participant that
steers the plant (directly or through its allocation).
"""

from __future__ import annotations

from orchestrator.errors import ScenarioError
from orchestrator.participant import BuildContext
from orchestrator.scenario import load_scenario
from rhnc.control.control_options import prediction_horizon
from rhnc.ship.identification import Horizon
from rhnc.ship.identify_run import allocation_between, find_plant_spec


def nmpc_horizon(scenario_path, plant: str | None = None) -> Horizon:
    """The horizon and interval of the control participant steering the scenario's plant.

    Raises
    ------
    ScenarioError
        No control participant steers the plant, or several with different horizons.
    """
    scenario = load_scenario(scenario_path)
    spec = find_plant_spec(scenario, plant)
    allocation = allocation_between(scenario, spec)
    steered = {spec.name} | ({allocation[0].name} if allocation is not None else set())
    controllers = [p for p in scenario.participants if p.type == "control"
                   and any(c.source == p.name and c.target in steered for c in scenario.connections)]
    if not controllers:
        raise ScenarioError(f"{scenario.path}: identify fits the model for the NMPC's horizon, and no "
                            f"participant of type 'control' steers the plant '{spec.name}' (connect its tau_u, "
                            "tau_r to the plant or its allocation)")
    horizons = {}
    for controller in controllers:
        context = BuildContext(where=f"{scenario.path}: participants.{controller.name}",
                               scenario_dir=scenario.directory,
                               step_size=controller.every * scenario.simulation.dt_s,
                               start_time=scenario.simulation.start_s, stop_time=scenario.simulation.stop_s)
        steps, interval = prediction_horizon(controller.options, context)
        horizons[controller.name] = Horizon(steps * interval, interval)
    if len(set(horizons.values())) > 1:
        raise ScenarioError(f"{scenario.path}: the controllers {', '.join(horizons)} steering '{spec.name}' "
                            "predict over different horizons; identify the model for one scenario per NMPC")
    return next(iter(horizons.values()))
