"""Imazu's 22 problems: the published geometry, the classes it implies, and the JSON round trip."""

import math

import numpy as np
import pytest

from rhnc.encounters.colregs import classify
from rhnc.encounters.imazu import PROBLEMS, problem_geometry, write_situations
from rhnc.encounters.traffic_situation import load_traffic_situation

NM = 1852.0
KN = NM / 3600.0


def _velocity(ship):
    c = math.radians(ship["course_deg"])
    return np.array([math.cos(c), math.sin(c)]) * ship["speed_kn"]


def test_one_to_three_targets():
    counts = [len(PROBLEMS[n]) for n in range(1, 23)]
    assert counts == [1] * 4 + [2] * 8 + [3] * 10


@pytest.mark.parametrize("number", range(1, 23))
def test_every_ship_reaches_the_common_point_at_the_meeting_time(number):
    ships = problem_geometry(number, tcpa_min=25.0)
    meeting = [np.asarray(s["start_nm"]) + _velocity(s) * 25.0 / 60.0 for s in ships]
    for point in meeting:
        np.testing.assert_allclose(point, [7.5, 0.0], atol=1e-9)


@pytest.mark.parametrize("number, classes", [
    (1, ["head_on"]), (2, ["crossing_give_way"]), (3, ["overtaking"]), (4, ["crossing_stand_on"]),
    (13, ["head_on", "crossing_stand_on", "crossing_stand_on"]),
])
def test_classes_at_the_start(number, classes):
    own, *targets = problem_geometry(number)
    found = [classify((0.0, 0.0), 0.0, own["speed_kn"] * KN, np.asarray(t["start_nm"]) * NM,
                      _velocity(t) * KN).encounter_class for t in targets]
    assert found == classes


def test_written_files_load_back_to_the_same_plane(tmp_path):
    paths = write_situations(tmp_path)
    assert len(paths) == 22
    situation = load_traffic_situation(paths[12])  # problem 13
    ships = problem_geometry(13)
    assert situation.title == "imazu-13" and len(situation.targets) == 3
    for target, ship in zip(situation.targets, ships[1:]):
        np.testing.assert_allclose(target.start_nm, ship["start_nm"], atol=1e-6)  # < 2 mm
        assert target.course_deg == ship["course_deg"] and target.speed_kn == ship["speed_kn"]


def test_unknown_problem():
    with pytest.raises(ValueError, match="problem 23 does not exist"):
        problem_geometry(23)
