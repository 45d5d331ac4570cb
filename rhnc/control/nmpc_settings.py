"""What the NMPC is asked and what it answers: its settings and the outcome of one control step.

:class:`NMPCSettings` gathers the horizon, solver, limits, weights, scaling and collision
domains of :class:`rhnc.control.nmpc.NMPCController` (the module docstring of :mod:`rhnc.control.nmpc`
explains the scaling the weights act on); :class:`NMPCSolution` is what one
``solve`` returns: the applied input, the prediction and the telemetry.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from orchestrator.geometry import KNOT
from rhnc.control.nmpc_domain_settings import DomainSettings
from rhnc.control.nmpc_problem import DISTURBANCE_SIZE

#: the KCS's service speed [m/s]: the default speed bound
SERVICE_SPEED_MPS = 24.0 * KNOT

SOLVERS = ("ipopt", "fatrop", "sqpmethod", "acados")


@dataclasses.dataclass(frozen=True)
class NMPCSettings:
    """Settings of the NMPC (one object instead of many arguments).

    Attributes
    ----------
    horizon_steps : int
        N_c, number of control intervals in the horizon.
    control_interval_s : float
        delta, length of one control interval [s]; the input is held over it.
    substeps : int
        RK4 steps per control interval, also the points where collisions are checked.
    solver : str
        ``"ipopt"``, ``"fatrop"``, ``"sqpmethod"`` (CasADi's ``nlpsol``) or ``"acados"``
        (:mod:`rhnc.control.nmpc_acados`: an optional install; its SQP bounds itself by its
        iteration limit and runs in this process, the time limits are not used).
    max_iterations : int
        Iteration limit of the NLP solver (each attempt).
    iteration_budget : int or None
        Iterations of one control step, both attempts together (None: ``max_iterations``
        each): the hard attempt gets half, the relaxed one the rest, or all of it when it is
        the only attempt.  An attempt that runs out of iterations at a point that keeps
        every constraint to the solver's tolerance has found a plan (feasible, not yet
        optimal; the next step goes on from it): bounded solves at the control rate.
    cpu_time_limit_s : float or None
        Limit of the processor time of each solver attempt [s] (Linux, see
        :mod:`rhnc.control.solver_watchdog`): the worker's timer ends a solve there, wherever
        it is.  Processor time, not wall time, so that the verdict does not depend on the
        machine's load.  The default (2 s) stops runaways only; the encounter suites bound
        every solve at 0.2 s, and with an iteration budget the controller then caps the
        iterations at what fits at the processor time per iteration measured in the run
        (:mod:`rhnc.control.solve_pace`), so that a solve stops at a plan it can use.
    wall_time_limit_s : float or None
        Hard wall-time limit of one control step's solves [s], whatever the load.  Both
        None: iteration limit only, solves in this process.
    max_obstacles : int
        Obstacle slots in the problem; the nearest ones are used when more are given.
    own_radius_m : float
        R, hazard radius of own ship [m].
    q, r, r_rate : tuple of float
        Diagonals of Q (6), R (2) and R1 (2) on the scaled quantities (module docstring).
    length_scale_m : float or None
        L for positions and yaw rate; None takes ``lpp`` of the parameter set (else 230 m).
    speed_scale_mps : float
        U for surge and sway speed [m/s].
    terminal_weight : bool
        Use the DARE terminal weight P (else P = Q).
    collision_slack_weight : float or None
        Soft collision constraints as the second attempt: one slack sigma_k >= 0 per stage
        relaxes that stage's clearance constraints, at the cost ``w (sigma_k + sigma_k^2)``.
        Each step first solves the hard problem (the slacks fixed at zero by their bounds,
        the same NLP); only when that fails (an obstacle noticed too late, a target that
        closes faster than the ship can turn) it re-solves with the slacks free and returns
        the plan that violates the clearance least, instead of a fallback that ignores the
        obstacle.  (The L1 term is an exact penalty: were the hard problem feasible, the
        soft one would give the same plan.)  After a step whose plan needed the slacks, or
        whose attempts both failed, the next step solves the soft problem alone.  None: no
        slacks and no second attempt.
    max_speed_mps : float
        Upper bound of the surge speed u [m/s] (and cap of the reference speed).
    colregs : bool
        Collision domains shaped by encounter class and role (:mod:`rhnc.control.nmpc_colregs`).
    clearance_margin_m, clearance_margin_growth_mps : float
        Margin added to R + R_i [m] and its growth per second of prediction [m/s].
    stand_on_action_tcpa_s, stand_on_action_range_factor : float
        When a stand-on ship acts (Rule 17), see :class:`rhnc.control.nmpc_colregs.DomainSettings`.
    apparent_alteration_deg, give_way_action_tcpa_s : float
        The readily apparent alteration of a give-way (or acting stand-on) ship and when a
        give-way ship begins it (``alteration_deg``, ``give_way_action_tcpa_s`` of
        :class:`rhnc.control.nmpc_colregs.DomainSettings`).
    disturbance_observer : bool
        Estimate current and body-frame loads and predict with them (offset-free).
    observer_gain : float
        Fraction of the observer's correction applied per step, in (0, 1].
    codegen : bool
        Compile the NLP's functions to C once per machine and reuse the cached library
        (:mod:`rhnc.control.nmpc_codegen`: one interval's code mapped over the horizon); without a
        compiler, or with ``RHNC_NMPC_CODEGEN=0``, they stay interpreted (the same
        solutions, slower).  On by default: measured in closed loop, a compiled step takes
        about 40 % less processor time (``docs/nmpc-performance.md``).
    warm_start_duals : bool
        Start IPOPT from the previous solve's multipliers, shifted by one interval like
        the plan (``warm_start_init_point``): about half the iterations.  fatrop's
        interface takes no multipliers, so it is ignored there.
    tau_rate_max : tuple of float or None
        Largest rates of the surge force [N/s] and yaw moment [N m/s] the actuators can
        follow (from the ship's steering gear and shaft, :func:`rhnc.control.allocation.tau_rate_limits`):
        the k-th planned input stays within k intervals' worth of change from the last
        applied one, so the first, applied one never asks more than one interval's.
        None: no rate bound (only the R1 weight).
    coastline_slots : int
        Constraint slots for the nearest edges of land and no-go areas, after the
        obstacles' (default 0; :mod:`rhnc.control.nmpc_coastline`, filled once the
        controller is given a chart).
    real_time_iterations : bool
        With ``solver = "acados"``: one SQP iteration per control step (acados's SQP_RTI,
        the real-time iteration scheme) instead of iterating to convergence; each step goes
        on from the last plan, so the plan converges over the steps.  Off by default: see
        ``docs/nmpc-performance.md`` for how its closed loop compares.
    reachable_reference : bool
        Move the reference back along its path until it leads the ship by no more than the
        prediction model's speed reserve makes up over the horizon
        (:mod:`rhnc.control.reachable_reference`): for a ship whose reference speed is close
        to its top speed.  Off by default (the timed reference as it is).
    tau_u_min_N : float or None
        Smallest surge force the actuators give [N] (0 for a propeller that turns ahead only,
        as the allocation's does: the hull's drag alone slows the ship); None: the bound is
        symmetric, -tau_u_max.
    """

    horizon_steps: int = 15
    control_interval_s: float = 20.0
    substeps: int = 4
    solver: str = "fatrop"
    max_iterations: int = 200
    iteration_budget: int | None = None
    cpu_time_limit_s: float | None = 2.0
    wall_time_limit_s: float | None = 20.0
    max_obstacles: int = 4
    own_radius_m: float = 0.0
    q: tuple[float, ...] = (0.1, 0.1, 10.0, 1.0, 1.0, 1.0)
    r: tuple[float, ...] = (0.01, 0.01)
    r_rate: tuple[float, ...] = (0.01, 0.01)
    length_scale_m: float | None = None
    speed_scale_mps: float = 1.0
    terminal_weight: bool = True
    collision_slack_weight: float | None = 1.0e4
    max_speed_mps: float = SERVICE_SPEED_MPS
    colregs: bool = False
    clearance_margin_m: float = 0.0
    clearance_margin_growth_mps: float = 0.0
    stand_on_action_tcpa_s: float = 600.0
    stand_on_action_range_factor: float = 2.0
    apparent_alteration_deg: float = 35.0
    give_way_action_tcpa_s: float = 900.0
    disturbance_observer: bool = False
    observer_gain: float = 0.5
    codegen: bool = True
    warm_start_duals: bool = True
    tau_rate_max: tuple[float, float] | None = None
    coastline_slots: int = 0
    real_time_iterations: bool = False
    reachable_reference: bool = False
    tau_u_min_N: float | None = None

    def __post_init__(self) -> None:
        if self.iteration_budget is not None and not 2 <= self.iteration_budget <= self.max_iterations:
            raise ValueError(f"iteration_budget must be from 2 to max_iterations ({self.max_iterations}), "
                             f"got {self.iteration_budget}")
        if self.horizon_steps < 1:
            raise ValueError(f"horizon_steps must be >= 1, got {self.horizon_steps}")
        if self.tau_rate_max is not None and not (len(self.tau_rate_max) == 2 and min(self.tau_rate_max) > 0.0):
            raise ValueError(f"tau_rate_max must be two positive rates [N/s, N m/s], got {self.tau_rate_max}")
        if self.control_interval_s <= 0.0:
            raise ValueError(f"control_interval_s must be > 0, got {self.control_interval_s}")
        if self.substeps < 1:
            raise ValueError(f"substeps must be >= 1, got {self.substeps}")
        if self.coastline_slots < 0:
            raise ValueError(f"coastline_slots must be >= 0, got {self.coastline_slots}")
        if self.solver not in SOLVERS:
            raise ValueError(f"solver must be one of {', '.join(SOLVERS)}, got '{self.solver}'")
        if len(self.q) != 6 or len(self.r) != 2 or len(self.r_rate) != 2:
            raise ValueError("weights: q needs 6 values, r and r_rate 2 each")
        if min(self.q + self.r + self.r_rate) < 0.0:
            raise ValueError("weights must be >= 0")
        if self.collision_slack_weight is not None and not self.collision_slack_weight > 0.0:
            raise ValueError(f"collision_slack_weight must be > 0 or None, got {self.collision_slack_weight}")
        for name in ("cpu_time_limit_s", "wall_time_limit_s"):
            value = getattr(self, name)
            if value is not None and not value > 0.0:
                raise ValueError(f"{name} must be > 0 or None, got {value}")
        if not self.max_speed_mps > 0.0:
            raise ValueError(f"max_speed_mps must be > 0, got {self.max_speed_mps}")
        for name in ("clearance_margin_m", "clearance_margin_growth_mps", "stand_on_action_tcpa_s",
                     "stand_on_action_range_factor", "apparent_alteration_deg", "give_way_action_tcpa_s"):
            if getattr(self, name) < 0.0:
                raise ValueError(f"{name} must be >= 0, got {getattr(self, name)}")
        if self.real_time_iterations and self.solver != "acados":
            raise ValueError(f"real_time_iterations needs solver = 'acados', got solver = '{self.solver}'")
        if self.tau_u_min_N is not None and not math.isfinite(self.tau_u_min_N):
            raise ValueError(f"tau_u_min_N must be a finite force [N] or None, got {self.tau_u_min_N}")
        if not 0.0 < self.observer_gain <= 1.0:
            raise ValueError(f"observer_gain must be in (0, 1], got {self.observer_gain}")

    def domain_settings(self) -> DomainSettings:
        """The collision-domain part of the settings."""
        return DomainSettings(
            own_radius_m=self.own_radius_m, colregs=self.colregs, clearance_margin_m=self.clearance_margin_m,
            clearance_margin_growth_mps=self.clearance_margin_growth_mps,
            stand_on_action_tcpa_s=self.stand_on_action_tcpa_s,
            stand_on_action_range_factor=self.stand_on_action_range_factor,
            alteration_deg=self.apparent_alteration_deg, give_way_action_tcpa_s=self.give_way_action_tcpa_s,
        )


@dataclasses.dataclass(kw_only=True)
class NMPCSolution:
    """Outcome of one control step (built by keyword: fifteen fields are not read by position).

    Attributes
    ----------
    tau : numpy.ndarray
        Applied input [tau_u N, tau_r N·m].
    states : numpy.ndarray
        (N+1, 6) predicted states in SI (absolute positions), row 0 the measured state.
    inputs : numpy.ndarray
        (N, 2) planned inputs in SI.
    solve_time_s : float
        Wall time of the NLP solver calls [s].
    iterations : int
        Solver iterations.
    status : str
        Solver's return status (``wall_time_exceeded`` when stopped at the time limit).
    success : bool
        Solver reported success.
    fallback : bool
        The applied input came from the fallback, not from this solve.
    cost : float
        Optimal (or last) objective value (scaled, dimensionless); -1 when the solve left
        no finite iterate (stopped at the time limit, NaN).
    constraint_violation : float
        Largest violation of the NLP's constraints and bounds at the returned point
        (scaled); -1 when unknown, as for the cost.
    collision_slack : float
        Largest collision slack sigma of the plan (0: every clearance is kept; > 0: the
        soft constraints had to give way, see ``collision_slack_weight``).
    timed_out : bool
        The wall-time limit stopped a solve of this step.
    disturbance : numpy.ndarray
        Disturbance estimate used by the prediction (5,): current north, east [m/s],
        w_u, w_v [N], w_r [N m]; zeros with the observer off.
    encounter_classes : numpy.ndarray
        Per obstacle row: index into ``ENCOUNTER_CLASSES`` (-1: not classified).
    domain_active : numpy.ndarray
        Per obstacle row: 1 when its collision constraint was on.
    solve_cpu_time_s : float
        Processor time of the solver calls [s]: the solve's cost whatever else the machine
        runs (``solve_time_s`` is wall time, pipe to the worker included).
    preparation_cpu_s : float
        Processor time [s] spent outside the solve on new solver objects (fatrop, after a
        difficult solve: built by the worker after its answer, see
        :mod:`rhnc.control.solver_watchdog`).
    build_cpu_s : float
        Processor time [s] of solver objects built within the step for a new iteration cap
        (outside ``solve_cpu_time_s`` and its limit; part of ``step_cpu_time_s``).
    step_cpu_time_s : float
        Processor time of the whole control step [s]: the controller's own work around the
        solve (reference, domains, warm start, unpacking) in this process, plus the solver
        calls wherever they ran (the watchdog's worker's share included, with the solver
        objects it built for the step's caps; its preparation of new solver objects after an
        answer left out as in ``solve_cpu_time_s``).
    """

    tau: np.ndarray
    states: np.ndarray
    inputs: np.ndarray
    solve_time_s: float
    iterations: int
    status: str
    success: bool
    fallback: bool
    cost: float
    constraint_violation: float
    collision_slack: float = 0.0
    timed_out: bool = False
    disturbance: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(DISTURBANCE_SIZE))
    encounter_classes: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(0))
    domain_active: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(0))
    solve_cpu_time_s: float = 0.0
    preparation_cpu_s: float = 0.0
    build_cpu_s: float = 0.0
    step_cpu_time_s: float = 0.0
