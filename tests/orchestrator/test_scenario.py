"""Scenario loading: good files load, bad ones fail with the message a user reads."""

import pytest

from orchestrator.errors import ScenarioError
from orchestrator.scenario import load_scenario

GOOD = """
connections = ["clock.count -> echo.value"]

[simulation]
stop_s = 10.0
dt_s = 2.0

[participants.clock]
type = "python"
class = "sample_participants:Clock"

[participants.echo]
type = "python"
class = "sample_participants:Echo"
every = 2
"""


def test_good_scenario_loads_with_defaults(write_scenario):
    scenario = load_scenario(write_scenario(GOOD, "passage.toml"))
    assert scenario.simulation.name == "passage"
    assert scenario.simulation.steps == 5
    assert [p.name for p in scenario.participants] == ["clock", "echo"]
    assert scenario.participant("echo").every == 2
    assert str(scenario.connections[0]) == "clock.count -> echo.value"
    assert scenario.outputs.format == "parquet"
    assert len(scenario.sha256) == 64


def test_steps_instead_of_stop(write_scenario):
    text = GOOD.replace("stop_s = 10.0", "steps = 7")
    assert load_scenario(write_scenario(text)).simulation.stop_s == pytest.approx(14.0)


@pytest.mark.parametrize(
    "edit, message",
    [
        (("dt_s = 2.0", "dt_s = 2.0\nspeed = 3"), r"scenario.toml: unknown key 'simulation.speed'"),
        (("dt_s = 2.0", "dt_s = -1.0"), r"'simulation.dt_s' must be positive"),
        (("dt_s = 2.0", "dt_s = \"fast\""), r"'simulation.dt_s' must be a finite number, got 'fast'"),
        (("stop_s = 10.0", "stop_s = 9.0"), r"whole number of 'dt_s' steps"),
        (("stop_s = 10.0", "stop_s = 10.0\nsteps = 5"), r"exactly one of 'simulation.stop_s' or 'simulation.steps'"),
        (("every = 2", "every = 0"), r"'participants.echo.every' must be a positive integer"),
        (("every = 2", "every = 2\ncolour = 1"), r"unknown key 'participants.echo.colour'"),
        (('class = "sample_participants:Clock"', ""), r"'participants.clock.class' must name"),
        (("clock.count -> echo.value", "clock.count => echo.value"), r"must read \"source.port -> target.port\""),
        (("clock.count -> echo.value", "radar.count -> echo.value"), r"no participant 'radar'"),
        (("clock.count -> echo.value", "clock -> echo.value"), r"'clock' must read participant.port"),
        (('["clock.count -> echo.value"]', '["clock.count -> echo.value", "clock.time -> echo.value"]'),
         r"echo.value is already driven"),
    ],
)
def test_bad_scenarios_name_file_and_key(write_scenario, edit, message):
    old, new = edit
    assert old in GOOD
    with pytest.raises(ScenarioError, match=message):
        load_scenario(write_scenario(GOOD.replace(old, new, 1)))


def test_connections_after_a_table_get_a_hint(write_scenario):
    text = GOOD.replace('connections = ["clock.count -> echo.value"]\n', "") + '\nconnections = ["a.b -> c.d"]\n'
    with pytest.raises(ScenarioError, match=r"'participants.echo.connections' \('connections' must come before"):
        load_scenario(write_scenario(text))


def test_missing_file_and_bad_toml(write_scenario, tmp_path):
    with pytest.raises(ScenarioError, match=r"nowhere.toml: scenario file not found"):
        load_scenario(tmp_path / "nowhere.toml")
    with pytest.raises(ScenarioError, match=r"scenario.toml: not valid TOML"):
        load_scenario(write_scenario("[simulation\nstop_s = 1"))


def test_missing_tables(write_scenario):
    with pytest.raises(ScenarioError, match=r"missing table \[simulation\]"):
        load_scenario(write_scenario("[participants.a]\nfmu = 'KCS'\n"))
    with pytest.raises(ScenarioError, match=r"missing table \[participants\]"):
        load_scenario(write_scenario("[simulation]\nsteps = 1\ndt_s = 1.0\n"))


def test_participant_needs_fmu_or_type(write_scenario):
    text = GOOD.replace('type = "python"\nclass = "sample_participants:Clock"', "every = 1")
    with pytest.raises(ScenarioError, match=r"'participants.clock' needs either 'fmu' or 'type'"):
        load_scenario(write_scenario(text))


def test_mapping_entries_are_checked(write_scenario):
    text = GOOD + '\n[participants.ship]\nfmu = "KCS"\n[participants.ship.mapping]\nx = { variable = "n", scale = 0 }\n'
    with pytest.raises(ScenarioError, match=r"'participants.ship.mapping.x.scale' must not be zero"):
        load_scenario(write_scenario(text))
    text = GOOD + '\n[participants.ship]\nfmu = "KCS"\n[participants.ship.mapping]\nx = { name = "n" }\n'
    with pytest.raises(ScenarioError, match=r"'participants.ship.mapping.x' must be"):
        load_scenario(write_scenario(text))


def test_outputs_format_is_checked(write_scenario):
    with pytest.raises(ScenarioError, match=r"'outputs.format' must be one of parquet, csv, got 'xlsx'"):
        load_scenario(write_scenario(GOOD + '\n[outputs]\nformat = "xlsx"\n'))


def test_overrides_replace_keys_and_change_the_hash(write_scenario):
    path = write_scenario(GOOD)
    plain = load_scenario(path)
    varied = load_scenario(path, {"simulation.dt_s": 1.0, "participants.echo.options.gain": 2})
    assert varied.simulation.steps == 10
    assert varied.participant("echo").options == {"gain": 2}
    assert varied.sha256 != plain.sha256
    with pytest.raises(ScenarioError, match=r"override 'simulation.dt_s.x': 'simulation.dt_s' is a value"):
        load_scenario(path, {"simulation.dt_s.x": 1})
    with pytest.raises(ScenarioError, match=r"unknown key 'simulation.warp'"):
        load_scenario(path, {"simulation.warp": 9})


@pytest.mark.parametrize("condition", ['"clock.count ~ 3"', '"count < 3"', '"clock.count < many"', "5"])
def test_malformed_stop_condition(write_scenario, condition):
    text = GOOD.replace("dt_s = 2.0", f"dt_s = 2.0\nstop_when = {condition}")
    with pytest.raises(ScenarioError, match=r"'simulation.stop_when' (entry .* must read|must be a condition)"):
        load_scenario(write_scenario(text))


def test_analysis_options_need_a_listed_analysis(write_scenario):
    text = GOOD + '\n[outputs]\nanalyses = ["voyage"]\n[outputs.options.encounter]\nx = 1\n'
    with pytest.raises(ScenarioError, match=r"'outputs.options.encounter' is for an analysis not listed"):
        load_scenario(write_scenario(text))
