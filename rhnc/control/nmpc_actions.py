"""The readily apparent actions of the COLREG-aware NMPC (Rules 8, 13-17), target by target.

:class:`ActionDecisions` is the part of :class:`rhnc.control.nmpc_colregs.CollisionDomains` that
decides, at every solve, when a give-way ship's alteration begins and when it ends, to which side
and how large, whether the speed comes down with it or alone, or, for a stand-on ship overtaken
by another that does not keep clear and left no other way, goes up, and how far a turn back to
port may go (Rule 17(c)).  The
domains module turns those decisions into the NMPC's heading and speed bounds.
"""

from __future__ import annotations

import logging
import math

import numpy as np

from orchestrator.geometry import wrap_angle
from rhnc.control.nmpc_domain_settings import DomainSettings
from rhnc.control.nmpc_manoeuvre import (ManoeuvreResponse, closing_on_the_port_side, port_return_limit,
                                         response_clearance_m, side_clearance_m)
from rhnc.encounters.colregs import ACTION_BUFFER_S, cpa_tcpa, latest_alteration_s

LOG = logging.getLogger(__name__)

STAND_ON_CLASSES = ("crossing_stand_on", "overtaken")
#: how far to port of the reference heading the plan may go while that holds [deg]
PORT_ALLOWANCE_DEG = 2.0
#: a ship turning away from its reference by this much has begun a manoeuvre [deg] (the
#: analysis's threshold of a change of course)
MANOEUVRE_DEG = 5.0
#: the alteration ends when the target is past (TCPA <= 0) and this many R + R_i away
ALTERATION_CLEAR_FACTOR = 2.0
#: ... or, held at least this long [s], when the target no longer closes (TCPA <= 0, or the
#: range closing slower than ``ALONGSIDE_CLOSING_MPS`` [m/s]) and a return to the reference
#: keeps every target clear, taken up as the ship can (a ship staying alongside)
ALTERATION_MIN_HOLD_S = 300.0
ALONGSIDE_CLOSING_MPS = 0.05
#: classes in which the own ship gives way (Rules 13-16)
GIVE_WAY_CLASSES = ("head_on", "crossing_give_way", "overtaking")
#: a readily apparent reduction of speed brings it to this fraction of the speed at its
#: beginning (the analysis reads a reduction of at least half as readily apparent)
SLOW_FACTOR = 0.45
#: a stand-on ship weighs speeding up to its top speed only when that is at least this much faster
SPEED_UP_MIN_GAIN = 0.05
#: the larger turns weighed when no readily apparent one keeps the traffic clear [deg]
LARGER_ALTERATIONS_DEG = (60.0, 90.0)
#: the floor of a turn back to port held short (:meth:`ActionDecisions._return_floor`) is
#: dated this far back [s]: its ramp (of no size) has long reached it
RETURN_FLOOR_AGE_S = 3600.0


class ActionDecisions:
    """The decisions of readily apparent actions, per target row, kept between solves (the state
    :class:`rhnc.control.nmpc_colregs.CollisionDomains` initialises and resets)."""

    settings: DomainSettings
    response: ManoeuvreResponse
    alterations: int
    _acting: set[int]
    _altering: dict[int, tuple[float, float, float, float]]
    _altered: set[int]
    _onset_heading: dict[int, float]
    _slowing: dict[int, float]
    _hastening: dict[int, tuple[float, float, float]]  # speed asked for [m/s], since [s], from [m/s]

    def _return_floor(self, rows: np.ndarray, classes, state: np.ndarray, own_course: float, own_speed: float,
                      reference_heading_rad: float | None, time_s: float) -> tuple[float, float, float] | None:
        """The heading floor (as an alteration to starboard already made: time, heading, heading)
        that keeps a turn to port back to the reference from making a ship crossing from port one
        we stand on for with that turn under way (Rule 17(c)), or None (``colregs`` with
        alterations only).

        While a ship crossing from port that we stand on for is still in risk of collision (its CPA
        at the present velocities within ``risk_cpa_m`` and ``risk_tcpa_s`` ahead), no turn to port
        at all: keep the course (Rule 17(a)(i)).  Else, a turn to port of more than
        ``MANOEUVRE_DEG`` towards the reference goes only as far as
        :func:`rhnc.control.nmpc_manoeuvre.port_return_limit` allows for the targets in no risk of
        collision: those not classified yet and those we stand on for that our course has taken
        out of risk.  The bound is a floor like an alteration's, and yields to immediate danger.

        Holding the course for as long as such a ship was still to pass (TCPA > 0, the CPA
        anywhere) trapped a ship that had turned to starboard for another target: beside two
        ships crossing from port, 3 nm off and no longer in risk, it kept a course parallel to
        theirs for 75 minutes while its speed fell, and arrived 73 minutes late.
        """
        s = self.settings
        if not s.colregs or s.alteration_deg <= 0.0 or reference_heading_rad is None or own_speed < 1.0:
            return None
        drift = own_course - float(state[2])
        reference_course = reference_heading_rad + drift
        if wrap_angle(reference_course - own_course) > -math.radians(MANOEUVRE_DEG):
            return None
        standing_on = [c is not None and c.encounter_class == "crossing_stand_on" and c.tcpa_s > 0.0 for c in classes]
        if any(on and c.cpa_m <= s.risk_cpa_m and c.tcpa_s <= s.risk_tcpa_s for on, c in zip(standing_on, classes)):
            limit: float | None = own_course
        else:
            free = [(rows[j, :2], rows[j, 2:4]) for j, c in enumerate(classes)
                    if c is not None and (c.encounter_class == "none" or standing_on[j])]
            limit = port_return_limit(state[:2], own_speed, own_course, reference_course, free, s.risk_cpa_m,
                                      s.risk_tcpa_s)
        if limit is None:
            return None
        heading = limit - drift
        return time_s - RETURN_FLOOR_AGE_S, heading, heading


    def _update_alteration(self, index: int, encounter, reference_heading_rad: float, heading_rad: float,
                           time_s: float, separation_m: float, motion=None, port_allowed: bool = True,
                           traffic=(), yaw_rate_rps: float = 0.0) -> None:
        """Begin, keep or end the readily apparent alteration for one target (Rules 8, 16, 17).

        A give-way ship begins it once the target's CPA is at most
        ``give_way_action_tcpa_s`` ahead, predicted at the present velocities or with the
        own ship already on the altered course (whichever comes first: turning away brings
        the CPA forward, an overtaking ship's CPA most, as it closes slowly), or as soon as
        the ship, holding no other alteration, turns away from its reference by
        ``MANOEUVRE_DEG`` (the NMPC has begun to give way by itself: held to a readily
        apparent alteration, not left at the 12-20 deg that opened the CPA just enough, a
        succession of small alterations Rule 8(b) asks to avoid); a stand-on ship once it acts (Rule 17(b)).  It is
        to starboard, except when overtaking or being overtaken, where either side is
        allowed (Rule 13): then it continues a turn the plan has already begun (more than
        ``PORT_ALLOWANCE_DEG`` off the reference; when overtaken, only while another alteration
        is held), else it turns away from the other ship;
        to starboard, though, when ``port_allowed`` is false (another target's Rule 14, 15
        or 17(c) rules out a turn to port: a port alteration would be dropped, and with it
        the give-way action).  Where the side is free (Rule 13), it is the one that keeps
        away from this target unless that side takes the own ship, on the altered course,
        into a clearance of ``traffic`` ((position, velocity, clearance) per target) and the
        other side does not (:func:`side_clearance_m`): turning away from a ship overtaking
        from astern took the own ship into a faster one on the other quarter.  Only then: a
        side chosen for the least intrusion alone turned a ship away from a target it gave
        way to to starboard.  It ends, for the rest of the encounter, when the target is
        past and clear (Rule 13(d)): TCPA <= 0 and the range at least
        ``ALTERATION_CLEAR_FACTOR`` times R + R_i (``separation_m``).  Ending it at TCPA <= 0 alone let a ship alongside an overtaken
        target, 1.3 nm off, turn back towards it, and the solver failed from that warm
        start; holding it until the tracker's 4 nm release made long detours.  A target that
        stays alongside never gets that far: an alteration held at least
        ``ALTERATION_MIN_HOLD_S`` also ends once the target no longer closes and a return to the
        reference keeps every target clear (:meth:`_resumes_clear`).  A ship that stood on
        for a ship crossing from port, which then kept our course and speed 1.05 nm off, held
        its alteration for an hour and arrived late.
        """
        s = self.settings
        if s.alteration_deg <= 0.0 or index in self._altered:
            return
        if index in self._altering or index in self._slowing or index in self._hastening:
            past = encounter.tcpa_s <= 0.0 and encounter.range_m >= ALTERATION_CLEAR_FACTOR * separation_m
            if past or self._resumes_clear(index, encounter, reference_heading_rad, time_s, motion, traffic):
                self._altering.pop(index, None)  # past and clear
                self._slowing.pop(index, None)
                self._hastening.pop(index, None)
                self._altered.add(index)
            return
        name = encounter.encounter_class
        if name not in GIVE_WAY_CLASSES and name not in STAND_ON_CLASSES:
            return
        side = 1.0
        deviation = math.degrees(wrap_angle(heading_rad - reference_heading_rad))
        # turning away from the reference (not back to it) by more than a manoeuvre
        manoeuvring = (not self._altering and abs(deviation) >= MANOEUVRE_DEG
                       and deviation * yaw_rate_rps > 0.0)
        if name in ("overtaking", "overtaken"):
            side = self._free_side(encounter, deviation, reference_heading_rad, motion, traffic, port_allowed)
        size, speed = s.alteration_deg, 1.0
        if name == "overtaken" and index in self._acting and encounter.tcpa_s > 0.0 and motion is not None and traffic:
            side, size, speed = self._stand_on_action(side, port_allowed, reference_heading_rad, motion, traffic)
        if side == 0.0:  # a change of speed alone
            self._begin_speed_change(index, encounter, motion[1], speed, time_s)
            return
        goal = self._alteration_goal(index, reference_heading_rad, side, size)
        if name in GIVE_WAY_CLASSES:
            begin = ((self._give_way_due(encounter, goal, side, separation_m, motion) or manoeuvring)
                     and encounter.tcpa_s > 0.0 and encounter.cpa_m < s.risk_cpa_m)
        else:
            begin = index in self._acting and encounter.tcpa_s > 0.0
        if not begin:
            return
        # a stand-on ship overtaken has chosen among the traffic above; one crossing ahead of a
        # ship from port chooses here, to starboard (Rule 17(c)), as a give-way ship does
        if (name in GIVE_WAY_CLASSES or name == "crossing_stand_on") and motion is not None and len(traffic) > 1:
            side, size, speed = self._action_among_traffic(index, name, side, goal, reference_heading_rad, motion,
                                                           traffic)
            if side == 0.0:
                self._begin_speed_change(index, encounter, motion[1], speed, time_s)
                return
            goal = self._alteration_goal(index, reference_heading_rad, side, size)
        self._altering[index] = (time_s, heading_rad, goal, side)
        if speed != 1.0:
            self._change_speed(index, motion[1], speed, time_s)
        self.alterations += 1
        LOG.info("target %d (%s): altering %.0f deg to %s%s (CPA %.0f m in %.0f s)", index, name, size,
                 "starboard" if side > 0 else "port",
                 "" if speed == 1.0 else " and slowing" if speed < 1.0 else " and speeding up", encounter.cpa_m,
                 encounter.tcpa_s)

    def _resumes_clear(self, index: int, encounter, reference_heading_rad: float, time_s: float, motion,
                       traffic) -> bool:
        """Whether the alteration held for target ``index`` (for ``ALTERATION_MIN_HOLD_S`` at
        least) may end before the target is past and clear: it no longer closes on us (TCPA <= 0,
        or the range closing slower than ``ALONGSIDE_CLOSING_MPS``) and the turn back to the
        reference at the present speed keeps the whole ``traffic`` clear (:meth:`_clearance`)."""
        held = self._altering.get(index)
        if held is None or motion is None or not traffic or time_s - held[0] < ALTERATION_MIN_HOLD_S:
            return False
        own_xy, _, target_xy, target_velocity, own_velocity = motion
        relative = np.asarray(target_xy, dtype=float) - np.asarray(own_xy, dtype=float)
        range_rate = float(relative @ (np.asarray(target_velocity, dtype=float) - own_velocity)) / max(
            float(np.hypot(*relative)), 1.0)
        if encounter.tcpa_s > 0.0 and range_rate < -ALONGSIDE_CLOSING_MPS:
            return False
        return self._clearance(motion, reference_heading_rad, 1.0, traffic) >= 0.0

    def _alteration_goal(self, index: int, reference_heading_rad: float, side: float, size_deg: float) -> float:
        """The heading [rad] an alteration of ``size_deg`` to ``side`` holds: off the reference,
        and at least ``alteration_deg`` off the heading the ship had at the target's onset of risk."""
        goal = reference_heading_rad + side * math.radians(size_deg)
        onset = self._onset_heading.get(index)
        if onset is not None:
            # at least the alteration from the heading the ship had at the onset of risk, the
            # course the other ship saw: a reference pointing back to the route after an
            # earlier detour (or a turn under way at the onset) left alterations of 20-28 deg
            # of course over ground from it, not readily apparent (Rule 8(b))
            beyond = wrap_angle(onset + side * math.radians(self.settings.alteration_deg) - goal)
            if side * beyond > 0.0:
                goal += beyond
        return goal

    def _free_side(self, encounter, deviation_deg: float, reference_heading_rad: float, motion, traffic,
                   port_allowed: bool) -> float:
        """The side (+1 starboard, -1 port) of an alteration Rule 13 leaves free: overtaking or
        being overtaken.

        A turn the plan has begun is an avoiding one when overtaking (the constraint is on) or
        while another alteration is held; a stand-on ship that has kept its course has begun
        none: its deviation is the way back to the route, and continuing it turned a ship
        towards the overtaker it acted for (0.85 nm).  Else away from the other ship (pass it on
        its port side when it is on our starboard side), unless the other side keeps the whole
        traffic clearer.  To starboard whenever a turn to port is ruled out."""
        if abs(deviation_deg) > PORT_ALLOWANCE_DEG and (encounter.encounter_class == "overtaking" or self._altering):
            side = math.copysign(1.0, deviation_deg)
        else:
            side = -1.0 if encounter.relative_bearing_deg > 0.0 else 1.0
            if motion is not None and traffic:
                alteration = math.radians(self.settings.alteration_deg)
                clearance = {turn: side_clearance_m(motion[0], motion[1], reference_heading_rad + turn * alteration,
                                                    traffic) for turn in (side, -side)}
                if clearance[side] < 0.0 <= clearance[-side]:
                    side = -side
        return side if port_allowed else 1.0

    def _change_speed(self, index: int, own_speed_mps: float, factor: float, time_s: float) -> None:
        """Hold a change of speed to ``factor`` of ``own_speed_mps`` for a target: a readily
        apparent reduction (``SLOW_FACTOR``), or speeding up (to the top speed), which keeps the
        time ``time_s`` [s] and the speed it began at (its ramp runs from them)."""
        if factor < 1.0:
            self._slowing[index] = factor * own_speed_mps
        else:
            self._hastening[index] = (factor * own_speed_mps, time_s, own_speed_mps)

    def _begin_speed_change(self, index: int, encounter, own_speed_mps: float, factor: float,
                            time_s: float) -> None:
        """Hold a change of speed alone for a target (:meth:`_change_speed`)."""
        self._change_speed(index, own_speed_mps, factor, time_s)
        self.alterations += 1
        LOG.info("target %d (%s): %s to %.0f %% of the speed (CPA %.0f m in %.0f s)", index, encounter.encounter_class,
                 "slowing" if factor < 1.0 else "speeding up", 100.0 * factor, encounter.cpa_m, encounter.tcpa_s)

    def _clearance(self, motion, course_rad: float, factor: float, traffic) -> float:
        """The least clearance [m] from ``traffic`` of a manoeuvre to ``course_rad`` at ``factor``
        of the present speed, taken up as the ship can (``self.response``).  Speeding up is
        followed past the risk window to the end of the encounter: ahead of a ship faster still,
        it only puts the closest approach off (two ships coming up on both quarters, one nm in
        half an hour, scored it the clearest of all)."""
        own_xy, own_speed, _, _, own_velocity = motion
        heading = math.atan2(own_velocity[1], own_velocity[0])
        return response_clearance_m(own_xy, own_speed, heading, course_rad, factor * own_speed, traffic,
                                    self.response, beyond=factor > 1.0)

    def _action_among_traffic(self, index: int, name: str, side: float, goal: float, reference_heading_rad: float,
                              motion, traffic) -> tuple[float, float, float]:
        """The readily apparent action of a give-way ship among other traffic (Rules 8, 16), or
        of a ship standing on for one crossing from port that acts (Rule 17(b)): the turn to
        ``goal`` at the present speed when it keeps every other target clear; else the first of
        the manoeuvres :meth:`_choose` weighs, to the same side, that keeps the whole traffic
        clear (not the reduction of speed alone for a head-on ship: Rule 14 asks for a turn to
        starboard; nor for the stand-on ship, whose slowing takes it into the path of a give-way
        ship passing astern of it; speeding up only for the stand-on ship).  Returns (``side``, or 0 for no
        turn; size of the turn [deg]; the speed to take, as a factor of the present one).

        A turn to starboard for a ship crossing ahead, with a faster ship converging from the
        starboard quarter, took the own ship across the faster ship's bow (0.75 nm): the 35 deg
        turn alone is what the rules ask of a ship with nobody else about.  The same for a ship
        standing on for one crossing from port, with a ship coming up slowly on its starboard
        quarter: the plain turn to starboard took it across the overtaker's course (0.86 nm)."""
        others = [target for j, target in enumerate(traffic) if j != index]
        if self._clearance(motion, goal, 1.0, others) >= 0.0:
            return side, self.settings.alteration_deg, 1.0
        return self._choose((side,), name not in ("head_on", "crossing_stand_on"), reference_heading_rad, motion,
                            traffic, speed_up=name == "crossing_stand_on")

    def _stand_on_action(self, side: float, port_allowed: bool, reference_heading_rad: float, motion,
                         traffic) -> tuple[float, float, float]:
        """The readily apparent action of a ship overtaken by another that does not keep clear
        (Rule 17(b)): the first of the manoeuvres :meth:`_choose` weighs, to each side the rules
        allow (``side``, the one chosen above, first), that keeps the traffic clear, speeding up
        among them.  Returns (side of the turn, 0 for none; size of the turn [deg]; the speed to
        take, as a factor of the present one).

        A ship overtaking us is faster and, converging from a quarter, crosses our course
        ahead of us: a 35 deg turn alone, to the side another target leaves us (a head-on
        ship ahead rules out a turn to port), kept it converging, and the plan then raced it
        (18 -> 23 kn) and lost the clearance (15 of 28 such targets).  Slowing lets it pass
        ahead; the speed is a manoeuvre Rules 8(e) and 17 name.  No turn to port is weighed
        while another ship forward of our port quarter closes on us, classified yet or not: it
        may become a ship crossing from port, for which Rule 17(c) rules out that turn (a turn to
        port chosen for the clearance broke it twice).

        Speeding up is weighed last: a ship coming up slowly from the starboard quarter,
        converging, with a ship crossing from port ruling out the turn to port, left no turn
        nor reduction of speed that kept it clear (0.86 nm), where holding the course at the
        top speed kept every target clear."""
        if not port_allowed or closing_on_the_port_side(motion[0], motion[1], reference_heading_rad, traffic):
            turns: tuple[float, ...] = (1.0,)
        else:
            turns = (side, -side)
        return self._choose(turns, True, reference_heading_rad, motion, traffic, speed_up=True)

    def _choose(self, sides: tuple[float, ...], slow_alone: bool, reference_heading_rad: float, motion,
                traffic, speed_up: bool = False) -> tuple[float, float, float]:
        """Of the manoeuvres, in this order: a turn of ``alteration_deg`` to each of ``sides`` at
        the present speed, the same turns with the speed brought down to ``SLOW_FACTOR`` of it, the
        reduction of speed alone (if ``slow_alone``), then the larger turns of
        ``LARGER_ALTERATIONS_DEG``, at speed and slowed, and last (if ``speed_up`` and the ship's
        top speed, ``response.top_speed_mps``, is ``SPEED_UP_MIN_GAIN`` faster) the reference course
        and the turns of ``alteration_deg`` at the top speed: the first that keeps the whole
        traffic clear (:meth:`_clearance`: the course and speed taken up as the ship can), else
        the one that keeps it clearest (a tie goes to the earlier).  Returns (side, 0 for no
        turn; size [deg]; the speed to take, as a factor of the present one).

        With only 35 deg turns weighed, a ship crossing from port and a faster one coming up
        from astern left none that kept both clear, and the least bad (turning and slowing)
        let the overtaker by at 0.86 nm; a 60-75 deg turn at speed kept both clear."""
        size = self.settings.alteration_deg
        options = ([(turn, size, 1.0) for turn in sides] + [(turn, size, SLOW_FACTOR) for turn in sides]
                   + ([(0.0, size, SLOW_FACTOR)] if slow_alone else [])
                   + [(turn, larger, factor) for larger in LARGER_ALTERATIONS_DEG for turn in sides
                      for factor in (1.0, SLOW_FACTOR)])
        top = self.response.top_speed_mps
        own_speed = float(motion[1])
        if speed_up and top is not None and own_speed > 0.0 and top >= (1.0 + SPEED_UP_MIN_GAIN) * own_speed:
            faster = top / own_speed
            options += [(0.0, size, faster)] + [(turn, size, faster) for turn in sides]
        scores = []
        for turn, degrees, factor in options:
            scores.append(self._clearance(motion, reference_heading_rad + turn * math.radians(degrees), factor, traffic))
            if scores[-1] >= 0.0:
                return turn, degrees, factor
        turn, degrees, factor = options[int(np.argmax(scores))]
        return turn, degrees, factor

    def _give_way_due(self, encounter, goal: float, side: float, separation_m: float, motion) -> bool:
        """Whether a give-way alteration to ``goal`` is due: the CPA at most
        ``give_way_action_tcpa_s`` ahead at the present velocities or on the altered course,
        or the last moment it still opens the CPA (plus margin) within ``ACTION_BUFFER_S``."""
        s = self.settings
        tcpa = encounter.tcpa_s
        if motion is not None:  # turning away brings the CPA forward (an overtaker's most)
            own_xy, own_speed, target_xy, target_velocity, _ = motion
            altered = own_speed * np.array([math.cos(goal), math.sin(goal)])
            tcpa_altered = cpa_tcpa(own_xy, altered, target_xy, target_velocity)[1]
            if tcpa_altered > 0.0:
                tcpa = min(tcpa, tcpa_altered)
        latest = math.inf
        if motion is not None:  # the last moment the alteration still opens the CPA (plus margin)
            own_xy, _, target_xy, target_velocity, own_velocity = motion
            latest = latest_alteration_s(own_xy, own_velocity, target_xy, target_velocity,
                                         separation_m + s.clearance_margin_m, side)
        return 0.0 < tcpa <= s.give_way_action_tcpa_s or latest <= ACTION_BUFFER_S


