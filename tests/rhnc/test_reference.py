"""Reference states from timed path points (Eq. 19)."""

import math

import numpy as np

from rhnc.reference import reference_states


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
