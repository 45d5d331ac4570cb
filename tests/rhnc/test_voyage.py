"""Voyage accounting and the CII against hand-computed values."""

import numpy as np
import pytest

from rhnc.energy import EnergyParameters, brake_power, cost_rate, emission_rate
from rhnc.metocean import KNOT, NM
from rhnc.voyage import account_voyage, cii_rating, cii_reference


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


def test_mean_speed_through_water_weights_by_time_and_counts_sway():
    # 1 h at 10 kn then 1 h at 20 kn (surge only); sway 3-4-5 on top of it at the end
    from rhnc.voyage import mean_speed_through_water_kn

    t = np.array([0.0, 3600.0, 3600.0, 7200.0])
    u = np.array([10.0, 10.0, 20.0, 20.0]) * KNOT
    assert mean_speed_through_water_kn(t, u, np.zeros(4)) == pytest.approx(15.0)
    t2 = np.array([0.0, 600.0, 3600.0])   # unequal spacing: a plain mean of samples would give 10/3 kn
    assert mean_speed_through_water_kn(t2, np.array([0.0, 0.0, 10.0]) * KNOT, np.zeros(3)) == pytest.approx(
        0.5 * 10.0 * 3000.0 / 3600.0)
    assert mean_speed_through_water_kn([0.0, 10.0], [3.0, 3.0], [4.0, 4.0]) == pytest.approx(5.0 / KNOT)
