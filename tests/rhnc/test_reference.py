"""Reference states from timed path points (Eq. 19)."""

import math

import numpy as np
import pytest

from rhnc.navigation.reference import reference_states


def test_circle_gives_yaw_rate_v_over_r():
    radius, speed, delta = 5000.0, 9.26, 20.0
    angle = np.arange(17) * speed * delta / radius
    # clockwise (starboard) turn seen from above with x north, y east: r > 0
    points = np.c_[radius * np.sin(angle), radius * (1 - np.cos(angle))]
    ref = reference_states(points, delta, start_time=100.0)
    assert ref.shape == (17, 7)
    assert np.allclose(ref[:, 0], 100.0 + delta * np.arange(17))
    assert np.allclose(ref[:, 6], speed / radius, rtol=1e-3)
    assert np.allclose(ref[:, 4], speed, rtol=1e-3)
    assert np.all(ref[:, 5] == 0.0)
    assert np.allclose(ref[1:-1, 3], angle[1:-1], atol=1e-6)


def test_two_point_and_straight_paths():
    two = reference_states(np.array([[0.0, 0.0], [100.0, 100.0]]), 20.0)
    assert np.allclose(two[:, 3], math.pi / 4)
    assert np.allclose(two[:, 4], math.hypot(100, 100) / 20)
    assert np.all(two[:, 6] == 0.0)
    line = reference_states(np.c_[np.linspace(0, -3000, 9), np.linspace(0, 1000, 9)], 30.0)
    assert np.allclose(line[:, 3], math.atan2(1000, -3000))
    assert np.allclose(line[:, 6], 0.0, atol=1e-12)


def test_path_stopping_at_the_goal_holds_heading_with_zero_yaw_rate():
    points = np.array([[0, 0], [100, 100], [200, 200], [250, 250], [250, 250], [250, 250]], dtype=float)
    ref = reference_states(points, 20.0)
    assert np.all(np.isfinite(ref))
    assert np.allclose(ref[:, 3], math.pi / 4)
    assert np.all(ref[-2:, 4] == 0.0) and np.all(ref[-2:, 6] == 0.0)


def test_path_at_rest_uses_initial_heading():
    ref = reference_states(np.zeros((4, 2)), 20.0, initial_heading=1.0)
    assert np.all(ref[:, 3] == 1.0) and np.all(ref[:, 4] == 0.0)





@pytest.mark.parametrize("points", [np.zeros(3), np.zeros((3, 3)), np.zeros((0, 2)), np.zeros((2, 2, 1))])
def test_points_of_the_wrong_shape_are_refused(points):
    with pytest.raises(ValueError, match=r"^path points must have shape \(N\+1, 2\), got \("):
        reference_states(points, 20.0)


@pytest.mark.parametrize("delta", [0.0, -1.0, float("nan")])
def test_a_non_positive_delta_is_refused(delta):
    with pytest.raises(ValueError, match="^delta must be positive$"):
        reference_states(np.zeros((2, 2)), delta)


def test_a_single_point_is_a_state_at_rest():
    np.testing.assert_array_equal(reference_states(np.array([[5.0, 6.0]]), 0.5, start_time=3.0, initial_heading=0.7),
                                  [[3.0, 5.0, 6.0, 0.7, 0.0, 0.0, 0.0]])
    np.testing.assert_array_equal(reference_states([[5.0, 6.0]], 0.5), [[0.0, 5.0, 6.0, 0.0, 0.0, 0.0, 0.0]])


def test_default_start_time_and_rest_threshold():
    slow = reference_states(np.array([[0.0, 0.0], [0.2, 0.0]]), 20.0)  # 0.01 m/s: moving
    np.testing.assert_allclose(slow[:, 0], [0.0, 20.0])
    np.testing.assert_allclose(slow[:, 4], 0.01)
    at_threshold = reference_states(np.array([[0.0, 0.0], [10.0, 0.0]]), 20.0, still_speed=0.5)
    assert np.all(at_threshold[:, 4] == 0.0)  # exactly the threshold speed counts as at rest


def test_three_points_use_second_order_ends_and_their_curvature():
    # x = t^2: second-order end differences give the exact speeds 0, 2, 4 m/s
    accelerating = reference_states(np.array([[0.0, 0.0], [1.0, 0.0], [4.0, 0.0]]), 1.0)
    np.testing.assert_allclose(accelerating[:, 4], [0.0, 2.0, 4.0], atol=1e-12)
    # three points on a circle of 5 km: r = v / R at every row, the ends held at the middle's
    radius, speed, delta = 5000.0, 9.26, 20.0
    angle = np.arange(3) * speed * delta / radius
    arc = reference_states(np.c_[radius * np.sin(angle), radius * (1 - np.cos(angle))], delta)
    np.testing.assert_allclose(arc[:, 6], speed / radius, rtol=2e-3)
    assert arc[0, 6] == arc[1, 6] == arc[2, 6]  # ends hold the middle's (one-sided ends are less accurate)


def test_end_yaw_rates_hold_the_neighbours_on_a_path_of_changing_curvature():
    t = np.arange(11.0)
    ref = reference_states(np.c_[9.0 * t, 0.02 * t ** 3], 1.0)
    assert ref[0, 6] == ref[1, 6] and ref[-1, 6] == ref[-2, 6]
    assert abs(ref[2, 6] - ref[1, 6]) > 1e-6 and abs(ref[-3, 6] - ref[-2, 6]) > 1e-6


def test_a_path_that_starts_at_rest_takes_its_first_moving_heading():
    points = np.array([[0, 0], [0, 0], [0, 0], [0, 100], [0, 200], [0, 300]], dtype=float)
    ref = reference_states(points, 20.0)
    np.testing.assert_allclose(ref[:, 3], math.pi / 2)
    assert np.all(ref[:2, 4] == 0.0) and np.all(ref[:2, 6] == 0.0)
    held = reference_states(points, 20.0, initial_heading=1.0)
    np.testing.assert_allclose(held[:2, 3], 1.0)
    np.testing.assert_allclose(held[2:, 3], math.pi / 2)
    np.testing.assert_array_equal(reference_states(np.zeros((3, 2)), 20.0)[:, 3], 0.0)  # never moves


def test_a_path_that_starts_at_rest_and_turns_keeps_its_end_yaw_rate():
    points = np.array([[0, 0], [0, 0], [0, 0], [10, 0], [30, 5], [50, 20], [65, 40]], dtype=float)
    ref = reference_states(points, 10.0)
    assert ref[0, 4] == 0.0 and ref[0, 6] == 0.0  # at rest: no turn
    assert ref[-1, 6] == ref[-2, 6] != 0.0
