"""Trajectory-tracking NMPC with collision constraints (paper Eq. 20-23), time-bounded.

The optimal-control problem (:mod:`rhnc.control.nmpc_problem`) is built once as a CasADi
``nlpsol`` with parameters (reference, previous input, terminal weight, disturbance
estimate, obstacle domains) and re-solved every control interval with new parameter values
and a warm start from the shifted previous solution (:mod:`rhnc.control.nmpc_warm_start`).

Scaling (so that the paper's Q = diag(0.1, 0.1, 10, 1, 1, 1), R = R1 = diag(0.01, 0.01)
keep a meaning at full scale): errors and inputs are made dimensionless the way naval
architects do with the "prime" system,

- positions in ship lengths ``L`` (``lpp`` of the parameter set, 230 m for the KCS),
- heading in radians, wrapped through ``2 (1 - cos e)`` (= e² near 0, no minimum at pi),
- surge and sway speed in m/s (``speed_scale_mps`` = 1 m/s, about 2 kn),
- yaw rate in units of (1 m/s) / L, i.e. as the difference of the bow's and the stern's
  transverse speeds in m/s,
- forces and moments in units of their bounds ``tau_max``.

So a cross-track error of one ship length costs as much (0.1) as a heading error of
0.1 rad, a speed error of 1 m/s costs 1 and a full-scale force step 0.01.  The speed unit
is deliberately not the service speed: with speeds in units of U, stopping dead costs 1
per step against 10 for a 60 deg course alteration, and the NMPC with the paper's Q then
stops in front of a 2 nm obstacle on its track instead of passing it (seen in trials).
The decision variables are the same scaled quantities, with positions measured from the
ship's position at the solve, which keeps the solver's numbers of order one.

Terminal weight P: the DARE solution about straight motion at the reference speed
(:mod:`rhnc.control.nmpc_terminal`).

Collision constraints (only while ET = 1) at every RK4 substep of every interval, one
circle per obstacle (:mod:`rhnc.control.nmpc_problem`); the circles are the paper's R + R_i, or,
with ``colregs``, shaped by each target's encounter class and the own ship's role
(:mod:`rhnc.control.nmpc_colregs`), widened by a margin that grows with the prediction time.

When the problem with hard constraints has no solution (an obstacle noticed too late),
the step is solved again with one slack per stage relaxing them at a heavy L1 + L2 cost
(``collision_slack_weight``): the plan that violates the clearance least, reported in the
telemetry as ``collision_slack``.

Speed bound: u <= ``max_speed_mps`` at every node after the first (the KCS's service
speed, 24 kn, unless the scenario says otherwise), and the reference speed is capped at
the same value; a ship measured faster is allowed to slow down at its deceleration limit.
While a readily apparent reduction of speed is held (``DomainReport.speed_goal_mps``, a
ship overtaking us), the bound comes down from the measured speed at ``SLOWING_SHARE`` of the
deceleration full astern force and the hull's drag give, to the speed asked for.  While
speeding up is held instead (``DomainReport.speed_up_goal_mps``, a ship overtaking us that nothing
else kept clear), the reference speed goes up from the speed and time it began at (or from the
measured speed, where that asks for more) at ``SPEEDING_SHARE`` of the acceleration the ship has
left at the speed asked for, and the reference positions run from the ship along the reference
course at that speed (the route's positions pulled a ship turned off its route back down to the
route's speed times the cosine of the turn).  It is a cost, not a bound: a floor
under the speed made the relaxed problem of a ship already inside a domain fail (fatrop),
33 times in one run, where the cost alone sped the ship up as asked.

Time limits: every solve is limited to ``max_iterations``, to ``cpu_time_limit_s`` of
processor time per attempt and to ``wall_time_limit_s`` (both attempts together,
:mod:`rhnc.control.solver_watchdog`), and its iterations to the cap that fits in the
processor-time limit at this run's measured pace (:mod:`rhnc.control.solve_pace`).  A prediction from the measured state
that is not finite (a state far outside the model's range) skips the solver.

Failures: when neither attempt reports success, or the time limit stops the solve, the
controller applies the previous plan shifted by one interval (its next input and
predicted states) and flags the step; when no previous plan is left it holds the
previous surge force with zero yaw moment, or, while a readily apparent alteration is
held, with the yaw moment that steers to the alteration's heading
(:func:`rhnc.control.nmpc_alteration.alteration_steering`).  A solve stopped at its
iteration budget leaves its unfinished iterate as the next step's warm start, so that
successive steps continue one solve (:class:`rhnc.control.nmpc_warm_start.PlanMemory`).

Offset-free tracking: with ``disturbance_observer`` on, the current and body-frame loads
estimated by :mod:`rhnc.control.disturbance_observer` enter the prediction model as parameters.

The settings and the outcome of a step: :mod:`rhnc.control.nmpc_settings`; this module is the
control step itself (:class:`NMPCController`).
"""

from __future__ import annotations

import dataclasses
import logging
import math
import time

import numpy as np

from orchestrator.interrupts import stop_requested
from rhnc.encounters.colregs import ENCOUNTER_CLASSES
from rhnc.control.disturbance_observer import DisturbanceObserver, trimmed_reference
from rhnc.control.nmpc_codegen import NLPLibrary
from rhnc.control.nmpc_alteration import alteration_steering, heading_bounds
from rhnc.control.nmpc_bounds import SLOWING_SHARE, SPEEDING_SHARE, StepBounds
from rhnc.control.nmpc_coastline import CoastlineDomains
from rhnc.control.nmpc_colregs import CollisionDomains, DomainReport
from rhnc.control.nmpc_manoeuvre import ManoeuvreResponse
from rhnc.control.nmpc_problem import (ACCEPTABLE_VIOLATION, DISTURBANCE_SIZE, FRESH_SOLVER_PLUGINS, OBSTACLE_FIELDS,
                               StepEvaluator, build_problem, renew_solver_after, solver_options)
from rhnc.control.nmpc_settings import SOLVERS, NMPCSettings, NMPCSolution
from rhnc.control.nmpc_terminal import MIN_TERMINAL_SPEED_MPS, TerminalWeight
from rhnc.control.nmpc_warm_start import PlanMemory, push_guess_clear
from rhnc.control.reachable_reference import reachable_lead_m, reachable_reference
from rhnc.ship.ship_model import ShipParameters, hull_forces
from rhnc.control.solve_pace import IterationPace
from rhnc.control.solver_watchdog import BoundedSolver

LOG = logging.getLogger(__name__)

__all__ = ["OBSTACLE_FIELDS", "MIN_TERMINAL_SPEED_MPS", "SOLVERS", "NMPCSettings", "NMPCSolution",
           "NMPCController", "reference_inputs", "ENCOUNTER_CLASSES"]

#: collision slack (scaled clearance, |p - c|^2 / rho^2 - 1) below which a plan counts as
#: keeping its clearance: the solver's tolerance, about 0.05 % of the distance
SLACK_TOLERANCE = 1e-3
#: cost and constraint violation reported when a solve left no finite iterate (stopped, NaN)
UNKNOWN = -1.0
#: times one attempt may go on from the iterate it stopped at, at the cap of an estimated pace,
#: within the step's processor-time limit (rhnc.control.solve_pace)
MAX_CONTINUATIONS = 2


def renew_every_solve(outcome) -> bool:
    """A new solver object after every solve (with an iteration budget, see :func:`renew_rule`)."""
    return True


def renew_rule(solver: str, compiled: bool, iteration_budget: int | None):
    """After which solves a solver gets a new object: None (never), or ``rule(outcome) -> bool``.

    fatrop's objects keep data of their last solve (compiled: a new one costs about 1 ms;
    interpreted, nlpsol derives the NLP's functions anew, about 0.5 s: never).  Without an
    iteration budget, after a failed or long solve (:func:`renew_solver_after`); with one,
    after every solve: an object kept over a run of short solves (<= 6 iterations each) ran
    990 iterations, 1 s of processor time, on the next step of a drawn run despite its
    iteration limit of 90, where a new object on the same arguments took 18 (replayed from
    the recorded solver inputs).
    """
    if solver not in FRESH_SOLVER_PLUGINS or not compiled:
        return None
    return renew_solver_after if iteration_budget is None else renew_every_solve


def reference_inputs(reference: np.ndarray, dt: float, params: ShipParameters,
                     tau_max: np.ndarray | None = None) -> np.ndarray:
    """Feed-forward inputs tau_d (N, 2) [SI] for reference states (N+1, 6) spaced ``dt`` [s].

    Inverse of the surge and yaw equations with v_d = 0 (the paper's Eq. 19 reference):
    ``tau_u = m11 udot + d11 u``, ``tau_r = m33 rdot + d33 r`` (plus the other hull forces of
    a wider model, :func:`rhnc.ship.ship_model.hull_forces`), derivatives by forward
    differences, clipped to the bounds (``tau_max``, default the parameters').
    """
    u = reference[:, 3]
    r = reference[:, 5]
    surge, _, yaw = hull_forces(params, u[:-1], np.zeros(len(u) - 1), r[:-1])
    tau = np.empty((len(u) - 1, 2))
    tau[:, 0] = params.m11 * ((u[1:] - u[:-1]) / dt) - surge
    tau[:, 1] = params.m33 * ((r[1:] - r[:-1]) / dt) - yaw
    bound = params.tau_max if tau_max is None else tau_max
    return np.minimum(np.maximum(tau, -bound, out=tau), bound, out=tau)


class NMPCController(StepBounds):
    """Multiple-shooting NMPC of the 3-DOF ship, built once, re-solved every interval.

    Parameters
    ----------
    params : ShipParameters
        Prediction model (same set as the plant, without disturbances).
    settings : NMPCSettings
        Horizon, interval, solver, weights, scaling, domains, limits.
    """

    def __init__(self, params: ShipParameters, settings: NMPCSettings | None = None) -> None:
        self.params = params
        self.settings = settings or NMPCSettings()
        s = self.settings
        self.length_scale = float(s.length_scale_m or params.extras.get("lpp", 230.0))
        self.speed_scale = float(s.speed_scale_mps)
        L, U = self.length_scale, self.speed_scale
        #: SI value = scaled value * state_scale (positions relative to the solve's origin).
        self.state_scale = np.array([L, L, 1.0, U, U, U / L])
        self.input_scale = params.tau_max.copy()
        self.problem = build_problem(params, s.horizon_steps, s.control_interval_s, s.substeps,
                                     s.max_obstacles + s.coastline_slots,
                                     s.q, s.r, s.r_rate, s.collision_slack_weight, self.state_scale,
                                     self.input_scale)
        self._F_scaled = self.problem.step
        self._next_state = StepEvaluator(self.problem.step)
        self.terminal_weight = TerminalWeight(self.problem.step, params, s.q, s.r, U, self.input_scale,
                                              s.terminal_weight)
        # with an iteration budget, each attempt's solver gets its share as its iteration
        # limit; with slacks a step is one attempt, the relaxed problem, which gets the whole
        # budget (see _attempt_order), without them the hard problem gets it
        budget = s.iteration_budget
        limit = s.max_iterations if budget is None else budget
        self.attempt_iterations = {"hard": limit, "relaxed": limit, "relaxed_alone": limit}
        self.pace = IterationPace(None)  # the nlpsol solvers' watchdog sets the limit
        if s.solver == "acados":
            self.library, self.solvers = self._acados_solvers()
        else:
            self.library, self.solvers = self._nlpsol_solvers()
        self.domains = CollisionDomains(s.domain_settings(), s.max_obstacles)
        # a manoeuvre is chosen with this ship's deceleration: full astern force at the share the
        # speed bound ramps with, without the hull's drag, which only helps; and with the
        # acceleration its reference speed ramps with when speeding up, to the speed bound
        self.speeding_mps2 = max(0.0, SPEEDING_SHARE * (params.tau_max[0] - params.equilibrium_tau(s.max_speed_mps)[0])
                                 / params.m11)
        self.domains.response = ManoeuvreResponse(deceleration_mps2=SLOWING_SHARE * params.tau_max[0] / params.m11,
                                                  acceleration_mps2=self.speeding_mps2,
                                                  top_speed_mps=s.max_speed_mps if self.speeding_mps2 > 0.0 else None)
        self.observer = (DisturbanceObserver(params, self.state_scale, s.observer_gain)
                         if s.disturbance_observer else None)
        self.memory = PlanMemory(s.horizon_steps, s.control_interval_s, self._rollout)
        self.coastline: CoastlineDomains | None = None
        self.fallback_count = 0
        self.failure_count = 0
        self.timeout_count = 0
        self._bound_templates: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
        self._no_disturbance = np.zeros(DISTURBANCE_SIZE)

    def _nlpsol_solvers(self):
        """The NLP's functions (compiled once per machine and cached, or interpreted) and the
        attempts' nlpsol solvers behind the watchdog (:mod:`rhnc.control.solver_watchdog`)."""
        s = self.settings
        options = solver_options(s.solver, self.problem.equality, s.max_iterations, s.wall_time_limit_s,
                                 s.cpu_time_limit_s, s.warm_start_duals)
        # the NLP's functions compiled once per machine and cached (or interpreted)
        library = NLPLibrary(self.problem.nlp, s.solver, options, s.codegen, self.problem.compact_nlp)
        budget = s.iteration_budget

        def limited(iterations: int) -> dict:
            return solver_options(s.solver, self.problem.equality, iterations, s.wall_time_limit_s,
                                  s.cpu_time_limit_s, s.warm_start_duals)

        def factory(nlp_name: str, attempt: str):
            share = self.attempt_iterations[attempt]

            def build(cap: int | None = None):
                # cap: the iterations the processor time allows (rhnc.control.solve_pace)
                if cap is not None:
                    return library.solver(nlp_name, limited(min(cap, share)))
                return library.solver(nlp_name) if budget is None else library.solver(nlp_name, limited(share))
            return build

        factories = {"hard": factory("rhnc_nmpc", "hard")}
        solvers = {"hard": factories["hard"]()}
        # The second, relaxed attempt gets a solver of its own: a solver keeps state between
        # calls (fatrop), and a failed hard attempt left in it spoils the relaxed one started
        # from the same guess (seen: 162 iterations and failure, against 59 and success from a
        # fresh solver).  Built here, before the worker is forked, rather than on first need:
        # building it costs about 0.5 s of processor time, which inside a control step showed
        # up as an 8 s solve on a loaded machine.
        if self.problem.sigma_index.size:
            factories["relaxed"] = factory("rhnc_nmpc_relaxed", "relaxed")
            solvers["relaxed"] = factories["relaxed"]()
            if budget is not None:
                factories["relaxed_alone"] = factory("rhnc_nmpc_relaxed", "relaxed_alone")
                solvers["relaxed_alone"] = factories["relaxed_alone"]()
        # a new solver object after a difficult solve, where building one is cheap (compiled:
        # about 1 ms; interpreted, nlpsol derives the NLP's functions anew: about 0.5 s)
        renew = renew_rule(s.solver, library.mode == "compiled", budget)
        bounded = BoundedSolver(solvers, factories, s.wall_time_limit_s, s.cpu_time_limit_s, renew=renew)
        # iteration caps from the measured pace: where the worker's timer bounds the solve
        self.pace = IterationPace(bounded.cpu_time_s if bounded.in_worker else None)
        return library, bounded

    def _acados_solvers(self):
        """The generated acados solver (cached once per machine) and the attempts' solver objects:
        in this process, bounded by their iteration limits (:mod:`rhnc.control.nmpc_acados`)."""
        from rhnc.control.nmpc_acados import AcadosLayout, AcadosLibrary, AcadosSolvers  # optional: only when chosen

        s = self.settings
        library = AcadosLibrary(self.params, s, self.state_scale, self.input_scale, self.problem.nlp)
        layout = AcadosLayout.of(self.problem, s.control_interval_s, s.max_obstacles + s.coastline_slots)
        names = ("hard", "relaxed") if self.problem.sigma_index.size else ("hard",)
        names += ("relaxed_alone",) if self.problem.sigma_index.size and s.iteration_budget is not None else ()
        return library, AcadosSolvers(library, self.problem, layout,
                                      {name: self.attempt_iterations[name] for name in names})

    def use_chart(self, chart) -> None:
        """Keep the clearance of ``chart`` (:class:`rhnc.chart.chart.Chart`) in the coastline slots."""
        self.coastline = CoastlineDomains(chart, self.settings.coastline_slots)

    # ------------------------------------------------------------------ state handling

    def reset(self) -> None:
        """Forget the previous plan (warm start and fallback), encounter classes and estimate."""
        self.memory.reset()
        self.domains.reset()
        if self.observer is not None:
            self.observer.reset()

    def start(self) -> None:
        """Start the solver's worker process now: forking it took 10-40 ms in the first solve."""
        self.solvers.start()

    def close(self) -> None:
        """Stop the solver's worker process (also done when the controller is collected)."""
        self.solvers.close()

    @staticmethod
    def _origin_shift(origin: np.ndarray) -> np.ndarray:
        """(north, east, 0, 0, 0, 0) [m]: what a state is measured from in the scaled problem."""
        shift = np.zeros(6)
        shift[:2] = origin[:2]
        return shift

    def _to_scaled(self, state: np.ndarray, origin: np.ndarray) -> np.ndarray:
        shifted = np.asarray(state, dtype=float) - self._origin_shift(origin)
        return shifted / self.state_scale

    def _from_scaled(self, z: np.ndarray, origin: np.ndarray) -> np.ndarray:
        return z * self.state_scale + self._origin_shift(origin)

    def _rollout(self, state: np.ndarray, inputs: np.ndarray, disturbance: np.ndarray | None = None) -> np.ndarray:
        """States (n+1, 6) [SI] from ``state`` under ``inputs`` (n, 2) [SI] with the prediction model."""
        d = self._no_disturbance if disturbance is None else disturbance
        state = np.asarray(state, dtype=float)
        inputs = np.asarray(inputs) / self.input_scale
        rows = np.empty((len(inputs) + 1, 6))
        rows[0] = state / self.state_scale
        rows[0, :2] = 0.0  # positions from the state's own: the solve's origin
        for k, w in enumerate(inputs):
            rows[k + 1] = self._next_state(rows[k], w, d)
        rows *= self.state_scale
        rows[:, :2] += state[:2]
        return rows

    # ------------------------------------------------------------------ solving

    def solve(
        self,
        time_s: float,
        state: np.ndarray,
        reference: np.ndarray,
        obstacles: np.ndarray | None = None,
        et: bool = False,
        previous_tau: np.ndarray | None = None,
    ) -> NMPCSolution:
        """One control step.

        Parameters
        ----------
        time_s : float
            Current time [s].
        state : numpy.ndarray
            Measured state (6,) [SI].
        reference : numpy.ndarray
            Reference states (N+1, 6) [SI] at ``time_s + k * control_interval_s``.
        obstacles : numpy.ndarray, optional
            (n, 5) rows x, y [m], vx, vy [m/s], radius [m] at ``time_s``.
        et : bool
            Event trigger: collision constraints on.
        previous_tau : numpy.ndarray, optional
            Input applied over the last interval [SI] (default: the last solution's).

        Returns
        -------
        NMPCSolution
            Applied input, prediction and telemetry; on failure or time-out the fallback.
        """
        cpu_start = time.process_time()
        solution = self._step(time_s, state, reference, obstacles, et, previous_tau)
        here = time.process_time() - cpu_start  # in-process solves: with their new solver objects
        solution.step_cpu_time_s = (here + solution.solve_cpu_time_s + solution.build_cpu_s if self.solvers.in_worker
                                    else here - solution.preparation_cpu_s)
        return solution

    def _step(self, time_s, state, reference, obstacles, et, previous_tau) -> NMPCSolution:
        """:meth:`solve` without its processor-time count: prepare, solve (hard, then relaxed), unpack."""
        step = self._prepare(time_s, state, reference, obstacles, et, previous_tau)
        if not np.all(np.isfinite(step.x0)):
            # a state far outside the model's range: the prediction itself overflows, and the
            # solver would iterate on NaN (seen: fatrop running for minutes); skip it
            LOG.warning("NMPC at t = %.1f s: prediction from the measured state is not finite; fallback", time_s)
            return self._fail(time_s, step.state, step.previous_tau, 0.0, 0, "prediction_not_finite", UNKNOWN,
                              UNKNOWN, False, step.disturbance, step.report)
        attempt = self._attempts(time_s, step)
        if not attempt.success:
            return self._failed_solve(time_s, step, attempt)
        return self._solved(time_s, step, attempt)

    def _prepare(self, time_s, state, reference, obstacles, et, previous_tau) -> "_StepProblem":
        """The step's NLP: parameters (reference, inputs, terminal weight, domains), bounds, warm start."""
        s = self.settings
        N = s.horizon_steps
        state = np.asarray(state, dtype=float)
        reference = np.asarray(reference, dtype=float)
        if reference.shape != (N + 1, 6):
            raise ValueError(f"reference must have shape ({N + 1}, 6), got {reference.shape}")
        origin = state[:2].copy()
        shift = self._origin_shift(origin)
        reference, tau_d, disturbance = self._trimmed_reference(time_s, state, reference)
        ref_scaled = ((reference - shift) / self.state_scale).T
        w_d = (tau_d / self.input_scale).T
        if previous_tau is None:
            previous_tau = self.memory.inputs[0] if self.memory.inputs is not None else self.params.equilibrium_tau(state[3])
        w_prev = np.clip(np.asarray(previous_tau, dtype=float) / self.input_scale, -1.0, 1.0)
        speed_ref = float(np.mean(np.hypot(reference[:, 3], reference[:, 4])))
        P = self.terminal_weight(speed_ref)
        closing = max(speed_ref, math.hypot(state[3], state[4])) * 1.25
        slots, report = self.domains.parameters(obstacles, state, origin, closing,
                                                s.control_interval_s / s.substeps, self.length_scale, et,
                                                reference_heading_rad=float(reference[0, 2]),
                                                horizon_s=N * s.control_interval_s, time_s=time_s)
        slots = self._with_coastline(slots, time_s, state, origin, reference, closing)
        # Rules 8, 16, 17: a readily apparent alteration once the ship gives way or acts
        reach = (self._heading_reach(state, previous_tau, disturbance)
                 if report.alteration_floor is not None or report.alteration_ceiling is not None
                 or report.no_port_turn else None)
        floor, ceiling = heading_bounds(report, time_s, float(state[2]), float(state[5]),
                                        time_s + s.control_interval_s * np.arange(1, N + 1), reach)
        if floor is not None or ceiling is not None:
            # the heading asked for within the alteration's bounds: a cost pulling across a bound
            # checked at the interval ends only is paid by dips between them (a yaw moment
            # changing sign every interval while the ship rides the bound)
            ref_scaled[2, 1:] = np.clip(ref_scaled[2, 1:], -np.inf if floor is None else floor,
                                        np.inf if ceiling is None else ceiling)
        speed_asked = self._speed_asked(report, state, time_s)
        if speed_asked is not None:  # speeding up (Rule 17(b)): the speed asked for as it can be reached
            ref_scaled[3, 1:] = np.maximum(ref_scaled[3, 1:], speed_asked / self.speed_scale)
            self._track_asked(ref_scaled, state)
        p = self.problem.parameters(ref_scaled, w_d, w_prev, P, disturbance, slots)
        lbx, ubx = self._bounds(state, origin)
        self._rate_and_heading_bounds(lbx, ubx, state, ref_scaled, w_prev, report, floor, ceiling,
                                      None if reach is None else reach[0])
        x0 = self._initial_guess(time_s, state, ref_scaled, w_d, origin, slots, disturbance)
        return _StepProblem(state, origin, previous_tau, disturbance, report, p, lbx, ubx, x0)

    def _with_coastline(self, slots, time_s, state, origin, reference, closing) -> np.ndarray:
        """The obstacles' slots followed by the coastline's: the chart's nearest edges to the
        reference and to the previous plan (always on, whatever the event trigger)."""
        s = self.settings
        if not s.coastline_slots:
            return slots
        if self.coastline is None:
            land = np.zeros((OBSTACLE_FIELDS, s.coastline_slots))
            land[6, :] = 1.0  # harmless radius: no chart, no constraint
            return np.hstack([slots, land])
        tracks = [reference[:, :2]]
        shifted = self.memory.shifted(time_s)
        if shifted is not None:
            tracks.append(shifted[0][:, :2])
        horizon_length = closing * s.horizon_steps * s.control_interval_s
        land = self.coastline.parameters(np.stack(tracks), state[:2], origin, self.length_scale, closing,
                                         s.control_interval_s / s.substeps, horizon_length)
        return np.hstack([slots, land])

    def _trimmed_reference(self, time_s, state, reference) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The reference on the heading nearest the ship and capped in speed, its feed-forward
        inputs and the disturbance estimate (offset-free: the drift angle and the force that
        hold the reference against it)."""
        s = self.settings
        # same heading, nearest turn (of the held alteration's: CollisionDomains.reference_turns):
        # the warm start must not begin a full circle away
        reference = reference.copy()
        reference[:, 2] -= self.domains.reference_turns(float(reference[0, 2]), float(state[2]))
        reference[:, 3] = np.minimum(reference[:, 3], s.max_speed_mps)
        if self.observer is None:
            reference = self._within_reach(reference, state, 0.0)
            return reference, reference_inputs(reference, s.control_interval_s, self.params, self.input_scale), \
                np.zeros(DISTURBANCE_SIZE)
        disturbance = self.observer.update(time_s, state)
        reference = self._within_reach(reference, state, float(disturbance[2]))
        reference, tau_d = trimmed_reference(reference, disturbance, s.control_interval_s, self.params)
        reference[:, 3] = np.minimum(reference[:, 3], s.max_speed_mps)
        return reference, tau_d, disturbance

    def _within_reach(self, reference: np.ndarray, state: np.ndarray, surge_load_N: float) -> np.ndarray:
        """With ``reachable_reference``: the reference no farther ahead of the ship than the model's
        speed reserve makes up over the horizon (:mod:`rhnc.control.reachable_reference`)."""
        s = self.settings
        if not s.reachable_reference:
            return reference
        lead = reachable_lead_m(self.params, reference, s.horizon_steps * s.control_interval_s, surge_load_N)
        return reachable_reference(reference, state[:2], lead)

    def _attempts(self, time_s: float, step: "_StepProblem") -> "_Attempts":
        """Solve the hard problem (slacks fixed at zero: the paper's constraints), and only when it
        fails, the soft one (slacks free): the plan that violates the clearance least.

        After a step that found no plan keeping the clearance, the soft one alone: the hard
        problem is then most likely infeasible again, and failing it took up to 200 iterations
        (~100 ms); should it be feasible, the exact L1 penalty gives its plan (zero slack).
        With an iteration budget, the relaxed one alone (the order: :meth:`_attempt_order`).
        """
        s = self.settings
        problem = self.problem
        lbx, ubx = step.lbx, step.ubx
        duals = self.memory.dual_guess(time_s) if s.warm_start_duals else {}
        tally = _Attempts()
        budget = s.wall_time_limit_s
        attempts = self._attempt_order(step.report.danger)
        for relaxed in attempts:
            if relaxed and stop_requested():  # Ctrl-C aborted the first attempt: no second one
                raise KeyboardInterrupt
            ubx[problem.sigma_index] = np.inf if relaxed else 0.0
            if budget is not None:
                self.solvers.wall_time_s = max(budget - tally.elapsed, 1e-3)
            attempt = "hard" if not relaxed else ("relaxed_alone" if len(attempts) == 1 and "relaxed_alone"
                                                  in self.solvers.factories else "relaxed")
            outcome = self._attempt(tally, attempt, relaxed, step, lbx, ubx, duals)
            if tally.success or outcome.timed_out:
                tally.timed_out = outcome.timed_out
                break
        outcome = tally.outcome
        tally.status = outcome.status
        if tally.accepted:
            tally.status = "Solved_To_Acceptable_Level" if outcome.acceptable else "Iteration_Budget_Feasible_Point"
        elif s.solver == "fatrop" and not tally.timed_out:  # fatrop reports an integer code
            tally.status = "Solve_Succeeded" if outcome.success else f"fatrop_return_code_{tally.status}"
        return tally

    def _attempt(self, tally: "_Attempts", attempt: str, relaxed: bool, step: "_StepProblem", lbx, ubx,
                 duals: dict):
        """One attempt of a step (its solver ``attempt``), going on from a point at the cap of an
        estimated pace while processor time is left (:mod:`rhnc.control.solve_pace`); ``tally``
        gathers it.  Returns the last solver outcome (one the timer ended included)."""
        s, problem = self.settings, self.problem
        allowed = self.attempt_iterations[attempt]
        cap, x0, cpu_left = self.pace.cap(allowed), step.x0, self.pace.cpu_time_limit_s
        stopped_at_cap = None  # the point a solve stopped at, at the cap, before going on
        for _ in range(MAX_CONTINUATIONS + 1):
            outcome = self.solvers.solve(attempt, x0=x0, p=step.p, lbx=lbx, ubx=ubx, lbg=problem.lbg,
                                         ubg=problem.ubg, iteration_cap=cap, cpu_time_s=cpu_left, **duals)
            self.pace.record(outcome.iterations, outcome.cpu_time_s, outcome.stopped_by == "cpu", allowed, cap)
            tally.elapsed += outcome.wall_time_s
            tally.cpu += outcome.cpu_time_s if np.isfinite(outcome.cpu_time_s) else 0.0
            tally.build += outcome.build_cpu_s
            if outcome.timed_out and stopped_at_cap is not None:
                break  # the timer ended the going-on: the point it went on from stays the step's
            tally.relaxed, tally.outcome = relaxed, outcome
            tally.preparation += outcome.preparation_cpu_s
            tally.iterations += max(outcome.iterations, 0)
            # a point the solver stopped at as acceptable, or at the end of its share of the
            # iteration budget, is used only when it keeps every constraint to the solver's
            # tolerance (never an infeasible iterate)
            out_of_budget = ((s.iteration_budget is not None or cap is not None) and not outcome.timed_out
                             and outcome.iterations >= (allowed if cap is None else cap))
            tally.out_of_budget = out_of_budget
            tally.accepted = ((outcome.acceptable or out_of_budget)
                              and bool(np.all(np.isfinite(outcome.x)) and np.all(np.isfinite(outcome.g)))
                              and problem.violation(outcome.x, outcome.g, lbx, ubx) <= ACCEPTABLE_VIOLATION)
            tally.success = (outcome.success or tally.accepted) and bool(np.all(np.isfinite(outcome.x)))
            if tally.success or outcome.timed_out or cap is None or not out_of_budget:
                break
            # stopped at the cap of an estimated pace with processor time left in the step: the
            # same attempt goes on from its iterate, capped at what the time left allows
            cap = self.pace.continuation(allowed - tally.iterations, tally.cpu)
            if cap is None or not np.all(np.isfinite(outcome.x)):
                break
            cpu_left = self.pace.time_left(tally.cpu)
            x0, stopped_at_cap = outcome.x.copy(), outcome
            if s.warm_start_duals:
                duals = {"lam_x0": outcome.lam_x, "lam_g0": outcome.lam_g}
        return outcome

    def _failed_solve(self, time_s: float, step: "_StepProblem", attempt: "_Attempts") -> NMPCSolution:
        """No attempt gave a plan: the fallback, with what the last attempt left."""
        outcome = attempt.outcome
        x_opt, g_opt = outcome.x, outcome.g
        finite = bool(np.all(np.isfinite(x_opt)) and np.all(np.isfinite(g_opt)) and np.isfinite(outcome.f))
        violation = self.problem.violation(x_opt, g_opt, step.lbx, step.ubx) if finite else UNKNOWN
        failed = self._fail(time_s, step.state, step.previous_tau, attempt.elapsed, attempt.iterations,
                            attempt.status, outcome.f if finite else UNKNOWN, violation, attempt.timed_out,
                            step.disturbance, step.report)
        failed.solve_cpu_time_s, failed.preparation_cpu_s, failed.build_cpu_s = (attempt.cpu, attempt.preparation,
                                                                                 attempt.build)
        # with an iteration budget, a relaxed attempt that ran out says nothing of the hard
        # problem's feasibility, and the relaxed problem is the slower one: the next step
        # tries the hard one first (solving the relaxed one alone after such a step failed
        # twenty steps in a row, Imazu 14)
        self.memory.clearance_relaxed = attempt.relaxed and self.settings.iteration_budget is None
        if attempt.out_of_budget and finite:
            # the budget stopped a solve that was on its way: the next step continues it
            # (its unfinished iterate as the warm start) instead of restarting from the
            # fallback's plan, which failed the same way step after step (trafficgen 13:
            # 14 steps holding the course towards two targets)
            self.memory.keep_iterate(time_s, self._from_scaled(x_opt[self.problem.z_index], step.origin),
                                     np.clip(x_opt[self.problem.w_index], -1.0, 1.0) * self.input_scale,
                                     outcome.lam_x, outcome.lam_g)
        return failed

    def _solved(self, time_s: float, step: "_StepProblem", attempt: "_Attempts") -> NMPCSolution:
        """The plan of a successful attempt: applied, kept for the next warm start."""
        problem, outcome = self.problem, attempt.outcome
        x_opt = outcome.x
        violation = problem.violation(x_opt, outcome.g, step.lbx, step.ubx)
        slack = float(np.max(x_opt[problem.sigma_index], initial=0.0))
        slack = slack if slack > SLACK_TOLERANCE else 0.0
        if slack > 0.0:
            LOG.warning("NMPC at t = %.1f s: collision clearance relaxed (slack %.3g): no plan keeps it",
                        time_s, slack)
        states = self._from_scaled(x_opt[problem.z_index], step.origin)
        # the solver meets the bounds |w| <= 1 only to its tolerance: never apply more than tau_max
        inputs = np.minimum(np.maximum(x_opt[problem.w_index], -1.0), 1.0) * self.input_scale
        solution = NMPCSolution(tau=inputs[0].copy(), states=states, inputs=inputs, solve_time_s=attempt.elapsed,
                                iterations=attempt.iterations, status=attempt.status, success=True, fallback=False,
                                cost=outcome.f, constraint_violation=violation, collision_slack=slack,
                                timed_out=False, disturbance=step.disturbance,
                                encounter_classes=step.report.class_codes, domain_active=step.report.active)
        solution.solve_cpu_time_s, solution.preparation_cpu_s, solution.build_cpu_s = (attempt.cpu, attempt.preparation,
                                                                                       attempt.build)
        self.memory.store(time_s, states, inputs, outcome.lam_x, outcome.lam_g)
        self.memory.clearance_relaxed = slack > 0.0
        if self.observer is not None:
            self.observer.applied(solution.tau)
        return solution

    def _attempt_order(self, danger: bool) -> tuple[bool, ...]:
        """The attempts of a step, in order: False the hard problem, True the relaxed one.

        Without an iteration budget, the hard problem first and the relaxed one when it
        fails; the relaxed one alone after a step whose plan needed slack, or with a target
        inside its clearance and closing (the hard problem then asks the range to open at
        once and is most likely infeasible).  With a budget, the relaxed problem alone,
        always: its L1 penalty is exact, so its plan is the hard problem's whenever that one
        is feasible (zero slack), and one attempt with the whole budget never spends half
        of it on a hard attempt that fails.  Split in two, the budget failed both attempts
        of steps whose hard problem needed 50-95 iterations (Imazu 14: 45 + 45 iterations,
        fallback; the hard problem alone solved in 57-65, the relaxed one in 60-70).
        """
        if not self.problem.sigma_index.size:
            return (False,)
        if self.settings.iteration_budget is not None or self.memory.clearance_relaxed or danger:
            return (True,)
        return (False, True)

    def _initial_guess(self, time_s, state, ref_scaled, w_d, origin, slots, disturbance) -> np.ndarray:
        """Shifted previous solution or unfinished iterate (re-based on this origin) or the reference,
        pushed clear of the domains."""
        problem = self.problem
        guess = np.zeros(problem.size)
        shifted = self.memory.guess(time_s)
        if shifted is not None:
            states, inputs = shifted
            # the heading on the measured one's turn: the plant wraps it at +-pi, and a plan
            # a full turn off that it begins from is 2 pi infeasible (a budgeted solve fell back)
            states = states.copy()
            states[:, 2] -= 2.0 * np.pi * round((states[0, 2] - state[2]) / (2.0 * np.pi))
            z = (states - self._origin_shift(origin)) / self.state_scale
            w = inputs / self.input_scale
        else:
            z = ref_scaled.T.copy()
            w = w_d.T.copy()
        z[0] = self._to_scaled(state, origin)
        push_guess_clear(z, slots, ref_scaled, self.settings.control_interval_s)
        guess[problem.z_index.ravel()] = z.ravel()
        w = np.minimum(np.maximum(w, -1.0), 1.0)
        guess[problem.w_index.ravel()] = w.ravel()
        # the first interval from the measured state: a non-finite value here means the
        # model cannot predict from this state at all
        z1 = self._next_state(z[0], w[0], disturbance)
        if not np.all(np.isfinite(z1)):
            guess[:] = np.nan
        return guess

    def _fail(self, time_s, state, previous_tau, elapsed, iterations, status, cost, violation, timed_out,
              disturbance, report: DomainReport) -> NMPCSolution:
        """Apply the fallback: the shifted previous plan, or hold the surge force with zero yaw moment
        (with an alteration held: the yaw moment that steers to it)."""
        self.failure_count += 1
        self.fallback_count += 1
        self.timeout_count += int(timed_out)
        steer = alteration_steering(report, float(self.params.tau_max[1]))
        states, inputs = self.memory.fallback_plan(time_s, state, previous_tau, self.params.tau_max, disturbance,
                                                   steer)
        if self.observer is not None:
            self.observer.applied(inputs[0])
        LOG.info("NMPC solve at t = %.1f s failed (%s); fallback applied", time_s, status)
        return NMPCSolution(tau=inputs[0].copy(), states=states, inputs=inputs, solve_time_s=elapsed,
                            iterations=iterations, status=status, success=False, fallback=True, cost=cost,
                            constraint_violation=violation, collision_slack=0.0, timed_out=timed_out,
                            disturbance=disturbance, encounter_classes=report.class_codes,
                            domain_active=report.active)


@dataclasses.dataclass
class _StepProblem:
    """One step's NLP as :meth:`NMPCController._prepare` set it up."""

    state: np.ndarray  # measured [SI]
    origin: np.ndarray  # north, east [m] the scaled positions are measured from
    previous_tau: np.ndarray  # input applied over the last interval [SI]
    disturbance: np.ndarray
    report: DomainReport
    p: np.ndarray  # the parameter vector
    lbx: np.ndarray
    ubx: np.ndarray
    x0: np.ndarray  # warm start


@dataclasses.dataclass
class _Attempts:
    """What the solve attempts of one step came to (:meth:`NMPCController._attempts`)."""

    outcome: object = None  # the last attempt's SolveOutcome
    relaxed: bool = False  # the last attempt was the relaxed problem
    success: bool = False
    accepted: bool = False  # an acceptable (or out-of-budget) point that keeps every constraint
    out_of_budget: bool = False  # the last attempt stopped at its share of the iteration budget
    timed_out: bool = False
    status: str = ""
    elapsed: float = 0.0  # wall time of the solver calls [s]
    cpu: float = 0.0  # their processor time [s]
    preparation: float = 0.0  # processor time of fresh solver objects [s]
    build: float = 0.0  # processor time of solver objects built for a new cap while the step waited [s]
    iterations: int = 0
