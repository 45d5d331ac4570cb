"""COLREG classification's borderline notes, the latest apparent alteration and the tracker's empty input,
on constructed geometries (x north, y east)."""

import math

import numpy as np
import pytest

from rhnc.encounters.colregs import (HEAD_ON_BEARING_DEG, EncounterTracker, classify, cpa_tcpa, latest_alteration_s,
                                     stand_on_latest_s)

NM = 1852.0
KN = NM / 3600.0


def _at(bearing_deg, range_nm):
    b = math.radians(bearing_deg)
    return (range_nm * NM * math.cos(b), range_nm * NM * math.sin(b))


def _velocity(course_deg, speed_kn):
    c = math.radians(course_deg)
    return (speed_kn * KN * math.cos(c), speed_kn * KN * math.sin(c))


@pytest.mark.parametrize("side, expected", [(1.0, "crossing_give_way"), (-1.0, "crossing_stand_on")])
def test_a_crossing_just_outside_the_head_on_sector_is_noted_as_borderline(side, expected):
    # on a reciprocal course, a degree beyond the head-on bearing, on either bow
    bearing = side * (HEAD_ON_BEARING_DEG + 1.0)
    target = _at(bearing, 4.0)
    encounter = classify((0.0, 0.0), 0.0, 12 * KN, target, _velocity(180.0 + 0.5 * bearing, 12.0))
    assert encounter.encounter_class == expected
    assert encounter.borderline.startswith(f"head-on: bearing {HEAD_ON_BEARING_DEG + 1.0:.1f} deg")


def _rotated(vector, degrees):
    c, s = math.cos(math.radians(degrees)), math.sin(math.radians(degrees))
    return (c * vector[0] - s * vector[1], s * vector[0] + c * vector[1])


@pytest.mark.parametrize("side", [1.0, -1.0])
def test_the_latest_alteration_does_not_depend_on_which_way_the_scene_faces(side):
    own, own_velocity = (0.0, 0.0), _velocity(0.0, 12.0)
    target, target_velocity = _at(40.0, 5.0), _velocity(250.0, 14.0)
    wait = latest_alteration_s(own, own_velocity, target, target_velocity, 0.8 * NM, side)
    assert 0.0 < wait < math.inf
    for turn in (30.0, 135.0, -100.0):
        assert latest_alteration_s(_rotated(own, turn), _rotated(own_velocity, turn), _rotated(target, turn),
                                   _rotated(target_velocity, turn), 0.8 * NM, side) == pytest.approx(wait)


def test_after_a_turn_square_to_a_stationary_target_the_closest_approach_is_at_the_turn():
    # heading north at 5 m/s for a buoy 1000 m ahead, a 90 deg turn (made at once): the range at the
    # turn is the closest, 1000 - 5 t; it is below 300.02 m from t = 140 s on
    wait = latest_alteration_s((0.0, 0.0), (5.0, 0.0), (1000.0, 0.0), (0.0, 0.0), 300.02, 1.0,
                               alteration_deg=90.0, turn_s=0.0, step_s=10.0)
    assert wait == 130.0
    # only the last wait (at the CPA itself) falls short of 40 m: the one before is the latest
    assert latest_alteration_s((0.0, 0.0), (5.0, 0.0), (1000.0, 0.0), (0.0, 0.0), 40.0, 1.0,
                               alteration_deg=90.0, turn_s=0.0, step_s=10.0) == 190.0


def test_a_stand_on_ship_alters_to_starboard_for_a_crossing_ship_and_away_from_one_overtaking():
    own, own_velocity = (0.0, 0.0), _velocity(0.0, 12.0)

    def both_sides(target, target_velocity):
        # looked back as far as the stand-on ship's own judgement looks (to the onset of risk,
        # 30 min before the CPA), so only the side differs between the two calls
        lookback = max(0.0, 30.0 * 60.0 - cpa_tcpa(own, own_velocity, target, target_velocity)[1])
        return [latest_alteration_s(own, own_velocity, target, target_velocity, 0.8 * NM, side, lookback_s=lookback)
                for side in (1.0, -1.0)]

    crossing = ((2.5 * NM, -3.94 * NM), _velocity(80.0, 16.0))  # from port, to pass 0.17 nm ahead
    encounter = classify(own, 0.0, 12 * KN, *crossing)
    assert encounter.encounter_class == "crossing_stand_on"
    starboard, port = both_sides(*crossing)
    assert starboard != port
    assert stand_on_latest_s("crossing_stand_on", encounter.relative_bearing_deg, own, own_velocity, *crossing,
                             0.8 * NM) == starboard
    for bearing in (150.0, -150.0):  # overtaken from either quarter: turn away from the overtaking ship
        overtaking = (_at(bearing, 1.5), _velocity(-0.1 * bearing, 20.0))
        starboard, port = both_sides(*overtaking)
        assert starboard != port
        away = port if bearing > 0 else starboard
        assert stand_on_latest_s("overtaken", bearing, own, own_velocity, *overtaking, 0.8 * NM) == away


def test_the_tracker_without_obstacles_reports_no_encounter():
    tracker = EncounterTracker()
    assert tracker.update((0.0, 0.0), 0.0, 6.0, None) == []
    assert tracker.update((0.0, 0.0), 0.0, 6.0, np.zeros((0, 5))) == []
    assert tracker.locked == {}


def test_cpa_tcpa_of_a_slow_closing_is_finite():
    # a relative speed of 0.5 m/s is a real approach, not "no relative motion": TCPA 200 s
    cpa, tcpa = cpa_tcpa((0.0, 0.0), (0.0, 0.0), (100.0, 30.0), (-0.5, 0.0))
    assert tcpa == pytest.approx(200.0)
    assert cpa == pytest.approx(30.0)


def test_the_range_uses_both_coordinates_of_the_own_ship():
    # own ship 1 km east of the origin, the target 4 km north of it: 4 km apart
    encounter = classify((0.0, 1000.0), 0.0, 6.0, (4000.0, 1000.0), (-6.0, 0.0))
    assert encounter.range_m == pytest.approx(4000.0)


def test_a_cpa_exactly_at_the_tcpa_limit_is_a_risk_of_collision():
    # own ship stopped, target 1000 m ahead closing at 10 m/s: TCPA exactly 100 s
    encounter = classify((0.0, 0.0), 0.0, 0.0, (1000.0, 0.0), (-10.0, 0.0), tcpa_limit_s=100.0)
    assert encounter.tcpa_s == 100.0
    assert encounter.encounter_class == "head_on"
    assert classify((0.0, 0.0), 0.0, 0.0, (1000.0, 0.0), (-10.0, 0.0), tcpa_limit_s=99.9).encounter_class == "none"


def test_a_crossing_ship_dead_ahead_is_not_on_our_starboard_side():
    # bearing exactly 0, crossing from port to starboard at 90 deg: Rule 15 gives way only to starboard
    encounter = classify((0.0, 0.0), 0.0, 5.0, (4000.0, 0.0), (0.0, 5.0))
    assert encounter.relative_bearing_deg == 0.0
    assert encounter.encounter_class == "crossing_stand_on"


def test_no_risk_of_collision_carries_no_borderline_note():
    # opening at 112.5 deg from our bow: the geometry is at the overtaken boundary, but there is no encounter
    encounter = classify((0.0, 0.0), 0.0, 10.0 * KN, _at(112.5, 1.0), _velocity(112.5, 10.0))
    assert encounter.encounter_class == "none"
    assert encounter.borderline == ""


@pytest.mark.parametrize("aspect, expected", [(113.5, "overtaking"), (111.5, "crossing_stand_on")])
def test_an_aspect_near_22_5_deg_abaft_the_targets_beam_is_borderline(aspect, expected):
    # a slower ship ahead, the own ship seen from it at 113.5 deg (overtaking) or 111.5 deg
    encounter = classify((0.0, 0.0), 0.0, 20.0 * KN, (NM, 0.0), _velocity(180.0 - aspect, 5.0))
    assert encounter.aspect_deg == pytest.approx(aspect) and encounter.encounter_class == expected
    assert encounter.borderline.startswith(f"overtaking: own ship {aspect:.1f} deg")


def test_a_head_on_bearing_exactly_at_the_borderline_band_edge_is_borderline():
    # bearing exactly 7.5 deg, 2.5 deg inside the head-on limit; exactly reciprocal courses
    encounter = classify((0.0, 0.0), 0.0, 18.0 * KN, (4.0 * NM, 975.2817021274284), (-18.0 * KN, 0.0))
    assert encounter.relative_bearing_deg == 7.5
    assert encounter.encounter_class == "head_on"
    assert encounter.borderline.startswith("head-on: bearing 7.5 deg")


def test_a_course_difference_exactly_at_the_borderline_band_edge_is_borderline():
    # dead ahead, courses exactly 12.5 deg from reciprocal (2.5 deg inside the limit)
    encounter = classify((0.0, 0.0), 0.0, 18.0 * KN, (4.0 * NM, 0.0), (-9.040501025930583, -2.0042308250668417))
    assert encounter.relative_bearing_deg == 0.0 and encounter.encounter_class == "head_on"
    assert encounter.borderline.endswith("courses 12.5 deg from reciprocal (nearly: <= 15)")


def test_the_latest_alteration_is_searched_in_10_s_steps_by_default():
    # as in the square-turn case above, without giving the step: the latest wait is 130 s
    assert latest_alteration_s((0.0, 0.0), (5.0, 0.0), (1000.0, 0.0), (0.0, 0.0), 300.02, 1.0,
                               alteration_deg=90.0, turn_s=0.0) == 130.0


def _turning_away_from_a_ship_on_the_port_bow():
    """Own ship northbound at 18 kn, turning to starboard at 0.3 deg/s from 20 s to 40 deg; a
    ship overtaken by us 1.0 nm ahead and 0.6 nm to port at 8 kn: the range opens while the
    own ship is still turning."""
    t = np.arange(0.0, 900.0, 5.0)
    course = np.radians(np.clip(0.3 * (t - 20.0), 0.0, 40.0))
    speed = np.full(t.size, 18.0 * 1852.0 / 3600.0)
    step = np.stack([np.cos(course), np.sin(course)], axis=1) * speed[:, None] * 5.0
    own = np.vstack([[0.0, 0.0], np.cumsum(step[:-1], axis=0)])
    velocity = np.array([8.0 * 1852.0 / 3600.0, 0.0])
    target = np.column_stack([1852.0 + velocity[0] * t, np.full(t.size, -0.6 * 1852.0),
                              np.full(t.size, velocity[0]), np.zeros(t.size), np.full(t.size, 0.3 * 1852.0)])
    return t, own, course, speed, target


def test_an_alteration_that_opens_the_range_while_turning_is_judged_by_what_it_became():
    from rhnc.encounters.colregs_judgement import JudgementSettings, judge_target
    t, own, course, speed, target = _turning_away_from_a_ship_on_the_port_bow()
    result = judge_target(t, own, course, speed, target, "overtaking", 0, 0.5 * 1852.0, JudgementSettings())
    turned_by_cpa = math.degrees(course[t <= result["time_of_cpa_s"]][-1])
    assert turned_by_cpa < 30.0  # the CPA comes before the alteration is readily apparent
    assert result["max_course_change_deg"] >= 30.0
    assert result["rule_8"] == "pass"
