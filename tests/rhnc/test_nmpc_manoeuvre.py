"""The manoeuvre the COLREG-aware NMPC chooses among other traffic, and how its ship takes it up.

A stand-on ship that acts for a ship overtaking it (Rule 17(b)), and a give-way ship whose plain
35 deg turn would take it into another target, weigh turns of 35, 60 and 90 deg to the sides the
rules allow, at speed and slowed, and the reduction of speed alone, and a stand-on ship last
speeding up: the first that keeps every target clear, else the clearest
(:mod:`rhnc.control.nmpc_colregs`), scored with the time the ship needs to turn, to slow and to
gather way (:mod:`rhnc.control.nmpc_manoeuvre`).  Own ship northbound at
18 kn from the origin; every target's R_i is 1 nm.
"""

import dataclasses
import math

import numpy as np
import pytest

from rhnc.control.nmpc import SLOWING_SHARE, SPEEDING_SHARE, NMPCController, NMPCSettings
from rhnc.control.nmpc_actions import SLOW_FACTOR
from rhnc.control.nmpc_colregs import CollisionDomains, DomainSettings
from rhnc.control.nmpc_manoeuvre import ManoeuvreResponse, own_track, response_clearance_m
from rhnc.encounters.colregs import ENCOUNTER_CLASSES
from rhnc.navigation.reference_participant import line_or_turn_reference
from rhnc.ship.ship_model import load_parameter_set

NM = 1852.0
KNOT = NM / 3600.0
N = 15
SPEED = 18 * KNOT
RADIUS = 1.0 * NM
STATE = np.array([0.0, 0.0, 0.0, SPEED, 0.0, 0.0])


@pytest.fixture(scope="module")
def kcs():
    return load_parameter_set("default")


def converging(bearing_deg, range_nm, closing_kn):
    """A target ``range_nm`` off at ``bearing_deg``, closing on us at ``closing_kn`` (CPA 0)."""
    bearing = math.radians(bearing_deg)
    position = range_nm * NM * np.array([math.cos(bearing), math.sin(bearing)])
    velocity = np.array([SPEED, 0.0]) - position / np.hypot(*position) * closing_kn * KNOT
    return [*position, *velocity, RADIUS]


def sailing(bearing_deg, range_nm, course_deg, speed_kn):
    bearing, course = math.radians(bearing_deg), math.radians(course_deg)
    return [range_nm * NM * math.cos(bearing), range_nm * NM * math.sin(bearing),
            speed_kn * KNOT * math.cos(course), speed_kn * KNOT * math.sin(course), RADIUS]


def act(targets, max_obstacles=3, response=None):
    domains = CollisionDomains(DomainSettings(colregs=True), max_obstacles=max_obstacles)
    if response is not None:
        domains.response = response
    _, report = domains.parameters(np.array(targets, dtype=float), STATE, np.zeros(2), SPEED, 5.0, 230.0, et=True,
                                   reference_heading_rad=0.0, time_s=0.0)
    return domains, report


def classes(report):
    return [ENCOUNTER_CLASSES[int(code)] for code in report.class_codes]


# -- the response the choice is scored with -------------------------------------------------

def test_the_own_ship_holds_on_for_the_delay_then_turns_and_slows_at_its_rates():
    response = ManoeuvreResponse(delay_s=20.0, turn_rate_rps=math.radians(0.5), deceleration_mps2=0.02, step_s=1.0,
                                 horizon_s=600.0)
    times, positions = own_track((0.0, 0.0), 10.0, 0.0, math.radians(30.0), 4.0, response)
    assert positions[20] == pytest.approx([200.0, 0.0])  # 20 s straight on at 10 m/s
    steps = np.diff(positions, axis=0)
    headings = np.degrees(np.arctan2(steps[:, 1], steps[:, 0]))
    speeds = np.hypot(*steps.T)
    assert headings[60] == pytest.approx(0.5 * 40.5, abs=0.1)  # turning at 0.5 deg/s after the delay
    assert headings[100] == pytest.approx(30.0, abs=1e-6)  # and holding the new course
    assert speeds[120] == pytest.approx(10.0 - 0.02 * 100.5, abs=1e-6)  # slowing at 0.02 m/s^2
    assert speeds[500] == pytest.approx(4.0)  # down to the goal, no further
    assert times[-1] == pytest.approx(600.0)


def test_the_own_ship_gathers_way_at_its_acceleration_up_to_the_goal():
    response = ManoeuvreResponse(delay_s=20.0, acceleration_mps2=0.01, step_s=1.0, horizon_s=600.0)
    _, positions = own_track((0.0, 0.0), 10.0, 0.0, 0.0, 12.0, response)
    speeds = np.hypot(*np.diff(positions, axis=0).T)
    assert speeds[10] == pytest.approx(10.0)  # holding on for the delay
    assert speeds[120] == pytest.approx(10.0 + 0.01 * 100.5, abs=1e-6)  # gathering way at 0.01 m/s^2
    assert speeds[500] == pytest.approx(12.0)  # up to the goal, no further


def test_speeding_up_ahead_of_a_faster_ship_is_followed_to_the_end_of_the_encounter():
    # a ship right astern at 26 kn, 3 nm off: at 24 kn the own ship keeps it more than a mile
    # off for the whole risk window (it closes 1.3 nm in it), but not for ever
    astern = (np.array([-3.0 * NM, 0.0]), np.array([26 * KNOT, 0.0]), RADIUS)
    response = ManoeuvreResponse(acceleration_mps2=0.01, top_speed_mps=24 * KNOT)
    window = response_clearance_m((0.0, 0.0), SPEED, 0.0, 0.0, 24 * KNOT, [astern], response)
    whole = response_clearance_m((0.0, 0.0), SPEED, 0.0, 0.0, 24 * KNOT, [astern], response, beyond=True)
    assert window > 0.0 and whole == pytest.approx(-RADIUS, abs=1.0)
    # ahead of a slower one, the whole encounter is the window's
    slower = (astern[0], np.array([23 * KNOT, 0.0]), RADIUS)
    assert response_clearance_m((0.0, 0.0), SPEED, 0.0, 0.0, 24 * KNOT, [slower], response, beyond=True) == \
        pytest.approx(response_clearance_m((0.0, 0.0), SPEED, 0.0, 0.0, 24 * KNOT, [slower], response))


def test_a_reduction_of_speed_scores_less_than_if_it_came_at_once():
    # a ship converging from the starboard quarter, 1.5 nm off (CPA 0): slowing lets it cross
    # ahead, but the ship sheds its speed over minutes, and meanwhile the overtaker comes closer
    position, velocity = np.split(np.array(converging(120.0, 1.5, 6.0)[:4]), 2)
    target = (position, velocity, RADIUS)
    slow = response_clearance_m((0.0, 0.0), SPEED, 0.0, 0.0, SLOW_FACTOR * SPEED, [target],
                                ManoeuvreResponse(deceleration_mps2=0.02))
    at_once = response_clearance_m((0.0, 0.0), SPEED, 0.0, 0.0, SLOW_FACTOR * SPEED, [target],
                                   ManoeuvreResponse(delay_s=0.0, deceleration_mps2=1e3))
    assert slow < at_once - 200.0


# -- being overtaken (Rule 17(b)) ------------------------------------------------------------

def test_overtaken_with_a_clear_turn_to_port_keeps_its_speed():
    _, report = act([converging(129.0, 1.5, 5.6)])
    assert report.alteration_ceiling is not None and report.speed_goal_mps is None


def test_overtaken_from_both_quarters_the_stand_on_ship_slows_down():
    # two faster ships converging from either quarter: a turn to either side runs into one of
    # them; slowing lets both by ahead
    _, report = act([converging(-135.0, 1.6, 7.0), converging(125.0, 1.6, 7.0)])
    assert classes(report) == ["overtaken", "overtaken"]
    assert report.alteration_floor is None and report.alteration_ceiling is None
    assert report.speed_goal_mps == pytest.approx(SLOW_FACTOR * SPEED)


def test_overtaken_with_a_ship_crossing_from_port_turns_further_than_35_deg():
    # a ship overtaking from right astern and a fast one crossing from port (no turn to port,
    # Rule 17(c)): no 35 deg turn, nor slowing, keeps both clear; 60 deg to starboard at speed does
    _, report = act([converging(-170.0, 1.9, 6.0), sailing(-74.0, 4.0, 60.0, 24.0)])
    assert classes(report) == ["overtaken", "crossing_stand_on"]
    assert report.alteration_ceiling is None and report.speed_goal_mps is None
    assert math.degrees(report.alteration_floor[2]) == pytest.approx(60.0)


def test_with_no_manoeuvre_keeping_the_traffic_clear_the_clearest_is_taken():
    # overtaken from the starboard quarter with a head-on ship ahead (no turn to port): every
    # manoeuvre weighed leaves one of them inside its clearance; the one chosen leaves the least
    targets = [sailing(0.0, 8.0, 180.0, 20.0), converging(129.0, 1.5, 5.6)]
    domains, report = act(targets)
    assert classes(report) == ["head_on", "overtaken"]
    traffic = [(np.array(t[:2]), np.array(t[2:4]), RADIUS) for t in targets]
    motion = (STATE[:2], SPEED, None, None, np.array([SPEED, 0.0]))
    side, size, speed = domains._choose((1.0,), True, 0.0, motion, traffic)
    scores = {(turn, degrees, factor): domains._clearance(motion, turn * math.radians(degrees), factor, traffic)
              for turn in (0.0, 1.0) for degrees in (35.0, 60.0, 90.0) for factor in (1.0, SLOW_FACTOR)}
    assert max(scores.values()) < 0.0
    chosen = scores[(side, size, speed)]
    assert chosen == pytest.approx(max(scores.values()))


def _kcs_response(kcs, top_speed_mps=24 * KNOT):
    """How the KCS gathers way, as the NMPC tells its domains (up to 24 kn)."""
    acceleration = SPEEDING_SHARE * (kcs.tau_max[0] - kcs.equilibrium_tau(top_speed_mps)[0]) / kcs.m11
    return ManoeuvreResponse(deceleration_mps2=SLOWING_SHARE * kcs.tau_max[0] / kcs.m11,
                             acceleration_mps2=acceleration, top_speed_mps=top_speed_mps)


def _overtaken_slowly_with_a_ship_crossing_from_port():
    """A ship at 22 kn coming up 1.2 nm off on the starboard quarter, converging (CPA 0 in about
    17 min), and one crossing from port, 5.7 nm off at 20.6 kn (CPA 0 in about 17 min): no turn
    to port (Rule 17(c)), and a turn to starboard runs across the overtaker's course."""
    return [sailing(158.0, 1.23, -4.2, 22.0), sailing(-65.0, 5.65, 62.5, 20.6)]


def test_overtaken_slowly_with_a_ship_crossing_from_port_the_stand_on_ship_speeds_up(kcs):
    domains, report = act(_overtaken_slowly_with_a_ship_crossing_from_port(), response=_kcs_response(kcs))
    assert classes(report) == ["overtaken", "crossing_stand_on"] and domains._acting == {0, 1}
    assert report.speed_up_goal_mps == pytest.approx(24 * KNOT)
    assert report.alteration_floor is None and report.alteration_ceiling is None and report.speed_goal_mps is None


def test_a_stand_on_ship_that_cannot_go_faster_turns_instead(kcs):
    # the same traffic for a ship already at its top speed: no speeding up to weigh, a turn instead
    domains, report = act(_overtaken_slowly_with_a_ship_crossing_from_port(), response=_kcs_response(kcs, SPEED))
    assert domains._acting == {0, 1} and report.speed_up_goal_mps is None
    assert report.alteration_floor is not None


def test_a_ship_standing_on_among_ships_it_gives_way_to_does_not_slow_down_alone(kcs):
    # two ships crossing from starboard that we give way to by slowing, and one crossing from port
    # that we stand on for and act for at once (trafficgen55g's situation 37 at its start): the
    # plain turn to starboard runs into the nearer ship from starboard; the stand-on action is a
    # turn to starboard, not the reduction of speed alone, which takes a ship into the path of a
    # give-way ship passing astern of it
    targets = [sailing(106.3, 2.48, 332.49, 23.9), sailing(59.4, 6.67, 286.54, 21.2), sailing(-63.1, 7.35, 74.6, 23.9)]
    domains, report = act(targets, response=_kcs_response(kcs))
    assert classes(report) == ["crossing_give_way", "crossing_give_way", "crossing_stand_on"]
    assert domains._acting == {2} and set(domains._slowing) >= {0, 1}
    assert 2 in domains._altering and domains._altering[2][3] > 0.0 and report.alteration_floor is not None


def test_a_plan_speeding_up_gathers_way_towards_the_speed_asked_for(kcs):
    controller = NMPCController(kcs, NMPCSettings(horizon_steps=N, control_interval_s=20.0, colregs=True))
    reference = line_or_turn_reference(20.0 * np.arange(N + 1), (0.0, 0.0), 0.0, SPEED)
    solution = controller.solve(0.0, STATE, reference, np.array(_overtaken_slowly_with_a_ship_crossing_from_port()),
                                et=True)
    controller.close()
    assert controller.domains._hastening and not solution.fallback
    # 300 s at the acceleration asked for: 18 -> 22.6 kn; the speed reference alone asks 18 kn
    assert solution.states[-1, 3] >= SPEED + 0.8 * controller.speeding_mps2 * 20.0 * N


def test_the_speed_asked_for_runs_from_where_speeding_up_began_not_from_the_speed_lost_since(kcs):
    # the decision at t = 0 at 18 kn; two minutes later the ship, turning as well, is down to
    # 16 kn: the plan is asked for the speed the ramp from the decision has reached, which the
    # choice counted on, not a new ramp from 16 kn
    domains, report = act(_overtaken_slowly_with_a_ship_crossing_from_port(), response=_kcs_response(kcs))
    assert report.speed_up_since == (0.0, pytest.approx(SPEED))
    controller = NMPCController(kcs, NMPCSettings(horizon_steps=N, control_interval_s=20.0, colregs=True))
    controller.close()
    slowed = STATE.copy()
    slowed[3] = 16 * KNOT
    asked = controller._speed_asked(report, slowed, 120.0)
    ramp = SPEED + controller.speeding_mps2 * (120.0 + 20.0 * np.arange(1, N + 1))
    assert asked == pytest.approx(np.minimum(ramp, 24 * KNOT))
    # a ship that made more way than the ramp (a following wind) is asked for more still
    ahead = STATE.copy()
    ahead[3] = 21 * KNOT
    assert controller._speed_asked(report, ahead, 120.0)[0] == pytest.approx(21 * KNOT + controller.speeding_mps2 * 20.0)


def test_a_plan_turning_and_speeding_up_gathers_way_in_the_turn(kcs):
    # drawn_020's traffic when the own ship acts: ships overtaking at 25 and 29 kn from the
    # starboard quarter and one crossing from port that we stand on for; the action is a 35 deg
    # turn to starboard at the top speed.  The plan must gather way through the turn as the
    # choice assumed, not shed it to keep near the route it turns away from
    targets = np.array([sailing(165.4, 2.83, 354.2, 25.06), sailing(136.0, 3.56, 345.6, 29.24),
                        sailing(-43.4, 2.57, 60.3, 8.66)])
    controller = NMPCController(kcs, NMPCSettings(horizon_steps=N, control_interval_s=20.0, colregs=True))
    reference = line_or_turn_reference(20.0 * np.arange(N + 1), (0.0, 0.0), 0.0, SPEED)
    solution = controller.solve(0.0, STATE, reference, targets, et=True)
    controller.close()
    assert controller.domains._hastening and controller.domains._altering and not solution.fallback
    assert math.degrees(solution.states[-1, 2]) > 30.0
    assert solution.states[-1, 3] >= SPEED + 0.8 * controller.speeding_mps2 * 20.0 * N


def test_speeding_up_is_not_chosen_for_a_ship_faster_than_the_top_speed(kcs):
    # a ship right astern at 26 kn, 3 nm off, and only the speed to choose with: speeding up to
    # 24 kn keeps it off for the risk window, and no further; it does not count as clear
    domains = CollisionDomains(DomainSettings(colregs=True), max_obstacles=3)
    domains.response = _kcs_response(kcs)
    astern = [(np.array([-3.0 * NM, 0.0]), np.array([26 * KNOT, 0.0]), RADIUS)]
    motion = (STATE[:2], SPEED, None, None, np.array([SPEED, 0.0]))
    assert domains._choose((), True, 0.0, motion, astern, speed_up=True)[2] == SLOW_FACTOR
    # a ship of 23 kn the own ship outruns
    slower = [(astern[0][0], np.array([23 * KNOT, 0.0]), RADIUS)]
    assert domains._choose((), True, 0.0, motion, slower, speed_up=True)[2] == pytest.approx(24 / 18)


def test_overtaken_with_a_ship_closing_from_port_weighs_no_turn_to_port():
    # the turn to port that keeps the overtaker clearest is not weighed while a ship on the port
    # bow closes on us: it may become a ship crossing from port (Rule 17(c))
    crossing = [9.0 * NM * math.cos(math.radians(-60.0)), 9.0 * NM * math.sin(math.radians(-60.0)), 0.0,
                15.0 * KNOT, RADIUS]
    _, report = act([converging(129.0, 1.5, 5.6), crossing])
    assert report.alteration_ceiling is None
    assert report.alteration_floor is not None or report.speed_goal_mps is not None


def test_the_reduction_of_speed_ends_when_the_overtakers_are_past_and_clear():
    targets = np.array([converging(-135.0, 1.6, 7.0), converging(125.0, 1.6, 7.0)])
    domains, report = act(targets)
    assert report.speed_goal_mps is not None
    past = targets.copy()
    past[0, :2] = [1.8 * NM, -1.0 * NM]  # ahead, opening: past, 2.06 nm off
    past[1, :2] = [1.8 * NM, 1.0 * NM]
    _, report = domains.parameters(past, STATE, np.zeros(2), SPEED, 5.0, 230.0, et=True,
                                   reference_heading_rad=0.0, time_s=20.0)
    assert report.speed_goal_mps is None


def test_a_plan_slowing_down_keeps_to_the_speed_the_ship_can_shed(kcs):
    # the plan's speed comes down at least at the deceleration asked for, to the goal speed
    # (two ships coming up on both quarters at 23 kn: a ship that could make 24 kn would outrun
    # them; this one cannot go faster)
    targets = np.array([converging(-135.0, 1.6, 7.0), converging(125.0, 1.6, 7.0)])
    controller = NMPCController(kcs, NMPCSettings(horizon_steps=N, control_interval_s=20.0, colregs=True))
    controller.domains.response = dataclasses.replace(controller.domains.response, top_speed_mps=None)
    reference = line_or_turn_reference(20.0 * np.arange(N + 1), (0.0, 0.0), 0.0, SPEED)
    solution = controller.solve(0.0, STATE, reference, targets, et=True)
    controller.close()
    goal = SLOW_FACTOR * SPEED
    slowing = SLOWING_SHARE * (kcs.tau_max[0] + kcs.equilibrium_tau(goal)[0]) / kcs.m11
    ramp = np.maximum(goal, SPEED - slowing * 20.0 * np.arange(1, N + 1))
    assert not solution.fallback
    assert np.all(solution.states[1:, 3] <= ramp + 1e-3)
    assert solution.states[-1, 3] <= goal + 1e-3


# -- giving way among other traffic (Rules 8, 16) --------------------------------------------

def _crossing_from_starboard():
    """A ship crossing from starboard, 4 nm off on the starboard bow, on a collision course (CPA
    0, about 11 min ahead): we give way."""
    return converging(40.0, 4.0, 22.0)


def test_a_give_way_ship_alone_turns_35_deg_at_speed():
    _, report = act([_crossing_from_starboard()])
    assert classes(report) == ["crossing_give_way"]
    assert math.degrees(report.alteration_floor[2]) == pytest.approx(35.0) and report.speed_goal_mps is None


def test_a_give_way_turn_into_an_overtaker_gives_way_otherwise():
    # the same ship crossing from starboard and a faster ship converging from the starboard
    # quarter, 3 nm off, not yet acted for (Rule 17: it may still keep clear): the 35 deg turn at
    # speed would run across its bow, so the give-way ship gives way otherwise
    domains, report = act([_crossing_from_starboard(), converging(130.0, 3.0, 8.0)])
    assert classes(report) == ["crossing_give_way", "overtaken"] and domains._acting == set()
    plain = report.alteration_floor is not None and math.isclose(math.degrees(report.alteration_floor[2]), 35.0)
    assert not (plain and report.speed_goal_mps is None)


def test_a_plan_holds_an_alteration_to_port_to_its_heading(kcs):
    # overtaking a slow ship fine on the starboard bow: the alteration goes to port, away from
    # it (Rule 13 leaves the side free); the plan's heading reaches the alteration's 35 deg to
    # port within the horizon, not just the few degrees the domain alone would ask for
    controller = NMPCController(kcs, NMPCSettings(horizon_steps=N, control_interval_s=20.0, colregs=True))
    reference = line_or_turn_reference(20.0 * np.arange(N + 1), (0.0, 0.0), 0.0, SPEED)
    slow_ahead = np.array([sailing(5.0, 2.0, 0.0, 6.0)])
    solution = controller.solve(0.0, STATE, reference, slow_ahead, et=True)
    controller.close()
    assert not solution.fallback and controller.domains._altering
    assert math.degrees(solution.states[-1, 2]) <= -35.0 + 0.5


def test_an_iteration_budget_may_be_as_small_as_two():
    assert NMPCSettings(iteration_budget=2).iteration_budget == 2
    with pytest.raises(ValueError, match="iteration_budget"):
        NMPCSettings(iteration_budget=1)


def test_the_disturbance_observer_is_on_when_asked(kcs):
    assert NMPCController(kcs, NMPCSettings(horizon_steps=5, disturbance_observer=True)).observer is not None
    assert NMPCController(kcs, NMPCSettings(horizon_steps=5)).observer is None
