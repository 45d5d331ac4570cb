"""Encounter classification (Rules 13-15) on constructed geometries, and its hysteresis."""

import math

import numpy as np
import pytest

from rhnc.encounters.colregs import EncounterTracker, classify, cpa_tcpa, stand_on_must_act, wrap_deg

NM = 1852.0
KN = NM / 3600.0


def _velocity(course_deg, speed_kn):
    c = math.radians(course_deg)
    return (speed_kn * KN * math.cos(c), speed_kn * KN * math.sin(c))


def _classify(target_nm, target_course_deg, target_speed_kn, own_course_deg=0.0, own_speed_kn=18.0):
    return classify((0.0, 0.0), math.radians(own_course_deg), own_speed_kn * KN,
                    (target_nm[0] * NM, target_nm[1] * NM), _velocity(target_course_deg, target_speed_kn))


@pytest.mark.parametrize("target_nm, course, speed, expected", [
    ((6.0, 0.1), 180.0, 15.0, "head_on"),              # dead ahead, reciprocal
    ((6.0, 0.5), 188.0, 15.0, "head_on"),              # nearly ahead, nearly reciprocal
    ((4.0, 4.0), 270.0, 15.0, "crossing_give_way"),    # from starboard, crossing to port
    ((4.0, -4.0), 90.0, 15.0, "crossing_stand_on"),    # from port, crossing to starboard
    ((2.0, 0.2), 0.0, 9.0, "overtaking"),              # slower ship ahead on our course
    ((-2.0, 0.2), 0.0, 25.0, "overtaken"),             # faster ship coming up astern
    ((6.0, -0.2), 0.0, 0.0, "static"),
    ((6.0, 6.0), 0.0, 18.0, "none"),                   # parallel course, never closes
    ((-4.0, 0.0), 180.0, 15.0, "none"),                # opening astern
])
def test_classes_of_constructed_geometries(target_nm, course, speed, expected):
    assert _classify(target_nm, course, speed).encounter_class == expected


def test_crossing_from_starboard_is_not_head_on_when_course_differs():
    # ahead, but crossing at 90 deg: Rule 15, not Rule 14
    assert _classify((6.0, 1.0), 270.0, 3.0).encounter_class == "crossing_give_way"


def test_roles():
    assert _classify((6.0, 0.1), 180.0, 15.0).role == "give_way"
    assert _classify((4.0, -4.0), 90.0, 15.0).role == "stand_on"
    assert _classify((-2.0, 0.2), 0.0, 25.0).role == "stand_on"


def test_cpa_tcpa_of_head_on_offset():
    cpa, tcpa = cpa_tcpa((0.0, 0.0), (10.0, 0.0), (1000.0, 50.0), (-10.0, 0.0))
    assert cpa == pytest.approx(50.0)
    assert tcpa == pytest.approx(50.0)


def test_wrap_deg():
    np.testing.assert_allclose(wrap_deg([190.0, -190.0, 180.0, -180.0, 540.0]), [-170.0, 170.0, 180.0, 180.0, 180.0])


def test_tracker_keeps_the_class_while_the_give_way_ship_turns():
    tracker = EncounterTracker()
    target = np.array([[4.0 * NM, 4.0 * NM, *_velocity(270.0, 15.0), NM]])
    first = tracker.update((0.0, 0.0), 0.0, 18.0 * KN, target)[0]
    assert first.encounter_class == "crossing_give_way"
    # after turning 40 deg to starboard the raw geometry would read differently
    raw = classify((0.5 * NM, 0.3 * NM), math.radians(40.0), 18.0 * KN, (4.0 * NM, 3.0 * NM), _velocity(270.0, 15.0))
    assert raw.encounter_class != "crossing_give_way"
    kept = tracker.update((0.5 * NM, 0.3 * NM), math.radians(40.0), 18.0 * KN,
                          np.array([[4.0 * NM, 3.0 * NM, *_velocity(270.0, 15.0), NM]]))[0]
    assert kept.encounter_class == "crossing_give_way"


def test_tracker_releases_after_the_encounter():
    tracker = EncounterTracker(release_range_m=4.0 * NM)
    tracker.update((0.0, 0.0), 0.0, 18.0 * KN, np.array([[6.0 * NM, 0.1 * NM, *_velocity(180.0, 15.0), NM]]))
    assert tracker.locked == {0: "head_on"}
    # passed and 5 nm apart, opening
    after = tracker.update((10.0 * NM, 0.0), 0.0, 18.0 * KN,
                           np.array([[5.0 * NM, 0.1 * NM, *_velocity(180.0, 15.0), NM]]))[0]
    assert tracker.locked == {}
    assert after.encounter_class == "none"
    # passed but still within the release range: kept
    tracker.update((0.0, 0.0), 0.0, 18.0 * KN, np.array([[6.0 * NM, 0.1 * NM, *_velocity(180.0, 15.0), NM]]))
    held = tracker.update((7.0 * NM, 0.0), 0.0, 18.0 * KN,
                          np.array([[5.0 * NM, 0.1 * NM, *_velocity(180.0, 15.0), NM]]))[0]
    assert held.encounter_class == "head_on"


def test_stand_on_must_act_is_one_rule_for_controller_and_analysis():
    separation = 1852.0
    # a CPA inside the separation, close in time: act
    assert stand_on_must_act(100.0, 300.0, 3.0 * separation, separation)
    # the same CPA far ahead in time, still far off: keep standing on
    assert not stand_on_must_act(100.0, 900.0, 3.0 * separation, separation)
    # far ahead in time but already within twice the separation (a slow overtaker): act
    assert stand_on_must_act(100.0, 900.0, 1.9 * separation, separation)
    # the CPA clears the separation, or lies behind: no need
    assert not stand_on_must_act(separation + 1.0, 300.0, 1.5 * separation, separation)
    assert not stand_on_must_act(100.0, -10.0, 1.5 * separation, separation)
    # the CPA less than a second ahead is still ahead: act
    assert stand_on_must_act(100.0, 0.5, 3.0 * separation, separation)
    # the thresholds are parameters
    assert stand_on_must_act(100.0, 900.0, 3.0 * separation, separation, action_tcpa_s=1000.0)


def test_controller_and_analysis_share_the_rule_17_thresholds():
    from rhnc.control import nmpc_colregs
    from rhnc.cosim import colregs_analysis
    from rhnc.encounters import colregs_judgement
    from rhnc.control.nmpc import NMPCSettings

    assert nmpc_colregs.stand_on_must_act is stand_on_must_act
    assert colregs_judgement.stand_on_must_act is stand_on_must_act
    settings = NMPCSettings()
    analysis = colregs_analysis.JudgementSettings()
    assert settings.stand_on_action_tcpa_s == analysis.stand_on_wait_min * 60.0
    assert settings.stand_on_action_range_factor == analysis.stand_on_range_factor


def _at_bearing(range_nm, bearing_deg):
    b = math.radians(bearing_deg)
    return (range_nm * math.cos(b), range_nm * math.sin(b))


def test_overtaken_only_from_more_than_22_5_deg_abaft_the_beam():
    # a faster ship on a course converging with ours, at exactly 112.5 deg and just beyond
    at_boundary = _classify(_at_bearing(1.5, 112.5), 350.0, 30.0)
    beyond = _classify(_at_bearing(1.5, 113.5), 350.0, 30.0)
    assert at_boundary.encounter_class == "crossing_give_way"
    assert beyond.encounter_class == "overtaken"
    assert "overtaken" in at_boundary.borderline and "overtaken" in beyond.borderline


def test_a_class_decided_near_a_boundary_is_borderline_and_a_clear_one_is_not():
    edge = _classify(_at_bearing(6.0, 10.0), 180.0, 18.0)  # nearly ahead at the limit
    assert edge.encounter_class == "head_on" and edge.borderline.startswith("head-on")
    just_outside = _classify(_at_bearing(6.0, 11.0), 180.0, 18.0)
    assert just_outside.encounter_class == "crossing_give_way" and just_outside.borderline.startswith("head-on")
    clear = _classify((6.0, 0.1), 180.0, 18.0)
    assert clear.encounter_class == "head_on" and clear.borderline == ""
    crossing = _classify((4.0, 4.0), 270.0, 15.0)
    assert crossing.borderline == ""
    far_from_head_on = _classify(_at_bearing(6.0, 10.0), 215.0, 18.0)  # ahead, but 35 deg off reciprocal
    assert far_from_head_on.encounter_class == "crossing_give_way" and far_from_head_on.borderline == ""


def test_the_tracker_keeps_the_borderline_note_of_the_onset():
    tracker = EncounterTracker()
    target = np.array([[*(np.array(_at_bearing(6.0, 10.0)) * NM), *_velocity(180.0, 18.0), NM]])
    first = tracker.update((0.0, 0.0), 0.0, 18.0 * KN, target)[0]
    assert first.borderline
    # later the geometry is far from any boundary: the class and its note stay as decided
    later = tracker.update((0.0, 3.0 * NM), 0.0, 18.0 * KN, target)[0]
    assert later.encounter_class == "head_on" and later.borderline == first.borderline


def test_the_last_moment_of_a_readily_apparent_alteration_comes_sooner_the_faster_the_closing():
    from rhnc.encounters.colregs import latest_alteration_s
    own_velocity = np.array([18.0 * KN, 0.0])

    def latest(range_nm, target_kn):
        return latest_alteration_s((0.0, 0.0), own_velocity, (range_nm * NM, 0.0), (-target_kn * KN, 0.0), 1.05 * NM)

    # head-on at 40.6 kn closing: at 8 nm there are some 5 min left, at 4.7 nm none
    assert 200.0 < latest(8.0, 22.6) < 400.0
    assert latest(4.7, 22.6) == -math.inf
    assert latest(8.0, 8.0) > latest(8.0, 22.6)  # a slower target leaves more time
    # a target passing clear anyway needs no alteration
    assert latest_alteration_s((0.0, 0.0), own_velocity, (5.0 * NM, 2.0 * NM), (-9.0 * KN, 0.0), NM) == math.inf


def test_a_stand_on_ship_acts_when_its_time_to_alter_runs_out_even_while_the_cpa_is_far_in_time():
    # a fast ship from astern: TCPA 15 min, range 3 nm, but only 60 s left for an alteration
    assert not stand_on_must_act(0.1 * NM, 900.0, 3.0 * NM, NM)
    assert stand_on_must_act(0.1 * NM, 900.0, 3.0 * NM, NM, latest_s=60.0)
    assert not stand_on_must_act(0.1 * NM, 900.0, 3.0 * NM, NM, latest_s=600.0)
    assert not stand_on_must_act(1.5 * NM, 900.0, 3.0 * NM, NM, latest_s=60.0)  # no risk: CPA outside


def test_a_stand_on_ship_that_no_apparent_alteration_helps_still_stands_on():
    # latest -inf: a 35 deg turn would not open the CPA even now; the TCPA and range decide
    assert not stand_on_must_act(0.1 * NM, 900.0, 3.5 * NM, NM, latest_s=-math.inf)
    assert stand_on_must_act(0.1 * NM, 500.0, 3.5 * NM, NM, latest_s=-math.inf)


def test_once_the_time_for_the_alteration_has_run_out_a_stand_on_ship_keeps_acting():
    # ships on steady courses, sampled every 10 s: once Rule 17 says act, it keeps saying so
    # until the CPA (a stand-on ship that had stopped acting would turn back into danger)
    from rhnc.encounters.colregs import stand_on_latest_s
    own_velocity = np.array([10.0 * KN, 0.0])
    for speed_kn, course_deg in ((30.0, 60.0), (40.0, 150.0), (20.0, 120.0), (30.0, 30.0)):
        course = math.radians(course_deg)
        target_velocity = speed_kn * KN * np.array([math.cos(course), math.sin(course)])
        meeting = own_velocity * 1200.0
        target_start = meeting - target_velocity * 1200.0 + np.array([0.0, 0.05 * NM])
        decisions = []
        for t in range(0, 1200, 10):
            own, target = own_velocity * t, target_start + target_velocity * t
            cpa, tcpa = cpa_tcpa(own, own_velocity, target, target_velocity)
            encounter = classify(own, 0.0, 10.0 * KN, target, target_velocity)
            latest = stand_on_latest_s(encounter.encounter_class, encounter.relative_bearing_deg, own, own_velocity,
                                       target, target_velocity, NM)
            decisions.append(stand_on_must_act(cpa, tcpa, encounter.range_m, NM, latest_s=latest))
        first = decisions.index(True)
        assert all(decisions[first:]), (speed_kn, course_deg)
