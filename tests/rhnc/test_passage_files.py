"""The shipped passages, written in latitude and longitude by scripts/make_passages.py, place
everything where their earlier files in nm of the chart's plane did (within metres): the start
and goal of the navigation, the goal monitor, the ship, the sea-route baseline's waypoints, the
comparison's [voyage] and the strait's target ship (the sea route's points added since to keep the
clearance aside). The runs of docs/passages-results.md sailed
those nm files; this is what lets them stand for the files shipped now."""

import json
from pathlib import Path

import numpy as np
import pytest

from orchestrator.geometry import NM
from orchestrator.participant import BuildContext
from orchestrator.scenario import load_scenario
from rhnc.chart.positions import projected_options
from rhnc.encounters.traffic import TrafficParticipant
from rhnc.voyage.voyage_comparison import VoyageComparison

ROOT = Path(__file__).resolve().parents[2]
PASSAGES = ROOT / "scenarios" / "passages"
IN_NM = json.loads((ROOT / "tests" / "data" / "passages_in_nm.json").read_text())
#: The nm files held positions to 0.001 nm (1.85 m) and x0, y0 from those to 0.1 m.
WITHIN_M = 2.0


def options_in_plane(scenario, name):
    spec = scenario.participant(name)
    return projected_options(spec.options, name, PASSAGES)


def assert_within(placed_m, old_m, what):
    placed_m, old_m = np.asarray(placed_m, dtype=float), np.asarray(old_m, dtype=float)
    assert placed_m.shape == old_m.shape, what
    assert np.max(np.abs(placed_m - old_m)) <= WITHIN_M, f"{what}: {placed_m} m against {old_m} m"


def assert_searoute_points_kept(placed_m, old_m):
    """The sea route's waypoints are the nm file's, in order, with only points added between them
    (where a leg of searoute's route came within the clearance: tests/rhnc/test_clear_route.py)."""
    kept = [int(np.argmin(np.hypot(*(placed_m - point).T))) for point in old_m]
    assert kept[0] == 0 and kept[-1] == len(placed_m) - 1 and np.all(np.diff(kept) > 0), kept
    assert_within(placed_m[kept], old_m, "sea route")


@pytest.mark.parametrize("name", [key for key in IN_NM if not key.startswith("_") and not key.endswith("_traffic")])
def test_a_passage_in_latitude_and_longitude_places_everything_where_its_nm_files_did(name):
    old = IN_NM[name]
    for file in (f"{name}.toml", f"{name}_sea_route.toml"):
        scenario = load_scenario(PASSAGES / file)
        goal = options_in_plane(scenario, "goal")
        assert_within(np.array(goal["goal_nm"]) * NM, np.array(old["goal_nm"]) * NM, f"{file}: goal")
        ship = scenario.participant("ship").initial
        assert_within([ship["x_m"], ship["y_m"]], old["ship_start_m" if file == f"{name}.toml" else
                                                      "route_ship_start_m"], f"{file}: ship's start")
    nav = options_in_plane(load_scenario(PASSAGES / f"{name}.toml"), "nav")
    assert_within(np.array(nav["start_nm"]) * NM, np.array(old["nav_start_nm"]) * NM, "navigation's start")
    assert_within(np.array(nav["goal_nm"]) * NM, np.array(old["nav_goal_nm"]) * NM, "navigation's goal")
    route = options_in_plane(load_scenario(PASSAGES / f"{name}_sea_route.toml"), "route")
    assert_searoute_points_kept(np.array(route["waypoints_nm"]) * NM, np.array(old["route_nm"]) * NM)
    compare = PASSAGES / f"{name}_compare.toml"
    import tomllib

    table = tomllib.loads(compare.read_text())["voyage"]
    voyage = VoyageComparison.from_table(table, compare, {"runs": [{"label": "RHNC", "scenario": f"{name}.toml"}]})
    assert_within(voyage.start_m, np.array(old["compare_start_nm"]) * NM, "[voyage] start")
    assert_within(voyage.goal_m, np.array(old["compare_goal_nm"]) * NM, "[voyage] goal")


def test_the_strait_with_traffic_places_its_target_where_its_nm_file_did():
    old = IN_NM["gibraltar_strait_traffic"]
    scenario = load_scenario(PASSAGES / "gibraltar_strait_traffic.toml")
    spec = scenario.participant("traffic")
    traffic = TrafficParticipant.from_options(
        "traffic", spec.options, BuildContext("traffic", PASSAGES, 60.0, 0.0, 3600.0))
    rows = traffic.obstacles_at(0.0)
    (target,) = old["targets"]
    assert len(rows) == 1
    assert_within(rows[0, :2], np.array(target["start_nm"]) * NM, "target's start")
    # the same course and speed: velocity to the nm file's 1e-4 kn
    assert rows[0, 2:4] / (NM / 3600.0) == pytest.approx(target["velocity_kn"], abs=2e-4)
    assert rows[0, 4] == pytest.approx(target["radius_nm"] * NM)
    nav = options_in_plane(scenario, "nav")
    assert_within(np.array(nav["start_nm"]) * NM, np.array(old["nav_start_nm"]) * NM, "navigation's start")
    ship = scenario.participant("ship").initial
    assert_within([ship["x_m"], ship["y_m"]], old["ship_start_m"], "ship's start")


@pytest.mark.parametrize("scenario", ["gibraltar_strait.toml", "gibraltar_strait_sea_route.toml"])
def test_a_comparison_gives_a_passage_written_in_latitude_and_longitude_its_voyage_in_that_form(scenario):
    """The [voyage] start and goal reach the runs as start_deg / goal_deg where the files give
    those (an nm override beside them would be refused as a position given both ways)."""
    import tomllib

    compare = PASSAGES / "gibraltar_strait_compare.toml"
    table = tomllib.loads(compare.read_text())["voyage"]
    # the RHNC run from a start 1.1 nm from its file's own; the sea route's polyline must keep its ends
    moved = {**table, "start_deg": [36.07, -4.97]} if scenario == "gibraltar_strait.toml" else table
    voyage = VoyageComparison.from_table(moved, compare, {"runs": [{"label": "RHNC", "scenario": scenario}]})
    overrides = voyage.run_overrides(PASSAGES / scenario, {}, "here")
    assert not any(key.endswith(("start_nm", "goal_nm")) and key.startswith("participants") for key in overrides)
    loaded = load_scenario(PASSAGES / scenario, overrides)
    ship = loaded.participant("ship").initial
    assert [ship["x_m"], ship["y_m"]] == pytest.approx(voyage.start_m, abs=1e-6)
    goal = options_in_plane(loaded, "goal")
    assert np.array(goal["goal_nm"]) * NM == pytest.approx(voyage.goal_m, abs=1e-6)
    if scenario == "gibraltar_strait.toml":
        nav = options_in_plane(loaded, "nav")
        assert np.array(nav["start_nm"]) * NM == pytest.approx(voyage.start_m, abs=1e-6)
