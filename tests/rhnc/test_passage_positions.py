"""Latitude and longitude wherever a passage places something: the comparison's start and goal,
the traffic's targets (and a trafficgen situation placed on the passage), the own ship's start
through the plant's mapping; each mistake refused with one line naming the key (exit 2)."""

import json
import re
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from orchestrator import fmu_build
from orchestrator.cli import main
from orchestrator.errors import ScenarioError
from orchestrator.fmu_participant import FmuParticipant, resolve_fmu
from orchestrator.geometry import KNOT, NM
from orchestrator.participant import BuildContext
from orchestrator.scenario import load_scenario
from rhnc.chart.chart import load_chart
from rhnc.encounters.traffic import TrafficParticipant
from rhnc.voyage.voyage_comparison import VoyageComparison

PASSAGES = Path(__file__).resolve().parents[2] / "scenarios" / "passages"
CHART = str(PASSAGES / "gibraltar_strait.chart.toml")
EUROPA_POINT = (36.0, -5.25)   # in the strait (lat, lon)
TANGIER_OFF = (35.85, -5.75)


def plane_m(lat, lon):
    north, east = load_chart(CHART).projection.to_local(lat, lon)
    return np.array([float(north), float(east)])


# -- the comparison's [voyage] ----------------------------------------------------------------------
def voyage(tmp_path, **keys):
    (tmp_path / "rhnc.toml").write_text("")
    table = {"arrival_radius_nm": 0.5, **keys}
    return VoyageComparison.from_table(table, tmp_path / "compare.toml", {"runs": [{"label": "RHNC",
                                                                                    "scenario": "rhnc.toml"}]})


def test_the_voyages_start_and_goal_in_latitude_and_longitude_are_the_charts_points(tmp_path):
    comparison = voyage(tmp_path, start_deg=list(EUROPA_POINT), goal_deg=list(TANGIER_OFF), chart=CHART)
    assert comparison.start_m == pytest.approx(plane_m(*EUROPA_POINT), abs=1e-6)
    assert comparison.goal_m == pytest.approx(plane_m(*TANGIER_OFF), abs=1e-6)
    # one of them in nm, the other geographic
    mixed = voyage(tmp_path, start_nm=[1.0, 2.0], goal_deg=list(TANGIER_OFF), chart=CHART)
    assert mixed.start_m == pytest.approx([NM, 2 * NM]) and mixed.goal_m == pytest.approx(plane_m(*TANGIER_OFF))


@pytest.mark.parametrize("keys, message", [
    ({"start_deg": list(EUROPA_POINT), "start_nm": [0.0, 0.0], "goal_nm": [1.0, 1.0], "chart": CHART},
     r"compare.toml: voyage: give either key 'start_nm' or 'start_deg', not both$"),
    ({"start_deg": list(EUROPA_POINT), "goal_nm": [1.0, 1.0]}, r"compare.toml: voyage: key 'start_deg' needs key 'chart'"),
    ({"start_nm": [0.0, 0.0], "goal_nm": [1.0, 1.0], "chart": CHART},
     r"compare.toml: voyage: key 'chart' places start_deg and goal_deg"),
    ({"start_nm": [0.0, 0.0], "goal_deg": [36.0, 200.0 + 200.0], "chart": CHART},
     r"compare.toml: voyage: key 'goal_deg' must be \[latitude, longitude\] in degrees, got \[36.0, 400.0\]$"),
    ({"goal_nm": [1.0, 1.0]}, r"voyage.start_nm: expected \[north, east\] in nm \(or start_deg = \[latitude, "
                              r"longitude\] with chart\), got None"),
])
def test_the_voyages_geographic_mistakes_name_the_key(tmp_path, keys, message):
    with pytest.raises(ScenarioError, match=message):
        voyage(tmp_path, **keys)


def test_a_voyage_given_both_ways_exits_2_with_one_line_and_writes_nothing(tmp_path, capsys):
    (tmp_path / "rhnc.toml").write_text("")
    path = tmp_path / "compare.toml"
    path.write_text(f'name = "passage"\nanalysis = "voyage"\nmetrics = ["cost_usd"]\n[voyage]\nstart_deg = [36.0, -5.25]\n'
                    f'start_nm = [1.0, 1.0]\ngoal_nm = [2.0, 2.0]\nchart = "{CHART}"\n'
                    '[[runs]]\nlabel = "RHNC"\nscenario = "rhnc.toml"\n')
    assert main(["compare", str(path), "--results", str(tmp_path / "results")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "voyage: give either key 'start_nm' or 'start_deg', not both" in err
    assert not (tmp_path / "results").exists()


# -- the traffic ------------------------------------------------------------------------------------
def context(tmp_path=PASSAGES):
    return BuildContext("passage.toml: participants.traffic", Path(tmp_path), 60.0, 0.0, 3600.0)


def test_targets_placed_in_latitude_and_longitude_sail_from_the_charts_points():
    traffic = TrafficParticipant.from_options("traffic", {"chart": CHART, "targets": [
        {"start_deg": list(EUROPA_POINT), "velocity_kn": [0.0, -10.0], "radius_nm": 0.5},
        {"waypoints_deg": [list(EUROPA_POINT), list(TANGIER_OFF)], "speed_kn": 12.0, "radius_nm": 0.5}]}, context())
    rows = traffic.obstacles_at(0.0)
    assert rows[0, :2] == pytest.approx(plane_m(*EUROPA_POINT), abs=1e-6)
    assert rows[0, 3] == pytest.approx(-10.0 * KNOT)
    assert rows[1, :2] == pytest.approx(plane_m(*EUROPA_POINT), abs=1e-6)
    assert traffic.targets[1].waypoints_m[-1] == pytest.approx(plane_m(*TANGIER_OFF), abs=1e-6)


def test_a_trafficgen_situation_is_placed_on_the_passage_by_the_chart(tmp_path):
    situation = {"ownShip": {"initial": {"position": {"lat": 36.08, "lon": -4.95}, "sog": 15.0, "cog": 260.0}},
                 "targetShips": [{"initial": {"position": {"lat": EUROPA_POINT[0], "lon": EUROPA_POINT[1]},
                                              "sog": 12.0, "cog": 90.0}},
                                 {"waypoints": [{"position": {"lat": 35.9, "lon": -5.9}, "leg": {"sog": 10.0}},
                                                {"position": {"lat": 35.95, "lon": -5.6}},
                                                {"position": {"lat": 36.0, "lon": -5.4}}]}]}
    (tmp_path / "situation.json").write_text(json.dumps(situation))
    traffic = TrafficParticipant.from_options("traffic", {
        "chart": CHART, "situation": "situation.json", "situation_radius_nm": 1.0,
        "targets": [{"start_nm": [1.0, 2.0], "velocity_kn": [0.0, 0.0], "radius_nm": 0.2}]}, context(tmp_path))
    rows = traffic.obstacles_at(0.0)
    assert rows[0, :2] == pytest.approx([NM, 2 * NM])                        # the table's target first
    # where its lat/lon lie (the entry holds nm to 6 decimals: 2 mm)
    assert rows[1, :2] == pytest.approx(plane_m(*EUROPA_POINT), abs=2e-3)
    assert rows[1, 2:4] == pytest.approx([0.0, 12.0 * KNOT], abs=1e-9) and rows[1, 4] == pytest.approx(NM)
    assert traffic.targets[2].waypoints_m[1] == pytest.approx(plane_m(35.95, -5.6), abs=2e-3)


@pytest.mark.parametrize("options, message", [
    ({"targets": [{"start_deg": list(EUROPA_POINT), "velocity_kn": [0, 0], "radius_nm": 1}]},
     r"participants.traffic.targets\[0\]: option 'start_deg' needs option 'chart'"),
    ({"chart": CHART, "targets": [{"start_deg": list(EUROPA_POINT), "start_nm": [0, 0], "velocity_kn": [0, 0],
                                   "radius_nm": 1}]},
     r"participants.traffic.targets\[0\]: give either option 'start_nm' or 'start_deg', not both$"),
    ({"chart": CHART, "targets": [{"waypoints_deg": [list(EUROPA_POINT), [95.0, -5.0]], "speed_kn": 10,
                                   "radius_nm": 1}]},
     r"option 'waypoints_deg' must be a list of \[latitude, longitude\] pairs"),
    ({"chart": CHART, "targets": [{"start_nm": [0, 0], "velocity_kn": [0, 0], "radius_nm": 1}]},
     r"participants.traffic: option 'chart' places geographic positions"),
    ({"situation": "gibraltar_strait.situation.json", "situation_radius_nm": 1.0},
     r"participants.traffic: option 'situation' needs option 'chart'"),
    ({"situation": "gibraltar_strait.situation.json", "chart": CHART},
     r"participants.traffic: option 'situation' needs 'situation_radius_nm'.*got None$"),
    ({"situation_radius_nm": 1.0}, r"participants.traffic: option 'situation_radius_nm' goes with option 'situation'"),
    ({"situation": "none.json", "chart": CHART, "situation_radius_nm": 1.0}, r"none.json: traffic-situation file not found"),
])
def test_the_traffics_geographic_mistakes_name_the_option(options, message):
    with pytest.raises(ScenarioError, match=message):
        TrafficParticipant.from_options("traffic", options, context())


# -- the own ship's start ---------------------------------------------------------------------------
SHIP = """
connections = ["helm.tau_u -> ship.tau_u", "helm.tau_r -> ship.tau_r"]
[simulation]
stop_s = 60.0
dt_s = 10.0
[participants.helm]
type = "scripted_tau"
[participants.helm.options]
tau_u_N = 0.0
[participants.ship]
fmu = "{fmu}"
{parameters}
[participants.ship.initial]
{initial}
{mapping}
"""
VENDOR_B_MAPPING = """[participants.ship.mapping]
x = { variable = "north_m", start = "north0_m" }
y = { variable = "east_m", start = "east0_m" }
psi = { variable = "heading_deg", start = "heading0_deg" }
u = { variable = "surge_speed_kn", start = "surge0_kn" }
v = "sway_speed_kn"
r = "yaw_rate_deg_s"
tau_u = "thrust_kN"
tau_r = "yaw_moment_kNm"
"""


def ship_scenario(tmp_path, initial, fmu="KCS", mapping="", parameters=""):
    path = tmp_path / "ship.toml"
    path.write_text(SHIP.format(fmu=fmu, initial=initial, mapping=mapping, parameters=parameters))
    return path


@pytest.mark.parametrize("fmu, mapping, north, east", [("KCS", "", "x0", "y0"),
                                                       ("KCSVendorB", VENDOR_B_MAPPING, "north0_m", "east0_m")])
def test_the_ships_start_in_latitude_and_longitude_reaches_its_start_parameters_through_the_mapping(
        tmp_path, fmu, mapping, north, east):
    fmu_build.ensure_built(fmu)
    path = ship_scenario(tmp_path, f'start_deg = [36.0, -5.25]\nchart = "{CHART}"\npsi_deg = 270.0', fmu, mapping)
    spec = load_scenario(path).participant("ship")
    expected = plane_m(*EUROPA_POINT)
    assert spec.initial == pytest.approx({"x_m": expected[0], "y_m": expected[1], "psi_deg": 270.0})
    where = f"{path}: participants.ship"
    ship = FmuParticipant(spec, resolve_fmu(spec.fmu, path.parent, where), where)
    try:
        assert [ship.parameters[north], ship.parameters[east]] == pytest.approx(expected, abs=1e-6)
        out = ship.setup(0.0, {})
        assert [out["x"], out["y"]] == pytest.approx(expected, abs=1e-6)
    finally:
        ship.terminate()


@pytest.mark.parametrize("initial, parameters, message", [
    (f'start_deg = [36.0, -5.25]\nx_nm = 1.0\nchart = "{CHART}"', "",
     r"ship.toml: participants.ship.initial: give either key 'x_nm' or 'start_deg', not both$"),
    ("start_deg = [36.0, -5.25]", "", r"participants.ship.initial: key 'start_deg' needs key 'chart'"),
    (f'chart = "{CHART}"\nx_nm = 1.0', "", r"participants.ship.initial: key 'chart' places 'start_deg'"),
    (f'start_deg = [36.0]\nchart = "{CHART}"', "",
     r"participants.ship.initial: key 'start_deg' must be \[latitude, longitude\] in degrees, got \[36.0\]$"),
    (f'start_deg = [36.0, -5.25]\nchart = "{CHART}"', "[participants.ship.parameters]\nx0 = 100.0",
     r"participants.ship.parameters.x0: the initial state is already given in \[initial\]"),
])
def test_the_ships_geographic_start_mistakes_exit_2_naming_the_key_and_write_nothing(
        tmp_path, capsys, initial, parameters, message):
    path = ship_scenario(tmp_path, initial, parameters=parameters)
    assert main(["run", str(path), "--results", str(tmp_path / "results"), "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and re.search(message, err.strip()), err
    assert not (tmp_path / "results").exists()


def test_the_voyage_moves_a_geographic_start_to_its_own():
    """A comparison replaces a start given in latitude and longitude with its [voyage] start."""
    from rhnc.voyage.voyage_geometry import _plant_start

    plant = SimpleNamespace(name="ship", mapping={}, parameters={"psi0": 0.0}, initial={"x_m": 5.0, "y_m": 6.0})
    overrides = _plant_start(plant, np.array([100.0, 200.0]), 0.5, geographic=True)
    assert overrides == {"participants.ship.initial": {"x_m": 100.0, "y_m": 200.0},
                         "participants.ship.parameters.psi0": 0.5}
