"""The split of a passage's saving: its parts add up to the saving, and each part is the one its name says."""

import importlib.util
import sys
from pathlib import Path

import pytest

from orchestrator.geometry import NM
from rhnc.ship.energy import EnergyParameters

SCRIPT = Path(__file__).resolve().parents[1] / "scripts" / "passage_decomposition.py"


@pytest.fixture(scope="module")
def script():
    spec = importlib.util.spec_from_file_location("passage_decomposition_under_test", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    yield module
    del sys.modules[spec.name]


class Path_:
    """A sailed path whose weather adds ``per_nm_at(speed)`` USD (and kg/1000) per nm at one speed."""

    def __init__(self, script, length_nm, arrival_s, per_nm_at, sailed_extra=0.0):
        self.script, self.energy = script, EnergyParameters()
        self.length_m, self.arrival_s, self.per_nm_at = length_nm * NM, arrival_s, per_nm_at
        calm = script.calm_cost(self.length_m, self.on_time_speed_mps(), self.energy)
        one = self.one_speed(self.on_time_speed_mps())
        self.sailed = (one[0] + sailed_extra, one[1] + sailed_extra / 1000.0)
        self.calm = calm

    def on_time_speed_mps(self):
        return self.length_m / self.arrival_s

    def weather_per_nm(self, speed_mps):
        return self.per_nm_at(speed_mps), self.per_nm_at(speed_mps) / 1000.0

    def one_speed(self, speed_mps):
        calm = self.script.calm_cost(self.length_m, speed_mps, self.energy)
        extra = self.weather_per_nm(speed_mps)
        return calm[0] + extra[0] * self.length_m / NM, calm[1] + extra[1] * self.length_m / NM


def test_the_parts_add_up_to_the_saving(script):
    baseline = Path_(script, 84.0, 19680.0, lambda v: 5.0 * v, sailed_extra=120.0)
    rhnc = Path_(script, 73.0, 19680.0, lambda v: 4.0 * v, sailed_extra=-60.0)
    split = script.decompose(baseline, rhnc)
    for what in ("cost", "co2"):
        assert sum(split[what][part] for part in script.PARTS) == pytest.approx(split[what]["saving"], abs=1e-9)
    assert split["cost"]["baseline closed loop"] == pytest.approx(100.0 * 120.0 / baseline.sailed[0])
    assert split["cost"]["RHNC speed profile and closed loop"] == pytest.approx(100.0 * 60.0 / baseline.sailed[0])


def test_in_calm_water_the_saving_is_the_track_length_alone(script):
    baseline = Path_(script, 84.0, 19680.0, lambda v: 0.0)
    rhnc = Path_(script, 73.0, 19680.0, lambda v: 0.0)
    split = script.decompose(baseline, rhnc)["cost"]
    assert split["track length, calm"] == pytest.approx(split["saving"]) and split["saving"] > 5.0
    for part in script.PARTS[1:]:
        assert split[part] == pytest.approx(0.0, abs=1e-9)


def test_equal_tracks_in_different_weather_save_by_the_weather_on_the_path_alone(script):
    baseline = Path_(script, 60.0, 16000.0, lambda v: 12.0)
    rhnc = Path_(script, 60.0, 16000.0, lambda v: 10.0)
    split = script.decompose(baseline, rhnc)["cost"]
    assert split["weather on the path at equal speed"] == pytest.approx(100.0 * 2.0 * 60.0 / baseline.sailed[0])
    assert split["weather on the path at equal speed"] == pytest.approx(split["saving"])
    for part in ("track length, calm", "track length, in the weather"):
        assert split[part] == pytest.approx(0.0, abs=1e-9)


def test_a_longer_track_sailed_faster_through_the_same_weather_is_put_to_the_track_length(script):
    # the weather's cost per nm grows with speed, the same on both paths: no part is the route's choice
    baseline = Path_(script, 84.0, 19680.0, lambda v: 3.0 * v * v)
    rhnc = Path_(script, 73.0, 19680.0, lambda v: 3.0 * v * v)
    split = script.decompose(baseline, rhnc)["cost"]
    assert split["weather on the path at equal speed"] == pytest.approx(0.0, abs=1e-9)
    assert split["track length, in the weather"] > 0.0
    assert split["track length, calm"] + split["track length, in the weather"] == pytest.approx(split["saving"])
