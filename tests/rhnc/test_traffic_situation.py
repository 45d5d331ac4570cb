"""Maritime-schema traffic situations (DNV trafficgen output) into scenarios and batches."""

import json
import math
import shutil
import textwrap
from pathlib import Path

import numpy as np
import pytest
from pyproj import Geod

from orchestrator.batch_spec import load_batch
from orchestrator.cli import main
from orchestrator.errors import ScenarioError
from orchestrator.scenario import load_scenario, read_toml
from rhnc.encounters.traffic_situation import load_traffic_situation, scenario_overrides

REPO = Path(__file__).resolve().parents[2]
DATA = REPO / "tests" / "data" / "traffic_situations"
NM = 1852.0


def _own_start(data):
    waypoint = data["ownShip"]["waypoints"][0]["position"]
    return waypoint["lat"], waypoint["lon"]


def test_positions_are_projected_about_the_own_ship_start():
    data = json.loads((DATA / "three_targets.json").read_text())
    situation = load_traffic_situation(DATA / "three_targets.json")
    lat0, lon0 = _own_start(data)
    assert situation.own_ship.start_nm == (0.0, 0.0)
    assert situation.own_ship.speed_kn == 18.0 and situation.own_ship.course_deg == pytest.approx(0.0, abs=1e-6)
    geod = Geod(ellps="WGS84")
    for target, raw in zip(situation.targets, data["targetShips"]):
        start = raw["waypoints"][0]["position"]
        azimuth, _, distance = geod.inv(lon0, lat0, start["lon"], start["lat"])
        north, east = target.start_nm
        # azimuthal equidistant about the own start: range and bearing from it are exact
        assert math.hypot(north, east) * NM == pytest.approx(distance, abs=0.5)
        assert math.degrees(math.atan2(east, north)) == pytest.approx(azimuth, abs=1e-4)
        assert target.speed_kn == raw["waypoints"][0]["leg"]["sog"]
    assert len(situation.targets) == 3 and situation.title == "three-targets"


def test_origin_shift_and_the_last_leg_is_extended():
    plain = load_traffic_situation(DATA / "head_on.json")
    shifted = load_traffic_situation(DATA / "head_on.json", origin_nm=(50.0, 40.0))
    assert shifted.own_ship.start_nm == (50.0, 40.0)
    np.testing.assert_allclose(shifted.targets[0].waypoints_nm, plain.targets[0].waypoints_nm + [50.0, 40.0])
    raw = json.loads((DATA / "head_on.json").read_text())["targetShips"][0]["waypoints"]
    # the target goes on along its last leg for 3 h instead of stopping at its last waypoint
    assert len(plain.targets[0].waypoints_nm) == len(raw) + 1
    last_leg = np.diff(plain.targets[0].waypoints_nm[-2:], axis=0)[0]
    assert np.hypot(*last_leg) == pytest.approx(3.0 * plain.targets[0].speed_kn)


def test_overrides_put_the_situation_into_a_base_scenario():
    base = REPO / "scenarios" / "exp3b_head_on.toml"
    data, _ = read_toml(base, "scenario")
    situation = load_traffic_situation(DATA / "crossing_give_way.json", origin_nm=(1.0, 2.0))
    overrides = scenario_overrides(situation, data, radius_nm=1.0, route_nm=12.0)
    assert overrides["participants.ship.parameters.psi0"] == pytest.approx(0.0, abs=1e-9)
    assert (overrides["participants.ship.parameters.x0"], overrides["participants.ship.parameters.y0"]) == (NM, 2 * NM)
    assert overrides["participants.ship.parameters.u0"] == pytest.approx(18.0 * NM / 3600.0)
    assert overrides["participants.ref.options.start_nm"] == [1.0, 2.0]
    assert overrides["participants.ref.options.course_deg"] == pytest.approx(0.0, abs=1e-6)
    (target,) = overrides["participants.traffic.options.targets"]
    assert target["radius_nm"] == 1.0 and target["speed_kn"] == situation.targets[0].speed_kn
    scenario = load_scenario(base, overrides)  # the scenario accepts them
    assert scenario.participants


def test_navigation_and_goal_get_a_goal_along_the_own_route():
    data = {"participants": {"ship": {}, "traffic": {}, "nav": {"type": "navigation"}, "goal": {"type": "goal"}}}
    situation = load_traffic_situation(DATA / "head_on.json", origin_nm=(50.0, 50.0))
    overrides = scenario_overrides(situation, data, radius_nm=1.0, route_nm=15.0)
    np.testing.assert_allclose(overrides["participants.nav.options.goal_nm"], [65.0, 50.0], atol=1e-5)
    assert overrides["participants.goal.options.goal_nm"] == overrides["participants.nav.options.goal_nm"]
    assert overrides["participants.nav.options.start_nm"] == [50.0, 50.0]
    with pytest.raises(ScenarioError, match="no participant 'boat'.*situations.plant"):
        scenario_overrides(situation, data, 1.0, 15.0, plant="boat")


def _broken(tmp_path, edit):
    data = json.loads((DATA / "head_on.json").read_text())
    edit(data)
    path = tmp_path / "broken.json"
    path.write_text(json.dumps(data))
    return path


@pytest.mark.parametrize("edit, message", [
    (lambda d: d.pop("ownShip"), r"broken.json: 'ownShip': missing field"),
    (lambda d: d["ownShip"]["waypoints"][0]["position"].pop("lat"),
     r"broken.json: 'ownShip.waypoints\[0\].position.lat': missing field"),
    (lambda d: d["targetShips"][0]["waypoints"][1]["position"].update(lon=200.0),
     r"'targetShips\[0\].waypoints\[1\].position.lon': 200.0 is outside \[-180, 180\]"),
    (lambda d: d["targetShips"][0]["waypoints"][0].pop("leg"),
     r"'targetShips\[0\].initial.sog': missing field \(and no 'waypoints\[0\].leg.sog'\)"),
    (lambda d: d["targetShips"][0]["waypoints"][0]["leg"].update(sog="fast"),
     r"'targetShips\[0\].waypoints\[0\].leg.sog': expected a number, got 'fast'"),
    (lambda d: d.update(targetShips={"a": 1}), r"'targetShips': expected a list"),
])
def test_malformed_situation_names_the_file_and_field(tmp_path, edit, message):
    with pytest.raises(ScenarioError, match=message):
        load_traffic_situation(_broken(tmp_path, edit))


def test_invalid_json_and_missing_file(tmp_path):
    path = tmp_path / "bad.json"
    path.write_text('{"ownShip": {"initial": ')
    with pytest.raises(ScenarioError, match=r"bad.json: not valid JSON: .*line 1"):
        load_traffic_situation(path)
    with pytest.raises(ScenarioError, match="nothere.json: traffic-situation file not found"):
        load_traffic_situation(tmp_path / "nothere.json")


# -- a folder of situations as a batch ---------------------------------------------------------
def _situation_batch(tmp_path, folder, extra=""):
    path = tmp_path / "situations.toml"
    path.write_text(textwrap.dedent(f"""
        [batch]
        scenario = "{REPO / 'scenarios' / 'exp3b_head_on.toml'}"
        [set]
        "simulation.steps" = 12
        [situations]
        files = "{folder}"
        radius_nm = 1.0
        origin_nm = [0.0, 0.0]
    """) + textwrap.dedent(extra))
    return path


def test_a_folder_of_situations_is_one_run_per_file(tmp_path):
    spec = load_batch(_situation_batch(tmp_path, DATA))
    runs = spec.runs()
    assert [run.parameters["situation"] for run in runs] == ["crossing_give_way.json", "head_on.json",
                                                             "three_targets.json"]
    assert [len(run.overrides["participants.traffic.options.targets"]) for run in runs] == [1, 1, 3]
    assert all(run.overrides["simulation.steps"] == 12 for run in runs)
    assert len({run.run_id for run in runs}) == 3


def test_situations_and_drawn_encounters_cannot_both_set_the_targets(tmp_path):
    path = _situation_batch(tmp_path, DATA, """
        [monte_carlo]
        seed = 1
        runs = 2
        [monte_carlo.own_ship]
        start_nm = [0.0, 0.0]
        course_deg = 0.0
        speed_kn = 18.0
        [[monte_carlo.encounters]]
        type = "head_on"
        cpa_nm = 0.0
        tcpa_min = 10.0
        speed_kn = 10.0
        radius_nm = 1.0
    """)
    with pytest.raises(ScenarioError, match="set the same scenario value"):
        load_batch(path)


def test_bad_situation_file_in_a_batch_exits_2_before_any_result(tmp_path, capsys):
    folder = tmp_path / "situations"
    folder.mkdir()
    shutil.copy(DATA / "head_on.json", folder / "a.json")
    (folder / "b.json").write_text('{"ownShip": {"waypoints": [{"position": {"lon": 3.0}}]}}')
    results = tmp_path / "results"
    assert main(["batch", str(_situation_batch(tmp_path, folder)), "--results", str(results), "--no-progress"]) == 2
    error = capsys.readouterr().err.strip().splitlines()
    assert len(error) == 1 and "b.json: 'ownShip.waypoints[0].position.lat': missing field" in error[0]
    assert not results.exists()


@pytest.mark.parametrize("table, message", [
    ('files = "nowhere/"\nradius_nm = 1.0', r"'situations.files': not found"),
    ('files = "DATA"', r"missing key 'situations.radius_nm'"),
    ('files = "DATA"\nradius_nm = -1.0', r"'situations.radius_nm' \(each target's hazard radius R_i\)"),
    ('files = "DATA"\nradius_nm = 1.0\nspeed = 3', r"unknown key 'situations.speed'"),
])
def test_malformed_situations_table(tmp_path, table, message):
    path = tmp_path / "b.toml"
    path.write_text(f'[batch]\nscenario = "{REPO / "scenarios" / "exp3b_head_on.toml"}"\n[situations]\n'
                    + table.replace("DATA", str(DATA)))
    with pytest.raises(ScenarioError, match=message):
        load_batch(path)
