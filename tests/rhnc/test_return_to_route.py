"""The turn back to the route after an alteration, with a ship on the port side (Rule 17(c)).

A ship that has given way turns back to its route once the target is past.  When that route
lies to port, the turn may make a ship on the port side, in no risk of collision so far, one
crossing from port: we would then stand on for it with a turn to port under way, which Rule
17(c) rules out.  The turn goes only as far as keeps that ship out of risk
(:func:`rhnc.control.nmpc_manoeuvre.port_return_limit`), and while a ship crossing from port
that we stand on for is still to pass, the course is kept (:mod:`rhnc.control.nmpc_colregs`).

Own ship at the origin at 16 kn on 035 (x north, y east, angles clockwise from north), back
from an alteration to a route on 000; the target 4.5 nm off on 313 (our port beam) steers 036
at 9.6 kn: no risk on our course, and on the route's it becomes a ship crossing from port.
"""

import math

import numpy as np
import pytest

from rhnc.control.nmpc_colregs import CollisionDomains, DomainSettings
from rhnc.control.nmpc_manoeuvre import RETURN_STEP_DEG, port_return_limit
from rhnc.encounters.colregs import ENCOUNTER_CLASSES, classify, cpa_tcpa

NM = 1852.0
KNOT = NM / 3600.0
SPEED = 16.0 * KNOT
COURSE = math.radians(35.0)
CPA_LIMIT, TCPA_LIMIT = 2.0 * NM, 1800.0


def vector(bearing_deg: float, length: float) -> np.ndarray:
    angle = math.radians(bearing_deg)
    return length * np.array([math.cos(angle), math.sin(angle)])


PORT_BEAM = (vector(-47.0, 4.5 * NM), vector(36.0, 9.6 * KNOT))
#: a ship 3 nm off on 350 (our port bow) steering 090 at 12 kn
CROSSING_FROM_PORT = (vector(-10.0, 3.0 * NM), vector(90.0, 12.0 * KNOT))


def cls(course_deg: float, target=PORT_BEAM) -> str:
    return classify((0.0, 0.0), math.radians(course_deg), SPEED, *target, CPA_LIMIT, TCPA_LIMIT).encounter_class


def test_the_situation_is_what_the_tests_say():
    assert cls(35.0) == "none" and cls(0.0) == "crossing_stand_on"


def test_the_turn_back_stops_a_step_short_of_the_first_course_making_a_ship_crossing_from_port():
    limit = port_return_limit((0.0, 0.0), SPEED, COURSE, 0.0, [PORT_BEAM], CPA_LIMIT, TCPA_LIMIT)
    assert limit is not None
    first = next(c for c in np.arange(35.0, -1.0, -RETURN_STEP_DEG) if cls(c) == "crossing_stand_on")
    assert math.degrees(limit) == pytest.approx(first + 2.0 * RETURN_STEP_DEG)
    # every course down to the limit (and one step beyond) keeps the ship out of risk
    assert all(cls(c) == "none" for c in np.arange(35.0, math.degrees(limit) - RETURN_STEP_DEG - 0.1,
                                                 -RETURN_STEP_DEG))


def test_the_turn_back_is_free_without_a_ship_it_would_bring_into_risk():
    starboard = (vector(80.0, 4.5 * NM), vector(36.0, 9.6 * KNOT))  # well clear on the starboard side
    assert port_return_limit((0.0, 0.0), SPEED, COURSE, 0.0, [starboard], CPA_LIMIT, TCPA_LIMIT) is None
    assert port_return_limit((0.0, 0.0), SPEED, COURSE, 0.0, [], CPA_LIMIT, TCPA_LIMIT) is None


def test_a_turn_to_starboard_is_never_limited():
    # a ship 4 nm off on 040 heading 180: on 070 it would be one crossing from port
    ahead = (vector(40.0, 4.0 * NM), vector(180.0, 12.0 * KNOT))
    assert cls(70.0, ahead) == "crossing_stand_on"
    assert port_return_limit((0.0, 0.0), SPEED, COURSE, math.radians(70.0), [ahead], CPA_LIMIT,
                             TCPA_LIMIT) is None


def test_the_limit_is_taken_within_half_a_turn_of_the_course():
    # the same situation with the course and the reference a full turn apart
    limit = port_return_limit((0.0, 0.0), SPEED, COURSE + 2.0 * math.pi, 0.0, [PORT_BEAM], CPA_LIMIT, TCPA_LIMIT)
    plain = port_return_limit((0.0, 0.0), SPEED, COURSE, 0.0, [PORT_BEAM], CPA_LIMIT, TCPA_LIMIT)
    assert limit == pytest.approx(plain + 2.0 * math.pi)


# -- in the NMPC's domains -------------------------------------------------------------------

def solve(targets, reference_deg: float, et: bool = False, domains=None):
    domains = domains or CollisionDomains(DomainSettings(colregs=True), max_obstacles=3)
    heading = COURSE
    state = np.array([0.0, 0.0, heading, SPEED, 0.0, 0.0])
    rows = np.array([[*position, *velocity, NM] for position, velocity in targets])
    _, report = domains.parameters(rows, state, np.zeros(2), SPEED, 5.0, 230.0, et=et,
                                   reference_heading_rad=math.radians(reference_deg), time_s=0.0)
    return domains, report


def test_the_nmpc_is_held_short_of_the_turn_even_with_its_constraints_off():
    # nothing is in risk, so the collision constraints are off: the floor is still reported
    _, report = solve([PORT_BEAM], 0.0)
    assert [ENCOUNTER_CLASSES[int(c)] for c in report.class_codes] == ["none"]
    limit = port_return_limit((0.0, 0.0), SPEED, COURSE, 0.0, [PORT_BEAM], CPA_LIMIT, TCPA_LIMIT)
    assert report.alteration_floor is not None
    assert report.alteration_floor[2] == pytest.approx(limit)
    assert report.alteration_floor[1] == report.alteration_floor[2]  # no ramp: held at once


def test_a_small_correction_to_port_is_not_held():
    # 3 deg to port is not a manoeuvre: not held, even standing on for a ship crossing from port
    _, report = solve([CROSSING_FROM_PORT], 32.0)
    assert report.alteration_floor is None


def test_without_colregs_nothing_is_held():
    domains = CollisionDomains(DomainSettings(colregs=False), max_obstacles=3)
    _, report = solve([PORT_BEAM], 0.0, domains=domains)
    assert report.alteration_floor is None


def test_a_ship_standing_on_for_a_ship_crossing_from_port_keeps_its_course():
    # a ship 3 nm off on the port bow on a collision course with us on 035: locked crossing from
    # port, we stand on; the reference's 35 deg to port is not taken while its CPA is ahead
    assert cls(35.0, CROSSING_FROM_PORT) == "crossing_stand_on"
    _, report = solve([CROSSING_FROM_PORT], 0.0)
    assert report.alteration_floor is not None
    assert report.alteration_floor[2] == pytest.approx(COURSE)


def test_a_ship_crossing_from_port_out_of_risk_no_longer_holds_the_course():
    # locked as crossing from port on a collision course; then it alters (or we did) and its CPA
    # opens beyond the risk limit while it is still to pass: the course is no longer held; the
    # turn back is limited as for any ship in no risk, which this one may come back into
    domains, report = solve([CROSSING_FROM_PORT], 0.0)
    assert report.alteration_floor is not None and report.alteration_floor[2] == pytest.approx(COURSE)
    opened = (vector(-30.0, 3.0 * NM), vector(40.0, 12.0 * KNOT))
    cpa, tcpa = cpa_tcpa((0.0, 0.0), vector(35.0, SPEED), *opened)
    assert cpa > CPA_LIMIT and 0.0 < tcpa < TCPA_LIMIT
    _, report = solve([opened], 0.0, domains=domains)
    assert [ENCOUNTER_CLASSES[int(c)] for c in report.class_codes] == ["crossing_stand_on"]  # still locked
    limit = port_return_limit((0.0, 0.0), SPEED, COURSE, 0.0, [opened], CPA_LIMIT, TCPA_LIMIT)
    assert limit is not None and limit < COURSE - 1e-6  # on the route's course it comes back into risk
    assert report.alteration_floor is not None
    assert report.alteration_floor[2] == pytest.approx(limit)
