"""Guidance field, normalisation, superposition and the gradient-descent planner (Eq. 4-6, Alg. 1)."""

import math

import numpy as np
import pytest

from rhnc.navigation.fields import (SuperpositionField, guidance_field, normalise, resample_weather, wrap_angle)
from orchestrator.geometry import KNOT, NM
from rhnc.weather.metocean import MetOceanField
from rhnc.weather.weather_generators import paper_default
from rhnc.navigation.planner import plan_local_path

SPEED = 18 * KNOT
STEP = 1.2 * NM


def weather(size_nm=50.0, resolution_nm=0.5, hs=None, wind_north=None):
    """A MetOceanField built by hand: calm water unless fields are given (functions of X, Y in m)."""
    axis = np.arange(0.0, size_nm + 1e-9, resolution_nm) * NM
    xx, yy = np.meshgrid(axis, axis, indexing="ij")
    zero = np.zeros_like(xx)
    fields = {
        "wind_north": zero if wind_north is None else wind_north(xx, yy),
        "wind_east": zero,
        "hs": np.full_like(xx, 2.0) if hs is None else hs(xx, yy),
        "current_north": zero,
        "current_east": zero,
    }
    return resample_weather(MetOceanField(axis, axis, fields), resolution_nm)


def patch(amplitude_m, centre_nm, sigma_nm, background_m=1.0):
    def hs(xx, yy):
        d2 = (xx - centre_nm[0] * NM) ** 2 + (yy - centre_nm[1] * NM) ** 2
        return background_m + amplitude_m * np.exp(-d2 / (2 * (sigma_nm * NM) ** 2))
    return hs


def test_wrap_angle_half_open_interval():
    assert wrap_angle(math.pi) == pytest.approx(math.pi)
    assert wrap_angle(-math.pi) == pytest.approx(math.pi)
    assert wrap_angle(3 * math.pi / 2) == pytest.approx(-math.pi / 2)


def test_guidance_field_lowest_at_goal_and_along_the_ship_goal_line():
    axis = np.arange(0, 41) * NM
    start, goal = (5 * NM, 5 * NM), (30 * NM, 20 * NM)
    g = guidance_field(axis, axis, start, goal, SPEED)
    assert np.unravel_index(np.argmin(g), g.shape) == (30, 20)
    assert g[30, 20] == 0.0
    # on a circle of 10 nm around the goal, G is least towards the ship
    angles = np.linspace(-math.pi, math.pi, 721)
    px, py = goal[0] + 10 * NM * np.cos(angles), goal[1] + 10 * NM * np.sin(angles)
    ring = guidance_field(px, py, start, goal, SPEED).diagonal()
    towards_ship = math.atan2(start[1] - goal[1], start[0] - goal[0])
    assert angles[np.argmin(ring)] == pytest.approx(towards_ship, abs=0.01)
    assert ring.min() == pytest.approx(10 * NM / SPEED)


def test_normalised_fields_in_unit_interval_and_constant_field_gives_zero():
    field = SuperpositionField(weather(hs=patch(3, (20, 30), 5), wind_north=lambda x, y: 5 + 0 * x),
                               (45 * NM, 40 * NM))
    field.update((2 * NM, 3 * NM), SPEED)
    for values in (normalise(field.ec), normalise(field.em), field.guidance_normalised()):
        assert values.min() == pytest.approx(0.0, abs=1e-9)
        assert values.max() == pytest.approx(1.0, abs=1e-6)
    constant = normalise(np.full((4, 5), 7.0))
    assert np.all(constant == 0.0)


def test_gradient_matches_np_gradient_interpolated_bilinearly():
    field = SuperpositionField(weather(hs=patch(3, (20, 30), 5)), (45 * NM, 40 * NM))
    field.update((2 * NM, 3 * NM), SPEED)
    gx, gy = np.gradient(field.potential(), field.dx, field.dy)
    for point in [(10.3 * NM, 20.7 * NM), (0.0, 0.1 * NM), (50 * NM, 33.33 * NM)]:
        assert field.gradient_at(*point) == pytest.approx(
            (float(field.sample(gx, *point)), float(field.sample(gy, *point))), rel=1e-6)


def test_uniform_weather_gives_the_straight_line():
    start, goal = np.array([3.0, 8.0]) * NM, np.array([44.0, 37.0]) * NM
    field = SuperpositionField(weather(), goal)
    field.update(start, SPEED)
    path = plan_local_path(field, start, STEP, 50)
    assert path.reached_goal
    line = (goal - start) / np.linalg.norm(goal - start)
    offsets = path.points - start
    cross = np.abs(offsets[:, 0] * line[1] - offsets[:, 1] * line[0])
    assert cross.max() < 0.01 * np.linalg.norm(goal - start)


def test_path_bends_around_a_high_cost_patch_and_costs_less():
    start, goal = np.array([0.0, 0.0]), np.array([50.0, 50.0]) * NM
    field = SuperpositionField(weather(hs=patch(6, (25, 26.5), 4)), goal)
    field.update(start, SPEED)
    path = plan_local_path(field, start, STEP, 80)
    assert path.reached_goal
    deviation = np.abs(path.points[:, 0] - path.points[:, 1]).max() / math.sqrt(2)
    assert deviation > 3 * NM
    arrived = int(np.argmax(np.all(path.points == goal, axis=1)))
    path_cost = field.sample(field.ec, path.points[:arrived, 0], path.points[:arrived, 1]).sum()
    along = np.arange(0.0, np.linalg.norm(goal), STEP) / math.sqrt(2)
    line_cost = field.sample(field.ec, along, along).sum()
    assert path_cost < line_cost


def test_path_stops_at_the_goal():
    start, goal = np.array([10.0, 10.0]) * NM, np.array([20.0, 15.0]) * NM
    field = SuperpositionField(weather(), goal)
    field.update(start, SPEED)
    path = plan_local_path(field, start, STEP, 30)
    steps = np.linalg.norm(np.diff(path.points, axis=0), axis=1)
    arrived = int(np.argmax(np.all(path.points == goal, axis=1)))
    assert path.reached_goal and 0 < arrived < 30
    assert np.all(path.points[arrived:] == goal)
    assert np.all(steps[: arrived - 1] == pytest.approx(STEP))
    assert 0 < steps[arrived - 1] <= STEP
    assert path.points.shape == (31, 2)


def test_planner_never_leaves_the_map():
    # a patch east of a path along the western border pushes the descent westwards, off the map
    start, goal = np.array([1.0, 0.5]) * NM, np.array([49.0, 0.5]) * NM
    field = SuperpositionField(weather(hs=patch(6, (25, 3), 5)), goal)
    field.update(start, SPEED)
    path = plan_local_path(field, start, STEP, 60)
    x_min, x_max, y_min, y_max = field.extent
    assert np.all(path.points[:, 0] >= x_min) and np.all(path.points[:, 0] <= x_max)
    assert np.all(path.points[:, 1] >= y_min) and np.all(path.points[:, 1] <= y_max)
    assert path.border_steps > 0
    assert path.reached_goal
    # a start outside the map is moved onto the border
    outside = plan_local_path(field, (-5 * NM, 60 * NM), STEP, 3)
    assert tuple(outside.points[0]) == (x_min, y_max)


def test_symmetric_patch_does_not_trap_the_path():
    start, goal = np.array([5.0, 25.0]) * NM, np.array([45.0, 25.0]) * NM
    field = SuperpositionField(weather(hs=patch(6, (25, 25), 5)), goal)
    field.update(start, SPEED)
    path = plan_local_path(field, start, STEP, 60)
    assert path.trapped_at is not None
    assert path.reached_goal
    # the step at which the trap is noticed already descends G alone: no step turns back
    steps = np.diff(path.points, axis=0)
    steps = steps[np.hypot(*steps.T) > 0]
    turns = np.sum(steps[1:] * steps[:-1], axis=1) / (np.hypot(*steps[1:].T) * np.hypot(*steps[:-1].T))
    assert turns.min() >= -0.5


def test_avoidance_state_descends_guidance_alone():
    start, goal = np.array([0.0, 0.0]), np.array([50.0, 50.0]) * NM
    field = SuperpositionField(weather(hs=patch(6, (25, 26.5), 4)), goal)
    field.update(start, SPEED)
    path = plan_local_path(field, start, STEP, 20, avoidance=True)
    assert np.abs(path.points[:, 0] - path.points[:, 1]).max() < 1e-6 * NM


def test_normalised_cost_and_emission_fields_coincide():
    """EC is affine and EM linear in P: Eq. 5 maps both to the same field (see rhnc.navigation.fields)."""
    field = SuperpositionField(weather(hs=patch(3, (20, 30), 5)), (45 * NM, 40 * NM))
    field.update((2 * NM, 3 * NM), SPEED)
    assert np.allclose(normalise(field.ec), normalise(field.em), atol=1e-12)


def test_final_approach_runs_straight_to_a_goal_within_the_horizon():
    from rhnc.navigation.fields import SuperpositionField, resample_weather
    from rhnc.navigation.planner import plan_local_path

    weather = resample_weather(paper_default(resolution_nm=1.0), 1.0)
    goal = (100 * 1852.0, 100 * 1852.0)
    field = SuperpositionField(weather, goal)
    start = (95 * 1852.0, 88 * 1852.0)
    field.update(start, 9.26)
    path = plan_local_path(field, start, 2222.4, 16, final_approach=True)
    direction = np.subtract(goal, start) / np.hypot(*np.subtract(goal, start))
    rel = path.points - start
    assert np.max(np.abs(rel[:, 0] * direction[1] - rel[:, 1] * direction[0])) < 1e-6
    assert path.reached_goal and np.allclose(path.points[-1], goal)
    np.testing.assert_allclose(np.hypot(*np.diff(path.points[:6], axis=0).T), 2222.4)
    # without it (the default, as in the paper), the descent does not head straight there
    plain = plan_local_path(field, start, 2222.4, 16)
    rel = plain.points - start
    assert np.max(np.abs(rel[:, 0] * direction[1] - rel[:, 1] * direction[0])) > 100.0


@pytest.mark.parametrize("time_varying", [False, True])
def test_the_planner_plans_on_the_data_not_on_a_band_of_held_edge_values(time_varying):
    """A map grown by held edge values (so that a ship may sail over the band) is planned on
    as the map itself: the band would change Eq. 5's normalisation and the route with it."""
    from rhnc.weather.weather_generators import moving_storm

    if time_varying:
        field = moving_storm(x_range_nm=(0.0, 30.0), y_range_nm=(0.0, 30.0), resolution_nm=1.0)
    else:
        field = paper_default(x_range_nm=(0.0, 30.0), y_range_nm=(0.0, 30.0), resolution_nm=1.0)
    held = field.with_edges_held(2.0 * NM)
    t_s = 0.5 * float(field.times_s[-1])
    plain, grown = resample_weather(field, 1.0, t_s=t_s), resample_weather(held, 1.0, t_s=t_s)
    np.testing.assert_array_equal(grown.x, plain.x)
    np.testing.assert_array_equal(grown.y, plain.y)
    np.testing.assert_allclose(grown.hs, plain.hs, rtol=0, atol=1e-12)
    assert held.snapshot(t_s).data_extent == field.data_extent   # a planner given the slice alike
    goal = (30 * NM, 30 * NM)
    paths = []
    for planning in (plain, grown):
        potential = SuperpositionField(planning, goal)
        potential.update((1 * NM, 2 * NM), SPEED)
        paths.append(plan_local_path(potential, (1 * NM, 2 * NM), STEP, 16).points)
    np.testing.assert_allclose(paths[1], paths[0], rtol=0, atol=1e-6)
