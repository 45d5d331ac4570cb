"""COLREG-aware collision domains for the NMPC (Rules 8 and 13-17), as problem parameters.

Each obstacle becomes one slot of the collision constraint of :mod:`rhnc.control.nmpc_problem`:
a circle that must stay clear of the own ship's predicted track.  With ``colregs`` off
it is the paper's circle of radius R + R_i about the obstacle.  With ``colregs`` on, each
target is classified by :class:`rhnc.encounters.colregs.EncounterTracker` (the same classes, with
the same hysteresis, that the ``colregs`` analysis judges a run by) and its circle is
shaped by the own ship's role:

``head_on`` (Rule 14: both alter to starboard, pass port to port)
    The circle's centre moves ``HEAD_ON_OFFSET`` (in units of the clearance rho) to the
    target's starboard and slightly ahead of it, and the radius grows by the offset, so
    the original circle of radius rho stays inside.  Passing on the target's port side
    (after our turn to starboard) keeps the paper's clearance rho; passing on its
    starboard side costs up to rho + 2 |offset| of detour.
``crossing_give_way`` (Rules 15, 16: keep out of the way, do not cross ahead)
    The centre moves ahead of the target (``GIVE_WAY_OFFSET``): crossing its bow needs a
    much wider berth than passing under its stern.
``overtaking`` (Rule 13: keep clear of the overtaken ship)
    The centre moves a little ahead (``OVERTAKING_OFFSET``): pass clear, on either side.
``crossing_stand_on``, ``overtaken`` (Rule 17: keep course and speed)
    The constraint is off, so the NMPC tracks its reference unchanged, until the give-way
    ship's action is clearly not enough: its predicted CPA (both ships at their present
    velocities) lies inside rho and either the CPA is less than ``stand_on_action_tcpa_s``
    away or the range is below ``stand_on_action_range_factor * rho``.  From then on the
    symmetric circle is on (Rule 17(b): act to avoid collision) until the encounter ends.
    For a ship overtaking us the action may be a reduction of speed as well as, or instead
    of, a turn (:meth:`rhnc.control.nmpc_actions.ActionDecisions._stand_on_action`).
``static``, ``none``
    The symmetric circle.

No alteration to port (Rules 14, 15, 17(c)): while a head-on or crossing target whose
way we give, or a crossing target on our port side that gives way to us (whether we
stand on or have had to act), is still approaching (TCPA > 0), the predicted heading may not fall more than
``PORT_ALLOWANCE_DEG`` to port of the reference heading (nor further to port than the
measured heading, if the ship is there already).  Without it the NMPC, whose
horizon (5-15 min) sees the domain of a ship crossing from starboard come in from that
side, first turned away from it to port and only later under its stern (seen in trials);
the bound leaves turning to starboard or slowing down, which is what the rules ask.  For
a stand-on crossing target the bound holds before we act too: avoiding a second ship
must not take us to port across the bow of a ship on our port side (seen in a
two-target trial).

The turn back to port (Rule 17(c), ``colregs`` only, whether the constraints are on or not):
while a crossing target on our port side that we stand on for is still approaching, the heading
may not fall to port of the present one (keep the course, Rule 17(a)(i)); else a turn of more
than ``MANOEUVRE_DEG`` to port towards the reference (back to the route after an alteration, or
a bend of the route) goes no further than keeps every target not yet in risk from becoming a
ship crossing from port (:func:`rhnc.control.nmpc_manoeuvre.port_return_limit`).  Turning back
at once made ships 4-6 nm on the port beam ships crossing from port in the middle of the turn.

Collision risk at the control rate (``colregs`` only): the constraints are on while the
navigation's trigger is set *or* any obstacle has a risk of collision by time (a CPA inside
``risk_cpa_m`` at most ``risk_tcpa_s`` ahead) or is within ``CLOSE_QUARTERS_FACTOR``
clearances, judged at every solve.  The paper's mode (``colregs`` off) keeps the paper's
4-min distance trigger alone.  A give-way ship begins its alteration when the CPA is
``give_way_action_tcpa_s`` ahead or, sooner, when a readily apparent alteration would open
the CPA to the clearance only if begun within ``ACTION_BUFFER_S``
(:func:`rhnc.encounters.colregs.latest_alteration_s`): a fast target is acted on early
enough wherever it comes from.  A stand-on ship acts by the same measure
(:func:`rhnc.encounters.colregs.stand_on_must_act`).

A target inside its clearance rho (it started there, or came in): its domain is a plain
circle of the present range, less what the range closes in ``INSIDE_RESPONSE_S``, growing
at ``INSIDE_OPENING_MPS``: the range must open at once, by turning and slowing together
(the NMPC's speed is free down to zero).  While such a target is still closing, the
heading rules (no turn to port, the alteration's bounds) are off: immediate danger comes
first (Rules 2(b), 17(b)).  A target outside rho but with the own ship inside its shifted
domain gets the plain circle.

Why shifted circles rather than side constraints or ellipses: a circle that contains the
paper's circle never admits a plan the paper's constraint forbids, so separation >= R + R_i
still follows from feasibility; it keeps one smooth constraint per slot (no switching
logic inside the NLP, no integer side choice); and together with the warm start pushed
out of the domain on the far side from its centre (:mod:`rhnc.control.nmpc_warm_start`), the
local solver starts on, and stays on, the side the rules ask for.  It is the familiar
ship-domain picture (Fujii, Goodwin, Coldwell: larger ahead and to starboard).

Clearance rho = R + R_i + ``clearance_margin_m``, and it grows by
``clearance_margin_growth_mps`` per second of prediction: the margin that absorbs the
prediction error of wind, waves, current and model error (constraint tightening).
"""

from __future__ import annotations

import dataclasses
import logging
import math

import numpy as np

from rhnc.encounters.colregs import (ENCOUNTER_CLASSES, EncounterTracker, cpa_tcpa, stand_on_latest_s, stand_on_must_act)
from rhnc.control.nmpc_actions import STAND_ON_CLASSES, ActionDecisions
from rhnc.control.nmpc_domain_settings import DomainSettings
from rhnc.control.nmpc_manoeuvre import ManoeuvreResponse
from rhnc.control.nmpc_problem import OBSTACLE_FIELDS

LOG = logging.getLogger(__name__)

#: domain centre offsets (ahead, to starboard of the target) in units of the clearance rho
HEAD_ON_OFFSET = (0.25, 0.5)
GIVE_WAY_OFFSET = (0.5, 0.25)
OVERTAKING_OFFSET = (0.25, 0.0)
OFFSETS = {"head_on": HEAD_ON_OFFSET, "crossing_give_way": GIVE_WAY_OFFSET, "overtaking": OVERTAKING_OFFSET}
#: classes under which the own ship must not alter to port while the target approaches
STARBOARD_CLASSES = ("head_on", "crossing_give_way", "crossing_stand_on")
#: collision risk at the control rate: an obstacle closer than this many clearances rho
#: turns the collision constraints on whatever its CPA
CLOSE_QUARTERS_FACTOR = 2.0
#: a target inside its clearance rho: the domain is the present range, less what the range
#: closes at its present rate in this time [s], growing at this rate [m/s]: the range must
#: open at once, by turning and slowing together
INSIDE_RESPONSE_S = 20.0
INSIDE_OPENING_MPS = 1.0


@dataclasses.dataclass
class DomainReport:
    """Per obstacle row: its class code (index of ``ENCOUNTER_CLASSES``, -1 unclassified) and
    whether its constraint is on in this solve; the heading rules of this solve.

    ``risk``: the controller's own collision-risk assessment turned the constraints on
    (``colregs`` only; see :meth:`CollisionDomains.parameters`); ``danger``: a target is
    inside its clearance and closing; ``escape_heading``: then, the heading [rad] straight away
    from the nearest such target (its range opens fastest), else None.
    ``speed_goal_mps``: a readily apparent reduction of speed held for a ship overtaking us
    (see :meth:`rhnc.control.nmpc_actions.ActionDecisions._stand_on_action`): the speed [m/s] the plan must come down
    to, at the deceleration the ship can make, or None.
    ``speed_up_goal_mps``: speeding up held as a stand-on ship's action (a ship overtaking us,
    or one crossing from port) when nothing else kept the traffic clear (held only without a
    reduction of speed): the speed [m/s] the plan is asked to come up to, at the acceleration
    the ship can make, or None; ``speed_up_since``: then, the time [s] it began and the speed
    [m/s] it began at, where that ramp starts.
    ``alteration_floor`` / ``alteration_ceiling``: a readily apparent alteration to
    starboard / to port, as (time it began [s], heading then [rad], heading to reach
    [rad]), or None; see :func:`rhnc.control.nmpc_alteration.heading_bounds`.
    """

    class_codes: np.ndarray
    active: np.ndarray
    no_port_turn: bool = False
    alteration_floor: tuple[float, float, float] | None = None
    alteration_ceiling: tuple[float, float, float] | None = None
    risk: bool = False
    danger: bool = False
    escape_heading: float | None = None
    speed_goal_mps: float | None = None
    speed_up_goal_mps: float | None = None
    speed_up_since: tuple[float, float] | None = None


class CollisionDomains(ActionDecisions):
    """Turn the obstacles seen at a solve into the NLP's slot parameters.

    Parameters
    ----------
    settings : DomainSettings
    max_obstacles : int
        Slots of the problem; the nearest obstacles get them.
    """

    def __init__(self, settings: DomainSettings, max_obstacles: int) -> None:
        self.settings = settings
        self.max_obstacles = max_obstacles
        self.tracker = EncounterTracker(settings.risk_cpa_m, settings.risk_tcpa_s)
        self._acting: set[int] = set()
        self._guarding: set[int] = set()
        self._altering: dict[int, tuple[float, float, float, float]] = {}
        self._altered: set[int] = set()
        self._onset_heading: dict[int, float] = {}
        self._slowing: dict[int, float] = {}
        self._hastening: dict[int, tuple[float, float, float]] = {}
        #: how fast the own ship takes up a manoeuvre, for choosing one (the NMPC sets its ship's)
        self.response = ManoeuvreResponse()
        self.stand_on_actions = 0
        self.alterations = 0

    def reset(self) -> None:
        """Forget classes, Rule 17 decisions and alterations."""
        self.tracker = EncounterTracker(self.settings.risk_cpa_m, self.settings.risk_tcpa_s)
        self._acting = set()
        self._guarding = set()
        self._altering = {}
        self._altered = set()
        self._onset_heading = {}
        self._slowing = {}
        self._hastening = {}

    def parameters(self, obstacles: np.ndarray | None, state: np.ndarray, origin: np.ndarray, closing_speed_mps: float,
                   substep_s: float, length_scale_m: float, et: bool, reference_heading_rad: float | None = None,
                   horizon_s: float | None = None, time_s: float = 0.0) -> tuple[np.ndarray, DomainReport]:
        """Slot parameters (OBSTACLE_FIELDS x max_obstacles, scaled) and the per-row report.

        Parameters
        ----------
        obstacles : (n, 5) array or None
            x, y [m], vx, vy [m/s], radius [m] at the solve.
        state : (6,) array
            Measured own state [SI].
        origin : (2,) array
            Position the scaled problem is measured from [m].
        closing_speed_mps : float
            Own speed bound used for the chord inflation [m/s].
        substep_s : float
            Time between collision checks [s].
        length_scale_m : float
            L [m].
        et : bool
            Event trigger: constraints on.
        reference_heading_rad : float, optional
            The reference's heading now [rad]: a readily apparent alteration is measured
            from it (default: the measured heading).
        horizon_s : float, optional
            Prediction horizon [s]: an obstacle that cannot reach its domain within it,
            whatever either ship does at its present speed, gets no slot (default: every
            obstacle gets one).
        time_s : float
            Time of the solve [s] (when an alteration begins).
        """
        s = self.settings
        slots = np.zeros((OBSTACLE_FIELDS, self.max_obstacles))
        slots[6, :] = 1.0  # harmless radius for inactive slots
        rows = np.zeros((0, 5)) if obstacles is None else np.atleast_2d(np.asarray(obstacles, dtype=float))
        active_rows = np.zeros(len(rows))
        if len(rows) == 0:
            return slots, DomainReport(np.zeros(0), active_rows)
        own_course = float(state[2] + math.atan2(state[4], state[3]))
        own_speed = float(math.hypot(state[3], state[4]))
        classes, codes = self._classify(rows, state[:2], own_course, own_speed, float(state[2]))
        return_floor = self._return_floor(rows, classes, state, own_course, own_speed, reference_heading_rad, time_s)
        rhos = s.own_radius_m + rows[:, 4] + s.clearance_margin_m
        own_velocity = own_speed * np.array([math.cos(own_course), math.sin(own_course)])
        risk = s.colregs and self._collision_risk(rows, rhos, state[:2], own_velocity)
        if not (et or risk):
            return slots, DomainReport(codes, active_rows, alteration_floor=return_floor)
        order = self._nearest(rows, rhos, origin)
        ranges, range_rates, inside, danger = self._closing(rows, rhos, state[:2], own_velocity, order)
        heading_now = float(state[2]) if reference_heading_rad is None else float(reference_heading_rad)
        no_port_turn = not danger and _port_turn_ruled_out(classes, order)
        # every target, for the side of an alteration the rules leave free (Rule 13)
        traffic = [(rows[j, :2], rows[j, 2:4], s.own_radius_m + rows[j, 4] + s.clearance_margin_m)
                   for j in range(len(rows))]
        altering = bool(self._altering)
        slot = 0
        for i in order:
            encounter = classes[i]
            name = encounter.encounter_class if encounter is not None else "static"
            if name in STAND_ON_CLASSES and not self._stands_clear(i, encounter, rows[i], state[:2], own_velocity,
                                                                   i in inside, altering):
                continue  # keep course and speed: this target's constraint stays off
            if s.colregs and encounter is not None:
                self._update_alteration(i, encounter, heading_now, float(state[2]), time_s,
                                        s.own_radius_m + rows[i, 4],
                                        (state[:2], own_speed, rows[i, :2], rows[i, 2:4], own_velocity),
                                        port_allowed=not no_port_turn, traffic=traffic, yaw_rate_rps=float(state[5]))
            offset, domain_radius, growth_mps = self._domain(rows[i], rhos[i], name, state[:2], ranges[i],
                                                             range_rates[i], i in inside)
            closing = closing_speed_mps + math.hypot(rows[i, 2], rows[i, 3])
            if horizon_s is not None and self._out_of_reach(rows[i], offset, domain_radius, state, closing, horizon_s):
                continue  # out of reach within the horizon: no constraint needed
            if slot >= self.max_obstacles:
                continue
            slots[:, slot] = _slot_column(rows[i], origin, offset, domain_radius, growth_mps,
                                          (closing * substep_s / (2.0 * domain_radius)) ** 2, length_scale_m)
            active_rows[i] = 1.0
            slot += 1
        floor, ceiling = self._alteration_bounds(danger, no_port_turn)
        if return_floor is not None and not danger and ceiling is None and (floor is None or return_floor[2] > floor[2]):
            floor = return_floor
        return slots, DomainReport(codes, active_rows, no_port_turn, floor, ceiling,
                                   bool(risk and not et), danger, _escape_heading(rows, rhos, state, range_rates, inside),
                                   min(self._slowing.values()) if self._slowing and not danger else None,
                                   *self._speed_up(danger))

    def _speed_up(self, danger: bool) -> tuple[float | None, tuple[float, float] | None]:
        """The speeding up held, as ``DomainReport.speed_up_goal_mps`` and ``speed_up_since``: the
        fastest asked for, from when and what speed it began (None, None: none held, or a
        reduction of speed held, or danger)."""
        if not self._hastening or self._slowing or danger:
            return None, None
        goal, since_s, from_mps = max(self._hastening.values())
        return goal, (since_s, from_mps)

    def _out_of_reach(self, row: np.ndarray, offset: np.ndarray, domain_radius: float, state: np.ndarray,
                      closing_mps: float, horizon_s: float) -> bool:
        """True when the target's domain cannot be reached within the horizon, whatever either
        ship does at its present speed."""
        centre = row[:2] + offset
        return bool(np.hypot(*(centre - state[:2])) - closing_mps * horizon_s
                    > domain_radius + self.settings.clearance_margin_growth_mps * horizon_s)

    def reference_turns(self, reference_heading_rad: float, heading_rad: float) -> float:
        """Whole turns [rad, a multiple of 2 pi] to take off the reference heading: the one within
        half a turn of the measured heading, or, while an alteration is held, of the heading it
        is measured from (its goal less the alteration), brought within half a turn of the
        measured heading.  A ship turned more than half a turn to starboard of its reference
        (a stand-on ship's hard turn away, 173 deg off a reference at -9 deg) keeps its
        reference on the side it turned from: taken nearest the measured heading, it jumped a
        full turn ahead, and the no-port-turn bound (no lower than the reference less the
        allowance, or the measured heading) then forbade the turn back, from a warm start that
        made it (the budgeted solve fell back twice)."""
        anchor = heading_rad
        floor, ceiling = self._alteration_bounds(False, False)
        held = floor if floor is not None else ceiling
        if held is not None:
            goal = held[2] - 2.0 * math.pi * round((held[2] - heading_rad) / (2.0 * math.pi))
            anchor = goal - math.copysign(math.radians(self.settings.alteration_deg), 1.0 if floor is not None else -1.0)
        return 2.0 * math.pi * round((reference_heading_rad - anchor) / (2.0 * math.pi))

    def _closing(self, rows: np.ndarray, rhos: np.ndarray, own_xy, own_velocity, order: list[int]):
        """Ranges [m] and range rates [m/s] of the rows, the rows inside their clearance
        (``colregs``), and whether one of those is closing: immediate danger, the range must
        open at once (Rules 2(b), 17(b): the heading rules give way to it)."""
        ranges = np.hypot(rows[:, 0] - own_xy[0], rows[:, 1] - own_xy[1])
        range_rates = np.array([(row[:2] - own_xy) @ (row[2:4] - own_velocity) / max(r, 1e-9)
                                for row, r in zip(rows, ranges)])
        inside = {i for i in order if self.settings.colregs and ranges[i] < rhos[i]}
        return ranges, range_rates, inside, any(range_rates[i] < 0.0 for i in inside)

    def _alteration_bounds(self, danger: bool, no_port_turn: bool) -> tuple[tuple | None, tuple | None]:
        """The alteration to starboard (floor) or, failing one, to port (ceiling) the plan
        must hold: (time it began, heading then, heading to reach) or None; none in danger."""
        floors = [a[:3] for a in self._altering.values() if a[3] > 0]
        ceilings = [a[:3] for a in self._altering.values() if a[3] < 0]
        floor = max(floors, key=lambda a: a[2]) if floors and not danger else None
        ceiling = (min(ceilings, key=lambda a: a[2]) if ceilings and floor is None and not no_port_turn
                   and not danger else None)
        return floor, ceiling

    def _classify(self, rows: np.ndarray, own_xy, own_course: float, own_speed: float, heading: float = 0.0):
        """Encounter per row (None without ``colregs``) and the class codes; forget the
        decisions of encounters the tracker released; note the ``heading`` at each onset of risk."""
        classes = [None] * len(rows)
        codes = np.full(len(rows), -1.0)
        if not self.settings.colregs:
            return classes, codes
        for index, encounter in enumerate(self.tracker.update(own_xy, own_course, own_speed, rows)):
            classes[index] = encounter
            codes[index] = ENCOUNTER_CLASSES.index(encounter.encounter_class)
        locked = set(self.tracker.locked)
        self._acting &= locked
        self._guarding &= locked
        self._altered &= locked
        self._altering = {i: v for i, v in self._altering.items() if i in locked}
        self._onset_heading = {i: v for i, v in self._onset_heading.items() if i in locked}
        self._slowing = {i: v for i, v in self._slowing.items() if i in locked}
        self._hastening = {i: v for i, v in self._hastening.items() if i in locked}
        for i in locked:  # the heading at the onset of risk, once per encounter
            self._onset_heading.setdefault(i, heading)
        return classes, codes

    def _nearest(self, rows: np.ndarray, rhos: np.ndarray, origin) -> list[int]:
        """Rows by distance from ``origin``, at most ``max_obstacles``, without zero domains."""
        distance = np.hypot(rows[:, 0] - origin[0], rows[:, 1] - origin[1]) - rows[:, 4]
        order = np.argsort(distance)
        if len(order) > self.max_obstacles:
            LOG.warning("%d obstacles given, NMPC uses the %d nearest", len(order), self.max_obstacles)
            order = order[: self.max_obstacles]
        return [int(i) for i in order if rhos[i] > 0.0]  # a zero domain needs no constraint

    def _stands_clear(self, i: int, encounter, row: np.ndarray, own_xy, own_velocity, inside: bool,
                      altering: bool) -> bool:
        """A stand-on target: whether its constraint is on (Rule 17(b) lets the ship act, or it
        keeps clear of it while altering for another target); False: keep course and speed."""
        s = self.settings
        if i in self._acting:
            return True
        x, y, vx, vy, radius = row
        cpa, tcpa = cpa_tcpa(own_xy, own_velocity, (x, y), (vx, vy))
        latest = stand_on_latest_s(encounter.encounter_class, encounter.relative_bearing_deg, own_xy, own_velocity,
                                   (x, y), (vx, vy), s.own_radius_m + radius)
        if inside or stand_on_must_act(cpa, tcpa, encounter.range_m, s.own_radius_m + radius,
                                       s.stand_on_action_tcpa_s, s.stand_on_action_range_factor, latest):
            LOG.info("Rule 17: target %d (%s) is not giving way enough (CPA %.0f m, TCPA %.0f s): acting",
                     i, encounter.encounter_class, cpa, tcpa)
            self._acting.add(i)
            self.stand_on_actions += 1
            return True
        if altering or i in self._guarding:
            # the own ship has left its course and speed for another target (it gives way to
            # it, or acts as stand-on ship for it: the analysis's Rule 17 allows both): keep
            # clear of this one too, for the rest of the encounter, or the alteration, and the
            # return to the route after it, may carry the ship into it (a turn away from a ship
            # overtaking from astern took it towards a faster one on the other quarter)
            self._guarding.add(i)
            return True
        return False

    def _domain(self, row: np.ndarray, rho: float, name: str, own_xy, range_m: float, range_rate: float,
                inside: bool) -> tuple[np.ndarray, float, float]:
        """Centre offset [m], radius [m] and growth [m/s] of one target's domain."""
        offset = np.zeros(2)
        if inside:
            # no shifted domain: the present range, less what it closes in the response
            # time, and growing: the range opens at once
            return offset, max(range_m + min(range_rate, 0.0) * INSIDE_RESPONSE_S, 0.25 * range_m), INSIDE_OPENING_MPS
        x, y, vx, vy, _ = row
        if name in OFFSETS:
            ahead = np.array([vx, vy]) / math.hypot(vx, vy)
            starboard = np.array([-ahead[1], ahead[0]])
            forward, side = OFFSETS[name]
            offset = rho * (forward * ahead + side * starboard)
            if np.hypot(*(np.array([x, y]) + offset - own_xy)) < rho + float(np.hypot(*offset)):
                offset = np.zeros(2)  # already inside the shifted domain: the plain circle
        return offset, rho + float(np.hypot(*offset)), self.settings.clearance_margin_growth_mps

    def _collision_risk(self, rows: np.ndarray, rhos: np.ndarray, own_xy, own_velocity) -> bool:
        """Collision risk by time as well as range, at every solve (``colregs``).

        Any obstacle whose CPA, both ships at their present velocities, lies inside
        ``risk_cpa_m`` and at most ``risk_tcpa_s`` ahead, or that is within
        ``CLOSE_QUARTERS_FACTOR`` clearances, turns the collision constraints on, whatever
        the navigation's distance trigger says (it looks every 4 min, and a target closing at
        40 kn covers 2.7 nm between two looks).  Which obstacles get a constraint is then
        decided by whether they can reach their domain within the horizon.
        """
        s = self.settings
        for row, rho in zip(rows, rhos):
            range_m = math.hypot(row[0] - own_xy[0], row[1] - own_xy[1])
            if range_m < CLOSE_QUARTERS_FACTOR * rho:
                return True
            cpa, tcpa = cpa_tcpa(own_xy, own_velocity, row[:2], row[2:4])
            if cpa < s.risk_cpa_m and 0.0 < tcpa <= s.risk_tcpa_s:
                return True
        return False

def _slot_column(row: np.ndarray, origin: np.ndarray, offset: np.ndarray, domain_radius: float, growth_mps: float,
                 inflation: float, length_scale_m: float) -> list[float]:
    """One obstacle slot (OBSTACLE_FIELDS values), lengths scaled by L: position from the
    origin, velocity, domain offset, radius and growth, chord inflation, active flag."""
    x, y, vx, vy, _ = row
    L = length_scale_m
    return [(x - origin[0]) / L, (y - origin[1]) / L, vx / L, vy / L, offset[0] / L,
            offset[1] / L, domain_radius / L, growth_mps / L, inflation, 1.0]


def _port_turn_ruled_out(classes, order) -> bool:
    """Rules 14, 15, 17(c): no alteration to port while a head-on or crossing target's CPA is
    ahead; known before any alteration begins, so that an overtaking ship's turns to starboard
    then."""
    return any(classes[i] is not None and classes[i].encounter_class in STARBOARD_CLASSES
               and classes[i].tcpa_s > 0.0 for i in order)


def _escape_heading(rows: np.ndarray, rhos: np.ndarray, state: np.ndarray, range_rates: np.ndarray,
                    inside) -> float | None:
    """The heading [rad] straight away from the nearest target (range less clearance) inside its
    clearance and closing (its range opens fastest), or None when there is none."""
    closing_inside = [i for i in inside if range_rates[i] < 0.0]
    if not closing_inside:
        return None
    nearest = min(closing_inside, key=lambda i: math.hypot(*(rows[i, :2] - state[:2])) - rhos[i])
    return math.atan2(state[1] - rows[nearest, 1], state[0] - rows[nearest, 0])
