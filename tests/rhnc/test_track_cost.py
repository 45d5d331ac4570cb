"""Cost of a timed track and the timing of a constant speed through water."""

import numpy as np
import pytest

from rhnc.ship.energy import EnergyParameters, brake_power, fuel_rate_t_h
from orchestrator.geometry import KNOT, NM
from rhnc.routing.track_cost import constant_speed_times, cost_of_track, densify
from weather_fixtures import storm_field

ENERGY = EnergyParameters()


def test_a_straight_track_in_uniform_weather_costs_rate_times_hours():
    field = storm_field(base_wind_ms=10.0, wind_from_deg=90.0)
    track = np.array([[2 * NM, 2 * NM], [12 * NM, 2 * NM]])  # 10 nm due north, wind on the beam
    times = np.array([100.0, 100.0 + 3600.0 * 10 / 16])
    account = cost_of_track(field, ENERGY, track, times)
    local = field.sample(5 * NM, 2 * NM)
    fuel_t_h = fuel_rate_t_h(brake_power(16 * KNOT, 0.0, local["wind_north"], local["wind_east"], local["hs"]))
    hours = 10 / 16
    assert account["fuel_t"] == pytest.approx(fuel_t_h * hours, rel=1e-12)
    assert account["cost_usd"] == pytest.approx(
        fuel_t_h * hours * ENERGY.fuel_price_usd_t + ENERGY.running_cost_usd_day / 24 * hours, rel=1e-12)
    assert account["co2_t"] == pytest.approx(3.114 * account["fuel_t"])
    assert account["distance_nm"] == pytest.approx(10.0)
    assert account["mean_speed_through_water_kn"] == pytest.approx(16.0)


def test_the_current_changes_the_speed_through_water_and_the_time():
    field = storm_field(base_wind_ms=0.0, current_ms=(0.5, 0.0))  # 0.5 m/s setting north
    track = densify(np.array([[0.0, 5 * NM], [10 * NM, 5 * NM]]), 0.25 * NM)
    speed = 8.0
    times = constant_speed_times(field, track, speed)
    assert times[-1] == pytest.approx(10 * NM / 8.5)
    back = constant_speed_times(field, track[::-1], speed)
    assert back[-1] == pytest.approx(10 * NM / 7.5)
    # the same speed through water both ways: the same fuel per hour
    there = cost_of_track(field, ENERGY, track, times)
    home = cost_of_track(field, ENERGY, track[::-1], back)
    assert there["mean_speed_through_water_kn"] == pytest.approx(speed / KNOT)
    assert there["fuel_t"] / there["duration_s"] == pytest.approx(home["fuel_t"] / home["duration_s"], rel=1e-9)


def test_head_wind_costs_more_than_following_wind():
    field = storm_field(base_wind_ms=15.0, wind_from_deg=0.0)
    north = np.array([[1 * NM, 1 * NM], [11 * NM, 1 * NM]])
    times = np.array([0.0, 3600.0])
    assert (cost_of_track(field, ENERGY, north, times)["fuel_t"]
            > 1.2 * cost_of_track(field, ENERGY, north[::-1], times)["fuel_t"])


def test_a_long_leg_is_costed_by_the_weather_along_it():
    # a storm midway: two waypoints only, but the storm's cost is counted
    stormy = storm_field(storms=[(10.0, 10.0, 2.0, 15.0)])
    calm = storm_field()
    track = np.array([[0.0, 0.0], [20 * NM, 20 * NM]])
    times = np.array([0.0, 7200.0])
    assert cost_of_track(stormy, ENERGY, track, times)["fuel_t"] > 1.1 * cost_of_track(calm, ENERGY, track, times)["fuel_t"]


@pytest.mark.parametrize("times, message", [
    ([0.0, 10.0, 5.0], "must not decrease"),
    ([0.0, 0.0, 5.0], "positive length takes no time"),
    ([0.0, 5.0], "as many times as waypoints"),
])
def test_bad_tracks(times, message):
    track = np.array([[0.0, 0.0], [NM, 0.0], [2 * NM, 0.0]])
    with pytest.raises(ValueError, match=message):
        cost_of_track(storm_field(), ENERGY, track, times)
