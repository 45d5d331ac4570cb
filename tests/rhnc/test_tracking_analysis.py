"""Estimation errors of a tracker, and the analyses judging the true tracks when a tracker feeds the NMPC."""

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from orchestrator.run import run_scenario
from rhnc.cosim.obstacle_ports import estimated_obstacles_participant, true_obstacles_column
from rhnc.encounters.tracker import TrackerParticipant
from rhnc.encounters.tracking_errors import tracking_errors

REPO = Path(__file__).resolve().parents[2]
NM = 1852.0


def test_tracking_errors_rms_coverage_and_breaks():
    t = np.arange(6.0)
    truth = np.zeros((6, 1, 5))
    truth[:, 0, 0] = 100.0 * t
    estimates = np.zeros((6, 2, 5))
    estimates[:, 0, 0] = 100.0 * t + 3.0          # row 0: 3 m ahead, until it is lost at t = 3
    estimates[:, 1, 0] = 100.0 * t - 4.0          # row 1: a new track from t = 4
    estimates[:, :, 2] = 0.5
    valid = np.array([[0, 0], [1, 0], [1, 0], [0, 0], [0, 1], [0, 1]])
    result = tracking_errors(t, truth, estimates, valid, gate_m=50.0)
    (target,) = result["targets"]
    assert target["first_tracked_s"] == 1.0
    assert target["coverage"] == pytest.approx(4 / 5)
    assert target["position_rms_m"] == pytest.approx(np.sqrt((2 * 9 + 2 * 16) / 4))
    assert target["position_max_m"] == pytest.approx(4.0)
    assert target["velocity_rms_mps"] == pytest.approx(0.5)
    assert target["track_breaks"] == 1  # lost once; coming back in another row is the same break
    far = tracking_errors(t, truth, estimates, valid, gate_m=2.0)
    assert far["targets_never_tracked"] == 1 and far["position_rms_max_m"] is None


def test_two_ships_passing_close_keep_their_own_tracks_in_the_figures():
    t = np.arange(21.0)
    truth = np.zeros((21, 2, 5))
    truth[:, 0, 0], truth[:, 1, 0] = 10.0 * t, 200.0 - 10.0 * t  # they pass each other at t = 10
    truth[:, 0, 2], truth[:, 1, 2] = 10.0, -10.0
    estimates = truth.copy()
    estimates[:, :, 0] += np.array([15.0, -15.0])  # each track lags its ship by 15 m
    result = tracking_errors(t, truth, estimates, np.ones((21, 2)), gate_m=100.0)
    assert result["track_breaks"] == 0
    assert result["position_rms_max_m"] == pytest.approx(15.0)
    assert result["velocity_rms_max_mps"] == pytest.approx(0.0)


class _Connection:
    def __init__(self, text):
        source, target = (part.strip() for part in text.split("->"))
        self.source, self.source_port = source.split(".")
        self.target, self.target_port = target.split(".")


class _Named:
    def __init__(self, name, outputs, estimates=False):
        self.name, self.output_names, self.estimates_targets = name, outputs, estimates


class _Cosim:
    def __init__(self, participants):
        self.participants = participants

    def participant(self, name):
        return next(p for p in self.participants if p.name == name)


def test_true_obstacles_are_the_traffic_behind_a_tracker():
    traffic, tracker = _Named("traffic", ("obstacles", "targets")), _Named("trk", ("obstacles",), True)
    scenario = type("S", (), {"connections": [_Connection("trk.obstacles -> ctrl.obstacles"),
                                              _Connection("traffic.targets -> ais.targets")]})
    cosim = _Cosim([tracker, traffic])
    assert true_obstacles_column(scenario, cosim) == "traffic.obstacles"
    assert estimated_obstacles_participant(scenario, cosim) == "trk"
    direct = type("S", (), {"connections": [_Connection("traffic.obstacles -> ctrl.obstacles")]})
    assert true_obstacles_column(direct, cosim) == "traffic.obstacles"
    assert estimated_obstacles_participant(direct, cosim) is None
    assert TrackerParticipant.estimates_targets is True


@pytest.mark.slow
def test_ais_encounter_is_judged_on_the_true_tracks_and_reports_tracker_errors(tmp_path):
    base = REPO / "scenarios" / "encounter_nmpc_ais.toml"
    report = run_scenario(base, tmp_path, progress=False, overrides={"simulation.steps": 120})
    assert report.ok, report.reason
    summary = json.loads((report.folder / "summary.json").read_text())
    frame = pd.read_parquet(report.folder / "timeseries.parquet")
    own = frame[["ship.x", "ship.y"]].to_numpy()
    truth = frame[["traffic.obstacles[0,0]", "traffic.obstacles[0,1]"]].to_numpy()
    (obstacle,) = summary["analyses"]["encounter"]["obstacles"]
    assert obstacle["min_distance_nm"] == pytest.approx(np.min(np.hypot(*(own - truth).T)) / NM, rel=1e-9)
    tracking = summary["analyses"]["tracking"]
    assert tracking["targets_never_tracked"] == 0 and 0.0 < tracking["position_rms_max_m"] < 30.0
