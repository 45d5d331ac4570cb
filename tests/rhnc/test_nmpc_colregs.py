"""COLREG-aware NMPC alone on a straight reference: head-on, crossing (give-way, stand-on), overtaking.

Own ship northbound at 18 kn on the reference x = 18 kn * t, y = 0; one target with R_i = 1 nm
(own R = 0) placed so that both ships would meet at (4.5 nm, 0) after 15 min.  The plant is
the prediction model itself (numpy RK4 at 0.5 s), so what is tested is the controller's
choice of manoeuvre, not its robustness.  Each test runs the paper's circle beside the
COLREG domain where the difference is the point.
"""

import math

import numpy as np
import pytest

from rhnc.encounters.colregs import wrap_deg
from rhnc.encounters.colregs import ENCOUNTER_CLASSES, cpa_tcpa
from rhnc.control.nmpc import NMPCController, NMPCSettings
from rhnc.control.nmpc_alteration import CATCH_UP_RATE_DEG_S, HEADING_TOLERANCE_DEG, YAW_TIME_CONSTANT_S, heading_bounds
from rhnc.control.nmpc_actions import PORT_ALLOWANCE_DEG
from rhnc.control.nmpc_colregs import CollisionDomains, DomainReport, DomainSettings
from rhnc.control.nmpc_problem import OBSTACLE_FIELDS
from rhnc.navigation.reference_participant import line_or_turn_reference
from rhnc.ship.ship_model import load_parameter_set, rk4_step

NM = 1852.0
KNOT = NM / 3600.0
N = 15
SPEED = 18 * KNOT
MEETING_S = 900.0
RADIUS = 1.0 * NM


@pytest.fixture(scope="module")
def kcs():
    return load_parameter_set("default")


def target_on_collision_course(course_deg, speed_kn, lateral_nm=0.0):
    """Start position and velocity of a target meeting the own ship at MEETING_S (+ lateral offset)."""
    velocity = speed_kn * KNOT * np.array([math.cos(math.radians(course_deg)), math.sin(math.radians(course_deg))])
    meeting = np.array([SPEED * MEETING_S, lateral_nm * NM])
    return meeting - velocity * MEETING_S, velocity


def encounter(kcs, start, velocity, colregs, dt=20.0, duration_s=1800.0, give_way_at_s=None):
    """Closed loop; returns own states and target positions every 0.5 s, and the controller."""
    controller = NMPCController(kcs, NMPCSettings(horizon_steps=N, control_interval_s=dt, colregs=colregs))
    state = np.array([0.0, 0.0, 0.0, SPEED, 0.0, 0.0])
    position, velocity = start.copy(), velocity.copy()
    own, other = [state.copy()], [position.copy()]
    for k in range(int(duration_s / dt)):
        t = k * dt
        if give_way_at_s is not None and t >= give_way_at_s:  # the target turns 60 deg to starboard, once
            turn = math.radians(60.0)
            velocity = np.array([[math.cos(turn), -math.sin(turn)], [math.sin(turn), math.cos(turn)]]) @ velocity
            give_way_at_s = None
        obstacles = np.array([[*position, *velocity, RADIUS]])
        reference = line_or_turn_reference(t + dt * np.arange(N + 1), (0.0, 0.0), 0.0, SPEED)
        solution = controller.solve(t, state, reference, obstacles, et=True)
        assert not solution.fallback
        for _ in range(int(dt / 0.5)):
            state = rk4_step(state, solution.tau, 0.5, 1, kcs)
            position = position + velocity * 0.5
            own.append(state.copy())
            other.append(position.copy())
    controller.close()
    return np.array(own), np.array(other), velocity, controller


def at_closest_approach(own, other, target_velocity):
    """Separation [m], relative bearing of the target [deg, + starboard] and aspect of the own ship."""
    distance = np.hypot(own[:, 0] - other[:, 0], own[:, 1] - other[:, 1])
    i = int(np.argmin(distance))
    bearing = wrap_deg(math.degrees(math.atan2(other[i, 1] - own[i, 1], other[i, 0] - own[i, 0]) - own[i, 2]))
    course = math.atan2(target_velocity[1], target_velocity[0])
    aspect = wrap_deg(math.degrees(math.atan2(own[i, 1] - other[i, 1], own[i, 0] - other[i, 0]) - course))
    return float(distance.min()), float(bearing), float(aspect)


@pytest.mark.slow
def test_head_on_slightly_to_starboard_passes_port_to_port(kcs):
    start, velocity = target_on_collision_course(180.0, 12.0, lateral_nm=0.3)
    own, other, velocity, _ = encounter(kcs, start, velocity, colregs=True)
    separation, bearing, _ = at_closest_approach(own, other, velocity)
    assert separation >= RADIUS
    assert bearing < -45.0  # the target passes down our port side
    before_cpa = int(np.argmin(np.hypot(*(own[:, :2] - other).T)))
    assert np.degrees(own[:before_cpa, 2]).min() > -PORT_ALLOWANCE_DEG - 1.0  # and never turned to port
    # the paper's circle takes the short way round: starboard to starboard
    own, other, velocity, _ = encounter(kcs, start, velocity, colregs=False)
    assert at_closest_approach(own, other, velocity)[1] > 45.0


@pytest.mark.slow
def test_crossing_from_starboard_turns_to_starboard_and_passes_astern(kcs):
    start, velocity = target_on_collision_course(270.0, 15.0)  # from the east, heading west
    own, other, velocity, controller = encounter(kcs, start, velocity, colregs=True)
    separation, _, aspect = at_closest_approach(own, other, velocity)
    assert separation >= RADIUS
    assert abs(aspect) > 112.5  # at the CPA we are abaft the target's beam: under its stern
    heading_deg = np.degrees(own[:, 2])
    first_alteration = heading_deg[np.argmax(np.abs(heading_deg) > 5.0)]
    assert first_alteration > 0.0  # the first real alteration is to starboard
    before_cpa = int(np.argmin(np.hypot(*(own[:, :2] - other).T)))
    assert heading_deg[:before_cpa].min() > -PORT_ALLOWANCE_DEG - 1.0
    # Rules 8, 16: readily apparent (the full alteration) and early (5 min before the CPA)
    apparent = int(np.argmax(heading_deg >= controller.settings.apparent_alteration_deg - 0.5))
    assert heading_deg[apparent] >= 29.5 and (before_cpa - apparent) * 0.5 >= 300.0
    # the paper's circle turns to port and crosses ahead of it
    own, other, velocity, _ = encounter(kcs, start, velocity, colregs=False)
    assert abs(at_closest_approach(own, other, velocity)[2]) < 90.0


@pytest.mark.slow
def test_crossing_from_port_stands_on_while_the_target_gives_way(kcs):
    # 40 s intervals: a 10 min horizon sees the conflict before the target acts at 4 min
    start, velocity = target_on_collision_course(90.0, 15.0)  # from the west, heading east
    own, other, velocity, controller = encounter(kcs, start, velocity, colregs=True, dt=40.0, give_way_at_s=240.0)
    assert np.abs(np.degrees(own[:, 2])).max() < 0.5  # course kept
    assert np.abs(own[:, 3] - SPEED).max() < 0.05  # and speed
    assert controller.domains.stand_on_actions == 0
    assert at_closest_approach(own, other, velocity)[0] >= RADIUS
    # the paper's circle manoeuvres for a ship that is giving way anyway
    own, _, _, _ = encounter(kcs, start, target_on_collision_course(90.0, 15.0)[1], colregs=False, dt=40.0,
                             give_way_at_s=240.0)
    assert np.abs(np.degrees(own[:, 2])).max() > 2.0


@pytest.mark.slow
def test_crossing_from_port_acts_when_the_target_does_not_give_way(kcs):
    start, velocity = target_on_collision_course(90.0, 15.0)
    own, other, velocity, controller = encounter(kcs, start, velocity, colregs=True)
    assert controller.domains.stand_on_actions == 1  # Rule 17(b)
    assert at_closest_approach(own, other, velocity)[0] >= RADIUS
    heading_deg = np.degrees(own[:, 2])
    assert heading_deg[np.argmax(np.abs(heading_deg) > 5.0)] > 0.0  # Rule 17(c): not to port


@pytest.mark.slow
def test_overtaking_passes_clear(kcs):
    velocity = np.array([8.0 * KNOT, 0.0])
    start = np.array([(SPEED - velocity[0]) * MEETING_S, 0.0])  # 2.5 nm ahead, same course
    own, other, velocity, _ = encounter(kcs, start, velocity, colregs=True)
    separation, bearing, _ = at_closest_approach(own, other, velocity)
    assert separation >= RADIUS
    assert own[-1, 0] > other[-1, 0] + 0.5 * NM  # got past it (slowly: it holds its alteration until clear)


def rho_circle_clearance(slots, slot, points_m, length_m):
    """Scaled clearance of points (m, relative to the solve origin) from one slot's domain at t = 0."""
    cx, cy, _, _, ox, oy, radius, _, _, _ = slots[:, slot]
    d = np.hypot(points_m[:, 0] / length_m - (cx + ox), points_m[:, 1] / length_m - (cy + oy))
    return d / radius - 1.0


@pytest.mark.parametrize("course_deg, bearing_deg, expected", [
    (180.0, 0.0, "head_on"), (270.0, 45.0, "crossing_give_way"), (0.0, 0.0, "overtaking"),
])
def test_domains_contain_the_circle_and_grow_ahead_and_to_starboard(course_deg, bearing_deg, expected):
    length = 230.0
    domains = CollisionDomains(DomainSettings(colregs=True, clearance_margin_m=100.0), max_obstacles=2)
    state = np.array([0.0, 0.0, 0.0, SPEED, 0.0, 0.0])
    target = 3.0 * NM * np.array([math.cos(math.radians(bearing_deg)), math.sin(math.radians(bearing_deg))])
    velocity = 10 * KNOT * np.array([math.cos(math.radians(course_deg)), math.sin(math.radians(course_deg))])
    slots, report = domains.parameters(np.array([[*target, *velocity, RADIUS]]), state, np.zeros(2), SPEED, 5.0,
                                       length, et=True)
    assert report.class_codes[0] >= 0 and report.active[0] == 1.0
    from rhnc.encounters.colregs import ENCOUNTER_CLASSES

    assert ENCOUNTER_CLASSES[int(report.class_codes[0])] == expected
    rho = RADIUS + 100.0
    angles = np.linspace(0.0, 2 * np.pi, 361)
    circle = target + rho * np.column_stack([np.cos(angles), np.sin(angles)])
    assert rho_circle_clearance(slots, 0, circle, length).max() <= 1e-9  # the circle R + R_i + margin is inside
    ahead = velocity / np.hypot(*velocity)
    starboard = np.array([-ahead[1], ahead[0]])
    extent = {name: domain_extent(slots, 0, target, direction, length)
              for name, direction in (("ahead", ahead), ("astern", -ahead), ("starboard", starboard),
                                      ("port", -starboard))}
    assert min(extent.values()) >= rho - 1e-6
    assert extent["ahead"] > extent["astern"] + 0.4 * rho
    if expected != "overtaking":
        assert extent["starboard"] > extent["port"] + 0.4 * rho


def domain_extent(slots, slot, target_m, direction, length_m):
    """Distance [m] from the target to the domain's edge along a unit direction (t = 0)."""
    cx, cy, _, _, ox, oy, radius, _, _, _ = slots[:, slot] * np.r_[length_m, length_m, 1, 1, length_m, length_m,
                                                                    length_m, 1, 1, 1]
    offset = np.array([cx + ox, cy + oy]) - target_m
    along = float(offset @ direction)
    return along + math.sqrt(along**2 - float(offset @ offset) + radius**2)


def test_stand_on_target_has_no_constraint_until_its_action_is_not_enough():
    domains = CollisionDomains(DomainSettings(colregs=True), max_obstacles=1)
    state = np.array([0.0, 0.0, 0.0, SPEED, 0.0, 0.0])
    start, velocity = target_on_collision_course(90.0, 15.0)
    # TCPA 900, 720, 660 s; a 35 deg alteration to starboard still opens the CPA to R + R_i if
    # begun within 420, 240, 180 s: the stand-on ship acts once that is down to ACTION_BUFFER_S
    for t, expected_active in ((0.0, 0.0), (180.0, 0.0), (240.0, 1.0)):
        own = state.copy()
        own[0] = SPEED * t
        slots, report = domains.parameters(np.array([[*(start + velocity * t), *velocity, RADIUS]]), own, own[:2],
                                           SPEED, 5.0, 230.0, et=True)
        assert report.active[0] == expected_active, t
        assert slots[OBSTACLE_FIELDS - 1, 0] == expected_active
    assert domains.stand_on_actions == 1


def test_no_port_turn_for_a_crossing_target_on_the_port_side_even_while_standing_on():
    domains = CollisionDomains(DomainSettings(colregs=True), max_obstacles=2)
    state = np.array([0.0, 0.0, 0.0, SPEED, 0.0, 0.0])
    start, velocity = target_on_collision_course(90.0, 15.0)  # from port, gives way to us
    _, report = domains.parameters(np.array([[*start, *velocity, RADIUS]]), state, np.zeros(2), SPEED, 5.0, 230.0,
                                   et=True)
    assert report.active[0] == 0.0  # standing on: its constraint is off ...
    assert report.no_port_turn  # ... and yet no turn to port across its bow (Rule 17(c))
    overtaken = np.array([[1.0 * NM, 0.0, 8 * KNOT, 0.0, RADIUS]])  # a slower ship ahead only
    _, report = CollisionDomains(DomainSettings(colregs=True), max_obstacles=2).parameters(
        overtaken, state, np.zeros(2), SPEED, 5.0, 230.0, et=True)
    assert not report.no_port_turn


def test_a_ship_swinging_to_port_when_port_turns_are_ruled_out_still_gets_a_plan(kcs):
    # turned to port for a target inside its domain, the ship swings on at 0.86 deg/s when a ship
    # crossing from port (we stand on for it) rules out turns to port (Rule 17(c)): no rudder
    # stops that swing at once, so a bound at the measured heading has no feasible plan, and the
    # controller fell back (five trafficgen situations at t = 40 s)
    controller = NMPCController(kcs, NMPCSettings(horizon_steps=N, control_interval_s=20.0, colregs=True))
    yaw_rate = math.radians(-0.86)
    state = np.array([0.0, 0.0, math.radians(-24.0), 7.1, 0.0, yaw_rate])
    start, velocity = target_on_collision_course(90.0, 15.0)  # from port, 4.5 nm off
    obstacles = np.array([[*start, *velocity, RADIUS]])
    reference = line_or_turn_reference(20.0 * np.arange(N + 1), (0.0, 0.0), 0.0, SPEED)
    solution = controller.solve(0.0, state, reference, obstacles, et=True)
    assert controller.domains.parameters(obstacles, state, np.zeros(2), SPEED, 5.0, 230.0, et=True)[1].no_port_turn
    assert not solution.fallback, solution.status
    heading = solution.states[:, 2]
    assert heading.min() < state[2] - math.radians(1.0)  # the swing carries on ...
    assert heading[-1] > state[2] + math.radians(20.0)  # ... and is stopped and turned back
    controller.close()

def test_an_alteration_to_starboard_asks_no_more_than_the_model_can_turn_from_a_swing_to_port(kcs):
    # a ship at 12.3 m/s swinging to port at 1.14 deg/s, held to a 35 deg alteration to
    # starboard with no turn to port allowed: the prediction model needs some 100 s under the
    # full moment to reverse that swing, far behind the floor's first-order cap, and every solve
    # failed (trafficgen situations, 1-5 fallbacks each). The floor now stays below the model's
    # own turn at REACH_MOMENT_SHARE of the moment, and the step has a plan
    import dataclasses
    controller = NMPCController(kcs, NMPCSettings(horizon_steps=N, control_interval_s=20.0, colregs=True))
    parameters = controller.domains.parameters

    def held_alteration(*args, **kwargs):
        slots, report = parameters(*args, **kwargs)
        return slots, dataclasses.replace(report, no_port_turn=True,
                                          alteration_floor=(0.0, 0.0, math.radians(35.0)))

    controller.domains.parameters = held_alteration
    state = np.array([0.0, 0.0, math.radians(-8.0), 12.3, 0.0, math.radians(-1.14)])
    reference = line_or_turn_reference(300.0 + 20.0 * np.arange(N + 1), (0.0, 0.0), 0.0, SPEED)
    previous = np.array([0.0, -kcs.tau_max[1]])  # full port moment until now
    step = controller._prepare(300.0, state, reference, None, True, previous)
    starboard, _ = controller._heading_reach(state, previous, step.disturbance)
    floor = step.lbx[controller.problem.z_index[1:, 2]]
    assert np.all(floor <= starboard - math.radians(HEADING_TOLERANCE_DEG) + 1e-12)
    solution = controller.solve(300.0, state, reference, None, et=True, previous_tau=previous)
    assert not solution.fallback, solution.status
    controller.close()

def test_alteration_bound_rises_to_the_alteration_and_never_lets_the_first_step_sag():
    report = DomainReport(np.zeros(1), np.ones(1), alteration_floor=(100.0, 0.0, math.radians(30.0)))
    times = 100.0 + 20.0 * np.arange(1, 31)
    floor, ceiling = heading_bounds(report, 100.0, 0.0, 0.0, times)
    assert ceiling is None
    floor_deg = np.degrees(floor)
    assert np.all(np.diff(floor_deg) >= -1e-9) and floor_deg[-1] == pytest.approx(30.0)
    assert floor_deg[0] < 3.0  # from a steady heading the ship is asked for a feasible start
    # a ship behind the ramp (here on 20 deg at 600 s) may not plan a first step below its
    # heading: applying only that step, it would otherwise put the turn off at every solve
    later = 600.0 + 20.0 * np.arange(1, 16)
    floor = np.degrees(heading_bounds(report, 600.0, math.radians(20.0), 0.0, later)[0])
    # progress from step 1: a first-order yaw response towards CATCH_UP_RATE_DEG_S, from
    # the measured heading less only the numerical tolerance
    response = CATCH_UP_RATE_DEG_S * (20.0 - YAW_TIME_CONSTANT_S * (1.0 - math.exp(-20.0 / YAW_TIME_CONSTANT_S)))
    assert floor[0] == pytest.approx(20.0 - HEADING_TOLERANCE_DEG + response) and floor[0] > 22.0
    assert floor[-1] == pytest.approx(30.0)
    # a yaw swing the other way is allowed for (the ship needs time to check it)
    swinging = np.degrees(heading_bounds(report, 600.0, math.radians(20.0), math.radians(-0.2), later)[0])
    assert swinging[0] < floor[0] - 3.0
    # to port (overtaking on the other side): the mirror image
    port = DomainReport(np.zeros(1), np.ones(1), alteration_ceiling=(100.0, 0.0, math.radians(-30.0)))
    lower, upper = heading_bounds(port, 100.0, 0.0, 0.0, times)
    assert lower is None and np.degrees(upper[-1]) == pytest.approx(-30.0)



def test_a_ship_turning_behind_the_alteration_is_asked_to_turn_faster_than_it_does():
    """From rest at every solve, the catch-up asked a ship turning at 0.15 deg/s for 2.9 deg
    a 20-s step: no more than it turned, and it held half the ramp's rate to the end."""
    report = DomainReport(np.zeros(1), np.ones(1), alteration_floor=(100.0, 0.0, math.radians(35.0)))
    later = 300.0 + 20.0 * np.arange(1, 16)
    turning = math.radians(0.15)
    for sign, alteration in ((1.0, report), (-1.0, DomainReport(np.zeros(1), np.ones(1), alteration_ceiling=(
            100.0, 0.0, math.radians(-35.0))))):
        lower, upper = heading_bounds(alteration, 300.0, sign * math.radians(10.0), sign * turning, later)
        first = sign * np.degrees(lower if sign > 0 else upper)[0]
        assert first - 10.0 > 0.15 * 20.0 + 1.0  # more than the rate it has would carry it
        still = sign * np.degrees(heading_bounds(alteration, 300.0, sign * math.radians(10.0), 0.0, later)[
            0 if sign > 0 else 1])[0]
        assert first > still  # the rate it has counts
        # and never more than the catch-up rate itself asks from a ship already at it
        at_rate = sign * np.degrees(heading_bounds(alteration, 300.0, sign * math.radians(10.0),
                                                   sign * math.radians(1.0), later)[0 if sign > 0 else 1])[0]
        assert at_rate - 10.0 == pytest.approx(CATCH_UP_RATE_DEG_S * 20.0 - HEADING_TOLERANCE_DEG)

def test_give_way_alteration_starts_with_the_encounter_and_ends_when_clear():
    domains = CollisionDomains(DomainSettings(colregs=True), max_obstacles=2)
    state = np.array([0.0, 0.0, 0.0, SPEED, 0.0, 0.0])
    start, velocity = target_on_collision_course(270.0, 15.0)  # crossing from starboard, CPA in 15 min
    earlier = start - velocity * 300.0  # CPA in 20 min: not yet
    obstacles = np.array([[*earlier, *velocity, RADIUS]])
    behind = state.copy()
    behind[0] = -SPEED * 300.0
    _, report = domains.parameters(obstacles, behind, behind[:2], SPEED, 5.0, 230.0, et=True,
                                   reference_heading_rad=0.0, time_s=0.0)
    assert report.alteration_floor is None
    ahead = start + velocity * 60.0  # CPA in 14 min: within give_way_action_tcpa_s
    moved = state.copy()
    moved[0] = SPEED * 60.0
    _, report = domains.parameters(np.array([[*ahead, *velocity, RADIUS]]), moved, moved[:2], SPEED, 5.0, 230.0,
                                   et=True, reference_heading_rad=0.0, time_s=360.0)
    assert report.alteration_floor == pytest.approx((360.0, 0.0, math.radians(DomainSettings().alteration_deg)))
    assert domains.alterations == 1
    def passed(range_nm, time_s):  # the target astern on our port quarter, heading away west
        where = moved[:2] + range_nm * NM * np.array([-math.sqrt(0.5), -math.sqrt(0.5)])
        return domains.parameters(np.array([[*where, *velocity, RADIUS]]), moved, moved[:2], SPEED, 5.0, 230.0,
                                  et=True, reference_heading_rad=0.0, time_s=time_s)[1]

    assert passed(1.5, 600.0).alteration_floor is not None  # past, not yet clear, held 4 min: held
    assert passed(2.5, 620.0).alteration_floor is None  # past and clear (2 R + R_i): ended
    assert passed(2.5, 640.0).alteration_floor is None and domains.alterations == 1  # not begun again


def test_an_alteration_for_a_ship_that_stays_alongside_ends_once_the_way_back_is_clear():
    """A ship on a parallel course at our speed never gets past and clear: the alteration
    ends, after ALTERATION_MIN_HOLD_S, once a return to the reference keeps it clear, and is
    held while that return would close it."""
    from rhnc.control.nmpc_actions import ALTERATION_MIN_HOLD_S

    heading = math.radians(35.0)  # altered 35 deg to starboard of a reference on north
    own = np.array([0.0, 0.0, heading, SPEED, 0.0, 0.0])
    velocity = SPEED * np.array([math.cos(heading), math.sin(heading)])  # the same course and speed

    def alongside(bearing_deg: float, time_s: float, reference_deg: float = 0.0, faster_kn: float = 0.0):
        domains = CollisionDomains(DomainSettings(colregs=True), max_obstacles=2)
        where = 1.05 * NM * np.array([math.cos(heading + math.radians(bearing_deg)),
                                      math.sin(heading + math.radians(bearing_deg))])
        start, crossing = target_on_collision_course(90.0, 15.0)  # first a ship crossing from port
        north = np.array([0.0, 0.0, 0.0, SPEED, 0.0, 0.0])
        domains.parameters(np.array([[*start, *crossing, RADIUS]]), north, north[:2], SPEED, 5.0, 230.0, et=True,
                           reference_heading_rad=0.0, time_s=0.0)
        assert domains.tracker.locked[0] == "crossing_stand_on"
        on_course = velocity * (1.0 + faster_kn * KNOT / SPEED)
        target = np.array([[*where, *on_course, RADIUS]])  # ... then on our course and speed, 1.05 nm off
        domains._altering[0] = (0.0, 0.0, heading, 1.0)  # an alteration held since t = 0
        domains.parameters(target, own, own[:2], SPEED, 5.0, 230.0, et=True,
                           reference_heading_rad=math.radians(reference_deg), time_s=time_s)
        return 0 in domains._altering

    late = ALTERATION_MIN_HOLD_S + 60.0
    assert not alongside(180.0, late)  # right astern: the way back opens the range: ended
    assert alongside(180.0, ALTERATION_MIN_HOLD_S - 60.0)  # ... not before the alteration is shown
    assert alongside(-90.0, late)  # abeam to port: turning back closes on it: held
    assert alongside(180.0, late, reference_deg=-90.0)  # a way back across its bow: held
    assert not alongside(90.0, late)  # abeam to starboard: the way back opens the range: ended
    assert alongside(100.0, late, faster_kn=2.0)  # ... but coming up on us from abaft the beam: held


def test_alteration_is_readily_apparent_from_the_heading_at_the_onset_of_risk():
    # the risk begins with the ship heading north; when the alteration begins, the reference
    # points 20 deg to port (back to the route after a detour): 35 deg from that reference
    # would leave the ship only 15 deg off the course the other ship saw at the onset
    domains = CollisionDomains(DomainSettings(colregs=True), max_obstacles=2)
    start, velocity = target_on_collision_course(270.0, 15.0)
    behind = np.array([-SPEED * 300.0, 0.0, 0.0, SPEED, 0.0, 0.0])
    _, report = domains.parameters(np.array([[*(start - velocity * 300.0), *velocity, RADIUS]]), behind, behind[:2],
                                   SPEED, 5.0, 230.0, et=True, reference_heading_rad=0.0, time_s=0.0)
    assert report.class_codes[0] == ENCOUNTER_CLASSES.index("crossing_give_way") and report.alteration_floor is None
    moved = np.array([SPEED * 60.0, 0.0, 0.0, SPEED, 0.0, 0.0])
    _, report = domains.parameters(np.array([[*(start + velocity * 60.0), *velocity, RADIUS]]), moved, moved[:2],
                                   SPEED, 5.0, 230.0, et=True, reference_heading_rad=math.radians(-20.0), time_s=360.0)
    assert math.degrees(report.alteration_floor[2]) == pytest.approx(DomainSettings().alteration_deg)
    # a reference already further to starboard than that keeps its own 35 deg
    domains = CollisionDomains(DomainSettings(colregs=True), max_obstacles=2)
    domains.parameters(np.array([[*(start - velocity * 300.0), *velocity, RADIUS]]), behind, behind[:2],
                       SPEED, 5.0, 230.0, et=True, reference_heading_rad=0.0, time_s=0.0)
    _, report = domains.parameters(np.array([[*(start + velocity * 60.0), *velocity, RADIUS]]), moved, moved[:2],
                                   SPEED, 5.0, 230.0, et=True, reference_heading_rad=math.radians(10.0), time_s=360.0)
    assert math.degrees(report.alteration_floor[2]) == pytest.approx(10.0 + DomainSettings().alteration_deg)


def test_a_give_way_ship_turning_away_by_itself_is_held_to_a_readily_apparent_alteration():
    # a ship crossing from starboard, CPA 25 min ahead (the alteration is not yet due); the
    # NMPC has begun to turn away from the reference for it (10 deg, still turning): the
    # alteration begins now and is held to 35 deg, not left at what opened the CPA just enough
    start, velocity = target_on_collision_course(270.0, 15.0)
    behind = np.array([-SPEED * 600.0, 0.0, math.radians(10.0), SPEED, 0.0, math.radians(0.3)])
    obstacles = np.array([[*(start - velocity * 600.0), *velocity, RADIUS]])

    def alteration(state):
        domains = CollisionDomains(DomainSettings(colregs=True), max_obstacles=2)
        _, report = domains.parameters(obstacles, state, state[:2], SPEED, 5.0, 230.0, et=True,
                                       reference_heading_rad=0.0, time_s=0.0)
        assert report.class_codes[0] == ENCOUNTER_CLASSES.index("crossing_give_way")
        return report.alteration_floor

    floor = alteration(behind)
    assert floor is not None and math.degrees(floor[2]) == pytest.approx(10.0 + DomainSettings().alteration_deg)
    returning = behind.copy()
    returning[5] = -returning[5]  # turning back to the reference: no manoeuvre
    assert alteration(returning) is None
    small = behind.copy()
    small[2] = math.radians(3.0)  # within the manoeuvre threshold
    assert alteration(small) is None


def test_stand_on_target_is_kept_clear_of_once_the_ship_gives_way_to_another():
    # a crossing ship from starboard (we give way, CPA in 14 min) and one from port (we stand
    # on, CPA in 25 min): once the own ship alters for the first, it no longer keeps its
    # course and speed, so the second one's constraint is on too, for the rest of its encounter
    state = np.array([0.0, 0.0, 0.0, SPEED, 0.0, 0.0])
    give_way_start, give_way_velocity = target_on_collision_course(270.0, 15.0)
    stand_on_velocity = 15.0 * KNOT * np.array([0.0, 1.0])
    stand_on_start = np.array([SPEED * 1500.0, 0.0]) - stand_on_velocity * 1500.0

    def rows(dt_s, with_give_way=True):
        stand_on = [*(stand_on_start + stand_on_velocity * dt_s), *stand_on_velocity, RADIUS]
        give_way = [*(give_way_start + give_way_velocity * (dt_s + 60.0)), *give_way_velocity, RADIUS]
        return np.array([stand_on, give_way] if with_give_way else [stand_on])

    def solve_parameters(domains, dt_s, with_give_way=True):
        own = state.copy()
        own[0] = SPEED * dt_s
        return domains.parameters(rows(dt_s, with_give_way), own, own[:2], SPEED, 5.0, 230.0, et=True,
                                  reference_heading_rad=0.0, time_s=dt_s)[1]

    domains = CollisionDomains(DomainSettings(colregs=True), max_obstacles=2)
    first = solve_parameters(domains, 0.0)
    assert first.class_codes[0] == ENCOUNTER_CLASSES.index("crossing_stand_on")
    assert first.alteration_floor is not None and first.active[0] == 0.0  # altering from this solve on
    assert solve_parameters(domains, 20.0).active[0] == 1.0
    assert domains.stand_on_actions == 0  # not a Rule 17 action: no stand-on alteration of its own
    domains._altering.clear()  # the give-way alteration is over (as when its target is released)
    assert solve_parameters(domains, 40.0).active[0] == 1.0  # still kept clear of
    alone = CollisionDomains(DomainSettings(colregs=True), max_obstacles=2)
    for dt_s in (0.0, 20.0, 40.0):
        assert solve_parameters(alone, dt_s, with_give_way=False).active[0] == 0.0  # stands on


def test_overtaking_ship_alters_when_the_altered_course_brings_the_cpa_within_reach():
    # 1.9 nm behind a 12 kn ship on the same course: at the present velocities the CPA is
    # 19 min ahead, but turning away (to port: it is a little to starboard) brings it to
    # about 2 min; the alteration begins now, not once the 15 min have run down
    domains = CollisionDomains(DomainSettings(colregs=True), max_obstacles=2)
    state = np.array([0.0, 0.0, 0.0, SPEED, 0.0, 0.0])
    target = np.array([[1.9 * NM, 0.1 * NM, 12.0 * KNOT, 0.0, RADIUS]])
    _, report = domains.parameters(target, state, np.zeros(2), SPEED, 5.0, 230.0, et=True,
                                   reference_heading_rad=0.0, time_s=0.0)
    assert report.class_codes[0] == ENCOUNTER_CLASSES.index("overtaking")
    assert report.alteration_floor is None
    assert report.alteration_ceiling == pytest.approx((0.0, 0.0, -math.radians(DomainSettings().alteration_deg)))


def test_targets_out_of_reach_within_the_horizon_get_no_constraint():
    # 18 kn own ship (closing speed taken 25 % higher) and a 12 kn head-on target: within a
    # 200 s horizon the two close by at most (22.5 + 12) kn * 200 s = 1.9 nm
    domains = CollisionDomains(DomainSettings(colregs=True), max_obstacles=2)
    state = np.array([0.0, 0.0, 0.0, SPEED, 0.0, 0.0])
    targets = np.array([[5.0 * NM, 0.1 * NM, -12 * KNOT, 0.0, RADIUS],   # 5 nm: out of reach
                        [2.5 * NM, -0.1 * NM, -12 * KNOT, 0.0, RADIUS]])  # 2.5 nm: may reach its domain
    slots, report = domains.parameters(targets, state, np.zeros(2), 1.25 * SPEED, 5.0, 230.0, et=True,
                                       horizon_s=200.0)
    np.testing.assert_array_equal(report.active, [0.0, 1.0])
    assert slots[-1, 0] == 1.0 and slots[-1, 1] == 0.0  # one slot filled, the second left off
    _, report = domains.parameters(targets, state, np.zeros(2), 1.25 * SPEED, 5.0, 230.0, et=True)
    np.testing.assert_array_equal(report.active, [1.0, 1.0])  # no horizon given: every target


def test_each_obstacle_in_reach_gets_its_own_slot_nearest_first():
    domains = CollisionDomains(DomainSettings(colregs=False), max_obstacles=4)
    state = np.array([0.0, 0.0, 0.0, SPEED, 0.0, 0.0])
    obstacles = np.array([[3 * NM, 0.0, 0.0, 0.0, RADIUS], [1 * NM, 0.0, 0.0, 0.0, RADIUS],
                          [2 * NM, 0.5 * NM, 0.0, 0.0, RADIUS]])
    slots, report = domains.parameters(obstacles, state, np.zeros(2), SPEED, 5.0, 230.0, et=True)
    np.testing.assert_array_equal(slots[OBSTACLE_FIELDS - 1], [1.0, 1.0, 1.0, 0.0])
    np.testing.assert_allclose(slots[0, :3] * 230.0, [1 * NM, 2 * NM, 3 * NM])
    np.testing.assert_allclose(slots[1, :3] * 230.0, [0.0, 0.5 * NM, 0.0])
    np.testing.assert_array_equal(report.active, [1.0, 1.0, 1.0])


@pytest.mark.parametrize("acting, alters", [(False, False), (True, True)])
def test_a_stand_on_ship_alters_only_once_it_acts(acting, alters):
    """A stand-on target kept clear of (guarded, while the ship gives way to another) begins no
    alteration of its own: only Rule 17's action does (with the CPA ahead)."""
    from types import SimpleNamespace

    domains = CollisionDomains(DomainSettings(colregs=True), max_obstacles=2)
    if acting:
        domains._acting.add(0)
    encounter = SimpleNamespace(encounter_class="crossing_stand_on", tcpa_s=300.0, cpa_m=100.0, range_m=2 * NM,
                                relative_bearing_deg=-60.0)
    domains._update_alteration(0, encounter, 0.0, 0.0, 50.0, RADIUS)
    assert (0 in domains._altering, domains.alterations) == (alters, int(alters))


def test_overtaking_ship_alters_to_starboard_when_another_target_rules_out_port():
    # the overtaking situation above (the overtaken ship a little to starboard: alone, the
    # alteration goes to port), plus a crossing ship from port that gives way to us: no turn
    # to port (Rule 17(c)), so the give-way alteration goes to starboard instead of none
    domains = CollisionDomains(DomainSettings(colregs=True), max_obstacles=2)
    state = np.array([0.0, 0.0, 0.0, SPEED, 0.0, 0.0])
    start, velocity = target_on_collision_course(90.0, 15.0)
    targets = np.array([[1.9 * NM, 0.1 * NM, 12.0 * KNOT, 0.0, RADIUS], [*start, *velocity, RADIUS]])
    _, report = domains.parameters(targets, state, np.zeros(2), SPEED, 5.0, 230.0, et=True,
                                   reference_heading_rad=0.0, time_s=0.0)
    assert [ENCOUNTER_CLASSES[int(code)] for code in report.class_codes] == ["overtaking", "crossing_stand_on"]
    assert report.no_port_turn
    assert report.alteration_ceiling is None
    assert report.alteration_floor == pytest.approx((0.0, 0.0, math.radians(DomainSettings().alteration_deg)))


def test_a_target_in_reach_gets_its_slot_behind_a_nearer_one_out_of_reach():
    # the reach test is per target: a static buoy 2.5 nm ahead cannot be reached in 200 s,
    # a 25 kn ship 3.5 nm off (farther, so sorted after it) can; the buoy's verdict must not
    # end the look at the rest.  The slot holds the target's position and velocity in the
    # problem's scaled units (L = 230 m), so that its predicted centre is (x + vx t) / L.
    domains = CollisionDomains(DomainSettings(own_radius_m=0.0, colregs=False), max_obstacles=2)
    state = np.array([0.0, 0.0, 0.0, SPEED, 0.0, 0.0])
    origin = np.array([100.0, -50.0])
    velocity = 25 * KNOT * np.array([-math.sqrt(0.5), math.sqrt(0.5)])
    rows = np.array([[2.5 * NM, 0.0, 0.0, 0.0, 0.1 * NM], [3.5 * NM, -0.5 * NM, *velocity, RADIUS]])
    slots, report = domains.parameters(rows, state, origin, 1.25 * SPEED, 5.0, 230.0, et=True, horizon_s=200.0)
    np.testing.assert_array_equal(report.active, [0.0, 1.0])
    for t in (0.0, 120.0):
        centre = (slots[0:2, 0] + slots[2:4, 0] * t) * 230.0 + origin
        np.testing.assert_allclose(centre, rows[1, :2] + velocity * t, rtol=0, atol=1e-6)
    assert slots[6, 0] * 230.0 == pytest.approx(RADIUS)


def test_a_target_past_its_cpa_no_longer_rules_out_a_turn_to_port():
    # a crossing ship from starboard (we give way): while it approaches, no turn to port;
    # once its CPA is past (still held in its class until 4 nm off), the bound is lifted
    domains = CollisionDomains(DomainSettings(colregs=True, alteration_deg=0.0), max_obstacles=1)
    state = np.array([0.0, 0.0, 0.0, SPEED, 0.0, 0.0])
    start, velocity = target_on_collision_course(270.0, 15.0)
    _, report = domains.parameters(np.array([[*start, *velocity, RADIUS]]), state, np.zeros(2), SPEED, 5.0, 230.0,
                                   et=True)
    assert report.class_codes[0] == ENCOUNTER_CLASSES.index("crossing_give_way") and report.no_port_turn
    past = np.array([[-1.5 * NM * math.sqrt(0.5), -1.5 * NM * math.sqrt(0.5), *velocity, RADIUS]])
    _, report = domains.parameters(past, state, np.zeros(2), SPEED, 5.0, 230.0, et=True)
    assert report.class_codes[0] == ENCOUNTER_CLASSES.index("crossing_give_way")  # held: past, within 4 nm
    assert not report.no_port_turn


def test_a_give_way_alteration_needs_the_cpa_inside_the_risk_distance():
    # a crossing ship from starboard, classified at 20 min with a CPA of nil, then seen on a
    # track that passes 2.5 nm off with its CPA 10 min away: the class is held, but there is
    # no longer a risk of collision to give way to, so no alteration begins
    settings = DomainSettings(colregs=True)
    domains = CollisionDomains(settings, max_obstacles=1)
    state = np.array([0.0, 0.0, 0.0, SPEED, 0.0, 0.0])
    start, velocity = target_on_collision_course(270.0, 15.0)
    behind = state.copy()
    behind[0] = -SPEED * 300.0
    _, report = domains.parameters(np.array([[*(start - velocity * 300.0), *velocity, RADIUS]]), behind, behind[:2],
                                   SPEED, 5.0, 230.0, et=True, reference_heading_rad=0.0, time_s=0.0)
    assert report.class_codes[0] == ENCOUNTER_CLASSES.index("crossing_give_way") and report.alteration_floor is None
    moved = state.copy()
    moved[0] = SPEED * 60.0
    # still heading west, placed so that its CPA is 2.5 nm (beyond the 2 nm of risk) in 10 min
    altered_velocity = velocity
    relative = altered_velocity - np.array([SPEED, 0.0])
    across = np.array([-relative[1], relative[0]]) / np.hypot(*relative)
    target = moved[:2] - 600.0 * relative + 2.5 * NM * across
    cpa, tcpa = cpa_tcpa(moved[:2], np.array([SPEED, 0.0]), target, altered_velocity)
    assert cpa > settings.risk_cpa_m and 0.0 < tcpa <= settings.give_way_action_tcpa_s
    _, report = domains.parameters(np.array([[*target, *altered_velocity, RADIUS]]), moved, moved[:2], SPEED, 5.0,
                                   230.0, et=True, reference_heading_rad=0.0, time_s=360.0)
    assert report.class_codes[0] == ENCOUNTER_CLASSES.index("crossing_give_way")
    assert report.alteration_floor is None and report.alteration_ceiling is None and domains.alterations == 0


def test_collision_risk_is_assessed_at_every_solve_without_the_navigation_trigger():
    # head-on at 40.6 kn closing, 6 nm off: the navigation's 4.5 nm trigger has not fired
    state = np.array([0.0, 0.0, 0.0, SPEED, 0.0, 0.0])
    target = np.array([[6.0 * NM, 0.05 * NM, -22.6 * KNOT, 0.0, RADIUS]])
    colregs = CollisionDomains(DomainSettings(colregs=True), max_obstacles=1)
    _, report = colregs.parameters(target, state, state[:2], SPEED, 5.0, 230.0, et=False, horizon_s=300.0)
    assert report.risk and report.alteration_floor is not None  # the alteration to starboard begins
    assert report.active[0] == 0.0  # its domain is still out of reach within the 5 min horizon ...
    state[0] = 1.0 * NM
    target[0, 0] -= 1.0 * NM * 22.6 / 18.0
    _, report = colregs.parameters(target, state, state[:2], SPEED, 5.0, 230.0, et=False, horizon_s=300.0, time_s=100.0)
    assert report.active[0] == 1.0  # ... and constrained as soon as it is within reach
    # the paper's mode keeps the paper's trigger
    paper = CollisionDomains(DomainSettings(colregs=False), max_obstacles=1)
    _, report = paper.parameters(target, state, state[:2], SPEED, 5.0, 230.0, et=False, horizon_s=300.0)
    assert report.active[0] == 0.0 and not report.risk and report.alteration_floor is None
    # a target passing far off raises no risk
    far = np.array([[6.0 * NM, 3.0 * NM, -22.6 * KNOT, 0.0, RADIUS]])
    _, report = CollisionDomains(DomainSettings(colregs=True), 1).parameters(far, state, state[:2], SPEED, 5.0, 230.0,
                                                                             et=False, horizon_s=300.0)
    assert report.active[0] == 0.0 and not report.risk


def test_a_give_way_ship_alters_once_its_time_to_alter_runs_out_even_with_a_long_tcpa():
    # a crossing ship from starboard at 30 kn: with the action TCPA set far
    # below, only the time a readily apparent alteration needs can start the alteration
    settings = DomainSettings(colregs=True, give_way_action_tcpa_s=60.0)
    state = np.array([0.0, 0.0, 0.0, SPEED, 0.0, 0.0])
    start, velocity = target_on_collision_course(250.0, 30.0)
    domains = CollisionDomains(settings, max_obstacles=1)
    began = None
    for t in np.arange(0.0, 900.0, 20.0):
        own = state.copy()
        own[0] = SPEED * t
        _, report = domains.parameters(np.array([[*(start + velocity * t), *velocity, RADIUS]]), own, own[:2], SPEED,
                                       5.0, 230.0, et=True, time_s=float(t))
        if report.alteration_floor is not None:
            began = t
            break
    assert began is not None and 900.0 - began > 300.0  # more than 5 min before the CPA


def test_a_target_inside_the_clearance_must_see_the_range_open_and_may_be_left_to_port():
    # a crossing ship 0.8 nm off on the starboard bow, closing: inside R + R_i
    domains = CollisionDomains(DomainSettings(colregs=True), max_obstacles=1)
    state = np.array([0.0, 0.0, 0.0, SPEED, 0.0, 0.0])
    bearing = math.radians(40.0)
    target = np.array([[0.8 * NM * math.cos(bearing), 0.8 * NM * math.sin(bearing),
                        *(12.0 * KNOT * np.array([math.cos(math.radians(300.0)), math.sin(math.radians(300.0))])),
                        RADIUS]])
    slots, report = domains.parameters(target, state, state[:2], SPEED, 5.0, 230.0, et=True, horizon_s=300.0)
    radius_m = slots[6, 0] * 230.0
    assert report.active[0] == 1.0
    assert 0.5 * NM < radius_m < 0.8 * NM  # within the present range: the range may not close further ...
    assert slots[7, 0] * 230.0 > 0.5  # ... and it must open
    assert np.allclose(slots[4:6, 0], 0.0)  # a plain circle about the target
    assert not report.no_port_turn and report.alteration_floor is None  # immediate danger: any way out
    # a fallback's way out: straight away from the target (bearing 40 deg, so 220 deg)
    assert math.degrees(report.escape_heading) % 360.0 == pytest.approx(220.0)


def test_a_target_inside_the_clearance_and_opening_asks_no_escape():
    domains = CollisionDomains(DomainSettings(colregs=True), max_obstacles=1)
    state = np.array([0.0, 0.0, 0.0, SPEED, 0.0, 0.0])
    # 0.8 nm on the starboard beam, running away to the east at 12 kn
    target = np.array([[0.0, 0.8 * NM, 0.0, 12.0 * KNOT, RADIUS]])
    _, report = domains.parameters(target, state, state[:2], SPEED, 5.0, 230.0, et=True, horizon_s=300.0)
    assert not report.danger and report.escape_heading is None


def _overtaken_by_two():
    """Own ship northbound at 18 kn, overtaken by a ship 1.9 nm astern, a little to port
    (Rule 17 lets us act: within two clearances), and by a faster one from the starboard
    quarter, 2.6 nm off, whose CPA is 0.4 nm some 20 min ahead."""
    state = np.array([0.0, 0.0, 0.0, SPEED, 0.0, 0.0])
    course = math.radians(-14.0)
    fast = 27.6 * KNOT * np.array([math.cos(course), math.sin(course)])
    meeting = np.array([SPEED * 1200.0, 0.4 * NM])
    targets = np.array([[-1.9 * NM, -0.1 * NM, 25.0 * KNOT, 0.0, RADIUS], [*(meeting - fast * 1200.0), *fast, RADIUS]])
    return state, targets


def test_a_free_side_is_chosen_with_the_other_targets_in_view():
    # Rule 13 leaves the side of the stand-on action free; turning away from the ship astern
    # (to starboard) would head for the faster one on the starboard quarter: port keeps both clear
    state, targets = _overtaken_by_two()
    domains = CollisionDomains(DomainSettings(colregs=True, own_radius_m=0.0), max_obstacles=2)
    _, report = domains.parameters(targets, state, np.zeros(2), SPEED, 5.0, 230.0, et=True,
                                   reference_heading_rad=0.0, time_s=0.0)
    assert [ENCOUNTER_CLASSES[int(code)] for code in report.class_codes] == ["overtaken", "overtaken"]
    assert report.alteration_floor is None
    assert report.alteration_ceiling == pytest.approx((0.0, 0.0, -math.radians(DomainSettings().alteration_deg)))


def test_a_stand_on_target_is_kept_clear_of_while_the_ship_acts_for_another():
    # the own ship acts for the ship astern (Rule 17(b)) and no longer keeps its course: the
    # other overtaking ship, which does not yet call for action itself, gets its constraint too
    state, targets = _overtaken_by_two()
    domains = CollisionDomains(DomainSettings(colregs=True, own_radius_m=0.0), max_obstacles=2)
    _, first = domains.parameters(targets, state, np.zeros(2), SPEED, 5.0, 230.0, et=True, time_s=0.0)
    assert list(first.active) == [1.0, 0.0] and domains._altering
    _, second = domains.parameters(targets, state, np.zeros(2), SPEED, 5.0, 230.0, et=True, time_s=20.0)
    assert list(second.active) == [1.0, 1.0]


def test_a_stand_on_ship_turning_back_to_its_route_acts_away_from_the_overtaker():
    # overtaken by a ship on the port quarter 1.9 nm off while turning back to port towards the
    # route (heading 8 deg to port of the reference): that turn is no avoiding one, the action
    # for the overtaker goes away from it, to starboard
    heading = math.radians(-8.0)
    state = np.array([0.0, 0.0, heading, SPEED, 0.0, 0.0])
    overtaker = np.array([[-1.5 * NM, -1.15 * NM, 24.0 * KNOT * math.cos(0.3), 24.0 * KNOT * math.sin(0.3), RADIUS]])
    domains = CollisionDomains(DomainSettings(colregs=True), max_obstacles=2)
    _, report = domains.parameters(overtaker, state, np.zeros(2), SPEED, 5.0, 230.0, et=True,
                                   reference_heading_rad=0.0, time_s=0.0)
    assert ENCOUNTER_CLASSES[int(report.class_codes[0])] == "overtaken" and domains._acting == {0}
    assert report.alteration_ceiling is None and report.alteration_floor is not None


def test_a_ship_turned_half_a_turn_off_its_reference_keeps_the_reference_on_the_side_it_turned_from(kcs):
    # a stand-on ship turning hard to starboard (alteration held: 35 deg off a reference at
    # 0 deg) has come to 173 deg; the reference is at -8.7 deg, 181.7 deg off.  Taken on the
    # turn nearest the heading, it jumped to +351.3 deg, and the no-port-turn bound (not
    # below the reference less 2 deg, or the measured heading) forbade the turn back that
    # the warm start made: the budgeted solve fell back
    controller = NMPCController(kcs, NMPCSettings(horizon_steps=10, control_interval_s=20.0, colregs=True))
    state = np.array([0.0, 0.0, math.radians(173.0), SPEED, 0.0, 0.0])
    reference = line_or_turn_reference(20.0 * np.arange(11), (0.0, 0.0), math.radians(-8.7), SPEED)
    free = controller._trimmed_reference(0.0, state, reference)[0]
    assert math.degrees(free[0, 2]) == pytest.approx(351.3, abs=0.5)  # no alteration held: nearest turn
    controller.domains._altering = {1: (0.0, 0.0, math.radians(35.0), 1.0)}
    held = controller._trimmed_reference(0.0, state, reference)[0]
    assert math.degrees(held[0, 2]) == pytest.approx(-8.7, abs=0.5)
    # mirrored: an alteration to port held, the ship at -173 deg, the reference at +8.7 deg
    controller.domains._altering = {1: (0.0, 0.0, math.radians(-35.0), -1.0)}
    port_state = np.array([0.0, 0.0, math.radians(-173.0), SPEED, 0.0, 0.0])
    mirrored = controller._trimmed_reference(0.0, port_state, line_or_turn_reference(
        20.0 * np.arange(11), (0.0, 0.0), math.radians(8.7), SPEED))[0]
    assert math.degrees(mirrored[0, 2]) == pytest.approx(8.7, abs=0.5)
