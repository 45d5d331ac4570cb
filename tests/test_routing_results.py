"""The routing sets' verdict: each set measured against the goal by the numbers it reports."""

import sys
from pathlib import Path

import pandas as pd
import pytest
from script_module import module_of_file

SCRIPT = Path(__file__).resolve().parents[1] / "scripts" / "routing_results.py"


@pytest.fixture(scope="module")
def script():
    yield module_of_file(SCRIPT, "routing_results_under_test")
    del sys.modules["routing_results_under_test"]


def members(shares, savings, failed=None, arrived=None):
    count = len(savings)
    return pd.DataFrame({"arrived": arrived or [True] * count, "share [%]": shares,
                         "saving vs equal-arrival line [%]": savings,
                         "failed runs and trials": failed or ["none"] * count})


def test_a_set_meets_the_goal_only_with_every_member_run_finished_and_within_the_bounds(script):
    good = members([95.0, 80.0, None, 120.0], [1.2, 0.8, 0.1, 2.0])
    verdict = script.routing_set_verdict(good, planned=4)
    assert verdict["met"] and verdict["with_share"] == 3 and verdict["median_share"] == pytest.approx(95.0)
    assert verdict["least_share"] == pytest.approx(80.0) and verdict["worst_saving"] == pytest.approx(0.1)
    # median below 90 %
    assert not script.routing_set_verdict(members([85.0, 80.0, None, 120.0], [1.2, 0.8, 0.1, 2.0]), 4)["met"]
    # one member below 75 % although the median holds
    assert not script.routing_set_verdict(members([95.0, 70.0, None, 120.0], [1.2, 0.8, 0.1, 2.0]), 4)["met"]
    # one member more than 0.5 % dearer than the line where no share is defined
    dearer = script.routing_set_verdict(members([95.0, 80.0, None, 120.0], [1.2, 0.8, -0.6, 2.0]), 4)
    assert not dearer["met"] and dearer["dearer"] == 1
    # a failed trial, a member that did not arrive, a member not run
    failed = members([95.0, 80.0, None, 120.0], [1.2, 0.8, 0.1, 2.0], failed=["none", "none", "trial: off", "none"])
    assert not script.routing_set_verdict(failed, 4)["met"]
    late = members([95.0, 80.0, None, 120.0], [1.2, 0.8, 0.1, 2.0], arrived=[True, True, False, True])
    assert not script.routing_set_verdict(late, 4)["met"]
    assert not script.routing_set_verdict(good, planned=5)["met"]


def test_a_sailed_track_ends_where_the_ship_crossed_the_arrival_radius(script, tmp_path):
    import json

    import numpy as np

    frame = pd.DataFrame({"time_s": [0.0, 60.0, 120.0, 180.0], "ship.x": [0.0, 100.0, 200.0, 300.0],
                          "ship.y": [0.0, 10.0, 20.0, 30.0], "ship.psi": [0.0] * 4})
    frame.to_parquet(tmp_path / "timeseries.parquet")
    (tmp_path / "summary.json").write_text(json.dumps({"analyses": {"voyage": {"arrival_time_min": 1.5}}}))
    points, times = script.sailed_track(tmp_path)
    np.testing.assert_allclose(times, [0.0, 60.0, 90.0])
    np.testing.assert_allclose(points, [[0.0, 0.0], [100.0, 10.0], [150.0, 15.0]])
    (tmp_path / "summary.json").write_text(json.dumps({"analyses": {"voyage": {"arrival_time_min": None}}}))
    assert script.sailed_track(tmp_path) is None
