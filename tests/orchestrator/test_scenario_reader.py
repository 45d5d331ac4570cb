"""The scenario reader key by key: what each table accepts up to its limits, the message each
refusal reads (file, dotted key, the value given), and what reaches the frozen specs."""

import datetime
import hashlib
import json

import pytest

from orchestrator.errors import ScenarioError
from orchestrator.plant_ports import INITIAL_KEYS
from orchestrator.scenario import load_scenario
from orchestrator.scenario_spec import StopCondition, VectorMapping
from orchestrator.toml_input import shown_text

BASE = """
connections = ["helm.tau_u -> ship.tau_u"]

[simulation]
stop_s = 10.0
dt_s = 2.0

[participants.helm]
type = "scripted_tau"
[participants.helm.options]
tau_u_N = 7.7e5

[participants.ship]
fmu = "KCS"
"""


@pytest.fixture
def load(write_scenario):
    """Load BASE with ``extra`` appended (or ``text`` instead); returns (scenario, path)."""

    def read(extra="", text=None, name="scenario.toml", overrides=None):
        path = write_scenario(BASE + extra if text is None else text, name)
        return load_scenario(path, overrides), path

    return read


@pytest.fixture
def refused(write_scenario):
    """The message loading BASE + ``extra`` fails with, the file's path replaced by FILE."""

    def message(extra="", text=None, name="scenario.toml", overrides=None):
        path = write_scenario(BASE + extra if text is None else text, name)
        with pytest.raises(ScenarioError) as raised:
            load_scenario(path, overrides)
        return str(raised.value).replace(str(path), "FILE")

    return message


# -- overrides and the scenario hash -----------------------------------------------------------
def test_overrides_enter_the_hash_in_one_canonical_form(load, write_scenario):
    scenario, path = load(overrides={"participants.helm.options.b": 2, "participants.helm.options.a": 1})
    raw = path.read_bytes() + b"\n# overrides\n" + json.dumps({"participants.helm.options.a": 1,
                                                               "participants.helm.options.b": 2}).encode()
    assert scenario.sha256 == hashlib.sha256(raw).hexdigest()
    reordered, _ = load(overrides={"participants.helm.options.a": 1, "participants.helm.options.b": 2})
    assert reordered.sha256 == scenario.sha256
    other, _ = load(overrides={"participants.helm.options.a": 1, "participants.helm.options.b": 3})
    assert other.sha256 != scenario.sha256


def test_an_override_value_json_cannot_encode_is_hashed_by_its_text(load):
    day = datetime.date(2026, 11, 25)
    scenario, _ = load(overrides={"participants.helm.options.day": day})
    assert scenario.participant("helm").options["day"] == day


def test_an_override_through_a_value_or_too_deep_names_the_file(refused):
    assert refused(overrides={"simulation.dt_s.x": 1.0}) == (
        "FILE: override 'simulation.dt_s.x': 'simulation.dt_s' is a value, not a table")
    deep = 1.0
    for _ in range(30):
        deep = [deep]
    assert refused(overrides={"participants.helm.options.deep": deep}).startswith(
        "FILE: 'participants.helm.options.deep[0][0]")
    assert refused(overrides={"simulation..dt_s": 1.0}) == "FILE: override 'simulation..dt_s' is not a dotted key path"


# -- other kinds of input file -------------------------------------------------------------------
def test_a_batch_or_comparison_file_is_sent_to_its_command(refused, write_scenario):
    path = write_scenario('[batch]\nname = "b"\n', "sweep.toml")
    with pytest.raises(ScenarioError) as raised:
        load_scenario(path)
    assert str(raised.value) == (f"{path}: a batch file (it has 'batch'), not a scenario: "
                                 f"use 'python -m orchestrator batch {path}'")
    assert refused(text='runs = []\n').endswith("a comparison file (it has 'runs'), not a scenario: "
                                                 "use 'python -m orchestrator compare FILE'")


@pytest.mark.parametrize("present", ["[participants.a]\ntype = \"x\"\n", "[simulation]\ndt_s = 1.0\n"])
def test_a_file_with_a_scenario_table_is_read_as_a_scenario(refused, present):
    assert "not a scenario" not in refused(text="[batch]\nname = \"b\"\n" + present)


# -- [simulation] and [outputs] -------------------------------------------------------------------
def test_simulation_and_outputs_values_reach_the_specs(load):
    scenario, _ = load(text=BASE.replace("dt_s = 2.0", "dt_s = 2.0\nstep_timeout_s = 12.5")
                       + '[outputs]\nformat = "csv"\n')
    assert scenario.simulation.step_timeout_s == 12.5
    assert scenario.outputs.format == "csv"


@pytest.mark.parametrize("dt, message", [
    ("0.0", "FILE: 'simulation.dt_s' must be positive, got 0.0"),
    ("-1.0", "FILE: 'simulation.dt_s' must be positive, got -1.0"),
    ("1e-7", "FILE: 'simulation.dt_s' must be at least 1e-06 s, got 1e-07"),
])
def test_the_macro_step_must_be_positive(refused, dt, message):
    assert refused(text=BASE.replace("dt_s = 2.0", f"dt_s = {dt}")) == message


@pytest.mark.parametrize("analyses", ['"energy"', '[""]', "[1]"])
def test_analyses_are_a_list_of_names(refused, analyses):
    assert refused(f"[outputs]\nanalyses = {analyses}\n") == "FILE: 'outputs.analyses' must be a list of names"


def test_analysis_options_are_tables(refused):
    assert refused("[outputs]\noptions = 5\n") == (
        "FILE: 'outputs.options' must be a table of [outputs.options.<analysis>] tables")
    assert refused('[outputs]\nanalyses = ["energy"]\noptions = { energy = 5 }\n') == (
        "FILE: 'outputs.options' entry 'energy' must be a table")


@pytest.mark.parametrize("entry, participant, port", [("ship.hull.x > 5", "ship", "hull.x"),
                                                      ("ship.x <= -2.5", "ship", "x")])
def test_a_stop_condition_splits_at_the_first_dot(load, entry, participant, port):
    scenario, _ = load(text=BASE.replace("dt_s = 2.0", f'dt_s = 2.0\nstop_when = "{entry}"'))
    condition = scenario.simulation.stop_when[0]
    assert (condition.participant, condition.port) == (participant, port)


@pytest.mark.parametrize("entry", ["ship.x < 5 < 6", "ship. < 5", ".x < 5", "ship.x < inf", "ship.x ~ 5"])
def test_a_malformed_stop_condition_is_quoted(refused, entry):
    assert refused(text=BASE.replace("dt_s = 2.0", f'dt_s = 2.0\nstop_when = ["{entry}"]')) == (
        f"FILE: 'simulation.stop_when' entry '{entry}' must read \"participant.port < number\" "
        "(operators <=, >=, <, >)")


def test_a_stop_condition_holds_by_its_operator():
    at = {op: StopCondition("ship", "x", op, 5.0) for op in ("<", "<=", ">", ">=")}
    assert [at[op].holds(5.0) for op in ("<", "<=", ">", ">=")] == [False, True, False, True]
    assert [at[op].holds(4.0) for op in ("<", "<=", ">", ">=")] == [True, True, False, False]
    assert [at[op].holds(6.0) for op in ("<", "<=", ">", ">=")] == [False, False, True, True]


def test_a_file_name_that_cannot_name_the_results_folder_is_named(refused):
    assert refused(name="trial .toml") == (
        "FILE: 'simulation.name' is not given and the file name cannot name a results folder: it must not "
        "start with '.', start or end with a space, or be a reserved device name, got 'trial '; give "
        "'simulation.name'")


def test_an_unknown_or_missing_key_is_named(refused):
    assert refused(text=BASE.replace("dt_s = 2.0", "dt_s = 2.0\nfoo = 1")) == (
        "FILE: unknown key 'simulation.foo' (valid: name, start_s, stop_s, steps, dt_s, stop_when, exchange, "
        "step_timeout_s)")
    assert refused(text=BASE.replace("dt_s = 2.0", "")) == "FILE: missing key 'simulation.dt_s'"


# -- connections ----------------------------------------------------------------------------------
def test_a_connection_port_may_hold_dots(load):
    scenario, _ = load(text=BASE.replace('"helm.tau_u -> ship.tau_u"', '"helm.tau_u -> ship.hull.tau_u"'))
    connection = scenario.connections[0]
    assert (connection.target, connection.target_port) == ("ship", "hull.tau_u")


@pytest.mark.parametrize("entry, message", [
    ("5", "connection 5 must read \"source.port -> target.port\""),
    ('"helm. -> ship.tau_u"', "connection 'helm. -> ship.tau_u': 'helm.' must read participant.port"),
    ('".tau_u -> ship.tau_u"', "connection '.tau_u -> ship.tau_u': '.tau_u' must read participant.port"),
    ('"pilot.tau_u -> ship.tau_u"', "connection 'pilot.tau_u -> ship.tau_u': no participant 'pilot' "
                                    "(declared: helm, ship)"),
    ('"helm.tau_u -> ship.tau_u", "helm.tau_r -> ship.tau_u"',
     "connection 'helm.tau_r -> ship.tau_u': ship.tau_u is already driven"),
])
def test_a_malformed_connection_is_quoted(refused, entry, message):
    assert refused(text=BASE.replace('"helm.tau_u -> ship.tau_u"', entry)) == f"FILE: {message}"


# -- participants ---------------------------------------------------------------------------------
def test_participant_values_reach_the_specs(load):
    scenario, _ = load(text=BASE.replace("[participants.helm.options]", "step_timeout_s = 7.0\n"
                                         "every = 1000000\n[participants.helm.options]")
                       + 'fmi_version = "3.0"\nstep_timeout_s = 9.0\n')
    assert scenario.participant("helm").step_timeout_s == 7.0
    assert scenario.participant("helm").every == 1_000_000
    assert scenario.participant("ship").fmi_version == "3.0"
    assert scenario.participant("ship").step_timeout_s == 9.0
    with pytest.raises(KeyError) as raised:
        scenario.participant("pilot")
    assert raised.value.args == ("pilot",)


@pytest.mark.parametrize("table, message", [
    ("every = true", "'participants.ship.every' must be a positive integer (at most 1000000), got True"),
    ("every = 1000001", "'participants.ship.every' must be a positive integer (at most 1000000), got 1000001"),
    ('fmu = ""', "'participants.ship.fmu' must be a model name or a path to an .fmu"),
    ("fmu = 5", "'participants.ship.fmu' must be a model name or a path to an .fmu"),
    ('mapping = { x = { variable = "" } }', "'participants.ship.mapping.x.variable' must be an FMU variable name"),
    ('mapping = { x = { variable = "x", scale = "2" } }',
     "'participants.ship.mapping.x.scale' must be a finite number, got '2'"),
    ('initial = { x_m = "a" }', "'participants.ship.initial.x_m' must be a finite number, got 'a'"),
    ("initial = { z_m = 1.0 }", f"unknown key 'participants.ship.initial.z_m' (valid: {', '.join(INITIAL_KEYS)})"),
])
def test_a_wrong_fmu_participant_value_is_named(refused, table, message):
    text = BASE.replace('fmu = "KCS"', table if table.startswith("fmu") else 'fmu = "KCS"\n' + table)
    assert refused(text=text) == f"FILE: {message}"


def test_a_python_class_must_be_named_by_a_string(refused):
    text = BASE.replace('type = "scripted_tau"', 'type = "python"\nclass = 5')
    assert refused(text=text) == "FILE: 'participants.helm.class' must name 'package.module:Class' for type = \"python\""


@pytest.mark.parametrize("origin", ["[89.9, 180.0]", "[-89.9, -180.0]", "[0.0, 0.0]"])
def test_a_geodetic_origin_within_the_globe_is_taken(load, origin):
    scenario, _ = load(f"[participants.ship.geodetic]\norigin_deg = {origin}\n")
    assert scenario.participant("ship").geodetic_origin_deg == tuple(json.loads(origin))


@pytest.mark.parametrize("origin", ["[90.0, 0.0]", "[-90.0, 0.0]", "[90.5, 0.0]", "[-90.5, 0.0]", "[95.0, 0.0]",
                                    "[0.0, 180.5]", "[0.0, -180.5]", "[1.0, 2.0, 3.0]", "[1.0, \"a\"]"])
def test_a_geodetic_origin_off_the_globe_is_refused(refused, origin):
    assert refused(f"[participants.ship.geodetic]\norigin_deg = {origin}\n").startswith(
        "FILE: 'participants.ship.geodetic.origin_deg' must be [latitude, longitude] in degrees, got [")


@pytest.mark.parametrize("vector, expected", [
    ('{ north = "cn", east = "ce", units = { north = "kn" } }',
     VectorMapping(north="cn", east="ce", units={"north": "kn"})),
    ('{ speed = "cs", direction = "cd", direction_is = "from" }',
     VectorMapping(speed="cs", direction="cd", direction_is="from")),
])
def test_a_vector_mapping_reaches_the_spec(load, vector, expected):
    scenario, _ = load(f"[participants.ship.mapping]\ncurrent = {vector}\n")
    assert scenario.participant("ship").mapping["current"] == expected


@pytest.mark.parametrize("part", ['speed = "s"', 'direction = "d"', 'north = "n"', 'east = "e"'])
def test_half_a_vector_mapping_is_named(refused, part):
    assert refused(f"[participants.ship.mapping]\ncurrent = {{ {part} }}\n") == (
        "FILE: 'participants.ship.mapping.current' needs variable = \"...\", or a vector: speed and direction, "
        "or north and east")


def test_a_vector_mapping_with_a_wrong_type_is_named(refused):
    assert refused('[participants.ship.mapping]\ncurrent = { north = "n", east = "e", units = 5 }\n') == (
        "FILE: 'participants.ship.mapping.current.units': input should be a valid dictionary, got 5")


def test_participant_names_are_identifiers_of_at_most_64_characters(load, refused):
    long_name = "s" * 64
    scenario, _ = load(text=BASE.replace("participants.ship", f"participants.{long_name}").replace(
        "-> ship.", f"-> {long_name}."))
    assert scenario.participant(long_name).fmu == "KCS"
    for name in ("s" * 65, "a-b"):
        assert refused(text=BASE.replace("participants.ship", f'participants."{name}"').replace(
            "-> ship.", f"-> {name}.")) == (f"FILE: participant name '{shown_text(name)}' must be an identifier "
                                           "(at most 64 characters)")


def test_an_empty_participants_table_is_named(refused):
    assert refused(text="[simulation]\nstop_s = 10.0\ndt_s = 2.0\n[participants]\n") == (
        "FILE: [participants] declares no participant")


def test_the_tables_that_check_outputs_and_mappings_are_the_loaded_spec(load):
    """One declaration per table: ``[outputs]`` and every port mapping are kept as the very
    models that checked them (no mirror copied field by field beside them)."""
    from orchestrator.scenario_spec import OutputSpec, VariableMapping
    from orchestrator.toml_input import TomlTable

    scenario, _ = load('[participants.ship.mapping]\nx = "x"\ny = { variable = "y", scale = 2.0 }\n'
                       '[outputs]\nformat = "csv"\nanalyses = ["voyage"]\n')
    mapping = scenario.participant("ship").mapping
    assert mapping["x"] == VariableMapping(variable="x")
    assert mapping["y"] == VariableMapping(variable="y", scale=2.0)
    assert scenario.outputs == OutputSpec(format="csv", analyses=["voyage"])
    for model in (OutputSpec, VariableMapping, VectorMapping):
        assert issubclass(model, TomlTable), model
