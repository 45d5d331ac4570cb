"""FMU parameters of every FMI type reach the FMU through the set call of their type, and a
refused call is named by its FMI function.

The built-in models declare real parameters only (and MetOcean one string), so these tests
give the KCS FMU further declared parameters (integer, enumeration, boolean, string; an
``Int32`` in FMI 3.0) and step it through a recording stand-in for
:class:`orchestrator.fmi_slave.FmiSlave`: what is checked is what the participant sends.
"""

import zipfile
from pathlib import Path

import pytest
from fmpy.fmi1 import FMICallException

from orchestrator import fmu_build, fmu_participant
from orchestrator.errors import FmuError, ModelError, ScenarioError
from orchestrator.fmi_slave import FmiSlave
from orchestrator.fmu_participant import FmuParticipant, read_parameter_set, resolve_fmu
from orchestrator.scenario_spec import ParticipantSpec, VariableMapping

from fmu_copies import copy_with_description

WHERE = "scenario.toml: participants.vendor"

ENUMERATION_TYPE = """<TypeDefinitions>
    <SimpleType name="RudderType"><Enumeration><Item name="spade" value="1"/><Item name="flap" value="2"/>
    </Enumeration></SimpleType>
  </TypeDefinitions>
  <LogCategories>"""

FMI2_PARAMETERS = """
    <ScalarVariable name="blades" valueReference="901" causality="parameter" variability="fixed">
      <Integer start="4" min="2" max="7"/></ScalarVariable>
    <ScalarVariable name="rudder_type" valueReference="902" causality="parameter" variability="fixed">
      <Enumeration declaredType="RudderType" start="1"/></ScalarVariable>
    <ScalarVariable name="shallow_water" valueReference="903" causality="parameter" variability="fixed">
      <Boolean start="false"/></ScalarVariable>
    <ScalarVariable name="hull_file" valueReference="904" causality="parameter" variability="fixed">
      <String start="kcs.hull"/></ScalarVariable>
  </ModelVariables>"""

FMI3_PARAMETERS = """
    <Int32 name="blades" valueReference="901" causality="parameter" variability="fixed" start="4" min="2" max="7"/>
  </ModelVariables>"""


def kcs_with(tmp_path: Path, fmi_version: str = "2.0", **replacements: str) -> Path:
    """A copy of the built-in KCS FMU whose modelDescription.xml has ``old`` replaced by ``new``."""

    def edit(text: str) -> str:
        for old, new in replacements.values():
            assert old in text, old
            text = text.replace(old, new, 1)
        return text

    return copy_with_description(fmu_build.ensure_built("KCS", fmi_version=fmi_version), tmp_path / "Vendor.fmu",
                                 edit)


@pytest.fixture
def typed_fmu(tmp_path):
    return kcs_with(tmp_path, types=("<LogCategories>", ENUMERATION_TYPE),
                    variables=("\n  </ModelVariables>", FMI2_PARAMETERS))


class RecordingSlave:
    """Stands in for FmiSlave: records each call in order and refuses the methods named in ``refused``."""

    refused: set[str] = set()
    made: list["RecordingSlave"] = []

    def __init__(self, model_description, unzip_dir, instance_name, sink):
        self.version = model_description.fmiVersion
        self.prefix = "fmi2" if self.version == "2.0" else "fmi3"
        self.calls = []
        RecordingSlave.made.append(self)

    name = FmiSlave.name

    def _record(self, method, *args):
        self.calls.append((method, *args))
        if method in self.refused:
            raise FMICallException(function=method, status=3)

    def instantiate(self):
        self._record("instantiate")

    def enter_initialization(self, start_time):
        self._record("enter_initialization", start_time)

    def exit_initialization(self):
        self._record("exit_initialization")

    def do_step(self, time, step_size):
        self._record("do_step", time, step_size)

    def terminate(self):
        self._record("terminate")

    def free(self):
        self._record("free")

    def set_reals(self, refs, values):
        self._record("set_reals", list(refs), list(values))

    def set_integers(self, refs, values):
        self._record("set_integers", list(refs), list(values))

    def set_booleans(self, refs, values):
        self._record("set_booleans", list(refs), list(values))

    def set_strings(self, refs, values):
        self._record("set_strings", list(refs), list(values))

    def get_reals(self, refs):
        self._record("get_reals", list(refs))
        return [0.0] * len(refs)

    # the per-step calls FmiSlave binds once: recorded as the calls they stand for
    def real_reader(self, refs):
        return lambda: self.get_reals(refs)

    def real_writer(self, refs):
        return lambda values: self.set_reals(refs, values)

    def stepper(self):
        return self.do_step


@pytest.fixture
def slave(monkeypatch):
    monkeypatch.setattr(fmu_participant, "FmiSlave", RecordingSlave)
    monkeypatch.setattr(RecordingSlave, "refused", set())
    monkeypatch.setattr(RecordingSlave, "made", [])
    return RecordingSlave


def participant(path: Path, parameters: dict, substitutions=None, **spec) -> FmuParticipant:
    return FmuParticipant(ParticipantSpec(name="vendor", every=1, fmu=str(path), parameters=parameters, **spec),
                          path, WHERE, substitutions)


def set_calls(calls):
    return [call for call in calls if call[0].startswith("set_")]


def test_each_parameter_type_is_set_through_its_own_call_between_entering_and_leaving_initialisation(
        typed_fmu, slave):
    vendor = participant(typed_fmu, {"blades": 5, "rudder_type": 2, "shallow_water": True,
                                     "hull_file": "${ships}/kcs.hull", "u0": 9},
                         substitutions={"ships": "/data/ships", "unused": "x"})
    try:
        vendor.setup(0.0, {})
        calls = slave.made[0].calls
        methods = [call[0] for call in calls]
        assert methods[:2] == ["instantiate", "enter_initialization"]
        assert methods[-2:] == ["exit_initialization", "get_reals"]
        assert set_calls(calls) == [("set_integers", [901], [5]), ("set_integers", [902], [2]),
                                    ("set_booleans", [903], [True]), ("set_strings", [904], ["/data/ships/kcs.hull"]),
                                    ("set_reals", [18], [9.0])]
        assert type(set_calls(calls)[-1][2][0]) is float and type(set_calls(calls)[0][2][0]) is int
    finally:
        vendor.terminate()


def test_a_string_parameter_without_placeholders_needs_no_substitutions(typed_fmu, slave):
    vendor = participant(typed_fmu, {"hull_file": "kcs.hull"}, substitutions=None)
    assert vendor.parameters == {"hull_file": "kcs.hull"}


@pytest.mark.parametrize("parameters, message", [
    ({"hull_file": "${grid}/kcs.hull"}, r"parameters.hull_file: unknown placeholder in '\$\{grid\}/kcs.hull'"),
    ({"u0": "9.0"}, r"parameters.u0: 'u0' is Real, got a string"),
    ({"blades": "4"}, r"parameters.blades: 'blades' is Integer, got a string"),
    ({"hull_file": 4}, r"parameters.hull_file: 'hull_file' is a String parameter"),
    ({"blades": 8}, r"parameters.blades: 8 is outside the range \[2, 7\] that Vendor.fmu declares for 'blades'"),
    ({"shallow_water": 1}, r"parameters.shallow_water: 'shallow_water' is a Boolean parameter"),
])
def test_a_parameter_of_the_wrong_kind_is_refused_naming_it(typed_fmu, slave, parameters, message):
    with pytest.raises((ScenarioError, FmuError), match=rf"^{WHERE}\.{message}"):
        participant(typed_fmu, parameters, substitutions={"ships": "/data/ships"})


@pytest.mark.parametrize("method, function, parameters", [
    ("set_reals", "fmi2SetReal", {"u0": 9.0}),
    ("set_integers", "fmi2SetInteger", {"blades": 5}),
    ("set_booleans", "fmi2SetBoolean", {"shallow_water": True}),
    ("set_strings", "fmi2SetString", {"hull_file": "kcs.hull"}),
])
def test_a_refused_parameter_is_named_by_the_fmi_function_of_its_type(typed_fmu, slave, method, function,
                                                                      parameters):
    slave.refused = {method}
    vendor = participant(typed_fmu, parameters)
    try:
        with pytest.raises(ModelError) as raised:
            vendor.setup(0.0, {})
        # no message from the FMU: the exception's own text is the detail
        assert str(raised.value) == (f"vendor (Vendor.fmu): {function} failed: "
                                     + str(FMICallException(function=method, status=3)))
    finally:
        vendor.terminate()


@pytest.mark.parametrize("mapping", [
    {},                                                                  # plain: the values as they come
    {"tau_u": VariableMapping(variable="tau_u", scale=1000.0)},          # scaled: the converting path
])
def test_a_refused_input_is_named_by_fmi_set_real(typed_fmu, slave, mapping):
    vendor = participant(typed_fmu, {}, mapping=mapping)
    try:
        vendor.setup(0.0, {"tau_u": 1.0, "tau_r": 0.0})
        slave.refused = {"set_reals"}
        with pytest.raises(ModelError, match=r"^vendor \(Vendor.fmu\): fmi2SetReal failed: "):
            vendor.step(0.0, 1.0, {"tau_u": 2.0})
    finally:
        vendor.terminate()


def test_an_int32_parameter_of_fmi3_is_set_as_an_integer(tmp_path, slave):
    path = kcs_with(tmp_path, "3.0", variables=("\n  </ModelVariables>", FMI3_PARAMETERS))
    vendor = participant(path, {"blades": 6})
    try:
        vendor.setup(0.0, {})
        assert set_calls(slave.made[0].calls) == [("set_integers", [901], [6])]
        slave.refused = {"set_integers"}
        vendor.terminate()
        with pytest.raises(ModelError, match=r"^vendor \(Vendor.fmu\): fmi3SetInt32 failed: "):
            vendor.setup(0.0, {})
    finally:
        vendor.terminate()


def test_a_model_exchange_only_fmu_is_refused(tmp_path, slave):
    source = zipfile.ZipFile(fmu_build.ensure_built("KCS")).read("modelDescription.xml").decode()
    co_simulation = next(line for line in source.splitlines() if "<CoSimulation " in line).strip()
    path = kcs_with(tmp_path, co_simulation=(co_simulation, '<ModelExchange modelIdentifier="KCS">'),
                    end=("</CoSimulation>", "</ModelExchange>"))
    with pytest.raises(FmuError, match=rf"^{WHERE}\.fmu: {path} is not an FMI 2.0 or 3.0 co-simulation FMU$"):
        participant(path, {})


def test_an_initial_state_becomes_the_start_parameters(typed_fmu, slave):
    vendor = participant(typed_fmu, {}, initial={"x_nm": 0.5, "u_kn": 10.0, "psi_deg": 90.0})
    assert vendor.parameters == pytest.approx({"x0": 926.0, "u0": 5.144444, "psi0": 1.570796})
    with pytest.raises(ScenarioError, match=rf"^{WHERE}\.parameters.u0: the initial state is already given"):
        participant(typed_fmu, {"u0": 8.0}, initial={"u_mps": 8.0})


def test_a_built_in_model_is_built_for_fmi_2_unless_told(monkeypatch, tmp_path):
    built = []
    monkeypatch.setattr(fmu_build, "ensure_built", lambda name, fmi_version: built.append((name, fmi_version)))
    resolve_fmu("KCS", tmp_path, WHERE)
    resolve_fmu("KCS", tmp_path, WHERE, fmi_version="3.0")
    assert built == [("KCS", "2.0"), ("KCS", "3.0")]


@pytest.mark.parametrize("reference", ["vendor/ship", "vendor\\ship"])
def test_a_reference_with_a_folder_is_a_file_even_without_the_fmu_suffix(tmp_path, reference):
    with pytest.raises(FmuError, match=rf"^{WHERE}\.fmu: FMU file not found: "):
        resolve_fmu(reference, tmp_path, WHERE)


def test_an_unknown_built_in_model_lists_the_valid_ones(tmp_path):
    with pytest.raises(FmuError) as raised:
        resolve_fmu("NoSuchShip", tmp_path, WHERE)
    assert str(raised.value) == (f"{WHERE}.fmu: no built-in model 'NoSuchShip' (valid: "
                                 f"{', '.join(fmu_build.model_names())}, or a path to an .fmu file)")


def test_a_model_without_parameter_sets_says_so():
    with pytest.raises(ScenarioError, match=rf"^{WHERE}\.parameter_set: model 'KCSVendorB' has no parameter sets "
                                            r"\(.*parameter_sets.toml missing\)$"):
        read_parameter_set("KCSVendorB", "default", WHERE)


def test_an_fmu_with_a_broken_description_is_named(tmp_path):
    path = tmp_path / "Vendor.fmu"
    with zipfile.ZipFile(path, "w") as archive:
        archive.writestr("modelDescription.xml", "<fmiModelDescription")
    with pytest.raises(FmuError, match=rf"^{WHERE}\.fmu: {path} is not a valid FMU: "):
        participant(path, {})


def test_an_fmu_unsafe_to_unpack_is_named_before_and_at_set_up(typed_fmu, tmp_path, slave):
    unsafe = tmp_path / "unsafe.fmu"
    with zipfile.ZipFile(unsafe, "w") as archive:
        archive.writestr("../escape.txt", "outside")
    with pytest.raises(FmuError, match=rf"^{WHERE}\.fmu: unsafe.fmu: entry '../escape.txt' points outside"):
        participant(unsafe, {})
    vendor = participant(typed_fmu, {})
    typed_fmu.write_bytes(unsafe.read_bytes())  # replaced between loading and set-up
    try:
        with pytest.raises(FmuError, match=rf"^{WHERE}\.fmu: Vendor.fmu: entry '../escape.txt' points outside"):
            vendor.setup(0.0, {})
    finally:
        vendor.terminate()


def test_remove_files_removes_the_unpacked_fmu_without_calling_it(typed_fmu, slave):
    vendor = participant(typed_fmu, {})
    vendor.remove_files()  # nothing unpacked yet: nothing to do
    vendor.setup(0.0, {})
    unpacked = Path(vendor._unzip_dir)
    calls = list(slave.made[0].calls)
    assert unpacked.is_dir()
    vendor.remove_files()
    assert not unpacked.exists()
    assert slave.made[0].calls == calls
    vendor.remove_files()  # the folder is gone already: nothing to do, no error
    vendor.terminate()
    assert [call[0] for call in slave.made[0].calls[len(calls):]] == ["terminate", "free"]


def test_an_initial_state_is_converted_into_a_unit_the_fmu_defines(tmp_path, slave):
    path = kcs_with(tmp_path, unit=('<Unit name="m/s">', '<Unit name="cm_per_s"><BaseUnit m="1" s="-1" factor="0.01"/>'
                                                        '</Unit>\n    <Unit name="m/s">'),
                    u0=('description="initial surge speed">\n      <Real displayUnit="kn" unit="m/s"',
                        'description="initial surge speed">\n      <Real unit="cm_per_s"'))
    assert participant(path, {}, initial={"u_mps": 8.0}).parameters == pytest.approx({"u0": 800.0})
