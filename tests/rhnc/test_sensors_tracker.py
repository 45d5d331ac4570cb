"""AIS and radar sensor participants and the target tracker, on constructed truths."""

import math
from pathlib import Path

import numpy as np
import pytest

from orchestrator.errors import ScenarioError
from orchestrator.participant import BuildContext
from rhnc.encounters.sensors import AisParticipant, RadarParticipant, reporting_interval_s
from rhnc.encounters.target_motion import Manoeuvre, ScriptedTarget
from rhnc.encounters.tracker import VACANT_OFFSET_M, TrackerParticipant

NM = 1852.0
KNOT = NM / 3600.0
QUIET = {"position_sigma_m": 0.0, "speed_sigma_kn": 0.0, "course_sigma_deg": 0.0, "dropout_probability": 0.0,
         "gaps_per_hour": 0.0, "latency_s": 0.0, "latency_jitter_s": 0.0}


def build(kind, options, step=1.0):
    return kind.from_options(kind.__name__, options, BuildContext("s.toml: participants.sensor", Path("."), step,
                                                                  0.0, 3600.0))


def straight(speed_kn, course_deg=0.0, start=(0.0, 0.0)):
    c = math.radians(course_deg)
    v = np.array([math.cos(c), math.sin(c)]) * speed_kn * KNOT
    return lambda t: np.r_[np.asarray(start) + v * t, v, NM][None, :]


def run_ais(options, truth, duration_s=600.0, step=1.0):
    """Every new report (received time, report) of target row 0."""
    ais = build(AisParticipant, options, step)
    ais.setup(0.0, {"targets": truth(0.0)})
    received, last = [], -math.inf
    for t in np.arange(step, duration_s + step / 2, step):
        report = ais.step(float(t), step, {"targets": truth(float(t))})["reports"][0]
        if report[0] == 1.0 and report[1] != last:
            received.append((float(t), report[1:].copy()))
            last = report[1]
    return ais, received


def test_class_a_reporting_intervals_follow_itu_r_m1371():
    assert reporting_interval_s(10.0, False) == 10.0
    assert reporting_interval_s(10.0, True) == pytest.approx(10.0 / 3.0)
    assert reporting_interval_s(18.0, False) == 6.0
    assert reporting_interval_s(18.0, True) == 2.0
    assert reporting_interval_s(25.0, False) == 2.0
    assert reporting_interval_s(2.0, False, at_anchor=True) == 180.0


@pytest.mark.parametrize("speed_kn, interval_s", [(10.0, 10.0), (18.0, 6.0), (24.0, 2.0)])
def test_ais_reports_at_the_interval_of_the_speed_with_true_positions_when_quiet(speed_kn, interval_s):
    truth = straight(speed_kn, 45.0)
    _, received = run_ais(QUIET, truth, step=0.5)
    stamps = np.array([report[0] for _, report in received])
    np.testing.assert_allclose(np.diff(stamps), interval_s, atol=1e-6)
    for _, report in received:
        np.testing.assert_allclose(report[1:3], truth(report[0])[0, :2], atol=1e-6)
        assert report[3] == pytest.approx(speed_kn * KNOT, abs=0.05 * KNOT)
        assert math.degrees(report[4]) == pytest.approx(45.0, abs=0.05)


def test_ais_reports_faster_while_the_ship_turns():
    target = ScriptedTarget([0.0, 0.0], [18 * KNOT, 0.0], [Manoeuvre(100.0, math.radians(90), math.radians(0.5),
                                                                     None, 0.02)], NM, 600.0)
    _, received = run_ais(QUIET, lambda t: target.state(t)[None, :], duration_s=400.0)
    stamps = np.array([report[0] for _, report in received])
    turning = (stamps[1:] > 110) & (stamps[1:] < 270)
    assert np.all(np.diff(stamps)[turning] == pytest.approx(2.0))
    assert np.all(np.diff(stamps)[stamps[1:] > 300] == pytest.approx(6.0))


def test_ais_latency_delays_reception_but_keeps_the_time_stamp():
    _, received = run_ais({**QUIET, "latency_s": 3.0, "latency_jitter_s": 2.0}, straight(18.0))
    delays = np.array([t - report[0] for t, report in received])
    assert delays.min() >= 3.0 - 1e-9 and delays.max() <= 5.0 + 1.0  # + one step of the receiver's sampling
    assert delays.mean() > 3.5


def test_ais_a_late_older_report_does_not_replace_a_newer_one():
    _, received = run_ais({**QUIET, "latency_s": 0.0, "latency_jitter_s": 30.0}, straight(18.0), step=1.0)
    stamps = np.array([report[0] for _, report in received])
    assert np.all(np.diff(stamps) > 0) and len(stamps) > 50


def test_ais_noise_dropouts_and_gaps_at_their_set_levels():
    truth = straight(10.0)
    ais, received = run_ais({**QUIET, "position_sigma_m": 10.0, "dropout_probability": 0.3}, truth,
                            duration_s=20000.0, step=2.0)
    errors = np.array([report[1:3] - truth(report[0])[0, :2] for _, report in received])
    assert np.std(errors) == pytest.approx(10.0, rel=0.1)
    assert ais.lost / ais.sent == pytest.approx(0.3, abs=0.04)
    ais, received = run_ais({**QUIET, "gaps_per_hour": 4.0, "gap_duration_s": 120.0}, truth, duration_s=20000.0)
    gaps = np.diff([report[0] for _, report in received])
    assert gaps.max() >= 120.0 and np.sum(gaps > 100.0) >= 5
    assert np.all((np.abs(gaps - 10.0) < 1e-6) | (gaps >= 120.0))


def test_ais_same_seed_same_series_other_seed_other_series():
    options = {"seed": 7}
    first = [report for _, report in run_ais(options, straight(18.0))[1]]
    again = [report for _, report in run_ais(options, straight(18.0))[1]]
    other = [report for _, report in run_ais({"seed": 8}, straight(18.0))[1]]
    np.testing.assert_array_equal(np.array(first), np.array(again))
    assert len(first) != len(other) or not np.array_equal(np.array(first), np.array(other))


def test_radar_detects_within_range_with_range_and_bearing_noise():
    radar = build(RadarParticipant, {"seed": 3, "range_sigma_m": 50.0, "bearing_sigma_deg": 1.0,
                                     "detection_range_nm": 6.0, "detection_probability": 1.0})
    targets = np.array([[3 * NM, 4 * NM, 0, 0, NM], [0.0, -7 * NM, 0, 0, NM], [-2 * NM, 0.0, 0, 0, NM]])
    radar.setup(0.0, {"x": 0.0, "y": 0.0, "targets": targets})
    ranges, bearings = [], []
    for k in range(2000):
        rows = radar.step(float(k), 1.0, {"x": 0.0, "y": 0.0, "targets": targets})["detections"]
        assert rows[-1, 0] == 0.0 and np.all(rows[:2, 0] == 1.0)  # the one at 7 nm: out of range, never seen
        rows = rows[:, 1:]
        np.testing.assert_array_equal(np.argsort(rows[:2, 2]), [0, 1])  # sorted by bearing
        first = rows[np.argmin(np.abs(rows[:2, 2] - math.atan2(4, 3)))]
        ranges.append(first[1])
        bearings.append(first[2])
    assert np.mean(ranges) == pytest.approx(5 * NM, abs=5.0)
    assert np.std(ranges) == pytest.approx(50.0, rel=0.1)
    assert np.degrees(np.std(bearings)) == pytest.approx(1.0, rel=0.1)


def test_radar_same_seed_same_series():
    targets = np.array([[3 * NM, 4 * NM, 0, 0, NM], [1 * NM, -2 * NM, 0, 0, NM]])
    series = []
    for seed in (5, 5, 6):
        radar = build(RadarParticipant, {"seed": seed})
        radar.setup(0.0, {"x": 0.0, "y": 0.0, "targets": targets})
        series.append(np.array([radar.step(float(k), 1.0, {"x": 0.0, "y": 0.0, "targets": targets})["detections"]
                                for k in range(1, 50)]))
    np.testing.assert_array_equal(series[0], series[1])
    assert not np.array_equal(series[0], series[2])


def test_sensor_option_errors_name_the_key():
    with pytest.raises(ScenarioError, match=r"'participants.sensor.options.dropout_probability' must be a probability"):
        build(AisParticipant, {"dropout_probability": 1.5})
    with pytest.raises(ScenarioError, match=r"unknown key 'participants.sensor.options.noise_m'"):
        build(AisParticipant, {"noise_m": 1.0})
    with pytest.raises(ScenarioError, match=r"'participants.sensor.options.detection_range_nm' must be positive"):
        build(RadarParticipant, {"detection_range_nm": 0.0})
    with pytest.raises(ScenarioError, match=r"'participants.sensor.options.detection_probability' must be a probability"):
        build(RadarParticipant, {"detection_probability": 2.0})
    with pytest.raises(ScenarioError, match=r"missing key 'participants.sensor.options.target_radius_nm'"):
        build(TrackerParticipant, {})


def track_run(truths, tracker_options, ais_options=None, radar_options=None, duration_s=1800.0, step=5.0,
              own=lambda t: (0.0, 0.0), break_after=None):
    """Drive sensors and tracker; return times, true rows (t, n, 5), published rows, valid flags, tracker."""
    ais = build(AisParticipant, ais_options, step) if ais_options is not None else None
    radar = build(RadarParticipant, radar_options, step) if radar_options is not None else None
    tracker = build(TrackerParticipant, tracker_options, step)
    times = np.arange(0.0, duration_s + step / 2, step)
    truth_rows, published, valid = [], [], []
    for k, t in enumerate(times):
        truth = np.vstack([f(t) for f in truths])
        x, y = own(t)
        inputs = {"x": x, "y": y}
        for sensor, port, source in ((ais, "ais_reports", {"targets": truth}),
                                     (radar, "radar_detections", {"x": x, "y": y, "targets": truth})):
            if sensor is not None:
                out = sensor.setup(t, source) if k == 0 else sensor.step(t, step, source)
                inputs[port] = next(iter(out.values()))
        if break_after is not None and t > break_after[0] and t < break_after[1]:
            inputs.pop("ais_reports", None)
        out = tracker.setup(t, inputs) if k == 0 else tracker.step(t, step, inputs)
        truth_rows.append(truth)
        published.append(out["obstacles"])
        valid.append(out["track_valid"])
    return times, truth_rows, published, valid, tracker


def test_ais_tracker_confirms_after_m_hits_and_estimates_within_the_noise():
    truth = straight(12.0, 30.0, (2 * NM, 1 * NM))
    times, truths, published, valid, tracker = track_run(
        [truth], {"target_radius_nm": 0.5, "confirm_hits": 3}, {"seed": 1, "latency_s": 2.0})
    first = next(k for k, v in enumerate(valid) if len(v) and v[0] == 1)
    assert 15.0 <= times[first] <= 45.0  # three reports at 10 s, the first within 10 s, + latency
    errors = np.array([p[0, :2] - tr[0, :2] for p, tr in zip(published[first:], truths[first:])])
    speed_errors = np.array([p[0, 2:4] - tr[0, 2:4] for p, tr in zip(published[first:], truths[first:])])
    assert np.sqrt(np.mean(errors ** 2)) < 6.0  # filtered: well below the reports' 10 m per axis
    assert np.sqrt(np.mean(speed_errors ** 2)) < 0.15  # one report: 0.1 m/s along, 0.2 m/s across
    assert published[-1][0, 4] == pytest.approx(0.5 * NM)
    assert tracker.summary() == {"tracks_initiated": 1, "tracks_confirmed": 1, "tracks_deleted": 0}


def test_manoeuvring_target_needs_the_process_noise_of_a_turning_ship():
    target = ScriptedTarget([3 * NM, 0.0], [18 * KNOT, 0.0], [Manoeuvre(600.0, math.radians(90), math.radians(0.5),
                                                                       None, 0.02)], NM, 1800.0)
    def truth(t):
        return target.state(t)[None, :]
    peaks = {}
    for q in (0.05, 0.0005):
        times, truths, published, valid, _ = track_run([truth], {"target_radius_nm": 1.0, "process_noise_mps2": q},
                                                       {"seed": 2}, duration_s=1200.0)
        turning = (times > 600) & (times < 900)
        peaks[q] = max(float(np.hypot(*(published[k][0, :2] - truths[k][0, :2]))) for k in np.nonzero(turning)[0])
    assert peaks[0.05] < 60.0
    assert peaks[0.0005] > 2 * peaks[0.05]


def test_radar_tracks_of_two_crossing_ships_keep_their_rows():
    north = straight(15.0, 0.0, (-3 * NM, 0.3 * NM))
    east = straight(15.0, 90.0, (0.3 * NM, -3 * NM))
    times, truths, published, valid, tracker = track_run(
        [north, east], {"target_radius_nm": 1.0}, radar_options={"seed": 4}, duration_s=1200.0)
    assert len(valid[-1]) == 2 and np.all(valid[-1] == 1)
    # each row follows one ship through the crossing (at t = 720 s both are near the origin)
    rows = np.array([p[:2, :2] if len(p) >= 2 else np.full((2, 2), np.nan) for p in published])
    truth = np.array(truths)[:, :, :2]
    settled = times > 120
    row_of_north = int(np.argmin(np.hypot(*(rows[np.nonzero(settled)[0][0]] - truth[np.nonzero(settled)[0][0], 0]).T)))
    error_north = np.hypot(*(rows[settled, row_of_north] - truth[settled, 0]).T)
    error_east = np.hypot(*(rows[settled, 1 - row_of_north] - truth[settled, 1]).T)
    assert error_north.max() < 250.0 and error_east.max() < 250.0
    assert tracker.summary()["tracks_deleted"] == 0


def test_track_deleted_after_silence_its_row_vacant_and_a_new_track_takes_a_new_slot():
    truth = straight(10.0, 0.0, (1 * NM, 0.0))
    times, truths, published, valid, tracker = track_run(
        [truth], {"target_radius_nm": 1.0, "delete_after_s": 60.0, "max_tracks": 2}, QUIET,
        duration_s=900.0, break_after=(300.0, 500.0), own=lambda t: (10.0, 20.0))
    at = {float(t): k for k, t in enumerate(times)}
    assert valid[at[350.0]][0] == 1  # coasting inside the deletion time
    assert len(valid[at[400.0]]) == 1 and valid[at[400.0]][0] == 0
    np.testing.assert_allclose(published[at[400.0]][0], [10.0 + VACANT_OFFSET_M, 20.0, 0, 0, 0])
    np.testing.assert_array_equal(valid[-1], [0, 1])  # the new track in a fresh slot, row 0 vacant
    np.testing.assert_allclose(published[-1][1, :2], truths[-1][0, :2], atol=1.0)
    assert tracker.summary()["tracks_deleted"] == 1


def test_static_obstacles_pass_through_after_the_tracks():
    tracker = build(TrackerParticipant, {"target_radius_nm": 1.0})
    island = np.array([[5 * NM, 5 * NM, 0.0, 0.0, 2 * NM]])
    out = tracker.setup(0.0, {"static_obstacles": island})
    np.testing.assert_array_equal(out["obstacles"], island)
    assert out["confirmed_tracks"] == 0.0


def test_a_new_track_takes_the_slot_vacated_longest_ago():
    tracker = build(TrackerParticipant, {"target_radius_nm": 1.0, "max_tracks": 3})

    class Stub:
        slot = None

    tracks = [Stub() for _ in range(4)]
    for track in tracks[:3]:
        tracker._assign_slot(track, 0.0)
    for slot, time in ((2, 200.0), (0, 100.0)):
        tracker._slots[slot] = None
        tracker._vacated_s[slot] = time
    tracker._assign_slot(tracks[3], 300.0)
    assert tracks[3].slot == 0
