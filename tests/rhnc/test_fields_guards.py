"""Planning grid, field formulas and local evaluation of rhnc.navigation.fields, checked against
direct computations: resampling limits and time, the energy fields with non-default
parameters, the guidance field's width c and its wrapping, normalisation thresholds,
grids not starting at the origin and points on and beyond the map's border."""

import math

import numpy as np
import pytest

from rhnc.ship.energy import EnergyParameters, brake_power, cost_rate, emission_rate, speed_through_water
from rhnc.navigation.fields import (GuidanceParameters, SuperpositionField, energy_rate_fields,
                         guidance_field, normalise, resample_weather)
from orchestrator.geometry import KNOT, NM
from rhnc.weather.metocean import MetOceanField

SPEED = 18 * KNOT
NAMES = ("wind_north", "wind_east", "hs", "current_north", "current_east")


def metocean(x_nm, y_nm, times_s=None, value=lambda xx, yy, name: 0 * xx + (2.0 if name == "hs" else 0.0)):
    x, y = np.asarray(x_nm) * NM, np.asarray(y_nm) * NM
    xx, yy = np.meshgrid(x, y, indexing="ij")
    if times_s is None:
        fields = {name: value(xx, yy, name) for name in NAMES}
    else:
        fields = {name: np.stack([value(xx, yy, name) * (1 + k) for k in range(len(times_s))]) for name in NAMES}
    return MetOceanField(x, y, fields, times_s=times_s)


def windy(xx, yy, name):
    """Wind towards the south-west varying over the map, waves, a current towards the east."""
    return {"wind_north": -8.0 - xx / (20 * NM), "wind_east": -3.0 + yy / (30 * NM),
            "hs": 1.5 + xx / (40 * NM), "current_north": 0 * xx, "current_east": 0.3 + 0 * xx}[name]


# -- resampling -----------------------------------------------------------------------

def test_resampling_defaults_to_one_nautical_mile_and_stops_inside_the_extent():
    weather = resample_weather(metocean(np.linspace(0, 10 - 0.5 / NM, 5), [0, 3, 6]))
    assert weather.spacing == (NM, NM)
    assert weather.x[-1] == 9 * NM  # 10 nm lies 0.5 m beyond the grid: not a node
    assert weather.y[-1] == 6 * NM


def test_resampling_stops_inside_the_extent_along_y_too():
    weather = resample_weather(metocean([0, 3, 6], np.linspace(0, 10 - 0.5 / NM, 5)))
    assert weather.y[-1] == 9 * NM  # 10 nm lies 0.5 m beyond the grid: not a node
    assert weather.x[-1] == 6 * NM


@pytest.mark.parametrize("resolution", [0.0, -1.0])
def test_resolution_must_be_positive(resolution):
    with pytest.raises(ValueError, match="^planning resolution must be positive$"):
        resample_weather(metocean([0, 5], [0, 5]), resolution)


@pytest.mark.parametrize("x_nm, y_nm", [([0, 0.5], [0, 5]), ([0, 5], [0, 0.5])])
def test_a_resolution_leaving_one_node_along_either_axis_is_refused(x_nm, y_nm):
    with pytest.raises(ValueError, match="^planning resolution 1.0 nm leaves fewer than 2 nodes on the map$"):
        resample_weather(metocean(x_nm, y_nm), 1.0)


@pytest.mark.parametrize("x_nm, y_nm", [([0, 1500, 3000], [0, 5]), ([0, 5], [0, 1500, 3000])])
def test_a_planning_grid_over_the_node_limit_along_either_axis_is_refused_before_it_is_built(x_nm, y_nm):
    # 3000 nm at 1 nm: 3001 nodes, over the limit of 2001 (measured over the whole axis, not from its second node)
    with pytest.raises(ValueError, match=r"^the planning resolution_nm gives 3e\+03 grid nodes along an axis, "
                                         r"more than the limit of 2001"):
        resample_weather(metocean(x_nm, y_nm), 1.0)


def test_two_nodes_along_each_axis_are_enough():
    weather = resample_weather(metocean([0, 1], [0, 1]), 1.0)
    assert (weather.x.size, weather.y.size) == (2, 2)


def test_a_time_varying_field_is_taken_at_the_planning_time():
    field = metocean([0, 2, 4], [0, 2, 4], times_s=[0.0, 100.0], value=windy)
    between = resample_weather(field, 1.0, t_s=25.0)
    xx, yy = np.meshgrid(between.x, between.y, indexing="ij")
    # the second slice is twice the first: at t = 25 s, 1.25 times it
    np.testing.assert_allclose(between.hs, 1.25 * windy(xx, yy, "hs"))
    np.testing.assert_allclose(between.wind_north, 1.25 * windy(xx, yy, "wind_north"))
    with pytest.raises(ValueError, match="varies in time"):
        resample_weather(field, 1.0)


def test_anything_with_axes_and_sample_can_be_resampled():
    class Plain:  # no is_time_varying, no snapshot
        x = np.array([0.0, 3 * NM])
        y = np.array([0.0, 3 * NM])

        def sample(self, xx, yy, t_s=None):
            return {name: 0 * xx + (t_s or 0.0) for name in NAMES}

    weather = resample_weather(Plain(), 1.0, t_s=7.0)
    assert np.all(weather.hs == 7.0) and weather.hs.shape == (4, 4)


# -- energy and guidance fields ---------------------------------------------------------

def test_energy_fields_are_the_rates_of_a_ship_heading_for_the_goal_with_the_given_parameters():
    weather = resample_weather(metocean(np.arange(0, 21, 2.0), np.arange(0, 31, 2.0), value=windy), 2.0)
    goal = (14 * NM, 26 * NM)  # x and y differ: the heading is a bearing, not a diagonal
    params = EnergyParameters(fuel_price_usd_t=900.0, co2_per_fuel_t_t=3.5, wind_area_m2=1500.0)
    ec, em = energy_rate_fields(weather, goal, SPEED, params)
    heading = np.arctan2(goal[1] - weather.y[None, :], goal[0] - weather.x[:, None])
    stw = speed_through_water(SPEED, heading, weather.current_north, weather.current_east)
    power = brake_power(stw, heading, weather.wind_north, weather.wind_east, weather.hs, params)
    np.testing.assert_allclose(ec, cost_rate(power, params), rtol=1e-12)
    np.testing.assert_allclose(em, emission_rate(power, params), rtol=1e-12)
    # the superposition uses its own parameters too
    field = SuperpositionField(weather, goal, energy=params)
    field.update((0.0, 0.0), SPEED)
    np.testing.assert_allclose(field.ec, ec, rtol=1e-12)


@pytest.mark.parametrize("c_rad", [0.5, 1.0, 1.7])
def test_guidance_abeam_of_the_ship_goal_line_is_scaled_by_exp_delta2_over_2c2(c_rad):
    start, goal = (3 * NM, 11 * NM), (3 * NM + 20 * NM, 11 * NM)  # the ship-goal line runs north
    abeam = (goal[0], goal[1] + 5 * NM)  # bearing to the goal: west, 90 deg off the line
    g = guidance_field([abeam[0]], [abeam[1]], start, goal, SPEED, GuidanceParameters(eps=2.0, c_rad=c_rad))
    expected = 2.0 * 5 * NM / SPEED * math.exp((math.pi / 2) ** 2 / (2 * c_rad ** 2))
    assert g[0, 0] == pytest.approx(expected, rel=1e-12)


def test_guidance_at_the_start_is_the_time_to_the_goal_times_eps():
    # on the ship-goal line the bearing difference is 0: G = eps * distance / speed, for a
    # line running neither north nor east from a start off the grid's diagonal
    start, goal = (2 * NM, 9 * NM), (30 * NM, 20 * NM)
    g = guidance_field([start[0]], [start[1]], start, goal, SPEED, GuidanceParameters(eps=2.0, c_rad=0.5))
    assert g[0, 0] == pytest.approx(2.0 * math.hypot(28 * NM, 11 * NM) / SPEED, rel=1e-12)


def test_superposition_guidance_matches_the_wrapped_formula_across_south():
    """The ship north of the goal: psi = pi, and the bearings to the goal from either side of
    the line are near +pi and -pi: the difference must be wrapped, not taken as ~2 pi."""
    weather = resample_weather(metocean(np.arange(0, 31, 1.0), np.arange(0, 31, 1.0)), 1.0)
    goal, start = (5 * NM, 15 * NM), (28 * NM, 15 * NM)
    guidance = GuidanceParameters(eps=1.5, c_rad=0.7)
    field = SuperpositionField(weather, goal, guidance=guidance)
    field.update(start, 7.0)
    reference = guidance_field(weather.x, weather.y, start, goal, 7.0, guidance)
    np.testing.assert_allclose(field.guidance_s(), reference, rtol=2e-5, atol=1e-3)


def test_normalised_guidance_spans_zero_to_one_with_the_goal_off_the_map():
    weather = resample_weather(metocean(np.arange(0, 21, 1.0), np.arange(0, 21, 1.0)), 1.0)
    field = SuperpositionField(weather, (35 * NM, 30 * NM))  # G > 0 everywhere on the map
    field.update((2 * NM, 3 * NM), SPEED)
    g_bar = field.guidance_normalised()
    assert g_bar.min() == 0.0 and g_bar.max() == pytest.approx(1.0, abs=1e-12)
    np.testing.assert_array_equal(field.potential(avoidance=True), g_bar)
    assert not np.array_equal(field.potential(), g_bar)


def test_normalise_treats_a_field_constant_to_rounding_as_constant():
    # relative spread 1e-13 of a large value: rounding, not a field
    assert np.all(normalise(np.array([1e6, 1e6 + 1e-7])) == 0.0)
    # small values keep an absolute floor of 1e-12: 1.5e-12 is a field
    np.testing.assert_allclose(normalise(np.array([0.0, 1.5e-12])), [0.0, 1.0])


def test_update_refuses_a_speed_that_is_not_positive_and_accepts_a_slow_one():
    weather = resample_weather(metocean([0, 5], [0, 5]), 1.0)
    field = SuperpositionField(weather, (4 * NM, 4 * NM))
    with pytest.raises(ValueError, match=r"^planning speed must be positive, got 0.0$"):
        field.update((0.0, 0.0), 0.0)
    field.update((0.0, 0.0), 0.5)
    assert field.speed == 0.5


def test_new_weather_on_the_same_grid_rebuilds_the_energy_fields():
    calm = resample_weather(metocean(np.arange(0, 11, 1.0), np.arange(0, 11, 1.0)), 1.0)
    stormy = resample_weather(metocean(np.arange(0, 11, 1.0), np.arange(0, 11, 1.0), value=windy), 1.0)
    field = SuperpositionField(calm, (9 * NM, 9 * NM))
    field.update((0.0, 0.0), SPEED)
    calm_ec = field.ec.copy()
    field.set_weather(stormy)
    field.update((0.0, 0.0), SPEED)  # same speed: rebuilt all the same
    np.testing.assert_allclose(field.ec, energy_rate_fields(stormy, field.goal, SPEED)[0])
    assert not np.allclose(field.ec, calm_ec)
    coarse = resample_weather(metocean(np.arange(0, 11, 2.0), np.arange(0, 11, 2.0)), 2.0)
    with pytest.raises(ValueError, match=r"^new planning weather has 6 x 6 nodes, the field 11 x 11$"):
        field.set_weather(coarse)


def test_new_weather_on_another_grid_is_refused_naming_both_node_counts():
    wide = resample_weather(metocean(np.arange(0, 11, 1.0), np.arange(0, 6, 1.0)), 1.0)
    field = SuperpositionField(wide, (9 * NM, 4 * NM))
    coarse = resample_weather(metocean(np.arange(0, 11, 2.0), np.arange(0, 6, 1.0)), 2.0)
    with pytest.raises(ValueError, match=r"^new planning weather has 6 x 3 nodes, the field 11 x 6$"):
        field.set_weather(coarse)


# -- local evaluation ------------------------------------------------------------------

def offset_field():
    """A field on a grid whose south-west node is not the origin, with curved U."""
    def hs(xx, yy, name):
        if name != "hs":
            return windy(xx, yy, name)
        return 1.0 + 3.0 * np.exp(-((xx - 30 * NM) ** 2 + (yy - 55 * NM) ** 2) / (2 * (6 * NM) ** 2))
    weather = resample_weather(metocean(np.arange(20, 51, 1.0), np.arange(40, 71, 1.0), value=hs), 1.0)
    field = SuperpositionField(weather, (47 * NM, 66 * NM))
    field.update((22 * NM, 42 * NM), SPEED)
    return field


POINTS_ON_MAP = [(33.3 * NM, 51.7 * NM), (20 * NM, 40 * NM), (50 * NM, 70 * NM),   # inside, corners
                 (49.6 * NM, 69.7 * NM), (35.2 * NM, 70 * NM), (50 * NM, 44.4 * NM)]  # last cells, borders


def test_gradient_on_an_offset_grid_and_at_its_borders_matches_np_gradient():
    field = offset_field()
    gx, gy = np.gradient(field.potential(), field.dx, field.dy)
    for point in POINTS_ON_MAP:
        expected = (float(field.sample(gx, *point)), float(field.sample(gy, *point)))
        assert field.gradient_at(*point) == pytest.approx(expected, rel=1e-6, abs=1e-15)


def test_sample_is_bilinear_between_nodes_of_an_offset_grid():
    field = offset_field()
    u = field.potential()
    # at nodes: the node's value; halfway between two nodes: their mean
    assert float(field.sample(u, 23 * NM, 47 * NM)) == pytest.approx(u[3, 7], rel=1e-12)
    assert float(field.sample(u, 50 * NM, 70 * NM)) == pytest.approx(u[-1, -1], rel=1e-12)
    assert float(field.sample(u, 23.5 * NM, 70 * NM)) == pytest.approx((u[3, -1] + u[4, -1]) / 2, rel=1e-12)


@pytest.mark.parametrize("outside, nearest", [((10 * NM, 55 * NM), (20 * NM, 55 * NM)),
                                              ((60 * NM, 55 * NM), (50 * NM, 55 * NM)),
                                              ((33 * NM, 30 * NM), (33 * NM, 40 * NM)),
                                              ((33 * NM, 85 * NM), (33 * NM, 70 * NM)),
                                              ((65 * NM, 90 * NM), (50 * NM, 70 * NM))])
def test_points_beyond_the_map_are_evaluated_at_the_nearest_border_point(outside, nearest):
    field = offset_field()
    u = field.potential()
    assert float(field.sample(u, *outside)) == float(field.sample(u, *nearest))
    assert field.gradient_at(*outside) == field.gradient_at(*nearest)


def test_a_field_read_before_its_first_update_says_to_update_it():
    field = SuperpositionField(resample_weather(metocean([0, 5, 10], [0, 5, 10])), (9 * NM, 9 * NM))
    assert field.speed is None
    for read in (field.guidance_s, field.guidance_normalised, field.potential,
                 lambda: field.gradient_at(NM, NM), lambda: field.gradient_at(NM, NM, avoidance=True)):
        with pytest.raises(RuntimeError, match=r"built by update\(start, speed\) first"):
            read()
    field.update((NM, NM), SPEED)
    assert field.speed == SPEED and field.potential().shape == field.shape
