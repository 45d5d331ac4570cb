"""Parts of the NMPC's collision domains checked alone: the reach test of a shifted domain, which
obstacles get the slots, the alteration's heading bounds for any time values, the classes
reported without risk, the close-quarters range, a give-way alteration at the CPA itself, the
plain circle for a ship already inside a shifted domain, and a stand-on target inside the
clearance."""

import math

import numpy as np
import pytest

from rhnc.control.nmpc_alteration import heading_bounds
from rhnc.control.nmpc_colregs import HEAD_ON_OFFSET, CollisionDomains, DomainReport, DomainSettings
from rhnc.encounters.colregs import ENCOUNTER_CLASSES

NM = 1852.0
KNOT = NM / 3600.0
SPEED = 18 * KNOT
RADIUS = 1.0 * NM
L = 230.0


def test_a_head_on_domain_shifted_towards_the_own_ship_is_in_reach_sooner_than_its_target():
    # a head-on target 6 nm ahead, southbound: its domain's centre lies a quarter rho ahead of
    # it (towards us) and half a rho to its starboard; the reach test over the horizon measures
    # from that centre, so the shortest horizon that gets it a slot follows from the shift
    rho = RADIUS
    target = np.array([6.0 * NM, 0.0, -12 * KNOT, 0.0, RADIUS])
    state = np.array([0.0, 0.0, 0.0, SPEED, 0.0, 0.0])
    forward, side = HEAD_ON_OFFSET
    centre = target[:2] + rho * (forward * np.array([-1.0, 0.0]) + side * np.array([0.0, -1.0]))
    domain_radius = rho * (1.0 + math.hypot(forward, side))
    closing = 1.25 * SPEED + 12 * KNOT
    horizon_s = (math.hypot(*centre) - domain_radius) / closing  # the domain's rim just within reach
    for horizon, in_reach in ((horizon_s + 10.0, True), (horizon_s - 10.0, False)):
        domains = CollisionDomains(DomainSettings(colregs=True), max_obstacles=1)
        slots, report = domains.parameters(target[None, :], state, np.zeros(2), 1.25 * SPEED, 5.0, L, et=True,
                                           horizon_s=horizon)
        assert ENCOUNTER_CLASSES[int(report.class_codes[0])] == "head_on"
        assert report.active[0] == float(in_reach)
        if in_reach:
            np.testing.assert_allclose(slots[4:6, 0] * L, centre - target[:2])  # the offset the test assumed
            assert slots[6, 0] * L == pytest.approx(domain_radius)


def test_with_more_obstacles_than_slots_the_nearest_by_position_get_them_whatever_their_speed():
    # the far one lies still, the near one moves fast across: distance is measured between positions
    domains = CollisionDomains(DomainSettings(colregs=False), max_obstacles=1)
    state = np.array([0.0, 0.0, 0.0, SPEED, 0.0, 0.0])
    far = [0.0, 4.0 * NM, 0.0, 0.0, 0.1 * NM]
    near = [0.0, 1.0 * NM, 10.0, 0.0, 0.1 * NM]
    slots, report = domains.parameters(np.array([far, near]), state, np.zeros(2), SPEED, 5.0, L, et=True)
    np.testing.assert_array_equal(report.active, [0.0, 1.0])
    np.testing.assert_allclose(slots[0:2, 0] * L, near[:2], atol=1e-9)


def test_the_alteration_bounds_are_the_same_for_integer_times():
    # times in whole seconds (an integer array) must bound the headings as the same times in floats do
    report = DomainReport(np.zeros(1), np.ones(1), alteration_floor=(0.0, 0.0, 0.5),
                          alteration_ceiling=None)
    whole = np.array([100, 400, 1000, 2000])
    lower, upper = heading_bounds(report, 50.0, 0.45, 0.0, whole)
    lower_f, _ = heading_bounds(report, 50.0, 0.45, 0.0, whole.astype(float))
    assert upper is None
    np.testing.assert_allclose(lower, lower_f)
    assert lower[-1] == pytest.approx(0.5)  # the goal, reached long after the ramp
    ceiling = DomainReport(np.zeros(1), np.ones(1), alteration_ceiling=(0.0, 0.0, -0.5))
    _, upper = heading_bounds(ceiling, 50.0, -0.45, 0.0, whole)
    _, upper_f = heading_bounds(ceiling, 50.0, -0.45, 0.0, whole.astype(float))
    np.testing.assert_allclose(upper, upper_f)
    assert upper[-1] == pytest.approx(-0.5)


def test_without_risk_the_report_still_gives_every_obstacle_its_class():
    # no trigger and no risk of collision (a ship 6 nm abeam, sailing with us): no constraint, but
    # the classes are reported all the same (the telemetry's encounter_class)
    domains = CollisionDomains(DomainSettings(colregs=True), max_obstacles=2)
    state = np.array([0.0, 0.0, 0.0, SPEED, 0.0, 0.0])
    abeam = np.array([[0.0, 6.0 * NM, SPEED, 0.0, RADIUS]])
    _, report = domains.parameters(abeam, state, np.zeros(2), SPEED, 5.0, L, et=False)
    assert not report.risk and list(report.active) == [0.0]
    assert report.class_codes is not None and len(report.class_codes) == 1


def test_a_ship_far_abeam_sailing_with_us_is_no_risk_of_collision():
    # 5 nm to starboard, same course and speed: no closest approach ahead, and not within two
    # clearances (the range counts both coordinates, not the one along our course alone)
    domains = CollisionDomains(DomainSettings(colregs=True), max_obstacles=1)
    rows = np.array([[0.0, 5.0 * NM, SPEED, 0.0, RADIUS]])
    assert not domains._collision_risk(rows, np.array([RADIUS]), np.zeros(2), np.array([SPEED, 0.0]))
    assert domains._collision_risk(rows * [1.0, 0.3, 1.0, 1.0, 1.0], np.array([RADIUS]), np.zeros(2),
                                   np.array([SPEED, 0.0]))  # 1.5 nm abeam: within two clearances


def test_a_give_way_alteration_is_not_due_at_the_closest_approach_itself():
    # TCPA exactly 0: the closest approach is now, nothing is ahead to give way for
    from rhnc.encounters.colregs import Encounter
    domains = CollisionDomains(DomainSettings(colregs=True), max_obstacles=1)
    now = Encounter("head_on", 0.0, 0.0, RADIUS, 0.2 * NM, 0.0)
    ahead = Encounter("head_on", 0.0, 0.0, RADIUS, 0.2 * NM, 60.0)
    assert not domains._give_way_due(now, 0.0, 1.0, RADIUS, None)
    assert domains._give_way_due(ahead, 0.0, 1.0, RADIUS, None)


def test_an_own_ship_already_inside_a_shifted_domain_gets_the_plain_circle():
    # a head-on target whose shifted domain (moved towards its starboard bow) holds the own ship,
    # though the plain circle about the target does not: the domain falls back to the plain circle
    domains = CollisionDomains(DomainSettings(colregs=True), max_obstacles=1)
    rho = RADIUS
    target = np.array([1.3 * NM, 1.2 * NM, -12 * KNOT, 0.0, RADIUS])  # south-bound, on our starboard bow
    forward, side = HEAD_ON_OFFSET
    shifted = target[:2] + rho * (forward * np.array([-1.0, 0.0]) + side * np.array([0.0, -1.0]))
    own = np.zeros(2)
    assert math.hypot(*(shifted - own)) < rho * (1.0 + math.hypot(forward, side))
    assert math.hypot(*target[:2]) > rho
    offset, radius, _ = domains._domain(target, rho, "head_on", own, math.hypot(*target[:2]), -10.0, False)
    np.testing.assert_array_equal(offset, [0.0, 0.0])
    assert radius == pytest.approx(rho)


def test_a_stand_on_target_inside_the_clearance_gets_its_constraint_even_while_opening():
    # a ship crossing from port, stood on for while far, is found inside the clearance and
    # opening: Rule 17(b)'s prediction (no CPA ahead) no longer asks for action, but the ship
    # inside the clearance does
    domains = CollisionDomains(DomainSettings(colregs=True), max_obstacles=1)
    state = np.array([0.0, 0.0, 0.0, SPEED, 0.0, 0.0])
    east = np.array([0.0, 15 * KNOT])
    far = np.array([[6.0 * NM, -6.0 * NM * 15 / 18, *east, RADIUS]])  # meets us in 20 min
    _, first = domains.parameters(far, state, np.zeros(2), SPEED, 5.0, L, et=True, time_s=0.0)
    assert ENCOUNTER_CLASSES[int(first.class_codes[0])] == "crossing_stand_on" and list(first.active) == [0.0]
    inside = np.array([[0.2 * NM, 0.9 * NM, *east, RADIUS]])  # ahead to starboard now, moving away
    _, second = domains.parameters(inside, state, np.zeros(2), SPEED, 5.0, L, et=True, time_s=20.0)
    assert ENCOUNTER_CLASSES[int(second.class_codes[0])] == "crossing_stand_on"
    assert list(second.active) == [1.0]


def test_an_alterations_heading_floor_rises_from_the_time_the_alteration_began():
    # began at 300 s: at 370 s the floor has risen 0.3 deg/s for the 50 s after the 20-s delay
    report = DomainReport(np.zeros(1), np.ones(1), alteration_floor=(300.0, 0.0, math.radians(35.0)))
    lower, _ = heading_bounds(report, 360.0, math.radians(30.0), 0.0, np.array([370.0]))
    assert math.degrees(lower[0]) == pytest.approx(15.0)


def test_of_two_alterations_to_port_the_one_furthest_to_port_is_held():
    domains = CollisionDomains(DomainSettings(colregs=True), max_obstacles=2)
    domains._altering = {0: (10.0, 0.0, -0.3, -1.0), 1: (20.0, 0.0, -0.6, -1.0)}
    assert domains._alteration_bounds(False, False) == (None, (20.0, 0.0, -0.6))


def test_a_reference_is_taken_on_the_turn_of_the_heading_an_alteration_is_measured_from():
    # an alteration of 35 deg to starboard held to 35 deg: it is measured from 0 deg, and a
    # reference at -125 deg is taken on that heading's turn (no whole turn off it), not on the
    # turn of a heading 35 deg beyond the goal, from which it is more than half a turn away
    domains = CollisionDomains(DomainSettings(colregs=True), max_obstacles=2)
    domains._altering = {1: (0.0, 0.0, math.radians(35.0), 1.0)}
    assert domains.reference_turns(math.radians(-125.0), math.radians(30.0)) == 0.0


def test_without_colregs_no_row_is_classified():
    domains = CollisionDomains(DomainSettings(colregs=False), max_obstacles=2)
    row = np.array([[3000.0, 500.0, -5.0, 0.0, 1852.0]])
    _, report = domains.parameters(row, np.array([0.0, 0.0, 0.0, 9.26, 0.0, 0.0]), np.zeros(2), 9.26, 5.0, 230.0,
                                   et=True)
    assert report.class_codes.tolist() == [-1.0]


def test_without_a_reference_an_alteration_is_measured_from_the_measured_heading():
    # a ship crossing from starboard on a collision course, 10 min ahead, the own ship heading
    # 10 deg: the alteration holds 35 deg off that heading
    heading = math.radians(10.0)
    speed = 9.26
    own_velocity = speed * np.array([math.cos(heading), math.sin(heading)])
    meeting = 600.0 * own_velocity
    target_velocity = np.array([0.0, -9.0])
    row = np.array([[*(meeting - 600.0 * target_velocity), *target_velocity, 1852.0]])
    domains = CollisionDomains(DomainSettings(colregs=True), max_obstacles=2)
    _, report = domains.parameters(row, np.array([0.0, 0.0, heading, speed, 0.0, 0.0]), np.zeros(2), speed, 5.0,
                                   230.0, et=True)
    assert ENCOUNTER_CLASSES[int(report.class_codes[0])] == "crossing_give_way"
    assert math.degrees(report.alteration_floor[2]) == pytest.approx(45.0)
