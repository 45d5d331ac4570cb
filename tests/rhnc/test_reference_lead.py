"""A timed reference that waits for its ship: ``max_lead_nm`` of the reference_path participant."""

from pathlib import Path

import numpy as np
import pytest

from orchestrator.errors import ModelError, ScenarioError
from orchestrator.participant import BuildContext
from rhnc.navigation.reference_participant import ReferencePathParticipant, path_progress_m

NM = 1852.0
KNOT = NM / 3600.0
DT = 60.0


def context():
    return BuildContext("baseline.toml: participants.route", Path("."), DT, 0.0, 1e5)


def route(**extra):
    options = {"waypoints_nm": [[0.0, 0.0], [0.0, 10.0], [5.0, 10.0]], "speed_kn": 12.0, "horizon_steps": 3, **extra}
    return ReferencePathParticipant.from_options("route", options, context())


def progress_of(reference):
    """The published virtual ship's arc length [m] along the route (first point)."""
    x, y = reference[0, 1], reference[0, 2]
    return y if x == 0.0 and y <= 10 * NM else 10 * NM + x


def test_progress_along_a_path_takes_the_nearest_point_and_never_goes_back():
    waypoints = np.array([[0.0, 0.0], [0.0, 10.0], [5.0, 10.0]]) * NM
    assert path_progress_m([0.3 * NM, 4.0 * NM], waypoints) == pytest.approx(4.0 * NM)
    assert path_progress_m([2.0 * NM, 10.5 * NM], waypoints) == pytest.approx(12.0 * NM)
    assert path_progress_m([0.0, 1.0 * NM], waypoints, at_least_m=3.0 * NM) == pytest.approx(3.0 * NM)


def test_without_a_lead_the_virtual_ship_keeps_its_schedule_whatever_the_ship_does():
    participant = route()
    participant.setup(0.0, {})
    for k in range(1, 31):
        reference = participant.step(k * DT, DT, {"x": 0.0, "y": 0.0})["reference"]
    assert progress_of(reference) == pytest.approx(30 * DT * 12 * KNOT)  # 6 nm ahead of a ship that stayed


def test_with_a_lead_the_virtual_ship_waits_for_a_ship_that_cannot_keep_up_and_it_ends_within_the_lead():
    participant = route(max_lead_nm=0.25)
    assert participant.input_names == ("x", "y")
    participant.setup(0.0, {})
    ship = 0.0
    for k in range(1, 121):  # the ship makes half the schedule's speed
        ship = min(ship + 6 * KNOT * DT, 15 * NM)
        position = {"x": 0.0, "y": ship} if ship <= 10 * NM else {"x": ship - 10 * NM, "y": 10 * NM}
        reference = participant.step(k * DT, DT, position)["reference"]
        assert progress_of(reference) <= ship + 0.25 * NM + 1e-6
        assert reference[0, 4] == pytest.approx(12 * KNOT) or progress_of(reference) == pytest.approx(15 * NM)
    assert progress_of(reference) - ship == pytest.approx(0.25 * NM)  # 12 nm of 15 sailed, the lead ahead


def test_a_lead_needs_the_ships_position_and_a_path_of_waypoints():
    participant = route(max_lead_nm=0.25)
    participant.setup(0.0, {})
    with pytest.raises(ModelError, match=r"route: option 'max_lead_nm' needs the inputs x, y connected"):
        participant.step(DT, DT, {})
    with pytest.raises(ScenarioError, match=r"participants.route: option 'max_lead_nm' needs a path of waypoints"):
        ReferencePathParticipant.from_options("route", {"start_nm": [0, 0], "course_deg": 0, "speed_kn": 12,
                                                        "max_lead_nm": 0.25}, context())
    with pytest.raises(ScenarioError, match=r"participants.route: option 'max_lead_nm' must be > 0"):
        route(max_lead_nm=0.0)
