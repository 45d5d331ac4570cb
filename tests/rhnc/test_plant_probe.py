"""The probe refuses mappings whose signs, angle convention or scales contradict the canonical frame."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import pytest

from orchestrator.cli import main
from orchestrator.errors import ScenarioError
from orchestrator.fmu_participant import FmuParticipant, resolve_fmu
from orchestrator.scenario import load_scenario
from rhnc.ship.plant_probe import probe_plant

REPO = Path(__file__).resolve().parents[2]
S175_SCENARIO = REPO / "scenarios" / "own_ship" / "exp3a_s175_identified.toml"
DEG = math.pi / 180.0
SPEED = 18.0 * 1852.0 / 3600.0

#: (line of the shipped mapping, its replacement, expected message)
MISTAKES = {
    "rate of turn with its sign reversed": (
        'r = "rot"', f'r = {{ variable = "rot", scale = {-DEG / 60.0!r} }}',
        r"mapping of psi or r contradicts the canonical frame.*-1 times the reported yaw rate.*sign reversed"),
    "heading counted anticlockwise from east (maths angle)": (
        'psi = { variable = "heading", start = "start_heading" }',
        f'psi = {{ variable = "heading", scale = {-DEG!r}, offset = {math.pi / 2!r}, start = "start_heading" }}',
        r"mapping of x, y, psi, u, v contradicts the canonical frame.*heading counted from east"),
    "heading with its sign reversed": (
        'psi = { variable = "heading", start = "start_heading" }',
        f'psi = {{ variable = "heading", scale = {-DEG!r}, start = "start_heading" }}',
        r"mapping of x, y, psi, u, v contradicts"),
    "heading in degrees read as radians (scale 1)": (
        'psi = { variable = "heading", start = "start_heading" }',
        'psi = { variable = "heading", scale = 1.0, start = "start_heading" }',
        r"mapping of x, y, psi, u, v contradicts"),
    "speed in knots read as m/s (scale 1)": (
        'u = { variable = "stw", start = "start_stw" }', 'u = { variable = "stw", scale = 1.0, start = "start_stw" }',
        r"differs by \d+ % from u, v along psi"),
    "rate of turn in deg/min read as deg/s": (
        'r = "rot"', f'r = {{ variable = "rot", scale = {DEG!r} }}',
        r"heading changes at 0\.0167 times the reported yaw rate r.*wrong unit or scale"),
    "sway with its sign reversed": (
        'v = "sway_speed"', f'v = {{ variable = "sway_speed", scale = {-1852.0 / 3600.0!r} }}',
        r"mapping of v contradicts the canonical frame.*the sway speed has its sign reversed"),
    "yaw moment with its sign reversed": (
        'tau_r = "rudder_moment"', 'tau_r = { variable = "rudder_moment", scale = -1000.0 }',
        r"a positive yaw moment turned the ship to port.*tau_r"),
    "surge force with its sign reversed": (
        'tau_u = "propeller_thrust"', 'tau_u = { variable = "propeller_thrust", scale = -1000.0 }',
        r"a positive surge force slowed the ship.*tau_u"),
}


def _builder(path: Path):
    scenario = load_scenario(path)
    spec = scenario.participant("ship")
    where = f"{path}: participants.ship"
    fmu = resolve_fmu(spec.fmu, scenario.directory, where)
    return (lambda initial: FmuParticipant(dataclasses.replace(spec, initial=initial), fmu, where)), where


def _edited(tmp_path: Path, old: str, new: str) -> Path:
    text = S175_SCENARIO.read_text()
    assert old in text
    path = tmp_path / S175_SCENARIO.name
    path.write_text(text.replace(old, new))
    (tmp_path / "S175_identified.toml").write_text((S175_SCENARIO.parent / "S175_identified.toml").read_text())
    return path


def test_the_shipped_mapping_passes_the_probe():
    build, where = _builder(S175_SCENARIO)
    measured = probe_plant(build, SPEED, 8e5, 1.65e8, where)
    assert measured["velocity_error"] < 1e-3
    assert measured["yaw_rate_gain"] == pytest.approx(1.0, abs=1e-3)
    assert measured["sway_gain"] == pytest.approx(1.0, abs=1e-2)


@pytest.mark.parametrize("mistake", list(MISTAKES))
def test_a_mapping_against_the_canonical_frame_is_refused(mistake, tmp_path):
    old, new, message = MISTAKES[mistake]
    build, where = _builder(_edited(tmp_path, old, new))
    with pytest.raises(ScenarioError, match=message):
        probe_plant(build, SPEED, 8e5, 1.65e8, where)


def test_identify_refuses_it_with_one_line_exit_2_and_nothing_written(tmp_path, capsys):
    old, new, _ = MISTAKES["heading counted anticlockwise from east (maths angle)"]
    path = _edited(tmp_path, old, new)
    results = tmp_path / "results"
    code = main(["identify", str(path), "--tau-u-max-N", "8e5", "--tau-r-max-Nm", "1.65e8",
                 "--results", str(results), "--out", str(tmp_path / "fitted.toml")])
    assert code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "contradicts the canonical frame" in err[0] and str(path) in err[0]
    assert not results.exists() and not (tmp_path / "fitted.toml").exists()
