"""Co-simulation participant around the NMPC: measured state + reference + obstacles -> tau.

Inputs: ``x, y, psi, u, v, r`` (floats, SI), ``reference`` ((M, 7): t, x, y, psi, u, v, r),
``et`` (float, optional), ``obstacles`` ((n, 5): x, y, vx, vy, radius, optional).
Outputs: ``tau_u`` [N], ``tau_r`` [N·m], ``prediction`` ((N_c+1, 7), absolute time
column), and per-solve telemetry ``solve_time_s``, ``iterations``, ``solver_ok``,
``fallback``, ``cost``, ``constraint_violation``, ``collision_slack`` (> 0 when the soft
collision constraints had to give way), ``timed_out`` (1 when the wall-time limit stopped
the solve), ``disturbance`` ((5,): the observer's current north, east [m/s], w_u, w_v [N],
w_r [N·m]), ``encounter_class`` ((max_obstacles,): per obstacle row the index into
:data:`rhnc.encounters.colregs.ENCOUNTER_CLASSES`, -1 unclassified or no such row) and
``domain_active`` ((max_obstacles,): 1 when the row's collision constraint was on).

The prediction model should be the plant's: a parameter set names the plants it is for
(``plant_fmu``: model names, ``plant_guid``: the GUID it was identified on).  When the
FMU feeding the measured state is neither, the run logs a warning and the summary's
``model_check`` says so (see :meth:`ControlParticipant.connected`).
"""

from __future__ import annotations

import logging
import math
from collections.abc import Mapping, Sequence
from types import SimpleNamespace
from typing import Any

import numpy as np

from orchestrator.errors import ModelError, ScenarioError
from orchestrator.geometry import KNOT
from orchestrator.participant import BuildContext, Participant, Value
from rhnc.control.control_options import OPTIONS, chart_from_options, controller_from_options
from rhnc.control.loop_delay import LoopDelay
from rhnc.control.nmpc import NMPCController
from rhnc.control.nmpc_acados import AcadosUnavailable
from rhnc.ship.identification import Horizon, recorded_horizon, same_horizon
from rhnc.ship.ship_model import STATE_NAMES

LOG = logging.getLogger(__name__)

_STATE_INFO = {"x": ("m", "measured position north of the scenario's origin"),
               "y": ("m", "measured position east of the scenario's origin"),
               "psi": ("rad", "measured heading, clockwise from north"),
               "u": ("m/s", "measured surge speed through the water"),
               "v": ("m/s", "measured sway speed through the water (to starboard)"),
               "r": ("rad/s", "measured yaw rate (clockwise)")}
_TIMED_STATE = ["t [s]", "x north [m]", "y east [m]", "psi heading [rad]", "u surge [m/s]", "v sway [m/s]",
                "r yaw rate [rad/s]"]
#: unit, description and the meaning of each column (array ports) of every port
PORT_INFO: dict[str, dict[str, Any]] = {
    **{name: {"unit": unit, "description": text} for name, (unit, text) in _STATE_INFO.items()},
    "reference": {"unit": "", "columns": _TIMED_STATE,
                  "description": "reference trajectory, one row per point: (t [s], x [m], y [m], psi [rad], "
                                 "u [m/s], v [m/s], r [rad/s]); times increasing and covering the horizon"},
    "et": {"unit": "", "description": "event trigger: 1 turns the collision constraints on, 0 off"},
    "obstacles": {"unit": "", "columns": ["x north [m]", "y east [m]", "vx north [m/s]", "vy east [m/s]",
                                          "radius R_i [m]"],
                  "description": "obstacles now, one row each: (x [m], y [m], vx [m/s], vy [m/s], radius [m]); "
                                 "rows of radius 0 are empty"},
    "tau_u": {"unit": "N", "description": "commanded surge force, held over the step"},
    "tau_r": {"unit": "N.m", "description": "commanded yaw moment (clockwise), held over the step"},
    "prediction": {"unit": "", "columns": _TIMED_STATE,
                   "description": "the NMPC's predicted states over its horizon: (t [s], x [m], y [m], psi [rad], "
                                  "u [m/s], v [m/s], r [rad/s])"},
    "solve_time_s": {"unit": "s", "description": "wall time of this step's solves"},
    "solve_cpu_time_s": {"unit": "s", "description": "processor time of this step's solves"},
    "iterations": {"unit": "", "description": "solver iterations of this step"},
    "solver_ok": {"unit": "", "description": "1 when the solver found a plan, else 0"},
    "fallback": {"unit": "", "description": "1 when the shifted previous plan was applied instead of a new one"},
    "cost": {"unit": "", "description": "optimal cost of the plan (scaled, dimensionless)"},
    "constraint_violation": {"unit": "", "description": "largest constraint violation of the plan (scaled)"},
    "collision_slack": {"unit": "", "description": "> 0 when the soft collision constraints had to give way"},
    "timed_out": {"unit": "", "description": "1 when the time limit stopped the solve"},
    "disturbance": {"unit": "", "columns": ["current north [m/s]", "current east [m/s]", "w_u [N]", "w_v [N]",
                                            "w_r [N.m]"],
                    "description": "the disturbance observer's estimate (zero when it is off)"},
    "encounter_class": {"unit": "", "columns": None,
                        "description": "per obstacle row: index into the encounter classes (head-on, crossing, "
                                       "overtaking, ...), -1 unclassified or no such row"},
    "domain_active": {"unit": "", "columns": None,
                      "description": "per obstacle row: 1 when its collision constraint was on"},
}

def interpolate_reference(reference: np.ndarray, times: np.ndarray) -> np.ndarray:
    """Reference states (len(times), 6) at ``times`` [s] from an (M, 7) timed reference.

    Linear in time between the reference's points (heading unwrapped first); before its
    first point the first point is held; past its last point the last point's velocity is
    held (straight on at its course and speed, r = 0).
    """
    reference = np.atleast_2d(np.asarray(reference, dtype=float))
    if reference.ndim != 2 or reference.shape[1] != 7 or len(reference) < 1:
        raise ValueError(f"reference must be an (M, 7) array, got shape {reference.shape}")
    t = reference[:, 0]
    columns = reference[:, 1:].copy()
    columns[:, 2] = np.unwrap(columns[:, 2])
    if len(reference) > 1 and np.any(np.diff(t) <= 0.0):
        raise ValueError("reference times must increase strictly")
    out = np.column_stack([np.interp(times, t, columns[:, j]) for j in range(6)])
    late = times > t[-1]
    if np.any(late):
        x, y, psi, u, v, _ = columns[-1]
        dt = times[late] - t[-1]
        out[late, 0] = x + (u * math.cos(psi) - v * math.sin(psi)) * dt
        out[late, 1] = y + (u * math.sin(psi) + v * math.cos(psi)) * dt
        out[late, 2] = psi
        out[late, 3] = u
        out[late, 4] = v
        out[late, 5] = 0.0
    return out


#: largest plausible speed [m/s] and yaw rate [rad/s] in a reference: far above any ship's, far
#: below a position or a time read as a speed
REFERENCE_SPEED_LIMIT_MPS = 50.0
REFERENCE_YAW_RATE_LIMIT = 1.0
REFERENCE_LAYOUT = "(t [s], x [m], y [m], psi [rad], u [m/s], v [m/s], r [rad/s])"


def check_reference(reference: np.ndarray, time: float, span_s: float) -> None:
    """Refuse a reference that cannot be rows of :data:`REFERENCE_LAYOUT` around ``time``.

    Its times must reach within ``span_s`` of ``time`` on both sides (a reference that ends
    long before now, or starts long after, is stale or has another column first), and its
    speeds and yaw rates must be those of a ship (a position or a time in the speed column
    is not).  A wrong layout otherwise gives a plan towards an absurd state: saturated
    forces, silently.

    Raises
    ------
    ValueError
        Naming the layout and what does not fit.
    """
    reference = np.atleast_2d(np.asarray(reference, dtype=float))
    t = reference[:, 0]
    if t[0] > time + span_s or t[-1] < time - span_s:
        raise ValueError(f"rows must be {REFERENCE_LAYOUT}; its times {t[0]:g} .. {t[-1]:g} s do not reach "
                         f"within {span_s:g} s of now")
    for column, name, limit, unit in ((4, "u", REFERENCE_SPEED_LIMIT_MPS, "m/s"), (5, "v", REFERENCE_SPEED_LIMIT_MPS, "m/s"),
                                      (6, "r", REFERENCE_YAW_RATE_LIMIT, "rad/s")):
        worst = int(np.argmax(np.abs(reference[:, column])))
        if abs(reference[worst, column]) > limit:
            raise ValueError(f"rows must be {REFERENCE_LAYOUT}; row {worst} has {name} = "
                             f"{reference[worst, column]:g} {unit} (more than {limit:g})")


class ControlParticipant(Participant):
    """NMPC trajectory tracking with collision constraints (docs/method.md, control).

    Options
    -------
    parameter_set : str
        Set of ``models/KCS/parameter_sets.toml`` for the prediction model (default ``default``).
    model_file, model_set : str
        Instead of ``parameter_set``: a parameter-set file (relative to the scenario; e.g.
        one written by ``python -m orchestrator identify``) and the set in it (default:
        its only set).
    parameter_overrides : table
        Single coefficients replacing the set's, by key (``m11``, ``d33``, ``tau_r_max``, ...:
        the keys of the set, units as in ``models/KCS/parameter_sets.toml``).  A model
        changed this way is still checked against the plant by the set's ``plant_fmu``.
    horizon_steps : int
        N_c (default 15).
    control_interval_s : float
        Prediction interval delta [s] (default: this participant's step size).
    substeps : int
        RK4 steps per interval, where collisions are also checked (default 4).
    own_radius_nm : float
        Own ship's hazard radius R [nm] (default 0).
    solver : str
        ``fatrop`` (default), ``ipopt``, ``sqpmethod`` or ``acados`` (optional install,
        :mod:`rhnc.control.nmpc_acados`).
    max_iterations, max_obstacles : int
        Solver iteration limit (200), obstacle slots (4).
    iteration_budget : int
        Iterations of one control step, both solver attempts together (default: none,
        ``max_iterations`` each); an attempt that runs out of them at a feasible point
        applies that plan (see :class:`rhnc.control.nmpc_settings.NMPCSettings`).
    weights : table
        ``q`` (6 values), ``r`` (2), ``r_rate`` (2) replacing the paper's diagonals.
    length_scale_m, speed_scale_mps : float
        Units of the scaled errors (see :mod:`rhnc.control.nmpc`).
    et_default : float
        Event trigger used when no ``et`` input is connected (default 0: constraints off).
    collision_slack_weight : float or false
        Weight of the soft collision constraints' slack (default 1e4, see
        :class:`rhnc.control.nmpc.NMPCSettings`); ``false`` makes them hard.
    cpu_time_limit_s : float or false
        Processor-time limit of each solver attempt [s] (default 2; the shifted previous
        plan is applied when it is hit; processor time, so the load of the machine does not
        change the outcome); ``false``: none.
    wall_time_limit_s : float or false
        Hard wall-time limit of one control step's solves [s] (default 20); ``false``: none
        (both false: iteration limit only).
    max_speed_kn : float
        Upper bound of the surge speed, also caps the reference (default 24, the KCS's
        service speed).
    colregs : bool
        Collision domains shaped by encounter class and role, Rules 8 and 13-17 (default
        false: the paper's circles R + R_i; see :mod:`rhnc.control.nmpc_colregs`).
    clearance_margin_nm, clearance_margin_growth_kn : float
        Margin added to R + R_i [nm] and its growth with prediction time [kn = nm/h]
        (default 0, 0): tightening against disturbances and model error.  A model set
        written by ``identify`` carries ``position_error_growth_mps``, the growth of its
        own prediction error; it is the default growth with that model.
    stand_on_action_tcpa_s, stand_on_action_range_factor : float
        Rule 17: when a stand-on ship stops standing on (defaults 600 s, 2; the
        ``colregs`` analysis judges with the same rule, :func:`rhnc.encounters.colregs.stand_on_must_act`).
    apparent_alteration_deg : float
        Rules 8, 16: a give-way ship (or a stand-on ship that acts) holds its heading at
        least this far off its reference to the side the rules ask for until the target
        is past and clear (default 35; 0: no minimum alteration).
    give_way_action_tcpa_s : float
        A give-way ship begins that alteration when the target's CPA is this close in time
        (default 900 s).
    disturbance_observer : bool
        Offset-free NMPC: estimate current and loads and predict with them (default false).
    observer_gain : float
        The observer's correction per step, in (0, 1] (default 0.5).
    codegen : bool
        Compile the NLP to C once per machine and reuse it (default true; see
        :mod:`rhnc.control.nmpc_codegen`); the summary reports ``codegen: compiled|interpreted``.
    warm_start_duals : bool
        IPOPT starts from the previous solve's multipliers shifted by one interval
        (default true; about half the iterations; ignored by fatrop).
    loop_delay_s : float
        Time from a step at ``t`` to its input acting on the plant [s] (default: the
        master's, 0 in our Gauss-Seidel order, one step of this participant in Jacobi
        order; an exported FMU declares it as a parameter, default one communication
        step).  The measured state is carried over it with the inputs already sent and
        the NMPC solves from there (:mod:`rhnc.control.loop_delay`).
    obstacle_age_s : float
        How old the ``obstacles`` input is when it arrives [s] (default: the master's, one
        step of a Python source in Jacobi order, else 0); the obstacles are carried over
        it and the loop delay at their velocity.
    chart : str
        A chart file (relative to the scenario; docs/passages.md): the NMPC keeps its
        declared clearance from land and no-go areas as constraints, always on, softened
        by the collision slack where no plan keeps it (:mod:`rhnc.control.nmpc_coastline`).
    coastline_slots : int
        Constraints for the chart's nearest edges along the predicted track (default 6,
        only with ``chart``).
    actuators_ship : str
        A ship name in ``ships/`` or a ship file whose ``[actuators]`` the NMPC's plant is
        steered by through an allocation: the planned tau changes no faster than the steering
        gear and shaft allow (:func:`rhnc.control.allocation.tau_rate_limits`), and the surge
        force stays >= 0 (the allocation turns the propeller ahead only).
    reachable_reference : bool
        The reference no farther ahead of the ship than the prediction model's speed reserve
        makes up over the horizon (default false; :mod:`rhnc.control.reachable_reference`):
        for a ship whose reference speed is close to its top speed.
    """

    OPTIONS = OPTIONS

    def __init__(self, name: str, controller: NMPCController, et_default: float, loop_delay_s: float = 0.0,
                 obstacle_age_s: float = 0.0) -> None:
        super().__init__(name)
        self.delay = LoopDelay(loop_delay_s, controller.params)
        self.obstacle_age_s = obstacle_age_s
        self.model_check: dict[str, Any] = {"set": controller.params.name, "check": "plant not seen"}
        self.scenario_file = "<this scenario>"   # for the identify command the model check asks for
        self._recorded = recorded_horizon(controller.params.extras, f"model set '{controller.params.name}'")
        self.margin_source = "scenario" if controller.settings.clearance_margin_growth_mps else "none"
        self._tau_r_history: list[float] = []
        self.controller = controller
        self.et_default = et_default
        n = controller.settings.horizon_steps
        self._prediction = np.zeros((n + 1, 7))
        self._applied: np.ndarray | None = None  # the input of the last solve, None before the first
        self._solve_times: list[float] = []
        self._steps = 0
        self._slack_steps = 0
        self._timeouts = 0
        self._speeds: list[float] = []
        self._cpu_times: list[float] = []
        self._step_cpu_times: list[float] = []

    @classmethod
    def from_options(cls, name: str, options: Mapping[str, Any], context: BuildContext) -> "ControlParticipant":
        """Build from scenario options (see :mod:`rhnc.control.control_options`); errors name the key."""
        params, settings, et_default, delays = controller_from_options(options, context)
        try:
            controller = NMPCController(params, settings)
        except AcadosUnavailable as error:
            raise ScenarioError(f"{context.where}: option 'solver': {error}") from None
        chart = chart_from_options(options, context)
        if chart is not None:
            controller.use_chart(chart)
        participant = cls(name, controller, et_default, *delays)
        if context.where.endswith(f": participants.{name}"):
            participant.scenario_file = context.where[: -len(f": participants.{name}")]
        if "clearance_margin_growth_kn" in options:
            participant.margin_source = "scenario"
        elif "position_error_growth_mps" in params.extras:
            participant.margin_source = "model's prediction error"
        else:
            participant.margin_source = "none"
        return participant

    @property
    def input_names(self) -> Sequence[str]:
        return (*STATE_NAMES, "reference", "et", "obstacles")

    @property
    def output_names(self) -> Sequence[str]:
        return (
            "tau_u", "tau_r", "prediction", "solve_time_s", "iterations",
            "solver_ok", "fallback", "cost", "constraint_violation", "collision_slack",
            "timed_out", "disturbance", "encounter_class", "domain_active", "solve_cpu_time_s",
        )

    def setup(self, start_time: float, inputs: Mapping[str, Value]) -> dict[str, Value]:
        """Reset the controller; initial outputs are zero inputs (the first step decides)."""
        self.controller.reset()
        self.controller.start()
        self._applied = None
        self.delay.reset()
        self.delay.hold(start_time, np.zeros(2))  # the set-up's zero forces act until the first decision does
        self._slack_steps = 0
        self._timeouts = 0
        self._speeds = []
        self._cpu_times = []
        self._step_cpu_times = []
        slots = self.controller.settings.max_obstacles
        idle = SimpleNamespace(solve_time_s=0.0, solve_cpu_time_s=0.0, iterations=0, success=True, fallback=False,
                               cost=0.0, constraint_violation=0.0, collision_slack=0.0, timed_out=False,
                               disturbance=np.zeros(5), encounter_classes=np.full(slots, -1.0),
                               domain_active=np.zeros(slots))
        return self._outputs(np.zeros(2), self._prediction, idle)

    def step(self, time: float, step_size: float, inputs: Mapping[str, Value]) -> dict[str, Value]:
        """Solve the NMPC at ``time`` from the measured state; return tau held over the step."""
        missing = [name for name in (*STATE_NAMES, "reference") if name not in inputs]
        if missing:
            raise ModelError(f"{self.name}: inputs not connected or not available: {', '.join(missing)}")
        state = np.array([float(inputs[name]) for name in STATE_NAMES])
        if not np.all(np.isfinite(state)):
            raise ModelError(f"{self.name}: non-finite measured state at t = {time} s: {state}")
        settings = self.controller.settings
        # the input decided now acts from time + delay: plan from the state it will meet
        decision_time, state = self.delay.predict(time, state)
        horizon = decision_time + settings.control_interval_s * np.arange(settings.horizon_steps + 1)
        try:
            reference = interpolate_reference(np.asarray(inputs["reference"]), horizon)
            check_reference(np.asarray(inputs["reference"]), time, horizon[-1] - time)
        except ValueError as error:
            raise ModelError(f"{self.name}: input 'reference' at t = {time} s: {error}") from None
        obstacles = np.asarray(inputs.get("obstacles", np.zeros((0, 5))), dtype=float).reshape(-1, 5).copy()
        # constant velocity over their age and the loop delay
        obstacles[:, :2] += obstacles[:, 2:4] * (self.obstacle_age_s + decision_time - time)
        et = float(inputs.get("et", self.et_default)) > 0.5
        # before the first solve no input has been applied: the controller then assumes the
        # one that holds the measured speed, not the zero outputs of set-up (a first solve
        # that failed held a zero surge force, and the input-rate cost pulled the first plan
        # towards it)
        solution = self.controller.solve(decision_time, state, reference, obstacles, et, previous_tau=self._applied)
        self._applied = solution.tau
        self.delay.sent(time, solution.tau)
        self._tau_r_history.append(float(solution.tau[1]))
        self._steps += 1
        self._solve_times.append(solution.solve_time_s)
        self._cpu_times.append(solution.solve_cpu_time_s)
        self._step_cpu_times.append(solution.step_cpu_time_s)
        if solution.fallback:
            LOG.warning("%s: NMPC failed at t = %.1f s (%s), fallback applied", self.name, time, solution.status)
        self._slack_steps += int(solution.collision_slack > 0.0)
        self._timeouts += int(solution.timed_out)
        self._speeds.append(float(state[3]))
        prediction = np.column_stack([horizon, solution.states])
        return self._outputs(solution.tau, prediction, solution)

    def _outputs(self, tau, prediction, solution) -> dict[str, Value]:
        slots = self.controller.settings.max_obstacles
        classes = np.full(slots, -1.0)
        active = np.zeros(slots)
        n = min(slots, len(solution.encounter_classes))
        classes[:n] = solution.encounter_classes[:n]
        active[:n] = solution.domain_active[:n]
        return {
            "tau_u": float(tau[0]),
            "tau_r": float(tau[1]),
            "prediction": prediction,
            "solve_time_s": float(solution.solve_time_s),
            "iterations": float(solution.iterations),
            "solver_ok": 1.0 if solution.success else 0.0,
            "fallback": 1.0 if solution.fallback else 0.0,
            "cost": float(solution.cost),
            "constraint_violation": float(solution.constraint_violation),
            "collision_slack": float(solution.collision_slack),
            "timed_out": 1.0 if solution.timed_out else 0.0,
            "solve_cpu_time_s": float(solution.solve_cpu_time_s),
            "disturbance": np.asarray(solution.disturbance, dtype=float).copy(),
            "encounter_class": classes,
            "domain_active": active,
        }

    def terminate(self) -> None:
        """Stop the solver's worker process."""
        self.controller.close()

    def fmu_parameters(self) -> dict[str, dict[str, Any]]:
        """The loop delay and the obstacles' age, which depend on the master's exchange order."""
        return {
            "loop_delay_s": {"start": self.delay.delay_s, "unit": "s",
                             "description": "time from a step at t to its tau acting on the ship (one communication "
                                            "step in a master that steps all FMUs at once, 0 when this FMU steps "
                                            "before the ship and hands tau on at once)"},
            "obstacle_age_s": {"start": self.obstacle_age_s, "unit": "s",
                               "description": "age of the obstacles input when it arrives; obstacles are carried over "
                                              "it at their velocity"},
        }

    def port_info(self, port: str) -> dict[str, Any]:
        """Unit, description and column meanings of a port (:data:`PORT_INFO`)."""
        return dict(PORT_INFO.get(port, {}))

    def summary_from_outputs(self, outputs: Mapping[str, np.ndarray]) -> dict[str, Any]:
        """Solves and yaw-moment sign changes per 100 solves from the recorded ``tau_r``."""
        if "tau_r" not in outputs:
            return {}
        tau_r = [float(value) for value in np.asarray(outputs["tau_r"], dtype=float)]
        return {"solves": len(tau_r),
                "tau_r_sign_changes_per_100_solves": tau_r_sign_changes_per_100(tau_r,
                                                                                self.controller.params.tau_r_max)}

    def summary(self) -> dict[str, Any]:
        """Solve-time median/max [s], solves, fallbacks and solver failures."""
        times = np.array(self._solve_times)
        return {
            "solver": self.controller.settings.solver,
            "solves": self._steps,
            "solve_time_median_s": float(np.median(times)) if len(times) else None,
            "solve_time_max_s": float(np.max(times)) if len(times) else None,
            "fallback_count": self.controller.fallback_count,
            "failure_count": self.controller.failure_count,
            "relaxed_clearance_steps": self._slack_steps,
            "timeout_count": self._timeouts,
            "iteration_capped_steps": self.controller.pace.capped,
            "solve_cpu_time_median_s": float(np.median(self._cpu_times)) if self._cpu_times else None,
            "solve_cpu_time_max_s": float(np.max(self._cpu_times)) if self._cpu_times else None,
            "step_cpu_time_median_s": float(np.median(self._step_cpu_times)) if self._step_cpu_times else None,
            "step_cpu_time_max_s": float(np.max(self._step_cpu_times)) if self._step_cpu_times else None,
            "stand_on_actions": self.controller.domains.stand_on_actions,
            "apparent_alterations": self.controller.domains.alterations,
            "max_speed_kn": float(max(self._speeds)) / KNOT if self._speeds else None,
            "tau_r_sign_changes_per_100_solves": tau_r_sign_changes_per_100(
                self._tau_r_history, self.controller.params.tau_r_max),
            "model_check": self.model_check,
            "loop_delay_s": self.delay.delay_s,
            "obstacle_age_s": self.obstacle_age_s,
            "clearance_margin_growth_kn": self.controller.settings.clearance_margin_growth_mps / KNOT,
            "clearance_margin_growth_from": self.margin_source,
            **self.controller.library.summary(),
        }

    def connected(self, sources: Mapping[str, Participant]) -> None:
        """Check the prediction model against the plant feeding the measured state.

        ``check``: ``identified`` (the set's ``plant_guid`` is the FMU's GUID, and the set
        was identified for this NMPC's horizon and control interval), ``identified for
        another NMPC set-up (...)`` (a set that records another horizon or interval: its
        model class was chosen for predictions over that one; a logged warning says to
        identify on this scenario), ``identified (horizon not recorded)`` (a set written
        before identify recorded it), ``declared`` (the FMU's model name is in the set's
        ``plant_fmu``), or ``neither identified on nor declared for this plant`` with a
        logged warning.
        """
        plant = sources.get("x")
        identity = getattr(plant, "identity", None)
        if plant is None or identity is None:
            return
        extras = self.controller.params.extras
        declared = extras.get("plant_fmu", ())
        declared = [declared] if isinstance(declared, str) else list(declared)
        check = "neither identified on nor declared for this plant"
        if extras.get("plant_guid") == identity["guid"]:
            check = self._horizon_check()
        elif identity["model_name"] in declared:
            check = "declared"
            if "tau_r" not in plant.input_names and "rudder_angle_cmd" in plant.input_names:
                check = "declared (through an allocation: the plant takes rudder and propeller)"
        self.model_check = {"set": self.controller.params.name, "plant": identity["model_name"],
                            "plant_guid": identity["guid"], "check": check, **self._horizons()}
        if check.startswith("identified for another"):
            LOG.warning("%s: the NMPC's prediction model '%s' was identified on the plant FMU %s for another NMPC "
                        "set-up (%s; this one %s), and its model class was chosen for that horizon; fit one for "
                        "this set-up with: python -m orchestrator identify %s (the bounds, --set and --ship as "
                        "the set was identified with)", self.name, self.controller.params.name,
                        identity["model_name"], self._setup_text(self._recorded), self._setup_text(self._own_horizon()),
                        self.scenario_file)
        if check.startswith("neither"):
            LOG.warning("%s: the NMPC's prediction model '%s' was neither identified on nor declared for the "
                        "plant FMU %s (%s); fit one with: python -m orchestrator identify <scenario>",
                        self.name, self.controller.params.name, identity["model_name"], identity["guid"])

    def _own_horizon(self) -> Horizon:
        settings = self.controller.settings
        return Horizon(settings.horizon_steps * settings.control_interval_s, settings.control_interval_s)

    def _horizons(self) -> dict[str, float | None]:
        own = self._own_horizon()
        return {"horizon_s": own.horizon_s, "control_interval_s": own.interval_s,
                "identified_for_horizon_s": self._recorded.horizon_s if self._recorded else None,
                "identified_for_control_interval_s": self._recorded.interval_s if self._recorded else None}

    @staticmethod
    def _setup_text(horizon: Horizon | None) -> str:
        return "not recorded" if horizon is None else f"{horizon.horizon_s:g}-s horizon every {horizon.interval_s:g} s"

    def _horizon_check(self) -> str:
        """The check of a set identified on this plant: for this NMPC's horizon and interval or not."""
        if self._recorded is None:
            return "identified (horizon not recorded)"
        if same_horizon(self._recorded, self._own_horizon()):
            return "identified"
        return (f"identified for another NMPC set-up ({self._setup_text(self._recorded)}; "
                f"this one {self._setup_text(self._own_horizon())})")


def tau_r_sign_changes_per_100(tau_r: Sequence[float], tau_r_max: float, deadband: float = 0.01) -> float | None:
    """Sign changes of the commanded yaw moment per 100 solves (chattering measure).

    Values within ``deadband`` * ``tau_r_max`` of zero carry no sign; a change is counted
    when a value's sign differs from the last signed one.  None without solves.
    """
    if not tau_r:
        return None
    changes, last = 0, 0.0
    for value in tau_r:
        if abs(value) <= deadband * tau_r_max:
            continue
        sign = math.copysign(1.0, value)
        changes += int(last != 0.0 and sign != last)
        last = sign
    return 100.0 * changes / len(tau_r)
