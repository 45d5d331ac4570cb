"""Energy, cost and emission model against values computed by hand (docs/method.md)."""

import math

import numpy as np
import pytest

from orchestrator.errors import ScenarioError
from rhnc.ship.energy import (EnergyParameters, brake_power, cost_rate, emission_rate, frictional_coefficient,
                         power_components, speed_through_water, wave_speed)

V18 = 18 * 1852 / 3600  # 9.26 m/s
NORTH = 0.0

# Hand computation at 18 kn (v = 9.26 m/s), default parameters:
#   Re = 9.26 * 230 / 1.27e-6 = 1.677e9, log10 Re = 9.2245
#   C_F = 0.075 / 7.2245^2 = 1.4369e-3
#   Ps  = 1025 * 1.4369e-3 * 9424 * 9.26^3 / 2 * (32000 * 0.5 / 40000 + 0.5)
#       = 5.5107e6 * 0.9 = 4.9596e6 W
#   Pa (no wind) = 0.1 * 1.225 * 1000 * 9.26^3 / 2 = 4.8634e4 W   (A: frontal area, ships/KCS.toml)
#   K  = 1 / (0.65 * (0.7 + 0.3 * 18/24)) = 1 / (0.65 * 0.925) = 1.66320
#   P  = 1.66320 * (4.9596e6 + 4.8634e4) = 8.3297e6 W
#   fuel = 8329.7 kW * 190 g/kWh = 1.58264 t/h
#   EC = 1.58264 * 640 + 12000 / 24 = 1512.89 USD/h,  EM = 1.58264 * 3114 = 4928.3 kg/h
CALM_PS = 4.9596e6
CALM_PA = 4.8634e4
CALM_P = 8.3297e6


def test_frictional_coefficient_ittc57_at_18_knots():
    assert frictional_coefficient(V18) == pytest.approx(1.4369e-3, rel=1e-4)


def test_calm_water_at_18_knots():
    parts = power_components(V18, NORTH, 0.0, 0.0, 0.0)
    assert parts["still_water"] == pytest.approx(CALM_PS, rel=1e-4)
    assert parts["added_wave"] == 0.0
    assert parts["wind"] == pytest.approx(CALM_PA, rel=1e-4)
    assert parts["propulsion_factor"] == pytest.approx(1.66320, rel=1e-5)
    assert parts["brake_power"] == pytest.approx(CALM_P, rel=1e-4)
    assert cost_rate(CALM_P) == pytest.approx(1512.89, rel=1e-4)
    assert emission_rate(CALM_P) == pytest.approx(4928.3, rel=1e-4)


def test_head_seas_hs_3m():
    # Waves travel with the wind: a 1 m/s wind from ahead (towards south) for a ship heading north.
    # Tp = 5 sqrt(3) = 8.660 s, c = 9.81 * 8.660 / (2 pi) = 13.521 m/s (head seas: u_wave = +13.521)
    # Pw = 0.57e-3 * 1025 * 9.81 * 1.5^2 * 32.2^2 / 230 * (9.26 + 13.521) = 1324.4 W
    # Pa = 0.1 * 1.225 * 1000 * (9.26 + 1)^3 / 2 = 6.6153e4 W
    # K  = max(1.66320, 1 / (0.65 * (1 - 0.3))) = 2.19780
    # P  = 2.19780 * (4.9596e6 + 1324.4 + 6.6153e4) = 1.10485e7 W
    parts = power_components(V18, NORTH, -1.0, 0.0, 3.0)
    assert parts["wave_encounter_speed"] == pytest.approx(13.521, rel=1e-4)
    assert parts["added_wave"] == pytest.approx(1324.4, rel=1e-4)
    assert parts["wind"] == pytest.approx(6.6153e4, rel=1e-4)
    assert parts["propulsion_factor"] == pytest.approx(2.19780, rel=1e-5)
    assert parts["brake_power"] == pytest.approx(1.10485e7, rel=1e-4)


def test_c_w_reading_gives_the_smaller_of_two_implausible_ratios():
    """0.57e-3 -> Pw/Ps = 0.027 %; 0.57e3 -> Pw/Ps = 267: the default is 0.57e-3 (see rhnc.ship.energy)."""
    ratios = {}
    for reading in (0.57e-3, 0.57e3):
        params = EnergyParameters(wave_drag_coefficient=reading)
        parts = power_components(V18, NORTH, -1.0, 0.0, 3.0, params)
        ratios[reading] = parts["added_wave"] / parts["still_water"]
    assert ratios[0.57e-3] == pytest.approx(2.670e-4, rel=1e-3)
    assert ratios[0.57e3] == pytest.approx(267.0, rel=1e-3)
    assert EnergyParameters().wave_drag_coefficient == 0.57e-3
    # the sea-state branch of K carries the wave effect: +32 % over the speed branch at Hs = 3 m
    calm = power_components(V18, NORTH, 0.0, 0.0, 0.0)["propulsion_factor"]
    rough = power_components(V18, NORTH, 0.0, 0.0, 3.0)["propulsion_factor"]
    assert rough / calm == pytest.approx(1.3214, rel=1e-4)


def test_head_wind_20_m_s():
    # Pa = 0.1 * 1.225 * 1000 * (9.26 + 20)^3 / 2 = 1.53437e6 W
    # P  = 1.66320 * (4.9596e6 + 1.53437e6) = 1.08008e7 W
    parts = power_components(V18, NORTH, -20.0, 0.0, 0.0)
    assert parts["head_wind"] == pytest.approx(20.0)
    assert parts["wind"] == pytest.approx(1.53437e6, rel=1e-4)
    assert parts["brake_power"] == pytest.approx(1.08008e7, rel=1e-4)
    # the same wind from astern helps
    assert brake_power(V18, NORTH, 20.0, 0.0, 0.0) < CALM_P


def test_wind_and_waves_are_relative_to_the_heading():
    east = math.pi / 2
    # wind towards west is a head wind for a ship heading east
    assert power_components(V18, east, 0.0, -20.0, 0.0)["head_wind"] == pytest.approx(20.0)
    # beam wind: no head component
    assert power_components(V18, NORTH, 0.0, -20.0, 0.0)["head_wind"] == pytest.approx(0.0, abs=1e-12)


def test_speed_through_water_subtracts_current_along_heading():
    assert speed_through_water(V18, NORTH, 1.0, 5.0) == pytest.approx(V18 - 1.0)
    assert speed_through_water(V18, math.pi, 1.0, 0.0) == pytest.approx(V18 + 1.0)
    assert speed_through_water(0.5, NORTH, 1.0, 0.0) == 0.0


def test_vectorised_over_a_grid_with_broadcasting():
    heading = np.linspace(-math.pi, math.pi, 7)[:, None]
    hs = np.linspace(0, 4, 5)[None, :]
    power = brake_power(V18, heading, -5.0, 2.0, hs)
    assert power.shape == (7, 5)
    assert power[0, 0] == pytest.approx(float(brake_power(V18, heading[0, 0], -5.0, 2.0, 0.0)))
    assert np.all(np.isfinite(brake_power(np.array([0.0, 1.0]), 0.0, 0.0, 0.0, 0.0)))


def test_wave_speed_from_hs():
    assert wave_speed(3.0) == pytest.approx(9.81 * 5 * math.sqrt(3) / (2 * math.pi))


def test_overrides_reject_unknown_keys():
    params = EnergyParameters().with_overrides({"fuel_price_usd_t": 500}, "s.toml: energy")
    assert params.fuel_price_usd_t == 500.0
    with pytest.raises(ScenarioError, match=r"s.toml: energy: unknown energy parameter 'C_w' \(valid: .*wave_drag"):
        EnergyParameters().with_overrides({"C_w": 0.1}, "s.toml: energy")
    with pytest.raises(ScenarioError, match=r"energy.cargo_t: expected a finite number"):
        EnergyParameters().with_overrides({"cargo_t": "lots"}, "s.toml: energy")


def test_speed_through_water_takes_both_current_components_along_the_heading():
    assert speed_through_water(5.0, math.pi / 2, 0.0, 1.0) == pytest.approx(4.0)  # eastbound, east set
    assert speed_through_water(5.0, math.pi / 3, 1.0, 0.0) == pytest.approx(4.5)  # cos 60 deg of a north set


def test_power_depends_on_the_wind_relative_to_the_heading_only():
    turned = math.pi / 3
    ahead = brake_power(V18, 0.0, 10.0, 0.0, 2.0)
    rotated = brake_power(V18, turned, 10.0 * math.cos(turned), 10.0 * math.sin(turned), 2.0)
    assert rotated == pytest.approx(ahead, rel=1e-12)


def test_waves_without_wind_meet_the_ship_abeam_and_scale_with_speed():
    slow = power_components(0.2, 0.0, 0.0, 0.0, 2.0)
    slower = power_components(0.1, 0.0, 0.0, 0.0, 2.0)
    assert np.all(np.isfinite([slow["added_wave"], slow["brake_power"]]))
    assert slow["wave_encounter_speed"] == 0.0
    assert slow["added_wave"] == pytest.approx(2.0 * slower["added_wave"])  # max(v + u_wave, 0) = v


def test_a_ship_at_rest_in_calm_air_needs_only_its_auxiliary_power():
    assert brake_power(0.0, 0.0, 0.0, 0.0, 0.0) == 0.0
    assert brake_power(0.0, 0.0, 0.0, 0.0, 0.0, EnergyParameters(auxiliary_power_w=5.0e5)) == 5.0e5


def test_small_waves_below_one_metre():
    assert wave_speed(0.25) == pytest.approx(9.81 * 5 * 0.5 / (2 * math.pi))
    assert wave_speed(-1.0) == 0.0


def test_the_parameters_given_are_the_ones_used():
    other = EnergyParameters(kinematic_viscosity_m2_s=2.0e-6, peak_period_coefficient=7.0,
                             specific_fuel_consumption_g_kwh=250.0)
    assert wave_speed(3.0, other) == pytest.approx(9.81 * 7 * math.sqrt(3) / (2 * math.pi))
    assert frictional_coefficient(V18, other) != frictional_coefficient(V18)
    args = (V18, 0.0, -8.0, 0.0, 3.0)  # head wind and sea
    assert brake_power(*args, other) == power_components(*args, other)["brake_power"] != brake_power(*args)
    from rhnc.ship.energy import fuel_rate_t_h

    power = 8.0e6
    assert fuel_rate_t_h(power, other) == pytest.approx(8.0e3 * 250.0 * 1e-6)
    assert cost_rate(power, other) == pytest.approx(2.0 * 640.0 + 12000.0 / 24.0)
    assert emission_rate(power, other) == pytest.approx(2.0 * 3.114 * 1000.0)


def test_an_unknown_parameter_lists_the_valid_names():
    with pytest.raises(ScenarioError, match=r"\(valid: air_density_kg_m3, air_drag_coefficient, "):
        EnergyParameters().with_overrides({"C_w": 0.1}, "s.toml: energy")


@pytest.mark.parametrize("change", [{"kinematic_viscosity_m2_s": 2.0e-6}, {"peak_period_coefficient": 7.0}])
def test_each_resistance_parameter_reaches_the_brake_power(change):
    args = (V18, 0.0, -8.0, 0.0, 3.0)  # head wind and sea
    assert brake_power(*args, EnergyParameters(**change)) != pytest.approx(brake_power(*args), rel=1e-9)


def test_ship_constants_come_from_the_ship_particulars():
    from rhnc.ship.ships import load_ship

    ship, params = load_ship("KCS"), EnergyParameters()
    assert params.wind_area_m2 == ship.wind_area_frontal_m2  # head-wind resistance: frontal area
    assert (params.length_m, params.beam_m, params.wetted_surface_m2, params.deadweight_t) == (
        ship.lpp_m, ship.beam_m, ship.wetted_surface_m2, ship.deadweight_t)
    assert params.design_speed_m_s == pytest.approx(24 * 1852 / 3600)
