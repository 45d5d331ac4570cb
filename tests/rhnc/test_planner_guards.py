"""The planner's guards (goal, flat field, map border, final approach) on fields whose
descent direction is known exactly: a linear potential U = -d . p has the same
descent direction d everywhere, so every step can be checked to the metre."""

import logging

import numpy as np
import pytest

from rhnc.navigation.planner import plan_local_path

SIZE_M = 100_000.0
STEP_M = 2000.0


class Slope:
    """A linear potential on a square map of ``SIZE_M``: descending it means moving along
    ``descent`` (a unit vector, or zero for a flat field)."""

    def __init__(self, descent, goal):
        self.extent = (0.0, SIZE_M, 0.0, SIZE_M)
        self.goal = (float(goal[0]), float(goal[1]))
        self._gradient = (-float(descent[0]), -float(descent[1]))

    def gradient_at(self, x, y, avoidance=False):
        return self._gradient


def plan(descent, start, goal, steps=1, **options):
    return plan_local_path(Slope(descent, goal), start, STEP_M, steps, **options)


def test_a_step_down_the_slope_away_from_borders_is_neither_flat_nor_projected():
    path = plan((0.6, 0.8), (50_000.0, 50_000.0), (90_000.0, 10_000.0), steps=3)
    np.testing.assert_array_equal(path.points[1:] - path.points[:-1], [[1200.0, 1600.0]] * 3)
    assert (path.flat_steps, path.border_steps, path.trapped_at) == (0, 0, None)
    assert path.reached_goal is False


def test_a_step_across_the_border_slides_along_it_with_its_full_length():
    path = plan((-0.6, 0.8), (500.0, 50_000.0), (50_000.0, 99_000.0))
    # the southward component (it would end at x = -700 m) is removed, the step keeps 2 km
    np.testing.assert_array_equal(path.points[1], [500.0, 52_000.0])
    assert path.border_steps == 1 and path.flat_steps == 0


def test_a_step_ending_exactly_on_the_border_is_taken_as_it_is():
    low = plan((-0.6, 0.8), (1200.0, 50_000.0), (50_000.0, 99_000.0))
    np.testing.assert_array_equal(low.points[1], [0.0, 51_600.0])
    high = plan((0.6, 0.8), (SIZE_M - 1200.0, 50_000.0), (50_000.0, 99_000.0))
    np.testing.assert_array_equal(high.points[1], [SIZE_M, 51_600.0])
    assert low.border_steps == high.border_steps == 0


@pytest.mark.parametrize("descent, start, end", [((-0.6, 0.8), (500.0, 98_200.0), (500.0, SIZE_M)),
                                                 ((-0.6, -0.8), (500.0, 1800.0), (500.0, 0.0))])
def test_a_slide_along_one_border_stops_on_the_next(descent, start, end):
    # the slide's 2 km along y would end 200 m beyond the other border: it stops on it
    path = plan(descent, start, (50_000.0, 50_000.0))
    np.testing.assert_array_equal(path.points[1], end)


def test_in_a_corner_the_step_goes_along_the_bearing_to_the_goal():
    start, goal = np.array([500.0, 99_500.0]), np.array([50_500.0, 49_500.0])
    path = plan((-0.6, 0.8), start, goal)  # both components lead off the map
    np.testing.assert_allclose(path.points[1], start + STEP_M * (goal - start) / np.hypot(*(goal - start)))
    assert path.border_steps == 1


def test_a_flat_field_is_crossed_along_the_bearing_to_the_goal():
    start, goal = (10_000.0, 10_000.0), (21_000.0, 10_000.0)  # 5.5 steps north
    for tiny in ((0.0, 0.0), (0.0, 1e-10)):  # below the default 1e-9 per metre: flat
        path = plan(tiny, start, goal, steps=8)
        np.testing.assert_array_equal(path.points[:6, 0], 10_000.0 + STEP_M * np.arange(6))
        assert np.all(path.points[:, 1] == 10_000.0)
        assert path.flat_steps == 5 and path.reached_goal is True
        assert np.all(path.points[6:] == goal)
    # a gradient above the threshold is descended, however small
    steep_enough = plan((0.0, 1e-8), start, goal)
    np.testing.assert_array_equal(steep_enough.points[1], [10_000.0, 12_000.0])
    assert steep_enough.flat_steps == 0


def test_a_goal_exactly_one_step_away_ends_the_path_on_it():
    start = (50_000.0, 50_000.0)
    goal = (52_000.0, 50_000.0)
    path = plan((0.0, 1.0), start, goal, steps=3)  # the slope leads east, the goal lies north
    assert path.reached_goal is True
    assert np.all(path.points[1:] == goal)


@pytest.mark.parametrize("goal, on_map", [((150_000.0, 50_000.0), (SIZE_M, 50_000.0)),
                                          ((-50_000.0, 50_000.0), (0.0, 50_000.0))])
def test_a_goal_off_the_map_is_replaced_by_the_nearest_point_on_it(goal, on_map):
    start = (on_map[0] + (-9000.0 if on_map[0] else 9000.0), 50_000.0)
    path = plan((0.0, 0.0), start, goal, steps=8)
    assert path.reached_goal is True
    assert np.all(path.points[-1] == on_map)
    assert np.all((path.points >= 0.0) & (path.points <= SIZE_M))


@pytest.mark.parametrize("start, moved", [((-5000.0, 50_000.0), (0.0, 50_000.0)),
                                          ((50_000.0, 120_000.0), (50_000.0, SIZE_M))])
def test_a_start_off_the_map_on_one_side_is_moved_onto_it(start, moved, caplog):
    with caplog.at_level(logging.WARNING, logger="rhnc.navigation.planner"):
        path = plan((0.0, 0.0), start, (50_000.0, 50_000.0))
    assert np.all(path.points[0] == moved)
    assert "outside the map" in caplog.text


def test_a_start_on_the_border_is_not_reported_as_off_the_map(caplog):
    with caplog.at_level(logging.WARNING, logger="rhnc.navigation.planner"):
        for start in ((0.0, 50_000.0), (SIZE_M, 50_000.0), (50_000.0, 0.0), (50_000.0, SIZE_M)):
            path = plan((0.0, 0.0), start, (50_000.0, 50_000.0))
            assert np.all(path.points[0] == start)
    assert caplog.records == []


@pytest.mark.parametrize("steps, length", [(0, STEP_M), (-1, STEP_M)])
def test_horizon_must_have_a_step(steps, length):
    with pytest.raises(ValueError, match="^horizon_steps must be at least 1$"):
        plan_local_path(Slope((0.0, 1.0), (0.0, 0.0)), (50_000.0, 50_000.0), length, steps)


@pytest.mark.parametrize("length", [0.0, -1.0, float("nan")])
def test_step_length_must_be_positive(length):
    with pytest.raises(ValueError, match="^step_length must be positive$"):
        plan_local_path(Slope((0.0, 1.0), (0.0, 0.0)), (50_000.0, 50_000.0), length, 3)


def test_the_shortest_horizon_and_steps_below_a_metre_are_planned():
    one = plan((0.0, 1.0), (50_000.0, 50_000.0), (0.0, 0.0), steps=1)
    assert one.points.shape == (2, 2)
    short = plan_local_path(Slope((0.0, 1.0), (0.0, 0.0)), (50_000.0, 50_000.0), 0.5, 2)
    np.testing.assert_array_equal(short.points[:, 1], [50_000.0, 50_000.5, 50_001.0])


def test_final_approach_to_a_goal_exactly_at_the_horizon():
    start, goal = (10_000.0, 10_000.0), (42_000.0, 10_000.0)  # 16 steps north; the slope leads east
    path = plan((0.0, 1.0), start, goal, steps=16, final_approach=True)
    assert path.points.shape == (17, 2)
    np.testing.assert_array_equal(path.points[:, 0], 10_000.0 + STEP_M * np.arange(17))
    assert np.all(path.points[:, 1] == 10_000.0)
    assert path.reached_goal is True
    assert (path.flat_steps, path.border_steps, path.trapped_at) == (0, 0, None)


def test_final_approach_runs_to_the_goal_and_stays_exactly_on_it():
    start, goal = np.array([12_345.6, 23_456.7]), np.array([30_000.7, 8000.9])  # 23.5 km: 12 steps
    path = plan((0.0, 1.0), start, goal, steps=16, final_approach=True)
    assert path.points.shape == (17, 2)
    to_goal = np.hypot(*(goal - path.points).T)
    np.testing.assert_allclose(np.diff(to_goal[:12]), -STEP_M)  # straight at it, step by step
    assert np.all(path.points[12:] == goal)  # exactly: the reference stops there


def test_final_approach_from_the_goal_stays_on_it():
    goal = (30_000.0, 40_000.0)
    path = plan((0.0, 1.0), goal, goal, steps=4, final_approach=True)
    assert path.points.shape == (5, 2) and np.all(path.points == goal) and path.reached_goal


class ValleyOverFlatGuidance:
    """U a valley along x = const (y = 51 km at its floor), G flat: the second step down U
    turns back, a local minimum, and G alone has no direction to offer."""

    extent = (0.0, SIZE_M, 0.0, SIZE_M)

    def __init__(self, goal):
        self.goal = goal

    def gradient_at(self, x, y, avoidance=False):
        return (0.0, 0.0) if avoidance else (0.0, float(np.sign(y - 51_000.0)))


def test_a_local_minimum_where_guidance_is_flat_is_left_along_the_bearing_to_the_goal():
    goal = (90_000.0, 52_000.0)  # due north of the first step's end
    path = plan_local_path(ValleyOverFlatGuidance(goal), (50_000.0, 50_000.0), STEP_M, 3)
    assert path.trapped_at == 1
    np.testing.assert_array_equal(path.points, [[50_000.0, 50_000.0], [50_000.0, 52_000.0],
                                                [52_000.0, 52_000.0], [54_000.0, 52_000.0]])
    assert path.flat_steps == 2 and path.border_steps == 0
