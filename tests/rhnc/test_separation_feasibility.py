"""Whether a single manoeuvre from the start keeps R + R_i from every target that started outside it."""

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from rhnc.ship.ship_model import load_parameter_set
from script_module import module_of_file

REPO = Path(__file__).resolve().parents[2]
KNOT = 1852.0 / 3600.0
NM = 1852.0
OWN = np.array([0.0, 0.0, 0.0, 18 * KNOT, 0.0, 0.0])   # x north, y east, 18 kn on 000 deg


@pytest.fixture(scope="module")
def feasibility():
    return module_of_file(REPO / "scripts" / "separation_feasibility.py", "separation_feasibility")


@pytest.fixture(scope="module")
def kcs():
    return load_parameter_set("default")


def target(bearing_deg, range_nm, course_deg, speed_kn, turn_at_s=None, new_course_deg=None):
    """A target as the run folder needs it: where it is at t = 0 (relative bearing from the own
    ship heading north), where it steers, and optionally a later course."""
    bearing, course = np.radians(bearing_deg), np.radians(course_deg)
    return {"xy": range_nm * NM * np.array([np.cos(bearing), np.sin(bearing)]),
            "velocity": speed_kn * KNOT * np.array([np.cos(course), np.sin(course)]),
            "turn_at_s": turn_at_s, "new_course_deg": new_course_deg, "speed_kn": speed_kn}


def write_run(folder: Path, run_id: str, targets, lost=None, started_inside=(), parameter_set="default",
              classes=None) -> Path:
    """A run folder with the summary and time series the script reads (every target that started
    outside lost unless ``lost`` names the ones that were; every target head-on unless ``classes``
    gives the class the analysis recorded for each)."""
    run = folder / "runs" / run_id
    run.mkdir(parents=True)
    lost = range(len(targets)) if lost is None else lost
    classes = ["head_on"] * len(targets) if classes is None else classes
    rows = [{"obstacle": k, "encounter_class": classes[k], "cpa_nm": 0.5 if k in lost else 1.5, "required_nm": 1.0,
             "separation_kept": k not in lost, "started_inside": k in started_inside} for k in range(len(targets))]
    (run / "summary.json").write_text(json.dumps({
        "run_id": run_id, "overrides": {}, "analyses": {"colregs": {"targets": rows}},
        "participants": {"ctrl": {"model_check": {"set": parameter_set}}}}))
    times = np.arange(0.0, 2000.0, 20.0)
    columns = {"time_s": times}
    for name, value in zip(["ship.x", "ship.y", "ship.psi", "ship.u", "ship.v", "ship.r"], OWN):
        columns[name] = np.full(times.size, value)
    for k, each in enumerate(targets):
        velocity = np.tile(each["velocity"], (times.size, 1))
        if each["turn_at_s"] is not None:
            course = np.radians(each["new_course_deg"])
            velocity[times >= each["turn_at_s"]] = each["speed_kn"] * KNOT * np.array([np.cos(course), np.sin(course)])
        xy = each["xy"] + np.vstack([np.zeros(2), np.cumsum(velocity[:-1] * 20.0, axis=0)])
        for j, values in enumerate([xy[:, 0], xy[:, 1], velocity[:, 0], velocity[:, 1], np.full(times.size, NM)]):
            columns[f"traffic.obstacles[{k},{j}]"] = values
    pd.DataFrame(columns).to_parquet(run / "timeseries.parquet")
    return run


def test_a_ship_head_on_five_miles_off_is_cleared_by_a_turn(feasibility, tmp_path):
    run = write_run(tmp_path, "head_on", [target(0.0, 5.0, 180.0, 18.0)])
    verdict = feasibility.judge_run(run, {})
    assert verdict["achievable"] and verdict["least_clearance_nm"] > 1.0
    assert verdict["best"].startswith("turn")


def test_a_head_on_ship_is_not_cleared_by_speed_alone(feasibility, kcs):
    # stopping, speeding up or holding on: the other ship still runs into us; only a turn helps
    family = feasibility.manoeuvre_family(kcs, OWN[3], offsets_deg=np.array([0.0]))
    each = target(0.0, 5.0, 180.0, 18.0)
    targets = feasibility.Targets(each["xy"][None], each["velocity"][None], np.array([NM]))
    tracks = feasibility.sail(OWN, family, kcs, (0.0, 24 * KNOT))
    assert np.max(feasibility.least_clearance(tracks, targets)) < 0.0


def test_a_fast_overtaker_close_astern_cannot_be_kept_off(feasibility, tmp_path):
    # 1.05 nm dead astern at 30 kn, the own ship at 18 kn and at most 24 kn: closing at 6-12 kn,
    # and no turn takes the own ship a mile off the overtaker's line in the five minutes it needs
    run = write_run(tmp_path, "overtaken", [target(180.0, 1.05, 0.0, 30.0)])
    verdict = feasibility.judge_run(run, {})
    assert not verdict["achievable"]
    assert verdict["least_clearance_nm"] < -0.2


def test_two_ships_converging_from_both_beams_cannot_both_be_kept_off(feasibility, tmp_path):
    run = write_run(tmp_path, "beams", [target(90.0, 1.1, 270.0, 18.0), target(-90.0, 1.1, 90.0, 18.0)])
    verdict = feasibility.judge_run(run, {})
    assert not verdict["achievable"]
    assert [index for index, _, _ in verdict["lost"]] == [0, 1]


def test_boxed_in_with_an_obstruction_ahead_only_stopping_keeps_clear(feasibility, tmp_path):
    # ships on both beams 1.15 nm off on our course and speed, a ship stopped 2 nm ahead: a turn
    # closes a beam ship, holding on or coasting runs into the one ahead; full astern stops in 0.6 nm
    boxed = [target(90.0, 1.15, 0.0, 18.0), target(-90.0, 1.15, 0.0, 18.0), target(0.0, 2.0, 0.0, 0.0)]
    run = write_run(tmp_path, "boxed", boxed)
    verdict = feasibility.judge_run(run, {})
    assert verdict["achievable"]
    assert verdict["best"].endswith("full astern")


def test_full_ahead_stops_at_the_speed_bound_and_full_astern_at_a_standstill(feasibility, kcs):
    # the linear hull would run on to 42 kn ahead, or astern, under the full force
    family = feasibility.manoeuvre_family(kcs, OWN[3], offsets_deg=np.array([0.0]),
                                          surge_names=("full ahead", "full astern"))
    end_velocity = feasibility.sail(OWN, family, kcs, (0.0, 24 * KNOT)).end_velocity
    assert end_velocity[0, 0] == pytest.approx(24 * KNOT, abs=0.1 * KNOT)
    assert end_velocity[1, 0] == pytest.approx(0.0, abs=0.1 * KNOT)


@pytest.mark.parametrize("offset_deg", [-180.0, -90.0, 10.0, 40.0, 170.0])
def test_the_turn_checks_its_swing_and_settles_on_the_new_heading_at_every_speed(feasibility, kcs, offset_deg):
    family = feasibility.manoeuvre_family(kcs, OWN[3], offsets_deg=np.array([offset_deg]))
    heading = np.degrees(feasibility.sail(OWN, family, kcs, (0.0, 24 * KNOT)).heading_rad)   # (n, 4 surge forces)
    assert np.max(np.sign(offset_deg) * (heading - offset_deg)) < 3.0     # no swing past the new heading
    assert np.all(np.abs(heading[-1] - offset_deg) < 0.5)                 # and on it at the end


def test_a_run_that_lost_only_a_target_starting_inside_is_not_judged(feasibility, tmp_path):
    run = write_run(tmp_path, "inside", [target(0.0, 0.8, 180.0, 18.0), target(0.0, 5.0, 180.0, 18.0)],
                    lost=[0], started_inside=[0])
    assert feasibility.judge_run(run, {}) is None


def test_a_target_that_turned_later_is_flagged(feasibility, tmp_path):
    run = write_run(tmp_path, "turned", [target(0.0, 5.0, 180.0, 18.0, turn_at_s=600.0, new_course_deg=150.0)])
    verdict = feasibility.judge_run(run, {})
    assert verdict["turned"] == {0: 600.0}
    assert "[obstacle 0 turned at 600 s]" in feasibility.run_line("batch", verdict, "")


def test_the_parameter_set_the_controller_used_is_the_one_judged(feasibility, tmp_path):
    # the paper's Table 2 is unstable above 0.25 m/s: at 18 kn its ship diverges, and says so
    run = write_run(tmp_path, "paper", [target(0.0, 5.0, 180.0, 18.0)], parameter_set="paper_table2")
    sets: dict = {}
    verdict = feasibility.judge_run(run, sets)
    assert set(sets) == {"paper_table2"} and verdict["parameter_set"] == "paper_table2"
    assert verdict["diverged"] > 0 and "the model diverged" in feasibility.run_line("batch", verdict, "")
    assert feasibility.judge_run(write_run(tmp_path, "kcs", [target(0.0, 5.0, 180.0, 18.0)]), sets)["diverged"] == 0


def test_main_prints_a_line_per_run_and_the_batch_totals(feasibility, tmp_path, capsys):
    batch = tmp_path / "suite"
    write_run(batch, "a_head_on", [target(0.0, 5.0, 180.0, 18.0)])
    write_run(batch, "b_beams", [target(90.0, 1.1, 270.0, 18.0), target(-90.0, 1.1, 90.0, 18.0)])
    write_run(batch, "c_clean", [target(0.0, 5.0, 180.0, 18.0)], lost=[])
    pd.DataFrame({"run_id": ["a_head_on", "b_beams", "c_clean"],
                  "param:situation": ["one.json", "two.json", "three.json"]}).to_csv(batch / "summary.csv", index=False)
    assert feasibility.main([str(batch)]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert len(lines) == 3
    assert lines[0].startswith("suite a_head_on one.json: lost obstacle 0 head_on CPA 0.50 nm")
    assert ": achievable keeping every side" in lines[0]
    assert lines[1].startswith("suite b_beams two.json") and "not achievable by a single manoeuvre from the start" in lines[1]
    assert lines[2] == ("suite: 3 lost targets in 2 runs; achievable keeping every side: 1 (1 runs); "
                        "achievable only against a side rule: 0 (0 runs); "
                        "not achievable by a single manoeuvre from the start: 2 (1 runs)")


def test_main_prints_the_totals_over_all_batches(feasibility, tmp_path, capsys):
    write_run(tmp_path / "one", "a_head_on", [target(0.0, 5.0, 180.0, 18.0)])
    write_run(tmp_path / "two", "b_bow", [target(70.0, 1.5, 270.0, 14.0)], classes=["crossing_give_way"])
    assert feasibility.main([str(tmp_path / "one"), str(tmp_path / "two")]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert "against the side of obstacle 0 crossing_give_way" in lines[2]
    assert lines[-1] == ("all 2 batches: 2 lost targets in 2 runs; achievable keeping every side: 1 (1 runs); "
                         "achievable only against a side rule: 1 (1 runs); "
                         "not achievable by a single manoeuvre from the start: 0 (0 runs)")


def test_a_closest_approach_after_the_window_counts(feasibility):
    # the own ship stopped at the origin, a target 5 nm north closing at 6 kn: it arrives at 50 min,
    # after the 30 min window; a manoeuvre that only postpones the encounter keeps nothing
    times = np.arange(0.0, feasibility.WINDOW_S + 1.0, 1.0)
    stopped = feasibility.Tracks(times, np.zeros((times.size, 1, 2)), np.zeros((times.size, 1)), np.zeros((1, 2)))
    targets = feasibility.Targets(np.array([[5 * NM, 0.0]]), np.array([[-6 * KNOT, 0.0]]), np.array([NM]))
    clearance = feasibility.least_clearance(stopped, targets)
    assert clearance[0] == pytest.approx(-NM, abs=1.0)


def test_the_closest_approach_between_samples_counts(feasibility):
    # two samples 200 s apart, the target passing 1.5 nm abeam at 20 kn halfway between them
    times = np.array([0.0, 200.0])
    stopped = feasibility.Tracks(times, np.zeros((2, 1, 2)), np.zeros((2, 1)), np.zeros((1, 2)))
    targets = feasibility.Targets(np.array([[-100 * 20 * KNOT, 1.5 * NM]]), np.array([[20 * KNOT, 0.0]]), np.array([NM]))
    assert feasibility.least_clearance(stopped, targets)[0] == pytest.approx(0.5 * NM)


def _sides(feasibility, kcs, targets, classes, offsets_deg, surge_names=("speed held",)):
    """``side_correct`` (manoeuvres, targets) and the least clearance [nm] of each manoeuvre."""
    family = feasibility.manoeuvre_family(kcs, OWN[3], offsets_deg=np.array(offsets_deg), surge_names=surge_names)
    judged = feasibility.Targets(np.array([each["xy"] for each in targets]), np.array([each["velocity"] for each in targets]),
                                 np.full(len(targets), NM), tuple(classes))
    tracks = feasibility.sail(OWN, family, kcs, (0.0, 24 * KNOT))
    until_s = max(3200.0, feasibility.closest_approach_after_window_s(tracks, judged))
    return (feasibility.judged_sides(feasibility.carried_on(tracks, until_s), judged),
            feasibility.least_clearance(tracks, judged) / NM)


def test_the_only_clear_turn_crosses_the_bow_of_a_ship_crossing_from_starboard(feasibility, tmp_path):
    # 1.5 nm off on the starboard bow, crossing at 14 kn: a turn to port runs ahead of her and
    # clear; to pass astern the own ship would have to turn towards her, and no turn does it in time
    run = write_run(tmp_path, "bow", [target(70.0, 1.5, 270.0, 14.0)], classes=["crossing_give_way"])
    verdict = feasibility.judge_run(run, {})
    assert verdict["achievable"] and "to port" in verdict["best"]
    assert verdict["against_sides"] == [(0, "crossing_give_way")]
    assert verdict["least_clearance_keeping_sides_nm"] < -0.5
    assert verdict["verdict"] == "achievable only against a side rule"
    assert ": achievable only against a side rule" in feasibility.run_line("batch", verdict, "")


def test_a_turn_to_starboard_passes_astern_of_a_ship_crossing_from_starboard(feasibility, kcs, tmp_path):
    crossing = target(45.0, 3.0, 270.0, 18.0)   # on a collision course, 3 nm off
    sides, clearance = _sides(feasibility, kcs, [crossing], ["crossing_give_way"], [-60.0, 60.0])
    assert sides[:, 0].tolist() == [False, True]          # to port: ahead of her; to starboard: astern
    assert clearance[1] > 0.2
    verdict = feasibility.judge_run(write_run(tmp_path, "astern", [crossing], classes=["crossing_give_way"]), {})
    assert verdict["verdict"] == "achievable keeping every side"
    assert verdict["least_clearance_keeping_sides_nm"] > 0.2


def test_a_head_on_ship_is_passed_port_to_port(feasibility, kcs, tmp_path):
    # fine on the starboard bow, 2.6 nm off at 24 kn: a turn to port passes her starboard to
    # starboard, clear and against Rule 14; with a ship 1.5 nm astern no turn to starboard (nor
    # round) keeps the separation
    head_on, astern = target(15.0, 2.6, 180.0, 24.0), target(180.0, 1.5, 0.0, 18.0)
    sides, _ = _sides(feasibility, kcs, [head_on, astern], ["head_on", "overtaken"], [-30.0, 60.0])
    assert sides.tolist() == [[False, None], [True, None]]     # starboard to starboard; across her bow, port to port
    run = write_run(tmp_path, "head_on", [head_on, astern], classes=["head_on", "overtaken"], lost=[0])
    verdict = feasibility.judge_run(run, {})
    assert verdict["achievable"] and "to port" in verdict["best"]
    assert verdict["against_sides"] == [(0, "head_on")]
    assert verdict["verdict"] == "achievable only against a side rule"


def test_a_stand_on_ship_does_not_turn_to_port_for_a_ship_crossing_from_port(feasibility, kcs):
    sides, _ = _sides(feasibility, kcs, [target(-50.0, 2.6, 90.0, 12.0)], ["crossing_stand_on"], [-30.0, 0.0, 30.0],
                      surge_names=("speed held", "full astern"))
    assert sides[:, 0].tolist() == [False, True, True, False, True, True]   # Rule 17(c); holding on or stopping keep it


@pytest.mark.parametrize("kind", ["overtaking", "overtaken", "static", "none"])
def test_no_side_is_judged_where_the_analysis_judges_none(feasibility, kcs, kind):
    sides, _ = _sides(feasibility, kcs, [target(-20.0, 2.0, 0.0, 10.0)], [kind], [-30.0, 30.0])
    assert sides[:, 0].tolist() == [None, None]


def test_no_side_is_judged_for_a_target_that_started_inside(feasibility, kcs):
    sides, _ = _sides(feasibility, kcs, [target(10.0, 0.9, 180.0, 18.0)], ["head_on"], [-30.0, 30.0])
    assert sides[:, 0].tolist() == [None, None]
