"""Participant.require_inputs: one message for a port a participant cannot step without."""

import pytest

from orchestrator.errors import ModelError
from rhnc.encounters.sensors import RadarOptions, RadarParticipant
from rhnc.encounters.separation_watch import SeparationWatch


@pytest.mark.parametrize("given, expected", [({"x": 0.0}, "inputs 'y', 'targets' must be connected"),
                                             ({"x": 0.0, "y": 0.0}, "input 'targets' must be connected")])
def test_every_missing_input_is_named_in_one_line(given, expected):
    radar = RadarParticipant("radar", RadarOptions())
    radar.setup(0.0, {})
    with pytest.raises(ModelError) as error:
        radar.step(0.0, 20.0, given)
    assert str(error.value) == f"participant 'radar': {expected}"


def test_the_separation_watch_names_its_missing_obstacles():
    watch = SeparationWatch("watch", 10.0, 600.0, 20.0)
    watch.setup(0.0, {})
    with pytest.raises(ModelError, match="participant 'watch': input 'obstacles' must be connected"):
        watch.step(0.0, 20.0, {"x": 0.0, "y": 0.0})


def test_a_participant_with_every_input_connected_steps():
    radar = RadarParticipant("radar", RadarOptions())
    radar.setup(0.0, {})
    assert "detections" in radar.step(0.0, 20.0, {"x": 0.0, "y": 0.0, "targets": []})
