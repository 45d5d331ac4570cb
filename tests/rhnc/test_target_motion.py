"""Targets as agents: scripted manoeuvres and recorded tracks (CSV and AIS NMEA) in the traffic participant."""

import math
import re
from pathlib import Path

import numpy as np
import pytest

from orchestrator.errors import ScenarioError
from orchestrator.participant import BuildContext
from rhnc.encounters.traffic import TrafficParticipant

NM = 1852.0
KNOT = NM / 3600.0


def traffic(targets, folder=Path("."), stop_s=3600.0):
    context = BuildContext("s.toml: participants.traffic", folder, 5.0, 0.0, stop_s)
    participant = TrafficParticipant.from_options("traffic", {"targets": targets}, context)
    participant.setup(0.0, {})
    return participant


def test_scripted_course_change_turns_at_its_rate_and_then_holds_the_new_course():
    target = traffic([{"start_nm": [0.0, 0.0], "velocity_kn": [10.0, 0.0], "radius_nm": 0.5,
                       "manoeuvres": [{"at_s": 600, "course_change_deg": 90, "turn_rate_deg_s": 0.5}]}])
    before = target.obstacles_at(590.0)[0]
    np.testing.assert_allclose(before, [590 * 10 * KNOT, 0.0, 10 * KNOT, 0.0, 0.5 * NM], atol=1e-6)
    halfway = target.obstacles_at(690.0)[0]  # 90 s at 0.5 deg/s: 45 deg to starboard
    assert math.degrees(math.atan2(halfway[3], halfway[2])) == pytest.approx(45.0, abs=0.6)
    after = target.obstacles_at(1200.0)[0]
    np.testing.assert_allclose(after[2:4], [0.0, 10 * KNOT], atol=1e-9)
    # the arc of radius v / r joins the two straight legs
    radius = 10 * KNOT / math.radians(0.5)
    np.testing.assert_allclose(after[:2], [600 * 10 * KNOT + radius, radius + (1200 - 780) * 10 * KNOT], rtol=2e-3)


def test_scripted_speed_change_at_its_acceleration():
    target = traffic([{"start_nm": [0.0, 0.0], "velocity_kn": [0.0, 12.0], "radius_nm": 0.5,
                       "manoeuvres": [{"at_s": 100, "speed_kn": 4, "acceleration_mps2": 0.04}]}])
    slowing = target.obstacles_at(150.0)[0]
    assert slowing[3] == pytest.approx(12 * KNOT - 0.04 * 50, abs=0.05)
    assert target.obstacles_at(1000.0)[0][3] == pytest.approx(4 * KNOT)


def write_csv(folder: Path, text: str, name="track.csv") -> Path:
    path = folder / name
    path.write_text(text)
    return path


def test_recorded_csv_interpolates_between_reports_and_sails_on_after_the_last(tmp_path):
    write_csv(tmp_path, "time_s,north_nm,east_nm\n100,1.0,0.0\n160,1.0,0.2\n220,1.1,0.2\n")
    target = traffic([{"track_file": "track.csv", "radius_nm": 0.3}], tmp_path)
    np.testing.assert_allclose(target.obstacles_at(30.0)[0], [NM, 0.1 * NM, 0.0, 0.2 * NM / 60, 0.3 * NM])
    np.testing.assert_allclose(target.obstacles_at(90.0)[0][:4], [1.05 * NM, 0.2 * NM, 0.1 * NM / 60, 0.0])
    np.testing.assert_allclose(target.obstacles_at(180.0)[0][:2], [1.2 * NM, 0.2 * NM])  # dead reckoning on


def test_recorded_csv_time_offset_and_iso_times(tmp_path):
    write_csv(tmp_path, "time,north_nm,east_nm\n2024-05-01T10:00:00Z,0,0\n2024-05-01T10:01:00Z,0.1,0\n")
    target = traffic([{"track_file": "track.csv", "radius_nm": 0.3, "time_offset_s": -60.0 + 1714557600}],
                     tmp_path)
    np.testing.assert_allclose(target.obstacles_at(90.0)[0][:2], [0.05 * NM, 0.0], atol=1e-6)


def nmea_lines(mmsi, points, first_time=1_700_000_000.0, interval_s=10.0):
    from pyais import encode_dict

    lines = []
    for k, (lat, lon) in enumerate(points):
        message = {"type": 1, "mmsi": mmsi, "lat": lat, "lon": lon, "speed": 12.0, "course": 90.0}
        try:
            sentence = encode_dict(message, talker_id="AI")[0]
        except ValueError:  # pyais before 3 names the talker in full
            sentence = encode_dict(message, talker_id="AIVDM")[0]
        lines.append(f"{first_time + k * interval_s:.1f} {sentence}")
    return lines


def test_nmea_replay_decodes_with_pyais_and_matches_the_same_track_as_csv(tmp_path):
    points = [(57.0, 3.0), (57.0, 3.001), (57.0005, 3.002)]
    other = nmea_lines(999, [(56.0, 2.0), (56.0, 2.1)], first_time=1_700_000_005.0)
    (tmp_path / "log.nmea").write_text("\n".join(nmea_lines(211000001, points) + other) + "\n")
    write_csv(tmp_path, "mmsi,time_s,lat,lon\n" + "".join(
        f"211000001,{10 * k},{lat},{lon}\n" for k, (lat, lon) in enumerate(points)) + "5,0,1,1\n5,3,1,1\n")
    common = {"radius_nm": 0.3, "mmsi": 211000001, "origin_deg": [57.0, 3.0]}
    nmea = traffic([{"track_file": "log.nmea", **common}], tmp_path)
    table = traffic([{"track_file": "track.csv", **common}], tmp_path)
    for t in (0.0, 5.0, 15.0, 40.0):
        np.testing.assert_allclose(nmea.obstacles_at(t)[0], table.obstacles_at(t)[0], atol=0.2)  # 1e-4 arcmin
    assert nmea.obstacles_at(10.0)[0][1] == pytest.approx(0.001 * math.radians(1) * 6.39e6 * math.cos(
        math.radians(57.0)), rel=0.01)


@pytest.mark.parametrize("content, entry, message", [
    (None, {}, r"s.toml: participants.traffic.targets\[0\]: 'track_file' .*missing.csv not found"),
    ("t,north_nm,east_nm\n0,0,0\n", {}, r"track.csv: missing column 'time_s'"),
    ("time_s,north_nm\n0,0\n", {}, r"track.csv: missing columns 'north_nm', 'east_nm'"),
    ("time_s,north_nm,east_nm\n0,0,0\n10,x,0\n", {}, r"track.csv: line 3: column 'north_nm' must be a finite"),
    ("time_s,north_nm,east_nm\n0,0,0\n", {}, r"track.csv: fewer than two position reports"),
    ("time_s,lat,lon\n0,57,3\n10,57,3.1\n", {}, r"track.csv gives latitude and longitude; set 'origin_deg'"),
    ("time_s,north_nm,east_nm\n0,0,0\n10,1,0\n", {"mmsi": 5}, r"option 'mmsi' given but the file has no 'mmsi'"),
    ("time_s,north_nm,east_nm\n0,0,0\n10,1,0\n", {"mmsi": -5}, r"targets\[0\]: 'mmsi' must be a positive integer"),
    ("time_s,north_nm,east_nm\n0,0,0\n10,1,0\n", {"velocity_kn": [1, 1]}, r"targets\[0\]: unknown option "
                                                                            r"'velocity_kn'"),
    ("time_s,north_nm,east_nm\n0,0,0\n10,1,0\n", {"origin_deg": [95, 0]}, r"'origin_deg' must be \[lat, lon\]"),
])
def test_recorded_track_errors_name_the_file_and_the_key(tmp_path, content, entry, message):
    name = "missing.csv" if content is None else "track.csv"
    if content is not None:
        write_csv(tmp_path, content)
    with pytest.raises(ScenarioError, match=message):
        traffic([{"track_file": name, "radius_nm": 0.3, **entry}], tmp_path)


def test_nmea_errors_name_the_line(tmp_path):
    lines = nmea_lines(1, [(57.0, 3.0), (57.0, 3.1)])
    (tmp_path / "a.nmea").write_text(lines[0] + "\n" + lines[1].split(" ", 1)[1] + "\n")
    with pytest.raises(ScenarioError, match=r"a.nmea: line 2: each sentence must be led by its reception time"):
        traffic([{"track_file": "a.nmea", "radius_nm": 0.3, "origin_deg": [57, 3]}], tmp_path)
    (tmp_path / "b.nmea").write_text(lines[0] + "\n1700000020 !AIVDM,1,1,,A,zzzz,0*00\n")
    with pytest.raises(ScenarioError, match=r"b.nmea: line 2: not a decodable AIS sentence"):
        traffic([{"track_file": "b.nmea", "radius_nm": 0.3, "origin_deg": [57, 3]}], tmp_path)
    (tmp_path / "c.nmea").write_text("\n".join(lines + nmea_lines(2, [(57.0, 3.0), (57.0, 3.1)])) + "\n")
    with pytest.raises(ScenarioError, match=r"c.nmea: position reports from 2 ships .*set the target's 'mmsi'"):
        traffic([{"track_file": "c.nmea", "radius_nm": 0.3, "origin_deg": [57, 3]}], tmp_path)


@pytest.mark.parametrize("manoeuvres, message", [
    ([], r"targets\[0\].manoeuvres: must be a non-empty list"),
    ([{"at_s": 10}], r"manoeuvres\[0\]: give 'course_change_deg' and/or 'speed_kn'"),
    ([{"at_s": 10, "course_change_deg": 200}], r"manoeuvres\[0\]: 'course_change_deg' must be within"),
    ([{"at_s": 10, "speed_kn": 3, "acceleration_mps2": 0}], r"manoeuvres\[0\]: 'acceleration_mps2' must be > 0"),
    ([{"at_s": -1, "speed_kn": 3}], r"manoeuvres\[0\]: 'at_s' must be >= 0"),
    ([{"at_s": 10, "speed_kn": 3}, {"at_s": 5, "speed_kn": 4}], r"manoeuvres\[1\]: 'at_s' = 5 is before"),
    ([{"at_s": 10, "turn_deg": 3}], r"manoeuvres\[0\]: unknown option 'turn_deg'"),
])
def test_manoeuvre_errors_name_the_key(manoeuvres, message):
    with pytest.raises(ScenarioError, match=message):
        traffic([{"start_nm": [0, 0], "velocity_kn": [10, 0], "radius_nm": 0.5, "manoeuvres": manoeuvres}])
    with pytest.raises(ScenarioError, match=r"'manoeuvres' goes with 'start_nm'"):
        traffic([{"waypoints_nm": [[0, 0], [1, 0]], "speed_kn": 5, "radius_nm": 0.5, "manoeuvres": manoeuvres}])


@pytest.mark.parametrize("edit, message", [
    (("targets = [{ start_nm = [7.5, 0.0], velocity_kn = [-18.0, 0.0], radius_nm = 1.0 }]",
      "targets = [{ track_file = 'gone.csv', radius_nm = 1.0 }]"), r"targets\[0\]: 'track_file' .*gone.csv not found"),
    (("[participants.ais.options]\nseed = 1", "[participants.ais.options]\nseed = 1\ndropout_probability = 2"),
     r"'participants.ais.options.dropout_probability' must be a probability"),
])
def test_cli_refuses_bad_traffic_input_in_one_line_with_exit_2_and_writes_nothing(tmp_path, capsys, edit, message):
    from orchestrator.cli import main

    repo = Path(__file__).resolve().parents[2]
    text = (repo / "scenarios" / "encounter_nmpc_ais.toml").read_text()
    assert edit[0] in text
    scenario = tmp_path / "bad.toml"
    scenario.write_text(text.replace(edit[0], edit[1]))
    results = tmp_path / "results"
    assert main(["run", str(scenario), "--results", str(results), "--no-progress"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"error: {scenario}") and re.search(message, err[0])
    assert not results.exists() or not any(results.rglob("*"))
