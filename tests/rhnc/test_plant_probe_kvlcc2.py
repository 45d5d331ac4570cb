"""The mapping checks on the second test ship, KVLCC2 (sphere, deg/s, MN, rudder and shaft
orders): a unit that contradicts the declared one is refused when the plant is built, and the
probe refuses mistaken signs, angle conventions and scales at force level and through the
allocation, as on the S175."""

from __future__ import annotations

import dataclasses
import math
import re
from pathlib import Path

import pytest

from orchestrator.cli import main
from orchestrator.errors import ScenarioError
from orchestrator.fmu_participant import FmuParticipant, resolve_fmu
from orchestrator.scenario import load_scenario
from rhnc.ship.plant_probe import probe_plant

OWN = Path(__file__).resolve().parents[2] / "scenarios" / "own_ship"
FORCE = OWN / "exp3a_kvlcc2_force.toml"
ALLOC = OWN / "exp3a_kvlcc2_alloc.toml"
DEG = math.pi / 180.0
SPEED = 15.5 * 1852.0 / 3600.0
TAU_U_MAX, TAU_R_MAX = 2.35e6, 5.87e8
HEADING = 'psi = { variable = "Heading", start = "InitialHeading" }'

#: (scenario, line of the shipped mapping, its replacement, expected message)
MISTAKES = {
    "rate of turn in deg/s read as rad/s": (
        FORCE, 'r = "YawRate"', 'r = { variable = "YawRate", scale = 1.0 }',
        r"heading changes at 0\.017\d* times the reported yaw rate r.*wrong unit or scale"),
    "rate of turn with its sign reversed": (
        FORCE, 'r = "YawRate"', f'r = {{ variable = "YawRate", scale = {-DEG!r} }}',
        r"-1 times the reported yaw rate.*sign reversed"),
    "heading counted anticlockwise from east": (
        FORCE, HEADING, f'psi = {{ variable = "Heading", scale = {-DEG!r}, offset = {math.pi / 2!r}, '
                        'start = "InitialHeading" }',
        r"contradicts the canonical frame.*heading counted from east"),
    "sway with its sign reversed": (
        FORCE, 'v = "SwaySpeed"', f'v = {{ variable = "SwaySpeed", scale = {-1852.0 / 3600.0!r} }}',
        r"the sway speed has its sign reversed"),
    "yaw moment with its sign reversed": (
        FORCE, 'tau_r = "YawMomentDemand"', 'tau_r = { variable = "YawMomentDemand", scale = -1e6 }',
        r"a positive yaw moment turned the ship to port.*tau_r"),
    "surge force with its sign reversed": (
        FORCE, 'tau_u = "SurgeForceDemand"', 'tau_u = { variable = "SurgeForceDemand", scale = -1e6 }',
        r"a positive surge force slowed the ship.*tau_u"),
    "rudder order counted positive to port, through the allocation": (
        ALLOC, 'rudder_angle_cmd = "RudderOrder"', f'rudder_angle_cmd = {{ variable = "RudderOrder", scale = {-DEG!r} }}',
        r"a positive yaw moment turned the ship to port"),
}


def _edited(tmp_path: Path, source: Path, old: str, new: str) -> Path:
    text = source.read_text()
    assert old in text
    path = tmp_path / source.name
    path.write_text(text.replace(old, new))
    for identified in OWN.glob("KVLCC2*_identified.toml"):
        (tmp_path / identified.name).write_text(identified.read_text())
    return path


def _builder(path: Path):
    scenario = load_scenario(path)
    spec = scenario.participant("ship")
    where = f"{path}: participants.ship"
    fmu = resolve_fmu(spec.fmu, scenario.directory, where)
    return (lambda initial: FmuParticipant(dataclasses.replace(spec, initial=initial), fmu, where)), where


def test_the_shipped_mapping_passes_the_probe():
    build, where = _builder(FORCE)
    measured = probe_plant(build, SPEED, TAU_U_MAX, TAU_R_MAX, where)
    assert measured["velocity_error"] < 1e-3
    assert measured["yaw_rate_gain"] == pytest.approx(1.0, abs=1e-3)
    assert measured["sway_gain"] == pytest.approx(1.0, abs=1e-2)


@pytest.mark.parametrize("mistake", [m for m in MISTAKES if MISTAKES[m][0] == FORCE])
def test_a_mapping_against_the_canonical_frame_is_refused(mistake, tmp_path):
    source, old, new, message = MISTAKES[mistake]
    build, where = _builder(_edited(tmp_path, source, old, new))
    with pytest.raises(ScenarioError, match=message):
        probe_plant(build, SPEED, TAU_U_MAX, TAU_R_MAX, where)


@pytest.mark.parametrize("mistake", [m for m in MISTAKES if MISTAKES[m][0] == ALLOC])
def test_identify_through_the_allocation_refuses_it_with_exit_2_and_nothing_written(mistake, tmp_path, capsys):
    source, old, new, message = MISTAKES[mistake]
    path = _edited(tmp_path, source, old, new)
    results = tmp_path / "results"
    code = main(["identify", str(path), "--tau-u-max-N", "2.35e6", "--tau-r-max-Nm", "5.87e8", "--speed-kn", "15.5",
                 "--results", str(results), "--out", str(tmp_path / "fitted.toml")])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and str(path) in err[0]
    assert re.search(message, err[0]), err[0]
    assert not results.exists() and not (tmp_path / "fitted.toml").exists()


@pytest.mark.parametrize("port, line, unit", [
    ("r", 'r = "YawRate"', "rad/s"),
    ("rudder_angle_cmd", 'rudder_angle_cmd = "RudderOrder"', "rad"),
    ("propeller_rps_cmd", 'propeller_rps_cmd = "ShaftSpeedOrder"', "1/s"),
])
def test_a_unit_contradicting_the_declared_one_is_refused_naming_both(port, line, unit, tmp_path):
    variable = line.split('"')[1]
    path = _edited(tmp_path, ALLOC, line, f'{port} = {{ variable = "{variable}", unit = "{unit}" }}')
    message = rf"mapping\.{port}: unit '{re.escape(unit)}' contradicts the unit '\S+' that the FMU declares for variable '{variable}'"
    with pytest.raises(ScenarioError, match=message):
        scenario = load_scenario(path)
        spec = scenario.participant("ship")
        FmuParticipant(spec, resolve_fmu(spec.fmu, scenario.directory, "ship"), f"{path}: participants.ship")

