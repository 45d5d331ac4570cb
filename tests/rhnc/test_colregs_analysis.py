"""Verdicts of the colregs analysis on constructed tracks (no co-simulation): one geometry per rule."""

import math

import numpy as np
import pytest

from rhnc.cosim.colregs_analysis import (FAIL, NOT_APPLICABLE, PASS, JudgementSettings, closest_approach,
                                   first_manoeuvre, judge_encounters)

NM = 1852.0
KN = NM / 3600.0
DT_S = 5.0


def own_track(duration_min, turns=(), speed_kn=18.0, rate_deg_s=0.5, slow_down=None):
    """Own ship from (0, 0) heading north; ``turns`` = [(time_min, new_course_deg), ...].

    The heading moves towards the ordered course at ``rate_deg_s``; ``slow_down`` =
    (time_min, speed_kn) changes the speed there.
    """
    t = np.arange(0.0, duration_min * 60.0 + DT_S / 2, DT_S)
    heading = np.zeros_like(t)
    x, y = np.zeros_like(t), np.zeros_like(t)
    ordered, psi = 0.0, 0.0
    speed = np.full_like(t, speed_kn * KN)
    if slow_down is not None:
        speed[t >= slow_down[0] * 60.0] = slow_down[1] * KN
    for k in range(1, t.size):
        for time_min, course in turns:
            if t[k] >= time_min * 60.0:
                ordered = course
        step = np.clip(ordered - psi, -rate_deg_s * DT_S, rate_deg_s * DT_S)
        psi += step
        heading[k] = math.radians(psi)
        x[k] = x[k - 1] + speed[k] * math.cos(heading[k]) * DT_S
        y[k] = y[k - 1] + speed[k] * math.sin(heading[k]) * DT_S
    return t, x, y, heading


def target_states(t, start_nm, course_deg, speed_kn, radius_nm=1.0):
    """(n, 1, 5) obstacle rows of a target sailing straight."""
    velocity = speed_kn * KN * np.array([math.cos(math.radians(course_deg)), math.sin(math.radians(course_deg))])
    rows = np.empty((t.size, 1, 5))
    rows[:, 0, :2] = np.asarray(start_nm) * NM + np.outer(t, velocity)
    rows[:, 0, 2:4] = velocity
    rows[:, 0, 4] = radius_nm * NM
    return rows


def judge(track, target, **settings):
    t, x, y, heading = track
    return judge_encounters(t, x, y, heading, target, 0.0, JudgementSettings(**settings))["targets"][0]


# -- head-on (Rule 14) --------------------------------------------------------------------
def test_head_on_starboard_turn_passes_port_to_port():
    track = own_track(20, turns=[(1.0, 45.0)])
    result = judge(track, target_states(track[0], (7.0, 0.1), 180.0, 18.0))
    assert result["encounter_class"] == "head_on" and result["role"] == "give_way"
    assert result["manoeuvre_side"] == "starboard" and result["manoeuvre_time_s"] == pytest.approx(70.0, abs=10)
    assert result["passing_side"] == "port" and result["separation_kept"]
    assert result["rule_14"] == PASS and result["rule_8"] == PASS and result["rule_16"] == PASS
    assert result["rule_15"] == NOT_APPLICABLE and result["rule_17"] == NOT_APPLICABLE
    assert result["verdict"] == PASS and result["side_correct"] is True


def test_head_on_port_turn_fails_rule_14():
    track = own_track(20, turns=[(1.0, -45.0)])
    result = judge(track, target_states(track[0], (7.0, 0.1), 180.0, 18.0))
    assert result["manoeuvre_side"] == "port" and result["passing_side"] == "starboard"
    assert result["separation_kept"]
    assert result["rule_14"] == FAIL and "altered to port" in result["reasons"]["rule_14"]
    assert result["rule_8"] == PASS  # large, early and clear: only the side is wrong
    assert result["verdict"] == FAIL and result["side_correct"] is False


def test_late_small_alteration_fails_rule_8_and_16():
    # 10 deg to starboard one minute before the ships would meet
    track = own_track(20, turns=[(10.5, 10.0)])
    result = judge(track, target_states(track[0], (7.0, 0.1), 180.0, 18.0))
    assert result["manoeuvre_time_s"] is not None and result["max_course_change_deg"] < 30.0
    assert result["rule_8"] == FAIL and "not readily apparent" in result["reasons"]["rule_8"]
    assert result["rule_16"] == FAIL and "before the CPA" in result["reasons"]["rule_16"]
    assert not result["separation_kept"]


def test_no_alteration_as_give_way_fails_rule_16():
    track = own_track(20)
    result = judge(track, target_states(track[0], (7.0, 0.5), 180.0, 18.0))
    assert result["encounter_class"] == "head_on"
    assert result["manoeuvre_time_s"] is None
    assert result["rule_16"] == FAIL and "no alteration" in result["reasons"]["rule_16"]
    assert result["rule_8"] == FAIL  # a give-way vessel is judged under Rule 8 even without acting


# -- crossing, own ship gives way (Rules 15 and 16) ------------------------------------------
def test_crossing_give_way_passing_astern_passes_rule_15():
    # target from starboard, heading west, would meet us 4.5 nm ahead in 15 min
    track = own_track(30, turns=[(2.0, 70.0)])
    result = judge(track, target_states(track[0], (4.5, 4.5), 270.0, 18.0))
    assert result["encounter_class"] == "crossing_give_way"
    assert result["crossed"] == "astern" and result["separation_kept"]
    assert result["rule_15"] == PASS and result["rule_16"] == PASS and result["rule_8"] == PASS
    assert result["verdict"] == PASS and result["side_correct"] is True


def test_crossing_give_way_crossing_ahead_fails_rule_15():
    # a turn to port puts us across the target's bow
    track = own_track(30, turns=[(2.0, -60.0)])
    result = judge(track, target_states(track[0], (4.5, 4.5), 270.0, 18.0))
    assert result["encounter_class"] == "crossing_give_way"
    assert result["crossed"] == "ahead"
    assert result["rule_15"] == FAIL and "crossed ahead" in result["reasons"]["rule_15"]
    assert result["side_correct"] is False


# -- overtaking (Rule 13) -----------------------------------------------------------------
def test_overtaking_with_clearance_passes_rule_13():
    track = own_track(40, turns=[(1.0, 35.0), (8.0, 0.0)])
    result = judge(track, target_states(track[0], (2.0, 0.1), 0.0, 8.0))
    assert result["encounter_class"] == "overtaking"
    assert result["separation_kept"] and result["rule_13"] == PASS
    assert result["rule_14"] == NOT_APPLICABLE and result["rule_15"] == NOT_APPLICABLE


def test_overtaking_into_the_target_fails_rule_13():
    track = own_track(40)
    result = judge(track, target_states(track[0], (2.0, 0.1), 0.0, 8.0))
    assert result["encounter_class"] == "overtaking"
    assert result["rule_13"] == FAIL and "CPA" in result["reasons"]["rule_13"]


# -- stand-on (Rule 17) -------------------------------------------------------------------
def _stand_on_target(t):
    # from port, heading east, 15 min from a collision 4.5 nm ahead
    return target_states(t, (4.5, -4.5), 90.0, 18.0)


def test_stand_on_keeping_course_then_acting_late_to_starboard_passes_rule_17():
    track = own_track(30, turns=[(9.0, 80.0)])  # TCPA 6 min, predicted CPA ~0
    result = judge(track, _stand_on_target(track[0]))
    assert result["encounter_class"] == "crossing_stand_on" and result["role"] == "stand_on"
    assert result["manoeuvre_side"] == "starboard"
    assert result["rule_17"] == PASS, result["reasons"]
    assert result["rule_15"] == NOT_APPLICABLE and result["rule_16"] == NOT_APPLICABLE


def test_stand_on_acting_early_fails_rule_17():
    track = own_track(30, turns=[(1.0, 80.0)])  # TCPA 14 min: too early to give up standing on
    result = judge(track, _stand_on_target(track[0]))
    assert result["rule_17"] == FAIL and "could still suffice" in result["reasons"]["rule_17"]


def test_stand_on_turning_to_port_fails_rule_17c():
    track = own_track(30, turns=[(9.0, -80.0)])
    result = judge(track, _stand_on_target(track[0]))
    assert result["rule_17"] == FAIL and "Rule 17(c)" in result["reasons"]["rule_17"]
    assert result["side_correct"] is False


def test_stand_on_manoeuvre_made_while_giving_way_to_another_target_is_allowed():
    # a head-on ship ahead (we give way) and a ship crossing from port (we stand on): the early
    # starboard turn answers the head-on encounter, so it breaks no stand-on obligation
    track = own_track(30, turns=[(1.0, 45.0)])
    t = track[0]
    obstacles = np.concatenate([target_states(t, (7.0, 0.1), 180.0, 18.0), _stand_on_target(t)], axis=1)
    head_on, stand_on = judge_encounters(*track, obstacles)["targets"]
    assert head_on["encounter_class"] == "head_on" and stand_on["encounter_class"] == "crossing_stand_on"
    assert stand_on["manoeuvre_time_s"] < 600.0
    assert stand_on["rule_17"] == PASS, stand_on["reasons"]
    assert stand_on["rule_8"] == NOT_APPLICABLE  # the turn was the head-on encounter's action
    assert head_on["rule_8"] == PASS
    alone = judge(track, _stand_on_target(t))  # the same turn with no one to give way to
    assert alone["rule_17"] == FAIL and alone["rule_8"] != NOT_APPLICABLE


def test_overtaken_ship_standing_on_passes_and_rule_8_does_not_apply():
    track = own_track(40)
    result = judge(track, target_states(track[0], (-2.0, 1.2), 0.0, 26.0))
    assert result["encounter_class"] == "overtaken"
    assert result["manoeuvre_time_s"] is None and result["rule_17"] == PASS
    assert result["rule_8"] == NOT_APPLICABLE and result["verdict"] == PASS


# -- no risk, static, several targets --------------------------------------------------------
def test_no_risk_of_collision_makes_every_rule_not_applicable():
    track = own_track(20)
    result = judge(track, target_states(track[0], (3.0, 6.0), 0.0, 18.0))
    assert result["encounter_class"] == "none" and result["onset_s"] is None
    assert all(result[rule] == NOT_APPLICABLE for rule in ("rule_8", "rule_13", "rule_14", "rule_15",
                                                             "rule_16", "rule_17"))
    assert result["verdict"] == NOT_APPLICABLE


def test_overall_verdict_and_side_over_two_targets():
    track = own_track(30, turns=[(1.0, 45.0)])
    t = track[0]
    obstacles = np.concatenate([target_states(t, (7.0, 0.1), 180.0, 18.0),          # head-on: passed correctly
                                target_states(t, (5.0, 0.0), 0.0, 0.0, 0.5)], axis=1)  # a static obstacle
    summary = judge_encounters(*track, obstacles)
    assert [target["encounter_class"] for target in summary["targets"]] == ["head_on", "static"]
    assert summary["targets"][1]["verdict"] == NOT_APPLICABLE
    assert summary["verdict"] == PASS and summary["side_correct"] is True and summary["rules_failed"] == []
    port = own_track(30, turns=[(1.0, -45.0)])
    summary = judge_encounters(*port, obstacles)
    assert summary["verdict"] == FAIL and "rule_14" in summary["rules_failed"]


# -- the measurements the verdicts rest on ------------------------------------------------------
def test_closest_approach_is_refined_between_samples():
    t = np.array([0.0, 10.0])
    own = np.array([[0.0, 0.0], [100.0, 0.0]])
    target = np.array([[100.0, 10.0], [0.0, 10.0]])
    cpa, time, index = closest_approach(t, own, target)
    assert cpa == pytest.approx(10.0) and time == pytest.approx(5.0) and index == pytest.approx(0.5)


def test_yaw_oscillation_is_not_a_manoeuvre():
    t = np.arange(0.0, 600.0, 5.0)
    heading = np.radians(6.0 * np.sin(2 * np.pi * t / 60.0))  # +-6 deg with a 1 min period
    assert first_manoeuvre(t, heading, 0, 600.0, JudgementSettings()) == (None, None)
    steady = np.radians(np.where(t >= 100.0, 8.0, 0.0))
    assert first_manoeuvre(t, steady, 0, 600.0, JudgementSettings()) == (100.0, "starboard")


def test_bad_settings_are_refused():
    with pytest.raises(ValueError, match="early_before_cpa_min"):
        JudgementSettings(early_before_cpa_min=-1.0)


def test_bad_analysis_option_is_refused_before_the_run(tmp_path, capsys):
    from pathlib import Path

    from orchestrator.cli import main

    repo = Path(__file__).resolve().parents[2]
    text = (repo / "scenarios" / "exp3b_head_on.toml").read_text()
    text = text.replace('analyses = ["encounter"]', 'analyses = ["encounter", "colregs"]')
    text += "\n[outputs.options.colregs]\nearly_before_cpa_min = -2.0\n"
    scenario = tmp_path / "bad.toml"
    scenario.write_text(text)
    results = tmp_path / "results"
    assert main(["run", str(scenario), "--results", str(results), "--no-progress"]) == 2
    error = capsys.readouterr().err.strip().splitlines()
    assert len(error) == 1 and "bad.toml: 'outputs.options.colregs': early_before_cpa_min must be" in error[0]
    assert not results.exists() or not any(results.rglob("summary.json"))


# -- course over ground, not heading -------------------------------------------------------------
def test_manoeuvres_are_read_from_the_course_over_ground_not_the_heading():
    # a ship holding its track north while its heading swings 30 deg into a cross wind
    # (drift angle) has not altered course; the other ship sees the track
    t, x, y, heading = own_track(20)
    drifting = np.radians(np.clip((t - 60.0) * 0.5, 0.0, 30.0))
    result = judge((t, x, y, drifting), target_states(t, (7.0, 0.5), 180.0, 18.0))
    assert result["manoeuvre_time_s"] is None and result["max_course_change_deg"] < 1.0
    assert result["max_drift_angle_deg"] == pytest.approx(30.0, abs=0.5)
    assert result["rule_16"] == FAIL and "no alteration" in result["reasons"]["rule_16"]
    # and a real 45 deg turn of the track counts even when the heading is held at zero
    t, x, y, _ = own_track(20, turns=[(1.0, 45.0)])
    result = judge((t, x, y, np.zeros_like(t)), target_states(t, (7.0, 0.1), 180.0, 18.0))
    assert result["manoeuvre_side"] == "starboard" and result["max_course_change_deg"] > 40.0
    assert result["rule_8"] == PASS and result["rule_14"] == PASS


# -- a situation that starts inside the domain ---------------------------------------------------
def test_target_starting_inside_the_domain_is_reported_apart_with_its_own_criterion():
    # a ship 0.8 nm off on the starboard quarter at the start (R + R_i = 1 nm), sailing
    # east while the own ship sails north: the range opens from the start
    track = own_track(20)
    t = track[0]
    target = target_states(t, (-0.6, 0.53), 90.0, 10.0)
    summary = judge_encounters(*track, target, 0.0, JudgementSettings())
    result = summary["targets"][0]
    assert result["started_inside"] and result["initial_range_nm"] == pytest.approx(0.8, abs=0.01)
    assert not result["separation_kept"]  # R + R_i was never held: said as it is
    assert result["range_kept_from_start"]
    assert summary["started_inside"] == [0] and summary["started_inside_range_kept"] is True
    assert summary["separation_kept"]  # the targets that started outside (none) kept it
    assert summary["separation_margin_nm"] is None  # nor does it count in the margin
    closing = own_track(20)  # a crossing ship 0.8 nm off on the starboard bow: the range closes
    summary = judge_encounters(*closing, target_states(closing[0], (0.6, 0.53), 270.0, 6.0), 0.0,
                               JudgementSettings())
    result = summary["targets"][0]
    assert result["started_inside"] and not result["range_kept_from_start"]
    assert summary["started_inside_range_kept"] is False
    failed = [reason for reason in result["reasons"].values() if "started 0.80 nm off" in reason]
    assert failed and result["verdict"] == FAIL


def test_target_starting_outside_counts_towards_separation():
    track = own_track(20)
    summary = judge_encounters(*track, target_states(track[0], (7.0, 0.5), 180.0, 18.0), 0.0, JudgementSettings())
    assert summary["started_inside"] == [] and summary["started_inside_range_kept"] is None
    assert summary["separation_kept"] is False and summary["targets"][0]["range_kept_from_start"] is None
    # the margin is the CPA less R + R_i: a head-on ship 0.5 nm off the track, no alteration
    assert summary["separation_margin_nm"] == pytest.approx(0.5 - 1.0, abs=1e-6)
    assert summary["separation_margin_nm"] == pytest.approx(summary["targets"][0]["cpa_nm"] - 1.0)


def test_separation_margin_is_the_smallest_over_the_targets_that_started_outside():
    track = own_track(20)
    t = track[0]
    far = target_states(t, (7.0, 0.8), 180.0, 18.0)  # CPA 0.8 nm
    near = target_states(t, (7.0, -0.3), 180.0, 18.0)  # CPA 0.3 nm
    inside = target_states(t, (-0.6, 0.53), 90.0, 10.0)  # starts 0.8 nm off: not counted
    summary = judge_encounters(*track, np.concatenate([far, near, inside], axis=1), 0.0, JudgementSettings())
    assert summary["started_inside"] == [2]
    assert summary["separation_margin_nm"] == pytest.approx(0.3 - 1.0, abs=1e-6)


def test_cpa_predicted_as_the_manoeuvre_began_is_reported_beside_the_sailed_one():
    # overtaking a 13 kn ship 1.5 nm ahead, 0.45 nm to port; the own ship turns away to
    # starboard after 2 min: the range stops closing during the turn, so the sailed CPA comes
    # early, while at the old velocities it lay about 16 min after the turn began
    track = own_track(40, turns=[(2.0, 35.0)])
    result = judge(track, target_states(track[0], (1.5, -0.45), 0.0, 13.0))
    assert result["encounter_class"] == "overtaking"
    began_s = 120.0
    closing_kn = 18.0 - 13.0
    expected_s = began_s + (1.5 * NM - 18.0 * KN * began_s + 13.0 * KN * began_s) / (closing_kn * KN)
    # read at the last sample before the course has moved by half the 5 deg threshold: the
    # velocity there is up to 2.5 deg into the turn, which moves a CPA 16 min off by < 1 min
    assert result["predicted_time_of_cpa_s"] == pytest.approx(expected_s, abs=60.0)
    assert result["time_of_cpa_s"] < began_s + 5 * 60  # the sailed CPA: within 5 min of the turn
    # the alteration came some 16 min before the CPA it avoided: early (Rule 16), though the
    # turn itself brought the sailed CPA to within 5 min of it
    assert result["manoeuvre_start_s"] == pytest.approx(began_s, abs=DT_S)
    assert result["rule_16"] == PASS and result["early_by"] == "predicted CPA"


def test_a_late_alteration_is_late_by_every_reading():
    # the same overtaking, the turn 14 min later: 2 min before the CPA predicted then, long
    # after the onset of risk
    track = own_track(40, turns=[(16.0, 35.0)])
    result = judge(track, target_states(track[0], (1.5, -0.45), 0.0, 13.0))
    assert result["encounter_class"] == "overtaking" and result["onset_s"] < 60.0
    assert result["rule_16"] == FAIL and result["early_by"] is None
    assert "min before the CPA predicted then" in result["reasons"]["rule_16"]
    assert "after it was called on to act" in result["reasons"]["rule_16"]


@pytest.mark.parametrize("turn_min, early", [(0.25, "at once"), (2.0, None)])
def test_an_alteration_at_once_is_early_when_the_risk_begins_closer_than_that(turn_min, early):
    # a head-on ship at risk from the start, its CPA 4.4 min ahead (36 kn closing, 2.6 nm):
    # "early ... if the circumstances of the case admit" (Rule 8(a)) is then an alteration
    # begun at once; begun 2 min later it is late
    track = own_track(12, turns=[(turn_min, 60.0)])
    result = judge(track, target_states(track[0], (2.6, 0.05), 180.0, 18.0, radius_nm=0.5))
    assert result["encounter_class"] == "head_on" and result["onset_s"] == 0.0
    assert result["time_of_cpa_s"] - result["manoeuvre_start_s"] < 5 * 60
    assert result["early_by"] == early
    assert (result["rule_16"] == PASS) == (early is not None)


def test_no_predicted_cpa_without_a_manoeuvre():
    track = own_track(20)
    result = judge(track, target_states(track[0], (7.0, 0.5), 180.0, 18.0))
    assert result["manoeuvre_time_s"] is None and result["predicted_time_of_cpa_s"] is None


def test_a_round_turn_to_starboard_stays_a_starboard_manoeuvre():
    # 350 deg to starboard at 2 deg/s: from 180 deg on, the wrapped change reads as a turn to port
    t = np.arange(0.0, 900.0, 5.0)
    course = np.radians(np.clip(2.0 * (t - 100.0), 0.0, 350.0))
    assert first_manoeuvre(t, course, 0, 900.0, JudgementSettings()) == (105.0, "starboard")


def test_a_borderline_class_is_reported_as_such():
    track = own_track(30, turns=[(8.0, 40.0)])
    b = math.radians(10.0)
    edge = judge_encounters(*track, target_states(track[0], (6.0 * math.cos(b), 6.0 * math.sin(b)), 180.0, 18.0),
                            0.0, JudgementSettings())
    assert edge["targets"][0]["encounter_class"] == "head_on"
    assert edge["targets"][0]["borderline"].startswith("head-on") and edge["borderline"] == [0]
    clear = judge_encounters(*track, target_states(track[0], (6.0, 0.05), 180.0, 18.0), 0.0, JudgementSettings())
    assert clear["targets"][0]["borderline"] == "" and clear["borderline"] == []


def test_a_target_starting_inside_must_see_the_range_open_within_60_s():
    # 0.8 nm off on the starboard beam, sailing north-west at 10 kn across our track behind
    # us: the range closes for a while although it ends up wide
    track = own_track(20)
    slow_to_open = judge_encounters(*track, target_states(track[0], (0.0, 0.8), 300.0, 10.0), 0.0,
                                    JudgementSettings())["targets"][0]
    assert slow_to_open["started_inside"] and slow_to_open["range_opening_s"] > 60.0
    assert slow_to_open["range_opened_in_time"] is False and slow_to_open["verdict"] == FAIL
    at_once = judge_encounters(*track, target_states(track[0], (0.0, 0.8), 120.0, 10.0), 0.0,
                               JudgementSettings())
    assert at_once["targets"][0]["range_opening_s"] <= 60.0 and at_once["started_inside_opened"] is True


def test_stand_on_manoeuvre_made_when_another_stand_on_target_required_it_is_allowed():
    # two faster ships coming up from astern: the nearer one's time to stand on runs out
    # first, and the own ship acts for it; that turn breaks no obligation to the farther one
    probe_t = own_track(40)[0]
    near = target_states(probe_t, (-1.5, 0.15), 0.0, 27.0)
    far = target_states(probe_t, (-4.5, -0.25), 0.0, 26.0)
    from rhnc.cosim.colregs_analysis import _stand_on_action_time
    own = own_track(40)
    own_xy = np.column_stack(own[1:3])
    velocity = np.column_stack(np.gradient(own_xy, own[0], axis=0).T)
    act_near = _stand_on_action_time(own[0], own_xy, velocity, near[:, 0], "overtaken", 0, 0.0, JudgementSettings())
    act_far = _stand_on_action_time(own[0], own_xy, velocity, far[:, 0], "overtaken", 0, 0.0, JudgementSettings())
    assert act_near is not None and act_far is not None and act_near + 120.0 < act_far
    track = own_track(40, turns=[(act_near / 60.0, -40.0)])
    both = judge_encounters(*track, np.concatenate([near, far], axis=1))["targets"]
    assert both[1]["encounter_class"] == "overtaken" and both[1]["manoeuvre_time_s"] < act_far
    assert both[1]["rule_17"] == PASS, both[1]["reasons"]
    alone = judge(track, far)  # the same turn with no other ship to act for
    assert alone["rule_17"] == FAIL


def test_an_alteration_is_timed_from_when_the_turn_began():
    # a slow turn (0.05 deg/s) shows as 5 deg of course only 100 s after it began
    track = own_track(40, turns=[(2.0, 35.0)], rate_deg_s=0.05)
    result = judge(track, target_states(track[0], (1.5, -0.45), 0.0, 13.0))
    assert result["manoeuvre_time_s"] == pytest.approx(220.0, abs=DT_S)
    assert result["manoeuvre_start_s"] == pytest.approx(120.0, abs=60.0)


def test_a_target_starting_inside_is_judged_by_the_range_opening_not_by_a_side():
    # a head-on ship 0.6 nm off on the starboard bow, closing at 36 kn: immediate danger from
    # the start (Rule 2(b)); the own ship turns away to port and the range opens at once
    track = own_track(12, turns=[(0.25, -90.0)], rate_deg_s=2.0)
    result = judge(track, target_states(track[0], (0.6, 0.05), 180.0, 18.0))
    assert result["encounter_class"] == "head_on" and result["started_inside"]
    assert result["manoeuvre_side"] == "port" and result["range_opened_in_time"]
    assert result["side_correct"] is None
    assert result["rule_14"] == PASS


def test_rules_8_and_16_judge_a_target_starting_inside_by_the_range_opening():
    # a ship crossing from starboard 0.54 nm off at 25 kn: immediate danger from the start; a
    # 12 deg turn, all a ship can make before the range opens 58 s later, is what the
    # circumstances admit (Rule 8(a), (b)), not "not readily apparent"
    track = own_track(12, turns=[(0.1, 12.0)])
    result = judge(track, target_states(track[0], (0.2, 0.5), 270.0, 25.0))
    assert result["started_inside"] and result["range_opening_s"] <= 60.0
    assert result["max_course_change_deg"] < JudgementSettings().apparent_course_change_deg
    assert (result["rule_8"], result["rule_16"]) == (PASS, PASS), result["reasons"]
    # the range closing for longer than 60 s still fails both
    slow = judge(track, target_states(track[0], (0.3, 0.5), 250.0, 20.0))
    assert slow["started_inside"] and slow["range_opening_s"] > 60.0
    assert (slow["rule_8"], slow["rule_16"]) == (FAIL, FAIL)


# -- a reduction of speed as the manoeuvre (Rules 8(b), 8(e)) ---------------------------------
def _crossing_from_starboard(t):
    # from starboard, heading west, would meet us 4.5 nm ahead in 15 min
    return target_states(t, (4.5, 4.5), 270.0, 18.0)


def test_a_reduction_of_speed_alone_is_a_give_way_manoeuvre():
    # 18 -> 8 kn one minute after the onset, the course kept: the ship crossing from starboard
    # passes ahead, and the slowing is an early and readily apparent action
    track = own_track(30, slow_down=(1.0, 8.0))
    result = judge(track, _crossing_from_starboard(track[0]))
    assert result["encounter_class"] == "crossing_give_way" and result["separation_kept"]
    assert result["manoeuvre_kind"] == "speed" and result["manoeuvre_side"] is None
    assert result["manoeuvre_time_s"] == pytest.approx(60.0, abs=DT_S)
    assert result["manoeuvre_start_s"] == pytest.approx(55.0, abs=DT_S)
    assert result["rule_16"] == PASS and result["rule_8"] == PASS, result["reasons"]
    # a course change later on does not make the slowing any less the first manoeuvre
    track = own_track(30, turns=[(4.0, 40.0)], slow_down=(1.0, 8.0))
    result = judge(track, _crossing_from_starboard(track[0]))
    assert result["manoeuvre_kind"] == "speed" and result["manoeuvre_side"] == "starboard"


def test_the_surge_of_a_seaway_is_no_manoeuvre():
    t = np.arange(0.0, 30 * 60.0 + DT_S / 2, DT_S)
    speed = 18.0 * KN * (1.0 + 0.15 * np.sin(2 * math.pi * t / 60.0))  # +-15 % over a minute
    x = np.concatenate([[0.0], np.cumsum(speed[1:] * DT_S)])
    result = judge((t, x, np.zeros_like(t), np.zeros_like(t)), _crossing_from_starboard(t))
    assert result["manoeuvre_time_s"] is None and result["manoeuvre_kind"] is None
    assert result["rule_16"] == FAIL and "no alteration" in result["reasons"]["rule_16"]
    # a lasting loss of a twentieth is no manoeuvre either
    track = own_track(30, slow_down=(1.0, 17.1))
    assert judge(track, _crossing_from_starboard(track[0]))["manoeuvre_time_s"] is None


def test_a_stand_on_ship_that_slows_early_fails_rule_17():
    track = own_track(30, slow_down=(1.0, 8.0))  # TCPA 14 min: too early to give up standing on
    result = judge(track, _stand_on_target(track[0]))
    assert result["manoeuvre_kind"] == "speed"
    assert result["rule_17"] == FAIL and "reduced speed" in result["reasons"]["rule_17"]
    assert result["side_correct"] is True  # no turn to port
