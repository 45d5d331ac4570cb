"""The navigation module as a co-simulation participant: fields, trigger, local path, reference.

Two methods, selected per scenario by the option ``method``:

* ``"routing"`` (the default): a receding-horizon route search with the energy cost of
  each step on the course it is sailed, weights in US dollars (fuel and hours), and a
  speed plan for a requested arrival time (:mod:`rhnc.navigation.navigation_routing`,
  :mod:`rhnc.navigation.route_navigation`, docs/navigation.md);
* ``"paper"``: the paper's potential fields and gradient descent (Algorithm 1), below.

Both take the planning start from Interface I and update the event trigger in the same
way.  With ``method = "paper"``, at every navigation instant t (every ``delta`` = the
participant's step size) it

1. takes the planning start: the controller's predicted state at t, interpolated in time
   from its ``prediction`` input (Interface I, Eq. 24), or the measured state
   (``start_from = "measured"``, or when no usable prediction covers t);
2. updates the event trigger (Eq. 7) from the measured position and the ``obstacles``;
3. rebuilds the guidance field for that start (EC and EM are kept while the planning
   speed is unchanged; see :mod:`rhnc.navigation.fields`) and plans N_L steps of
   ``alpha = v_s delta`` (Algorithm 1), descending G alone while ET = 1;
4. turns the path into reference states (Eq. 19) timed t + k delta.

Goal: once the goal lies within the horizon (N_L alpha) of the planning start, the path
runs straight to it and stops there (both methods): near the goal the bearing the energy
fields assume swings round, and the paper's descent would run along the map edge.

Delay of the reference: in a master that steps every participant at once (Jacobi: OSP's
libcosim and most FMI masters) the reference planned at t reaches the controller one
navigation step later, at ``t + d``; a reference timed from t would then be used only
from ``t + d`` on, and the ship would always follow a plan one step older than in our
master's Gauss-Seidel order (Experiment 2 made good 1.4 % less).  With ``output_delay_s
= d`` the navigation plans for the instant its reference arrives: the planning start is
the controller's predicted state at ``t + d`` (or the measured state carried over ``d`` at
its course and speed) and the reference is timed from ``t + d``.  The delay is the
master's (0 in Gauss-Seidel order, one navigation step in Jacobi order) and a parameter of
an exported navigation FMU.  The set-up's reference reaches the controller at once and is
timed from the start.

When the met-ocean field varies in time, the planning weather is resampled at each
navigation instant t (the fields then see the weather of that instant, held over the
horizon).

Planning speed v_s is the option ``speed_kn`` (over ground), used both for the step
length and for the fields, so the reference asks for a constant service speed.

With ``method = "routing"`` the route from the planning start follows the cheapest route
to the goal over the map; the reference points are placed along it at the planned speed
through water: ``speed_kn``, or, with ``arrival_time_min``, the remaining route length
over the remaining time (less the current along the route), bounded by ``max_speed_kn``.
In the collision-avoidance state (ET = 1) the route is kept (the NMPC's constraints do
the avoiding).

Interface I: a prediction whose states are all zero is the control participant's
placeholder published at set-up, not a prediction, and is not taken as the start.

Options (``[participants.<name>.options]``)
-------------------------------------------
goal_nm : [x, y]            goal, north and east [nm] (required; or goal_deg)
goal_deg, start_deg : [lat, lon]   instead of goal_nm, start_nm: latitude and longitude
                            [deg], projected by the chart (option ``chart``)
speed_kn : float            planning speed v_s [kn] (18)
horizon_steps : int         N_L (16)
k1, k2, k3 : float          weights of Eq. 6 (1, 1, 16)
guidance_eps, guidance_c_rad : float   constants of Eq. 4 (1, 1 rad)
resolution_nm : float       planning grid spacing [nm] (1)
energy : table              overrides of :class:`rhnc.ship.energy.EnergyParameters`
eps_ship_nm, eps_static_nm : float     warning ranges [nm] (4.5, 6)
start_from : str            "prediction" (default) or "measured"
start_nm : [x, y]           start used at set-up when the ship's position is not yet
                            known there (the ship is declared after the navigation)
method : str                "routing" (default) or "paper"
arrival_time_min : float    routing: requested arrival time after t = 0 [min] (none:
                            constant speed_kn through water)
max_speed_kn : float        routing: upper bound of the planned speed [kn] (24)
route_switch_margin_pct : float   routing: least saving, in percent of the remaining
                            passage's objective, for which the route followed is left for
                            a new one (0.1; 0 takes every cheaper route found)
output_delay_s : float      time from a step at t to its reference reaching the controller
                            [s] (the master's: 0 in Gauss-Seidel order, one step in Jacobi)
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from orchestrator.errors import ModelError, ScenarioError
from orchestrator.participant import BuildContext, Participant, Value, is_finite_number, reject_unknown_options
from rhnc.chart.positions import projected_options
from rhnc.ship.energy import EnergyParameters, brake_power, cost_rate, emission_rate
from rhnc.navigation.fields import FieldWeights, GuidanceParameters, SuperpositionField, bearing, resample_weather
from orchestrator.geometry import KNOT, NM
from rhnc.navigation.planner import plan_local_path
from rhnc.navigation.reference import reference_states
from rhnc.navigation.navigation_routing import RoutingMethod
from rhnc.navigation.route_navigation import DEFAULT_SWITCH_MARGIN
from rhnc.navigation.trigger import TRIGGERED, EventTrigger

OPTIONS = ("goal_nm", "speed_kn", "horizon_steps", "k1", "k2", "k3", "guidance_eps", "guidance_c_rad",
           "resolution_nm", "energy", "eps_ship_nm", "eps_static_nm", "start_from", "start_nm", "method",
           "arrival_time_min", "max_speed_kn", "route_switch_margin_pct", "output_delay_s", "chart")
METHODS = ("paper", "routing")
ROUTING_ONLY = ("arrival_time_min", "max_speed_kn", "route_switch_margin_pct", "chart")
PAPER_ONLY = ("k1", "k2", "k3", "guidance_eps", "guidance_c_rad")
#: Most planning steps of one horizon (the paper's N_L is 16; Experiment 1 plans 110).
MAX_HORIZON_STEPS = 1000


def _number(options: Mapping[str, Any], key: str, default: float, where: str, positive: bool = False) -> float:
    value = options.get(key, default)
    if not is_finite_number(value):
        raise ScenarioError(f"{where}.{key}: expected a number, got {value!r}")
    if positive and not value > 0:
        raise ScenarioError(f"{where}.{key}: must be positive, got {value!r}")
    if not positive and value < 0:
        raise ScenarioError(f"{where}.{key}: must not be negative, got {value!r}")
    return float(value)


def _chart(options: Mapping[str, Any], context: BuildContext, where: str, goal, start,
           written: Mapping[str, str] | None = None):
    """The option ``chart``: land and no-go areas the route keeps its clearance from (None
    without it); the goal and the start must lie in navigable water (a message names the key
    as ``written``: ``start_deg`` for a start given in latitude and longitude)."""
    if "chart" not in options:
        return None
    from rhnc.chart.chart import load_chart
    from rhnc.routing.routing_problem import check_navigable

    if not isinstance(options["chart"], str) or not options["chart"]:
        raise ScenarioError(f"{where}.chart: expected the path of a chart file, got {options['chart']!r}")
    chart = load_chart(context.scenario_dir / options["chart"])
    for label, point in (("goal_nm", goal), ("start_nm", start)):
        try:
            check_navigable(chart, point, "point") if point is not None else None
        except ValueError as exc:
            raise ScenarioError(f"{where}.{(written or {}).get(label, label)}: "
                                f"{str(exc).replace('the point ', '', 1)}") from None
    return chart


def _switch_margin(options: Mapping[str, Any], where: str) -> float:
    """``route_switch_margin_pct`` as a fraction (below 100 %)."""
    margin = _number(options, "route_switch_margin_pct", 100.0 * DEFAULT_SWITCH_MARGIN, where)
    if margin >= 100.0:
        raise ScenarioError(f"{where}.route_switch_margin_pct: must be below 100, got {margin!r}")
    return margin / 100.0


def _point_nm(options: Mapping[str, Any], key: str, where: str) -> tuple[float, float]:
    value = options[key]
    if not isinstance(value, (list, tuple)) or len(value) != 2 or not all(is_finite_number(v) for v in value):
        raise ScenarioError(f"{where}.{key}: expected [north, east] in nm (finite numbers), got {value!r}"[:300])
    return float(value[0]) * NM, float(value[1]) * NM


class NavigationParticipant(Participant):
    """RHNC navigation module (paper Section 3 and Interface I of Section 5).

    Inputs: ``x``, ``y`` [m], ``psi`` [rad], ``u`` [m/s] (measured), ``prediction``
    ((M, 7), optional), ``obstacles`` ((n, 5), optional).
    Outputs: ``reference`` ((N_L+1, 7)), ``et``, ``ec_rate`` [USD/h], ``em_rate``
    [kg CO2/h] at the ship's position and heading in the local weather, and
    ``goal_distance_m``.
    """

    OPTIONS = OPTIONS

    def __init__(self, name: str, metocean, delta: float, goal: tuple[float, float], speed: float,
                 horizon_steps: int, weights: FieldWeights, guidance: GuidanceParameters,
                 resolution_nm: float, energy: EnergyParameters, ship_range_m: float,
                 static_range_m: float, start_from: str = "prediction",
                 start: tuple[float, float] | None = None, method: str = "paper",
                 arrival_s: float | None = None, max_speed: float = 24.0 * KNOT,
                 switch_margin: float = DEFAULT_SWITCH_MARGIN, output_delay_s: float = 0.0, chart=None) -> None:
        super().__init__(name)
        if not (np.isfinite(output_delay_s) and output_delay_s >= 0.0):
            raise ValueError(f"output_delay_s must be a finite number of seconds >= 0, got {output_delay_s!r}")
        self.output_delay_s = float(output_delay_s)
        self.chart = chart
        self.metocean = metocean
        self.delta = float(delta)
        self.goal = goal
        self.speed = float(speed)
        self.horizon_steps = int(horizon_steps)
        self.energy = energy
        self.start_from = start_from
        self.start = start
        self.resolution_nm = float(resolution_nm)
        self.method = method
        self.arrival_s = arrival_s
        self.max_speed = float(max_speed)
        self.trigger = EventTrigger(ship_range_m, static_range_m)
        self.counts = {"plans": 0, "avoidance_plans": 0, "prediction_starts": 0, "measured_starts": 0,
                       "flat_steps": 0, "border_steps": 0}
        if method == "paper":
            self.weather = resample_weather(metocean, resolution_nm, t_s=0.0)
            self.field = SuperpositionField(self.weather, goal, energy, guidance, weights)
        else:
            self.routing = RoutingMethod(name, metocean, goal, energy, resolution_nm, self.delta, self.horizon_steps,
                                         self.speed, arrival_s, self.max_speed, switch_margin, keep_out=chart)
            self.route_planner = self.routing.planner
        self._reached_goal = False

    # -- construction from a scenario ---------------------------------------------------
    @classmethod
    def from_options(cls, name: str, options: Mapping[str, Any], context: BuildContext) -> "NavigationParticipant":
        """Build from ``[participants.<name>.options]``; errors name the key."""
        where = f"{context.where}.options"
        reject_unknown_options(options, (*OPTIONS, "goal_deg", "start_deg"), where)
        # the key a message names: the one the user wrote (start_deg for a start given so)
        written = {f"{n}_nm": f"{n}_deg" if f"{n}_deg" in options else f"{n}_nm" for n in ("start", "goal")}
        options = projected_options(options, where, context.scenario_dir, names=("start", "goal"))
        if context.metocean is None:
            raise ScenarioError(f"{context.where}: the navigation needs the scenario's [metocean] table")
        if "goal_nm" not in options:
            raise ScenarioError(f"{where}: missing option 'goal_nm' ([north, east] in nm)")
        goal = _point_nm(options, "goal_nm", where)
        if not bool(context.metocean.contains(goal[0], goal[1])):
            raise ScenarioError(f"{where}.{written['goal_nm']}: the goal lies outside the met-ocean map")
        start = _point_nm(options, "start_nm", where) if "start_nm" in options else None
        horizon = options.get("horizon_steps", 16)
        if isinstance(horizon, bool) or not isinstance(horizon, int) or not 1 <= horizon <= MAX_HORIZON_STEPS:
            raise ScenarioError(f"{where}.horizon_steps: expected an integer from 1 to {MAX_HORIZON_STEPS}, "
                                f"got {horizon!r}"[:300])
        start_from = options.get("start_from", "prediction")
        if start_from not in ("prediction", "measured"):
            raise ScenarioError(f"{where}.start_from: '{start_from}' is not valid (valid: measured, prediction)")
        energy_table = options.get("energy", {})
        if not isinstance(energy_table, Mapping):
            raise ScenarioError(f"{where}.energy: expected a table of energy parameters")
        energy = EnergyParameters().with_overrides(energy_table, f"{where}.energy")
        method = options.get("method", "routing")
        if method not in METHODS:
            raise ScenarioError(f"{where}.method: '{method}' is not valid (valid: {', '.join(METHODS)})")
        for key in ROUTING_ONLY if method == "paper" else PAPER_ONLY:
            if key in options:
                raise ScenarioError(f"{where}.{key}: applies to method "
                                    f"'{'routing' if method == 'paper' else 'paper'}' only (method is '{method}')")
        arrival_s = (_number(options, "arrival_time_min", 0.0, where, positive=True) * 60.0
                     if "arrival_time_min" in options else None)
        chart = _chart(options, context, where, goal, start, written)
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
                       start_from, start, method, arrival_s,
                       _number(options, "max_speed_kn", 24.0, where, positive=True) * KNOT,
                       _switch_margin(options, where),
                       _number(options, "output_delay_s", float(getattr(context, "output_delay_s", 0.0)), where),
                       chart)
        except ValueError as exc:
            raise ScenarioError(f"{where}: {exc}") from exc

    # -- ports ----------------------------------------------------------------------------
    @property
    def input_names(self):
        return ("x", "y", "psi", "u", "prediction", "obstacles")

    @property
    def output_names(self):
        names = ("reference", "et", "ec_rate", "em_rate", "goal_distance_m")
        return names if self.method == "paper" else names + ("planned_speed_mps",)

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
        return self._plan(start_time, measured, inputs, delay_s=0.0)  # the set-up's reference arrives at once

    def step(self, time: float, step_size: float, inputs: Mapping[str, Value]) -> dict[str, Value]:
        for port in ("x", "y"):
            if port not in inputs:
                raise ModelError(f"participant '{self.name}': input '{port}' is not connected")
        return self._plan(time, inputs, inputs, delay_s=self.output_delay_s)

    def fmu_parameters(self) -> dict[str, dict[str, Any]]:
        """The reference's delay, which depends on the master's exchange order."""
        return {"output_delay_s": {"start": self.output_delay_s, "unit": "s",
                                   "description": "time from a step at t to its reference reaching the controller (one "
                                                  "communication step in a master that steps all FMUs at once, 0 when "
                                                  "this FMU steps before the controller and hands it on at once)"}}

    def summary(self) -> dict[str, Any]:
        transitions = [t.as_dict() for t in self.trigger.transitions]
        extra = {} if self.method == "paper" else {"route_searches": self.route_planner.searches,
                                                   "route_switches": self.route_planner.switches,
                                                   "routes_kept": self.route_planner.kept}
        return {
            **self.counts,
            **extra,
            "method": self.method,
            "goal_reached_in_plan": self._reached_goal,
            "et_transitions": transitions,
            "et_activations": sum(1 for t in transitions if t["state"] == TRIGGERED),
        }

    def tables(self) -> dict[str, list[dict]]:
        """The event trigger's transitions (time, obstacle, kind, range, cause, state, ET)."""
        return {"et_transitions": [t.as_dict() for t in self.trigger.transitions]}

    # -- one planning instant -------------------------------------------------------------
    def _planning_start(self, time: float, measured: Mapping[str, Value],
                        inputs: Mapping[str, Value], measured_at: float | None = None) -> tuple[float, float, float, float]:
        """(x, y, psi, u) at ``time``: Interface I from the prediction, or the measurement.

        A prediction is used when it covers ``time`` and is not the all-zero placeholder
        the control participant publishes at set-up.  The measurement, taken at
        ``measured_at`` (default ``time``), is carried to ``time`` at its course and speed."""
        prediction = inputs.get("prediction")
        if self.start_from == "prediction" and prediction is not None:
            table = np.asarray(prediction, dtype=float)
            if (table.ndim == 2 and table.shape[1] == 7 and table.shape[0] >= 1
                    and np.all(np.isfinite(table[:, :5]))
                    and np.any(table[:, 1:] != 0.0)
                    and table[0, 0] - 1e-6 <= time <= table[-1, 0] + 1e-6):
                self.counts["prediction_starts"] += 1
                if table.shape[0] == 1:
                    return float(table[0, 1]), float(table[0, 2]), float(table[0, 3]), float(table[0, 4])
                unwrapped = np.unwrap(table[:, 3])
                return (float(np.interp(time, table[:, 0], table[:, 1])),
                        float(np.interp(time, table[:, 0], table[:, 2])),
                        float(np.interp(time, table[:, 0], unwrapped)),
                        float(np.interp(time, table[:, 0], table[:, 4])))
        self.counts["measured_starts"] += 1
        psi = measured.get("psi")
        if psi is None:
            psi = bearing(float(measured["x"]), float(measured["y"]), *self.goal)
        heading, u = float(psi), float(measured.get("u", self.speed))
        ahead = u * (time - (time if measured_at is None else measured_at))
        return (float(measured["x"]) + ahead * float(np.cos(heading)), float(measured["y"]) + ahead * float(np.sin(heading)),
                heading, u)

    def _local_rates(self, x: float, y: float, psi: float, u: float, time: float) -> tuple[float, float]:
        """EC [USD/h] and EM [kg/h] at the ship, speed through water u, in the weather at ``time``."""
        x_min, x_max, y_min, y_max = self.metocean.extent
        local = self.metocean.sample(min(max(x, x_min), x_max), min(max(y, y_min), y_max), t_s=time)
        power = brake_power(max(u, 0.0), psi, local["wind_north"], local["wind_east"], local["hs"], self.energy)
        return float(cost_rate(power, self.energy)), float(emission_rate(power, self.energy))

    def _plan(self, time: float, measured: Mapping[str, Value], inputs: Mapping[str, Value],
              delay_s: float) -> dict[str, Value]:
        x, y = float(measured["x"]), float(measured["y"])
        psi = float(measured.get("psi", bearing(x, y, *self.goal)))
        u = float(measured.get("u", self.speed))
        velocity = (u * np.cos(psi), u * np.sin(psi))
        obstacles = inputs.get("obstacles")  # an (n, 5) array, the same object
        et = self.trigger.update(time, (x, y), velocity, self.goal, None if obstacles is None else np.asarray(obstacles))
        # planned for the instant the reference reaches the controller
        arrives = time + delay_s
        start_x, start_y, start_psi, start_u = self._planning_start(arrives, measured, inputs, measured_at=time)
        if self.method == "routing":
            return self._plan_route(time, (x, y, psi, u), (start_x, start_y, start_psi, start_u), et, arrives)
        if self.metocean.is_time_varying:  # plan in the weather of this instant
            self.weather = resample_weather(self.metocean, self.resolution_nm, t_s=time)
            self.field.set_weather(self.weather)
        self.field.update((start_x, start_y), self.speed)
        path = plan_local_path(self.field, (start_x, start_y), self.speed * self.delta,
                               self.horizon_steps, avoidance=et > 0.5, final_approach=True)
        self.counts["plans"] += 1
        self.counts["avoidance_plans"] += int(et > 0.5)
        self.counts["flat_steps"] += path.flat_steps
        self.counts["border_steps"] += path.border_steps
        self._reached_goal = path.reached_goal
        reference = reference_states(path.points, self.delta, start_time=arrives, initial_heading=start_psi)
        return self._outputs(time, reference, et, (x, y, psi, u))

    def _outputs(self, time: float, reference: np.ndarray, et: float, ship: tuple[float, float, float, float],
                 **extra: float) -> dict[str, Value]:
        x, y, psi, u = ship
        ec, em = self._local_rates(x, y, psi, u, time)
        outputs: dict[str, Value] = {
            "reference": reference,
            "et": et,
            "ec_rate": ec,
            "em_rate": em,
            "goal_distance_m": float(np.hypot(self.goal[0] - x, self.goal[1] - y)),
            **extra,
        }
        if not np.all(np.isfinite(reference)) or not np.isfinite(ec) or not np.isfinite(em):
            raise ModelError(f"participant '{self.name}': non-finite reference or energy rate at t={time:.0f} s")
        return outputs

    def _plan_route(self, time: float, ship: tuple[float, float, float, float],
                    start: tuple[float, float, float, float], et: float, arrives: float) -> dict[str, Value]:
        plan = self.routing.plan(arrives, start)
        self.counts["plans"] += 1
        self.counts["avoidance_plans"] += int(et > 0.5)
        self._reached_goal = plan.reached_goal
        reference = reference_states(plan.points, self.delta, start_time=arrives, initial_heading=start[2])
        return self._outputs(time, reference, et, ship, planned_speed_mps=plan.speed_through_water_mps)
