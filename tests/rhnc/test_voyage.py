"""Voyage accounting and the CII against hand-computed values."""

import numpy as np
import pytest

from rhnc.ship.energy import EnergyParameters, brake_power, cost_rate, emission_rate
from orchestrator.geometry import KNOT, NM
from rhnc.voyage.voyage import account_voyage, cii_rating, cii_reference


def test_cii_reference_and_rating_by_hand():
    # MEPC.353(78) container ships: 1984 * 40000^-0.489
    assert cii_reference(40_000) == pytest.approx(1984 * 40_000 ** -0.489)
    assert cii_reference(40_000) == pytest.approx(11.146, abs=0.001)
    assert cii_rating(0.80, 1.0) == "A"
    assert cii_rating(0.90, 1.0) == "B"
    assert cii_rating(1.00, 1.0) == "C"
    assert cii_rating(1.10, 1.0) == "D"
    assert cii_rating(1.20, 1.0) == "E"


def test_calm_water_voyage_by_hand():
    # 2 h north at 18 kn in calm water: 36 nm, constant rates
    t = np.linspace(0.0, 7200.0, 31)
    u = np.full_like(t, 18 * KNOT)
    x = u * t
    zeros = np.zeros_like(t)
    account = account_voyage(t, x, zeros, u, zeros, zeros, zeros, zeros)
    power = brake_power(18 * KNOT, 0.0, 0.0, 0.0, 0.0)
    assert account.distance_nm == pytest.approx(36.0)
    assert account.time_min == pytest.approx(120.0)
    assert account.cost_usd == pytest.approx(2 * cost_rate(power))
    assert account.co2_t == pytest.approx(2 * emission_rate(power) / 1000)
    assert account.co2_per_nm_kg == pytest.approx(2 * emission_rate(power) / 36)
    attained = account.co2_t * 1e6 / (40_000 * 36.0)
    assert account.cii_attained == pytest.approx(attained)
    assert account.cii_required == pytest.approx(0.89 * cii_reference(40_000))
    assert account.cii_rating == cii_rating(attained, 0.89 * cii_reference(40_000))


def test_trapezoid_between_samples():
    # rates ramp linearly with speed^3 is not linear, so use two samples: trapezoid = mean * time
    t = np.array([0.0, 3600.0])
    u = np.array([8.0, 10.0])
    x = np.array([0.0, 9.0 * 3600.0])
    zeros = np.zeros(2)
    account = account_voyage(t, x, zeros, u, zeros, zeros, zeros, zeros, EnergyParameters())
    rates = cost_rate(brake_power(u, 0.0, 0.0, 0.0, 0.0))
    assert account.cost_usd == pytest.approx(rates.mean())
    assert account.distance_nm == pytest.approx(9.0 * 3600.0 / NM)


def test_unknown_cii_year():
    with pytest.raises(ValueError, match=r"cii_year 2031: reduction factor known for \[2023, 2024, 2025, 2026\]"):
        account_voyage([0.0, 1.0], [0.0, 1.0], [0.0, 0.0], [1.0, 1.0], [0.0, 0.0], [0, 0], [0, 0], [0, 0],
                       cii_year=2031)


def test_rating_boundaries_belong_to_the_worse_letter():
    assert [cii_rating(b, 1.0) for b in (0.83, 0.94, 1.07, 1.19)] == ["B", "C", "D", "E"]
    assert cii_rating(0.9, 2.0) == "A"  # attained / required, not attained * required
    assert cii_rating(2.0, 2.5) == "A" and cii_rating(2.5, 2.0) == "E"


def test_no_distance_sailed_gives_no_per_mile_figures_and_no_rating():
    t = np.array([0.0, 1800.0, 3600.0])
    zeros = np.zeros(3)
    account = account_voyage(t, zeros, zeros, zeros, zeros, zeros, zeros, zeros)
    assert account.distance_nm == 0.0 and account.time_min == pytest.approx(60.0)
    assert account.cost_usd == pytest.approx(cost_rate(brake_power(0.0, 0.0, 0.0, 0.0, 0.0)))  # running cost
    assert np.isnan(account.cost_per_nm_usd) and np.isnan(account.co2_per_nm_kg) and np.isnan(account.cii_attained)
    assert account.cii_rating == "n/a"
    assert account.cii_reference == pytest.approx(cii_reference(40_000)) and account.cii_year == 2026


def test_a_short_leg_below_one_mile_is_still_accounted():
    t = np.array([0.0, 100.0])
    x = np.array([0.0, 0.5 * NM])
    u = np.full(2, 0.5 * NM / 100.0)
    zeros = np.zeros(2)
    account = account_voyage(t, x, zeros, u, zeros, zeros, zeros, zeros)
    assert account.distance_nm == pytest.approx(0.5)
    assert account.cost_per_nm_usd == pytest.approx(account.cost_usd / 0.5)
    assert account.co2_per_nm_kg == pytest.approx(account.co2_t * 1000.0 / 0.5)
    assert account.cii_attained == pytest.approx(account.co2_t * 1e6 / (40_000 * 0.5))
    assert account.cii_rating in "ABCDE"


def test_a_single_sample_costs_nothing():
    one = np.array([0.0])
    account = account_voyage(np.array([600.0]), one, one, np.array([9.0]), one, one, one, one)
    assert (account.cost_usd, account.co2_t, account.time_min, account.distance_nm) == (0.0, 0.0, 0.0, 0.0)


def test_time_is_measured_from_the_first_sample():
    t = np.array([3600.0, 7200.0])
    x = np.array([0.0, 10 * NM])
    u = np.full(2, 10 * NM / 3600.0)
    zeros = np.zeros(2)
    assert account_voyage(t, x, zeros, u, zeros, zeros, zeros, zeros).time_min == pytest.approx(60.0)


def test_a_ship_going_astern_is_costed_as_stopped():
    t = np.array([0.0, 3600.0])
    zeros = np.zeros(2)
    astern = account_voyage(t, zeros, zeros, np.full(2, -2.0), zeros, zeros, zeros, zeros)
    stopped = account_voyage(t, zeros, zeros, zeros, zeros, zeros, zeros, zeros)
    assert astern.cost_usd == stopped.cost_usd and astern.co2_t == stopped.co2_t


def test_the_energy_parameters_given_are_the_ones_used():
    t = np.array([0.0, 3600.0])
    x = np.array([0.0, 9.0 * 3600.0])
    u = np.full(2, 9.0)
    zeros = np.zeros(2)
    costly = EnergyParameters(fuel_price_usd_t=1280.0, specific_fuel_consumption_g_kwh=250.0,
                              deadweight_t=60_000.0)
    base = account_voyage(t, x, zeros, u, zeros, zeros, zeros, zeros)
    other = account_voyage(t, x, zeros, u, zeros, zeros, zeros, zeros, costly)
    power = brake_power(9.0, 0.0, 0.0, 0.0, 0.0, costly)
    assert other.cost_usd == pytest.approx(cost_rate(power, costly)) and other.cost_usd > base.cost_usd
    assert other.co2_t == pytest.approx(emission_rate(power, costly) / 1000.0) and other.co2_t > base.co2_t
    assert other.cii_reference == pytest.approx(cii_reference(60_000.0))


def test_as_dict_rounds_floats_to_six_decimals_and_keeps_the_rest():
    t = np.array([0.0, 3600.0])
    x = np.array([0.0, 9.0 * 3600.0])
    zeros = np.zeros(2)
    account = account_voyage(t, x, zeros, np.full(2, 9.0), zeros, zeros, zeros, zeros, cii_year=2024)
    values = account.as_dict()
    assert values["cost_usd"] == round(account.cost_usd, 6) and values["cost_usd"] != account.cost_usd
    assert values["cii_rating"] == account.cii_rating and values["cii_year"] == 2024
    assert set(values) == {"cost_usd", "co2_t", "distance_nm", "time_min", "cost_per_nm_usd", "co2_per_nm_kg",
                           "cii_attained", "cii_required", "cii_reference", "cii_rating", "cii_year"}


def test_an_empty_track_is_an_empty_account():
    empty = np.array([])
    account = account_voyage(empty, empty, empty, empty, empty, empty, empty, empty)
    assert (account.cost_usd, account.co2_t, account.time_min, account.distance_nm) == (0.0, 0.0, 0.0, 0.0)
    assert account.cii_rating == "n/a"


def test_a_reported_brake_power_replaces_the_energy_model():
    t = np.array([0.0, 1800.0, 3600.0])
    x, y = np.array([0.0, 9260.0, 18520.0]), np.zeros(3)
    calm = np.zeros(3)
    power = np.full(3, 6.0e6)  # W
    account = account_voyage(t, x, y, np.full(3, 9.26), calm, calm, calm, calm, brake_power_w=power)
    fuel_t = 6000.0 * 190e-6  # t over one hour
    assert account.co2_t == pytest.approx(fuel_t * 3.114)
    assert account.cost_usd == pytest.approx(fuel_t * 640 + 500)
    modelled = account_voyage(t, x, y, np.full(3, 9.26), calm, calm, calm, calm)
    assert modelled.co2_t != pytest.approx(account.co2_t)


def test_a_power_the_plant_reports_is_costed_with_the_parameters_given():
    t = np.array([0.0, 3600.0])
    x = np.array([0.0, 9.0 * 3600.0])
    zeros = np.zeros(2)
    params = EnergyParameters(fuel_price_usd_t=1280.0, specific_fuel_consumption_g_kwh=250.0)
    reported = account_voyage(t, x, zeros, np.full(2, 9.0), zeros, zeros, zeros, zeros, params,
                              brake_power_w=np.array([0.5, 0.5]))  # half a watt: as good as nothing
    assert reported.cost_usd == pytest.approx(cost_rate(0.5, params))
    assert reported.co2_t == pytest.approx(emission_rate(0.5, params) / 1000.0)
    engine = account_voyage(t, x, zeros, np.full(2, 9.0), zeros, zeros, zeros, zeros, params,
                            brake_power_w=np.full(2, 8.0e6))
    assert engine.cost_usd == pytest.approx(cost_rate(8.0e6, params)) != pytest.approx(cost_rate(8.0e6))
    negative = account_voyage(t, x, zeros, np.full(2, 9.0), zeros, zeros, zeros, zeros, params,
                              brake_power_w=np.array([-1.0e6, -1.0e6]))  # a plant braking: no fuel credit
    assert negative.cost_usd == pytest.approx(cost_rate(0.0, params))


def test_mean_speed_through_water_weights_by_time_and_counts_sway():
    # 1 h at 10 kn then 1 h at 20 kn (surge only); sway 3-4-5 on top of it at the end
    from rhnc.voyage.voyage import mean_speed_through_water_kn

    t = np.array([0.0, 3600.0, 3600.0, 7200.0])
    u = np.array([10.0, 10.0, 20.0, 20.0]) * KNOT
    assert mean_speed_through_water_kn(t, u, np.zeros(4)) == pytest.approx(15.0)
    t2 = np.array([0.0, 600.0, 3600.0])   # unequal spacing: a plain mean of samples would give 10/3 kn
    assert mean_speed_through_water_kn(t2, np.array([0.0, 0.0, 10.0]) * KNOT, np.zeros(3)) == pytest.approx(
        0.5 * 10.0 * 3000.0 / 3600.0)
    assert mean_speed_through_water_kn([0.0, 10.0], [3.0, 3.0], [4.0, 4.0]) == pytest.approx(5.0 / KNOT)


def test_a_voyage_ends_at_the_crossing_of_the_arrival_radius_not_at_the_next_sample():
    from rhnc.cosim.analyses import cut_at_crossing

    # samples every 60 s; the goal distance falls from 700 m to 100 m between 60 and 120 s
    time = np.array([0.0, 60.0, 120.0, 180.0])
    distance = np.array([1000.0, 700.0, 100.0, 0.0])
    series = {"time_s": time, "cost": np.array([0.0, 1.0, 2.0, 3.0])}
    cut = cut_at_crossing(series, distance, first_inside=2, radius_m=400.0)
    # crossing 300 m of the 600 m between 60 s and 120 s: at 90 s
    assert cut["time_s"].tolist() == [0.0, 60.0, 90.0]
    assert cut["cost"][-1] == pytest.approx(1.5)
    # a ship inside at the first sample has sailed nothing
    assert cut_at_crossing(series, distance, first_inside=0, radius_m=2000.0)["time_s"].tolist() == [0.0]


def test_mean_speed_through_water_is_the_time_average_of_hypot_u_v():
    from rhnc.voyage.voyage import mean_speed_through_water_kn

    # two samples starting at t = 100 s: the average of 2 and 4 m/s
    assert mean_speed_through_water_kn([100.0, 160.0], [2.0, 4.0], [0.0, 0.0]) == pytest.approx(3.0 / KNOT)
    # sway counts: hypot(3, 4) = 5 m/s throughout
    assert mean_speed_through_water_kn([0.0, 30.0, 60.0], [3.0, 3.0, 3.0], [4.0, 4.0, 4.0]) == pytest.approx(5.0 / KNOT)
    # a repeated first sample adds no time
    assert mean_speed_through_water_kn([100.0, 100.0, 160.0], [2.0, 2.0, 4.0], [0.0] * 3) == pytest.approx(3.0 / KNOT)
    # no time elapsed: the speed at the only instant
    assert mean_speed_through_water_kn([50.0, 50.0], [3.0, 5.0], [0.0, 0.0]) == pytest.approx(3.0 / KNOT)
    assert mean_speed_through_water_kn([50.0], [3.0], [4.0]) == pytest.approx(5.0 / KNOT)
    assert np.isnan(mean_speed_through_water_kn([], [], []))
