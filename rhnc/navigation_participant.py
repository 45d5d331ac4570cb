"""The navigation module as a co-simulation participant: fields, trigger, local path, reference.

At every navigation instant t (every ``delta`` = the participant's step size) it

1. takes the planning start: the controller's predicted state at t, interpolated in time
   from its ``prediction`` input (Interface I, Eq. 24), or the measured state
   (``start_from = "measured"``, or when no usable prediction covers t);
2. updates the event trigger (Eq. 7) from the measured position and the ``obstacles``;
3. rebuilds the guidance field for that start (EC and EM are kept while the planning
   speed is unchanged; see :mod:`rhnc.fields`) and plans N_L steps of
   ``alpha = v_s delta`` (Algorithm 1), descending G alone while ET = 1;
4. turns the path into reference states (Eq. 19) timed t + k delta.

When the met-ocean field varies in time, the planning weather is resampled at each
navigation instant t (the fields then see the weather of that instant, held over the
horizon).

Planning speed v_s is the option ``speed_kn`` (over ground), used both for the step
length and for the fields, so the reference asks for a constant service speed.

Options (``[participants.<name>.options]``)
-------------------------------------------
goal_nm : [x, y]            goal, north and east [nm] (required)
speed_kn : float            planning speed v_s [kn] (18)
horizon_steps : int         N_L (16)
k1, k2, k3 : float          weights of Eq. 6 (1, 1, 16)
guidance_eps, guidance_c_rad : float   constants of Eq. 4 (1, 1 rad)
resolution_nm : float       planning grid spacing [nm] (1)
energy : table              overrides of :class:`rhnc.energy.EnergyParameters`
eps_ship_nm, eps_static_nm : float     warning ranges [nm] (4.5, 6)
start_from : str            "prediction" (default) or "measured"
start_nm : [x, y]           start used at set-up when the ship's position is not yet
                            known there (the ship is declared after the navigation)
"""

from __future__ import annotations

import logging
from collections.abc import Mapping
from typing import Any

import numpy as np

from orchestrator.errors import ModelError, ScenarioError
from orchestrator.participant import BuildContext, Participant, Value, is_finite_number, reject_unknown_options
from rhnc.energy import EnergyParameters, brake_power, cost_rate, emission_rate
from rhnc.fields import FieldWeights, GuidanceParameters, SuperpositionField, bearing, resample_weather
from rhnc.metocean import KNOT, NM
from rhnc.planner import plan_local_path
from rhnc.reference import reference_states
from rhnc.trigger import TRIGGERED, EventTrigger

log = logging.getLogger(__name__)

OPTIONS = ("goal_nm", "speed_kn", "horizon_steps", "k1", "k2", "k3", "guidance_eps", "guidance_c_rad",
           "resolution_nm", "energy", "eps_ship_nm", "eps_static_nm", "start_from", "start_nm")


def _number(options: Mapping[str, Any], key: str, default: float, where: str, positive: bool = False) -> float:
    value = options.get(key, default)
    if not is_finite_number(value):
        raise ScenarioError(f"{where}.{key}: expected a number, got {value!r}")
    if positive and not value > 0:
        raise ScenarioError(f"{where}.{key}: must be positive, got {value!r}")
    if not positive and value < 0:
        raise ScenarioError(f"{where}.{key}: must not be negative, got {value!r}")
    return float(value)


def _point_nm(options: Mapping[str, Any], key: str, where: str) -> tuple[float, float]:
    value = options[key]
    if (not isinstance(value, (list, tuple)) or len(value) != 2
            or not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value)):
        raise ScenarioError(f"{where}.{key}: expected [north, east] in nm, got {value!r}")
    return float(value[0]) * NM, float(value[1]) * NM


class NavigationParticipant(Participant):
    """RHNC navigation module (paper Section 3 and Interface I of Section 5).

    Inputs: ``x``, ``y`` [m], ``psi`` [rad], ``u`` [m/s] (measured), ``prediction``
    ((M, 7), optional), ``obstacles`` ((n, 5), optional).
    Outputs: ``reference`` ((N_L+1, 7)), ``et``, ``ec_rate`` [USD/h], ``em_rate``
    [kg CO2/h] at the ship's position and heading in the local weather, and
    ``goal_distance_m``.
    """

    def __init__(self, name: str, metocean, delta: float, goal: tuple[float, float], speed: float,
                 horizon_steps: int, weights: FieldWeights, guidance: GuidanceParameters,
                 resolution_nm: float, energy: EnergyParameters, ship_range_m: float,
                 static_range_m: float, start_from: str = "prediction",
                 start: tuple[float, float] | None = None) -> None:
        super().__init__(name)
        self.metocean = metocean
        self.delta = float(delta)
        self.goal = goal
        self.speed = float(speed)
        self.horizon_steps = int(horizon_steps)
        self.energy = energy
        self.start_from = start_from
        self.start = start
        self.resolution_nm = float(resolution_nm)
        self.weather = resample_weather(metocean, resolution_nm, t_s=0.0)
        self.field = SuperpositionField(self.weather, goal, energy, guidance, weights)
        self.trigger = EventTrigger(ship_range_m, static_range_m)
        self.counts = {"plans": 0, "avoidance_plans": 0, "prediction_starts": 0, "measured_starts": 0,
                       "flat_steps": 0, "border_steps": 0}
        self._reached_goal = False

    # -- construction from a scenario ---------------------------------------------------
    @classmethod
    def from_options(cls, name: str, options: Mapping[str, Any], context: BuildContext) -> "NavigationParticipant":
        """Build from ``[participants.<name>.options]``; errors name the key."""
        where = f"{context.where}.options"
        reject_unknown_options(options, OPTIONS, where)
        if context.metocean is None:
            raise ScenarioError(f"{context.where}: the navigation needs the scenario's [metocean] table")
        if "goal_nm" not in options:
            raise ScenarioError(f"{where}: missing option 'goal_nm' ([north, east] in nm)")
        goal = _point_nm(options, "goal_nm", where)
        if not bool(context.metocean.contains(goal[0], goal[1])):
            raise ScenarioError(f"{where}.goal_nm: the goal lies outside the met-ocean map")
        start = _point_nm(options, "start_nm", where) if "start_nm" in options else None
        horizon = options.get("horizon_steps", 16)
        if isinstance(horizon, bool) or not isinstance(horizon, int) or horizon < 1:
            raise ScenarioError(f"{where}.horizon_steps: expected a positive integer, got {horizon!r}")
        start_from = options.get("start_from", "prediction")
        if start_from not in ("prediction", "measured"):
            raise ScenarioError(f"{where}.start_from: '{start_from}' is not valid (valid: measured, prediction)")
        energy_table = options.get("energy", {})
        if not isinstance(energy_table, Mapping):
            raise ScenarioError(f"{where}.energy: expected a table of energy parameters")
        energy = EnergyParameters().with_overrides(energy_table, f"{where}.energy")
        weights = FieldWeights(k1=_number(options, "k1", 1.0, where), k2=_number(options, "k2", 1.0, where),
                               k3=_number(options, "k3", 16.0, where))
        guidance = GuidanceParameters(eps=_number(options, "guidance_eps", 1.0, where, positive=True),
                                      c_rad=_number(options, "guidance_c_rad", 1.0, where, positive=True))
        try:
            return cls(name, context.metocean, context.step_size, goal,
                       _number(options, "speed_kn", 18.0, where, positive=True) * KNOT,
                       horizon, weights, guidance,
                       _number(options, "resolution_nm", 1.0, where, positive=True), energy,
                       _number(options, "eps_ship_nm", 4.5, where, positive=True) * NM,
                       _number(options, "eps_static_nm", 6.0, where, positive=True) * NM,
                       start_from, start)
        except ValueError as exc:
            raise ScenarioError(f"{where}: {exc}") from exc

    # -- ports ----------------------------------------------------------------------------
    @property
    def input_names(self):
        return ("x", "y", "psi", "u", "prediction", "obstacles")

    @property
    def output_names(self):
        return ("reference", "et", "ec_rate", "em_rate", "goal_distance_m")

    # -- lifecycle ------------------------------------------------------------------------
    def setup(self, start_time: float, inputs: Mapping[str, Value]) -> dict[str, Value]:
        if "x" in inputs and "y" in inputs:
            measured = inputs
        elif self.start is not None:
            heading = float(bearing(self.start[0], self.start[1], *self.goal))
            measured = {"x": self.start[0], "y": self.start[1], "psi": heading, "u": self.speed}
        else:
            raise ScenarioError(
                f"participant '{self.name}': the ship's position is unknown at set-up; declare the ship "
                "before the navigation or give the option start_nm")
        return self._plan(start_time, measured, inputs)

    def step(self, time: float, step_size: float, inputs: Mapping[str, Value]) -> dict[str, Value]:
        for port in ("x", "y"):
            if port not in inputs:
                raise ModelError(f"participant '{self.name}': input '{port}' is not connected")
        return self._plan(time, inputs, inputs)

    def summary(self) -> dict[str, Any]:
        transitions = [t.as_dict() for t in self.trigger.transitions]
        return {
            **self.counts,
            "goal_reached_in_plan": self._reached_goal,
            "et_transitions": transitions,
            "et_activations": sum(1 for t in transitions if t["state"] == TRIGGERED),
        }

    def tables(self) -> dict[str, list[dict]]:
        """The event trigger's transitions (time, obstacle, kind, range, cause, state, ET)."""
        return {"et_transitions": [t.as_dict() for t in self.trigger.transitions]}

    # -- one planning instant -------------------------------------------------------------
    def _planning_start(self, time: float, measured: Mapping[str, Value],
                        inputs: Mapping[str, Value]) -> tuple[float, float, float]:
        """(x, y, psi) at ``time``: Interface I from the prediction, or the measurement."""
        prediction = inputs.get("prediction")
        if self.start_from == "prediction" and prediction is not None:
            table = np.asarray(prediction, dtype=float)
            if (table.ndim == 2 and table.shape[1] == 7 and table.shape[0] >= 1
                    and np.all(np.isfinite(table[:, :4]))
                    and table[0, 0] - 1e-6 <= time <= table[-1, 0] + 1e-6):
                self.counts["prediction_starts"] += 1
                if table.shape[0] == 1:
                    return float(table[0, 1]), float(table[0, 2]), float(table[0, 3])
                psi = np.unwrap(table[:, 3])
                return (float(np.interp(time, table[:, 0], table[:, 1])),
                        float(np.interp(time, table[:, 0], table[:, 2])),
                        float(np.interp(time, table[:, 0], psi)))
        self.counts["measured_starts"] += 1
        psi = measured.get("psi")
        if psi is None:
            psi = bearing(float(measured["x"]), float(measured["y"]), *self.goal)
        return float(measured["x"]), float(measured["y"]), float(psi)

    def _local_rates(self, x: float, y: float, psi: float, u: float, time: float) -> tuple[float, float]:
        """EC [USD/h] and EM [kg/h] at the ship, speed through water u, in the weather at ``time``."""
        x_min, x_max, y_min, y_max = self.metocean.extent
        local = self.metocean.sample(min(max(x, x_min), x_max), min(max(y, y_min), y_max), t_s=time)
        power = brake_power(max(u, 0.0), psi, local["wind_north"], local["wind_east"], local["hs"], self.energy)
        return float(cost_rate(power, self.energy)), float(emission_rate(power, self.energy))

    def _plan(self, time: float, measured: Mapping[str, Value], inputs: Mapping[str, Value]) -> dict[str, Value]:
        x, y = float(measured["x"]), float(measured["y"])
        psi = float(measured.get("psi", bearing(x, y, *self.goal)))
        u = float(measured.get("u", self.speed))
        velocity = (u * np.cos(psi), u * np.sin(psi))
        et = self.trigger.update(time, (x, y), velocity, self.goal, inputs.get("obstacles"))
        start_x, start_y, start_psi = self._planning_start(time, measured, inputs)
        if self.metocean.is_time_varying:  # plan in the weather of this instant
            self.weather = resample_weather(self.metocean, self.resolution_nm, t_s=time)
            self.field.set_weather(self.weather)
        self.field.update((start_x, start_y), self.speed)
        path = plan_local_path(self.field, (start_x, start_y), self.speed * self.delta,
                               self.horizon_steps, avoidance=et > 0.5)
        self.counts["plans"] += 1
        self.counts["avoidance_plans"] += int(et > 0.5)
        self.counts["flat_steps"] += path.flat_steps
        self.counts["border_steps"] += path.border_steps
        self._reached_goal = path.reached_goal
        reference = reference_states(path.points, self.delta, start_time=time, initial_heading=start_psi)
        ec, em = self._local_rates(x, y, psi, u, time)
        outputs = {
            "reference": reference,
            "et": et,
            "ec_rate": ec,
            "em_rate": em,
            "goal_distance_m": float(np.hypot(self.goal[0] - x, self.goal[1] - y)),
        }
        if not np.all(np.isfinite(reference)) or not np.isfinite(ec) or not np.isfinite(em):
            raise ModelError(f"participant '{self.name}': non-finite reference or energy rate at t={time:.0f} s")
        return outputs
