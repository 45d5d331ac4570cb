"""The routing weather set: reproducible members of three kinds, placed about any route."""

import numpy as np
import pytest

from orchestrator.errors import ScenarioError
from orchestrator.geometry import KNOT, NM
from rhnc.weather.metocean_sources import from_scenario_table
from rhnc.weather.routing_weather_set import KINDS, current_jet, routing_set_member
from rhnc.weather.weather_generators import routing_set

SOUTH_WEST = {"route_start_nm": (130.0, 80.0), "route_goal_nm": (15.0, 10.0)}


def test_members_are_reproducible_and_take_the_kinds_in_turn():
    members = [routing_set_member(2611, k, **SOUTH_WEST) for k in range(6)]
    assert [kind for kind, _ in members] == list(KINDS) * 2
    assert routing_set_member(2611, 4, **SOUTH_WEST) == members[4]
    assert routing_set_member(2612, 4, **SOUTH_WEST) != members[4]
    assert members[0][1] != members[3][1]


def test_the_jet_runs_along_the_route_at_its_offset():
    # a route heading west; the jet 10 nm to starboard (north of it), with the passage
    field = current_jet(x_range_nm=(0.0, 60.0), y_range_nm=(0.0, 100.0), route_start_nm=(30.0, 100.0),
                        route_goal_nm=(30.0, 0.0), offset_nm=10.0, width_nm=3.0, peak_kn=2.0)
    speed = np.hypot(field.current_north, field.current_east)
    core = field.x[np.argmax(speed[:, 50])] / NM
    assert core == pytest.approx(40.0)
    assert speed.max() == pytest.approx(2.0 * KNOT)
    assert np.all(field.current_east[speed > 0.1] < 0)   # towards the goal, west
    against = current_jet(x_range_nm=(0.0, 60.0), y_range_nm=(0.0, 100.0), route_start_nm=(30.0, 100.0),
                          route_goal_nm=(30.0, 0.0), offset_nm=10.0, towards_goal=False)
    assert np.all(against.current_east[np.hypot(against.current_north, against.current_east) > 0.1] > 0)


def test_a_moving_gale_crosses_the_route_near_the_ship():
    """Its centre crosses the straight route within the drawn lag (1.5 h) of a ship at 18 kn."""
    start, goal = np.array(SOUTH_WEST["route_start_nm"]), np.array(SOUTH_WEST["route_goal_nm"])
    along = (goal - start) / np.hypot(*(goal - start))
    for member in (1, 4, 7, 10):
        kind, storm = routing_set_member(2611, member, **SOUTH_WEST)
        assert kind == "moving gale"
        heading = np.radians(storm["heading_deg"])
        track = np.array([np.cos(heading), np.sin(heading)])
        centre = np.array(storm["centre_nm"])
        # time [h] at which the centre meets the route line, and where along it
        normal = np.array([-along[1], along[0]])
        hours = -np.dot(centre - start, normal) / (storm["translation_kn"] * np.dot(track, normal))
        where = np.dot(centre + track * storm["translation_kn"] * hours - start, along)
        assert abs(hours - where / 18.0) <= 1.5 + 1e-9
        assert 0.3 * np.hypot(*(goal - start)) - 1e-6 <= where <= 0.7 * np.hypot(*(goal - start)) + 1e-6


def test_the_set_is_built_from_a_scenario_table_and_checks_its_keys():
    table = {"generator": "routing_set", "seed": 2611, "member": 2, "route_start_nm": [130.0, 80.0],
             "route_goal_nm": [15.0, 10.0], "x_range_nm": [0.0, 140.0], "y_range_nm": [0.0, 90.0],
             "resolution_nm": 2.0}
    field = from_scenario_table(table, None, "s.toml: metocean")
    assert "routing_set seed 2611 member 2: current jet" in field.source
    assert field.extent == (0.0, 140.0 * NM, 0.0, 90.0 * NM)
    assert field.source == routing_set(**{k: v for k, v in table.items() if k != "generator"}).source
    with pytest.raises(ScenarioError, match=r"s.toml: metocean.towards_goal: expected true or false, got 1"):
        from_scenario_table({"generator": "current_jet", "towards_goal": 1}, None, "s.toml: metocean")
    with pytest.raises(ScenarioError, match=r"s.toml: metocean: seed and member must not be negative"):
        from_scenario_table({**table, "member": -1}, None, "s.toml: metocean")
