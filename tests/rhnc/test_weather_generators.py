"""Weather generators: hand-checkable properties of each, the registry and its key checks."""

import numpy as np
import pytest

from orchestrator.errors import ScenarioError
from orchestrator.geometry import KNOT, NM
from rhnc.weather.metocean import fetch_limited_hs
from rhnc.weather.metocean_sources import from_scenario_table
from rhnc.weather.weather_generators import (GENERATORS, STORM_SET_SIZE, cyclone, holland_wind_speed, list_generators,
                                     storm_off_route, storm_set, storm_set_member)

SMALL = {"resolution_nm": 2.0}
WHERE = "s.toml: metocean"


def build(table):
    return from_scenario_table(table, None, WHERE)


def test_registry_lists_every_generator():
    names = list_generators()
    assert list(names) == ["paper_default", "storm_off_route", "cyclone", "moving_storm", "storm_set", "current_jet",
                           "routing_set"]
    assert all(isinstance(summary, str) and summary for summary in names.values())


def test_storm_maximum_where_it_is_placed_and_waves_from_the_relation():
    field = storm_off_route(centre_nm=(30.0, 70.0), radius_nm=10.0, peak_wind_ms=20.0, background_wind_ms=5.0,
                            wind_from_deg=90.0, fetch_km=50.0, **SMALL)
    speed = field.wind_speed
    i, j = np.unravel_index(np.argmax(speed), speed.shape)
    assert (field.x[i] / NM, field.y[j] / NM) == (30.0, 70.0)
    assert speed[i, j] == pytest.approx(20.0)
    # one radius away the excess has fallen to exp(-1/2)
    assert field.sample(40.0 * NM, 70.0 * NM)["wind_speed"] == pytest.approx(5.0 + 15.0 * np.exp(-0.5))
    # from the east everywhere: the air moves west
    np.testing.assert_allclose(field.wind_direction, np.pi / 2)
    assert np.all(field.wind_east < 0)
    np.testing.assert_allclose(field.hs, fetch_limited_hs(speed, 50e3))
    np.testing.assert_allclose(np.hypot(field.current_north, field.current_east), 0.5 * KNOT)


def test_default_storm_is_off_the_direct_route():
    field = GENERATORS["storm_off_route"].build(**SMALL)
    i, j = np.unravel_index(np.argmax(field.wind_speed), field.wind_speed.shape)
    off_route_nm = abs(field.x[i] - field.y[j]) / np.sqrt(2) / NM
    assert off_route_nm == pytest.approx(20.0 / np.sqrt(2))  # (60, 40) nm: 14.1 nm off the diagonal


def test_holland_profile_peaks_at_the_radius_of_maximum_wind():
    r = np.linspace(0.1, 100.0, 20001) * NM
    speed = holland_wind_speed(r, 30.0, 20.0 * NM, 1.8)
    assert r[np.argmax(speed)] / NM == pytest.approx(20.0, abs=0.01)
    assert speed.max() == pytest.approx(30.0, rel=1e-9)
    assert holland_wind_speed(1.0, 30.0, 20.0 * NM, 1.8) < 1e-6  # calm eye, no overflow
    # by hand at r = 2 R_m, B = 1: 30 sqrt(0.5 e^0.5)
    assert holland_wind_speed(40.0 * NM, 30.0, 20.0 * NM, 1.0) == pytest.approx(30.0 * np.sqrt(0.5 * np.exp(0.5)))


@pytest.mark.parametrize("hemisphere, sense", [("north", 1.0), ("south", -1.0)])
def test_cyclone_rotation_sense_and_inflow(hemisphere, sense):
    field = cyclone(centre_nm=(50.0, 50.0), max_wind_ms=25.0, radius_max_wind_nm=15.0, inflow_deg=20.0,
                    hemisphere=hemisphere, resolution_nm=1.0)
    east_of_centre = field.sample(50.0 * NM, 65.0 * NM)  # at R_m due east
    north_of_centre = field.sample(65.0 * NM, 50.0 * NM)  # at R_m due north
    assert east_of_centre["wind_speed"] == pytest.approx(25.0)
    # counter-clockwise (north): east of the centre the air moves north, north of it west
    assert np.sign(east_of_centre["wind_north"]) == sense
    assert np.sign(north_of_centre["wind_east"]) == -sense
    # turned 20 degrees inwards from the tangent: east of the centre, towards the west
    inward = -east_of_centre["wind_east"] / east_of_centre["wind_speed"]
    assert inward == pytest.approx(np.sin(np.radians(20.0)))
    # circulation round a circle of 30 nm has the sign of the rotation
    angle = np.linspace(0, 2 * np.pi, 361)[:-1]
    x, y = (50 + 30 * np.cos(angle)) * NM, (50 + 30 * np.sin(angle)) * NM
    s = field.sample(x, y)
    # counter-clockwise seen from above is the direction of decreasing bearing
    tangent_ccw_north, tangent_ccw_east = np.sin(angle), -np.cos(angle)
    assert np.sign(np.mean(s["wind_north"] * tangent_ccw_north + s["wind_east"] * tangent_ccw_east)) == sense
    np.testing.assert_allclose(field.hs, fetch_limited_hs(field.wind_speed, 100e3))
    assert not field.is_time_varying


def test_moving_storm_moves_with_its_translation():
    field = build({"generator": "moving_storm", "resolution_nm": 1.0, "duration_h": 6.0})
    np.testing.assert_array_equal(field.times_s, np.arange(7) * 3600.0)
    for hour in (0, 2, 5):
        # the eye: the calmest node, 8 kn towards 315 deg from (30, 70) nm
        speed = field.wind_speed[hour]
        i, j = np.unravel_index(np.argmin(speed), speed.shape)
        step = 8.0 * hour / np.sqrt(2)
        assert field.x[i] / NM == pytest.approx(30.0 + step, abs=0.5)
        assert field.y[j] / NM == pytest.approx(70.0 - step, abs=0.5)
    # between the hourly steps the field is linear in time
    halfway = field.sample(40.0 * NM, 60.0 * NM, t_s=5400.0)["hs"]
    assert halfway == pytest.approx(0.5 * (field.sample(40.0 * NM, 60.0 * NM, t_s=3600.0)["hs"]
                                           + field.sample(40.0 * NM, 60.0 * NM, t_s=7200.0)["hs"]))


def test_storm_set_member_is_reproducible_from_the_seed_and_members_differ():
    members = [storm_set_member(2026, k) for k in range(STORM_SET_SIZE)]
    assert storm_set_member(2026, 7) == members[7]  # again, alone: the same storm
    assert storm_set_member(2027, 7) != members[7]
    assert len({m["centre_nm"] for m in members}) == STORM_SET_SIZE
    radii = [m["radius_nm"] for m in members]
    assert min(radii) >= 10.0 and max(radii) <= 30.0 and np.std(radii) > 2.0
    field = storm_set(seed=2026, member=7, **SMALL)
    again = build({"generator": "storm_set", "seed": 2026, "member": 7, **SMALL})
    np.testing.assert_array_equal(field.wind_north, again.wind_north)
    assert "member 7" in field.source
    other = storm_set(seed=2026, member=8, **SMALL)
    assert not np.allclose(field.wind_north, other.wind_north)


def test_storm_set_centres_lie_along_and_beside_the_route():
    for k in range(STORM_SET_SIZE):
        north, east = storm_set_member(2026, k)["centre_nm"]
        along = (north + east) / np.sqrt(2) / (100 * np.sqrt(2))
        across = (north - east) / np.sqrt(2)  # + to the left (north-west) of the route
        assert 0.25 - 1e-6 <= along <= 0.75 + 1e-6
        assert -30.0 - 1e-6 <= across <= 30.0 + 1e-6


def test_keys_are_checked_before_the_generator_runs():
    with pytest.raises(ScenarioError, match=r"metocean.generator: unknown generator 'typhoon' \(valid: paper_default, "):
        build({"generator": "typhoon"})
    with pytest.raises(ScenarioError, match=r"metocean: unknown key 'radius_nm' for generator 'cyclone' \(valid: "):
        build({"generator": "cyclone", "radius_nm": 10})
    with pytest.raises(ScenarioError, match=r"metocean.max_wind_ms: expected a number, got '25'"):
        build({"generator": "cyclone", "max_wind_ms": "25"})
    with pytest.raises(ScenarioError, match=r"metocean.member: expected an integer, got 1.5"):
        build({"generator": "storm_set", "member": 1.5})
    with pytest.raises(ScenarioError, match=r"metocean.centre_nm: expected two numbers \[a, b\], got \[1\]"):
        build({"generator": "storm_off_route", "centre_nm": [1]})
    with pytest.raises(ScenarioError, match=r"metocean.hemisphere: expected a string, got 1"):
        build({"generator": "cyclone", "hemisphere": 1})
    with pytest.raises(ScenarioError, match=r"s.toml: metocean: hemisphere 'east' is not valid"):
        build({"generator": "cyclone", "hemisphere": "east"})
    with pytest.raises(ScenarioError, match=r"s.toml: metocean: radius_nm must be positive, got -1.0"):
        build({"generator": "storm_off_route", "radius_nm": -1})
    with pytest.raises(ScenarioError, match=r"s.toml: metocean: time_step_h 30.0 is longer than duration_h 24.0"):
        build({"generator": "moving_storm", "time_step_h": 30})
    with pytest.raises(ScenarioError, match=r"s.toml: metocean: seed and member must not be negative"):
        build({"generator": "storm_set", "member": -1})
