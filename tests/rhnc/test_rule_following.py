"""Targets that follow the rules of the road themselves: give way to starboard, stand on, Rule 17(b)."""

import math
from pathlib import Path

import numpy as np
import pytest

from orchestrator.errors import ScenarioError
from orchestrator.participant import BuildContext
from rhnc.encounters.colregs import STAND_ON_ACTION_TCPA_S
from rhnc.encounters.traffic import TrafficParticipant

NM = 1852.0
KNOT = NM / 3600.0


def sail(targets, own_course_deg=0.0, own_speed_kn=18.0, duration_s=2400.0, step=5.0, own_start=(0.0, 0.0)):
    """Own ship straight at constant velocity (it never gives way); the targets' rows over time."""
    traffic = TrafficParticipant.from_options("traffic", {"targets": targets},
                                              BuildContext("s.toml: participants.traffic", Path("."), step, 0.0,
                                                           duration_s))
    psi = math.radians(own_course_deg)
    velocity = own_speed_kn * KNOT * np.array([math.cos(psi), math.sin(psi)])
    def own(t):
        return np.asarray(own_start) * NM + velocity * t

    def inputs(t):
        return {"x": own(t)[0], "y": own(t)[1], "psi": psi, "u": own_speed_kn * KNOT, "v": 0.0}
    times = np.arange(0.0, duration_s + step / 2, step)
    rows = [traffic.setup(0.0, inputs(0.0))["obstacles"]]
    rows += [traffic.step(t, step, inputs(t))["obstacles"] for t in times[1:]]
    return times, np.array([own(t) for t in times]), np.array(rows), traffic


def test_head_on_target_turns_to_starboard_and_passes_port_to_port():
    times, own, rows, traffic = sail([{"start_nm": [12.0, 0.0], "velocity_kn": [-18.0, 0.0], "radius_nm": 1.0,
                                       "behaviour": "rules"}])
    (action,) = traffic.tables()["actions"]  # 12 nm at 36 kn: TCPA 20 min at the start
    assert action["class"] == "head_on" and 890.0 <= action["tcpa_s"] <= 900.0
    course = np.degrees(np.arctan2(rows[:, 0, 3], rows[:, 0, 2])) % 360.0
    assert course.max() == pytest.approx(220.0, abs=0.5)  # 180 + 40: to its starboard
    distance = np.hypot(*(rows[:, 0, :2] - own).T)
    closest = int(np.argmin(distance))
    assert distance[closest] >= 1.0 * NM
    assert rows[closest, 0, 1] - own[closest, 1] < 0  # on the own ship's port side: port to port
    assert course[-1] == pytest.approx(180.0, abs=0.5)  # back on its base course once past


def test_give_way_target_crossing_from_port_turns_starboard_and_passes_astern():
    # the target comes from the own ship's port side: it has the own ship on its starboard side
    times, own, rows, traffic = sail([{"start_nm": [5.0, -5.0], "velocity_kn": [0.0, 18.0], "radius_nm": 1.0,
                                       "behaviour": "rules"}])
    (action,) = traffic.tables()["actions"]
    assert action["class"] == "crossing_give_way"
    distance = np.hypot(*(rows[:, 0, :2] - own).T)
    assert distance.min() >= 1.0 * NM
    crossing = int(np.argmin(np.abs(rows[:, 0, 1] - own[:, 1])))  # the target crosses the own ship's track
    assert rows[crossing, 0, 0] < own[crossing, 0]  # astern of the own ship


def test_stand_on_target_keeps_course_until_rule_17b_then_turns_to_starboard():
    # the own ship comes from the target's starboard side and does not give way
    times, own, rows, traffic = sail([{"start_nm": [5.0, 5.0], "velocity_kn": [0.0, -18.0], "radius_nm": 1.0,
                                       "behaviour": "rules"}])
    (action,) = traffic.tables()["actions"]
    assert action["class"] == "crossing_stand_on"
    assert 0.0 < action["tcpa_s"] <= STAND_ON_ACTION_TCPA_S and action["cpa_nm"] < 1.0
    course = np.degrees(np.arctan2(rows[:, 0, 3], rows[:, 0, 2])) % 360.0
    before = times < action["time_s"]
    np.testing.assert_allclose(course[before], 270.0, atol=1e-6)  # stood on until then
    assert course.max() == pytest.approx(310.0, abs=0.5)  # then to starboard, never to port
    assert course.min() >= 270.0 - 1e-6


def test_two_rule_following_targets_head_on_both_turn_to_starboard():
    targets = [{"start_nm": [0.0, 20.0], "velocity_kn": [15.0, 0.0], "radius_nm": 0.5, "behaviour": "rules"},
               {"start_nm": [10.0, 20.0], "velocity_kn": [-15.0, 0.0], "radius_nm": 0.5, "behaviour": "rules"}]
    times, own, rows, traffic = sail(targets)
    classes = {action["target"]: action["class"] for action in traffic.tables()["actions"]}
    assert classes == {1: "head_on", 2: "head_on"}
    distance = np.hypot(*(rows[:, 0, :2] - rows[:, 1, :2]).T)
    assert distance.min() >= 0.5 * NM
    first = np.degrees(np.arctan2(rows[:, 0, 3], rows[:, 0, 2]))
    second = np.degrees(np.arctan2(rows[:, 1, 3], rows[:, 1, 2])) % 360.0
    assert first.max() > 30.0 and first.min() >= -1e-6 and second.max() > 210.0 and second.min() >= 180.0 - 1e-6


def test_without_behaviour_the_same_target_does_not_react():
    times, own, rows, traffic = sail([{"start_nm": [8.0, 0.0], "velocity_kn": [-18.0, 0.0], "radius_nm": 1.0}])
    assert traffic.input_names == () and traffic.tables() == {}
    assert np.hypot(*(rows[:, 0, :2] - own).T).min() < 0.1 * NM


@pytest.mark.parametrize("entry, message", [
    ({"behaviour": "polite"}, r"targets\[0\]: 'behaviour' must be \"rules\""),
    ({"behaviour": "rules", "alteration_deg": 120}, r"targets\[0\]: 'alteration_deg' must be a number within"),
    ({"behaviour": "rules", "manoeuvres": [{"at_s": 1, "speed_kn": 2}]}, r"either 'manoeuvres' .* or 'behaviour'"),
])
def test_rule_following_errors_name_the_key(entry, message):
    with pytest.raises(ScenarioError, match=message):
        sail([{"start_nm": [8.0, 0.0], "velocity_kn": [-18.0, 0.0], "radius_nm": 1.0, **entry}], duration_s=10.0)
    with pytest.raises(ScenarioError, match=r"'behaviour' goes with 'start_nm'"):
        sail([{"waypoints_nm": [[0, 0], [1, 0]], "speed_kn": 5, "radius_nm": 1.0, "behaviour": "rules"}],
             duration_s=10.0)


def test_target_behaviour_makes_every_constant_velocity_target_follow_the_rules():
    options = {"target_behaviour": "rules", "targets": [
        {"start_nm": [8.0, 0.0], "velocity_kn": [-18.0, 0.0], "radius_nm": 1.0},
        {"waypoints_nm": [[0, 5], [1, 5]], "speed_kn": 5, "radius_nm": 1.0},
        {"start_nm": [0.0, 9.0], "velocity_kn": [0.0, 5.0], "radius_nm": 1.0,
         "manoeuvres": [{"at_s": 60, "speed_kn": 4}]}]}
    context = BuildContext("s.toml: participants.traffic", Path("."), 5.0, 0.0, 600.0)
    traffic = TrafficParticipant.from_options("traffic", options, context)
    assert [getattr(target, "reactive", False) for target in traffic.targets] == [True, False, False]
    with pytest.raises(ScenarioError, match=r"participants.traffic: 'target_behaviour' must be \"rules\""):
        TrafficParticipant.from_options("traffic", {"target_behaviour": "yes", "targets": []}, context)


def scripted_rows(start_nm, velocity_kn, change_deg, at_s, times, radius_nm=1.0):
    from rhnc.encounters.target_motion import Manoeuvre, ScriptedTarget

    ship = ScriptedTarget(np.asarray(start_nm) * NM, np.asarray(velocity_kn) * KNOT,
                          [Manoeuvre(at_s, math.radians(change_deg), math.radians(0.5), None, 0.02)],
                          radius_nm * NM, float(times[-1]))
    return np.array([ship.state(t) for t in times])


@pytest.mark.parametrize("target_turn_deg, mutual", [(40.0, 0), (-40.0, 1)])
def test_traffic_judgement_finds_a_mutual_turn_into_each_other(target_turn_deg, mutual):
    from rhnc.cosim.traffic_colregs_analysis import judge_traffic

    times = np.arange(0.0, 2400.0, 5.0)
    own = scripted_rows([0.0, 0.0], [18.0, 0.0], 40.0, 300.0, times)
    target = scripted_rows([12.0, 0.2], [-18.0, 0.0], target_turn_deg, 300.0, times)  # + : its starboard
    result = judge_traffic(times, own[:, 0], own[:, 1], target[:, None, :])
    (entry,) = result["targets"]
    assert entry["class_against_own_ship"] == "head_on" and entry["own_manoeuvre_side"] == "starboard"
    assert entry["manoeuvre_side"] == ("starboard" if target_turn_deg > 0 else "port")
    assert result["mutual_turns_into_each_other"] == mutual
    assert result["targets_side_correct"] is (mutual == 0)


def test_traffic_judgement_of_a_rule_following_target_in_a_crossing():
    from rhnc.cosim.traffic_colregs_analysis import judge_traffic

    times, own, rows, traffic = sail([{"start_nm": [5.0, -5.0], "velocity_kn": [0.0, 18.0], "radius_nm": 1.0,
                                       "behaviour": "rules"}])
    result = judge_traffic(times, own[:, 0], own[:, 1], rows[:, :1, :])
    (entry,) = result["targets"]
    assert entry["class_against_own_ship"] == "crossing_give_way" and entry["side_correct"] is True
    assert entry["separation_kept"] and result["mutual_turns_into_each_other"] == 0


def test_reactive_targets_without_the_own_ship_connected_are_refused_in_one_line(tmp_path, capsys):
    from orchestrator.cli import main

    repo = Path(__file__).resolve().parents[2]
    text = (repo / "scenarios" / "encounter_nmpc_autonomous.toml").read_text()
    scenario = tmp_path / "bad.toml"
    scenario.write_text(text.replace('  "ship.psi -> traffic.psi",\n', ""))
    assert main(["run", str(scenario), "--results", str(tmp_path / "results"), "--no-progress"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"error: {scenario}: participants.traffic: targets with behaviour = \"rules\" react to the own "
                   f"ship; connect its state to traffic.psi"]
    assert not (tmp_path / "results").exists() or not any((tmp_path / "results").rglob("*"))
