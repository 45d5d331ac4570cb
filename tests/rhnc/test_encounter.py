"""Separation and cross-track figures."""

import numpy as np
import pytest

from rhnc.encounters.encounter import (cross_track_error, reference_at_times, segment_min_distance, separations,
                             time_back_on_track)
from orchestrator.geometry import NM


def test_segment_min_distance_catches_a_crossing_between_samples():
    # own ship passes straight through the obstacle between two samples 2 km apart
    distance, fraction = segment_min_distance([[0.0, -1000.0]], [[0.0, 1000.0]], [[0.0, 0.0]], [[0.0, 0.0]])
    assert distance[0] == pytest.approx(0.0)
    assert fraction[0] == pytest.approx(0.5)
    # head-on, both moving: closest when they meet
    distance, _ = segment_min_distance([[0.0, 0.0]], [[100.0, 0.0]], [[200.0, 30.0]], [[0.0, 30.0]])
    assert distance[0] == pytest.approx(30.0)


def test_separations_per_obstacle():
    t = np.array([0.0, 10.0, 20.0])
    x = np.array([-1000.0, 0.0, 1000.0])
    y = np.zeros(3)
    obstacles = np.zeros((3, 1, 5))
    obstacles[:, 0, 1] = 500.0
    obstacles[:, 0, 4] = 400.0
    (row,) = separations(t, x, y, obstacles, own_radius_m=50.0)
    assert row["min_distance_nm"] == pytest.approx(500.0 / NM)
    assert row["min_clearance_nm"] == pytest.approx(50.0 / NM)
    assert row["time_of_min_s"] == 10.0


def test_cross_track_sign_and_return():
    # reference heading north; ship 100 m east = starboard = positive
    assert cross_track_error(0.0, 100.0, 0.0, 0.0, 0.0) == pytest.approx(100.0)
    assert cross_track_error(0.0, 0.0, 0.0, 100.0, np.pi / 2) == pytest.approx(0.0)
    t = np.arange(6.0)
    cross = np.array([0.0, 500.0, 300.0, 100.0, 50.0, 20.0])
    assert time_back_on_track(t, cross, after_s=1.0, tolerance_m=200.0) == 3.0
    assert time_back_on_track(t, cross + 1000, after_s=1.0, tolerance_m=200.0) is None


def test_reference_is_read_at_each_samples_own_time():
    # one trajectory published at t = 0 (points every 60 s), held over three samples 20 s apart
    trajectory = np.array([[0.0, 0.0, 0.0, 0.0, 5.0, 0.0, 0.0],
                           [60.0, 300.0, 0.0, 0.0, 5.0, 0.0, 0.0]])
    held = np.repeat(trajectory[None], 3, axis=0)
    states = reference_at_times(held, [0.0, 20.0, 40.0])
    np.testing.assert_allclose(states[:, 0], [0.0, 100.0, 200.0])
