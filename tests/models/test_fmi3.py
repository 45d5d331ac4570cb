"""FMI 3.0 builds of the C models: the same sources, fmpy's validation, the FMI 2.0 trajectory.

Also the modelDescription's metadata and declared ranges, which both standards share.
"""

from __future__ import annotations

import textwrap
import xml.etree.ElementTree as ET
import zipfile

import numpy as np
import pandas as pd
import pytest
from fmpy import read_model_description
from fmpy.validation import validate_fmu

from orchestrator import fmu_build
from orchestrator.errors import ScenarioError
from orchestrator.run import run_scenario
from orchestrator.scenario import load_scenario

MODELS = ("KCS", "KCSVendorB", "MetOcean")
#: every model `python -m orchestrator build --fmi-version 3.0` builds, each validated
ALL_MODELS = tuple(fmu_build.model_names())


@pytest.fixture(scope="module")
def fmus3(tmp_path_factory):
    out = tmp_path_factory.mktemp("fmus")
    return {name: fmu_build.build_fmu(name, out, fmi_version="3.0") for name in ALL_MODELS}


@pytest.fixture(scope="module")
def fmus2(tmp_path_factory):
    out = tmp_path_factory.mktemp("fmus2")
    return {name: fmu_build.build_fmu(name, out, fmi_version="2.0") for name in MODELS}


def test_every_model_is_built_for_fmi3_and_validated():
    assert set(MODELS) < set(ALL_MODELS) and len(ALL_MODELS) == 6


@pytest.mark.parametrize("name", ALL_MODELS)
def test_fmi3_fmu_passes_fmpy_validation(fmus3, name):
    assert validate_fmu(str(fmus3[name])) == []
    description = read_model_description(str(fmus3[name]))
    assert description.fmiVersion == "3.0"
    assert description.coSimulation is not None and description.modelExchange is None


def test_fmi3_fmu_carries_its_sources_and_build_description(fmus3):
    with zipfile.ZipFile(fmus3["KCS"]) as z:
        names = set(z.namelist())
        build = ET.fromstring(z.read("sources/buildDescription.xml"))
    assert {"sources/fmu_core.c", "sources/fmi3_api.c", "sources/model.c", "sources/model_bounds.h"} <= names
    assert "sources/fmi2_api.c" not in names
    listed = {f.get("name") for f in build.iter("SourceFile")}
    assert listed == {"fmu_core.c", "fmi3_api.c", "model.c"}


@pytest.mark.parametrize("version", ["2.0", "3.0"])
def test_model_description_is_complete(fmus2, fmus3, version):
    fmu = (fmus2 if version == "2.0" else fmus3)["KCS"]
    with zipfile.ZipFile(fmu) as z:
        root = ET.fromstring(z.read("modelDescription.xml"))
    for key in ("author", "version", "license", "generationDateAndTime", "copyright"):
        assert root.get(key), key
    description = read_model_description(str(fmu))
    variables = {v.name: v for v in description.modelVariables}
    assert variables["psi"].displayUnit == "deg"
    assert variables["u"].displayUnit == "kn"
    assert variables["hs"].min == "0" or float(variables["hs"].min) == 0.0
    units = {u.name: {d.name: d.factor for d in u.displayUnits} for u in description.unitDefinitions}
    assert units["rad"]["deg"] == pytest.approx(180.0 / np.pi)
    assert units["m/s"]["kn"] == pytest.approx(3600.0 / 1852.0)


SCENARIO = """
connections = ["helm.tau_u -> ship.tau_u", "helm.tau_r -> ship.tau_r",
               "env.current_north -> ship.current_north", "env.current_east -> ship.current_east",
               "env.wind_speed -> ship.wind_speed", "env.wind_direction -> ship.wind_direction",
               "env.hs -> ship.hs", "ship.x -> env.x", "ship.y -> env.y"]
[simulation]
name = "fmi{tag}"
stop_s = 1800.0
dt_s = 5.0
[metocean]
generator = "paper_default"
[participants.helm]
type = "scripted_tau"
[participants.helm.options]
tau_u_N = 7.7377e5
tau_r_steps = [[60.0, 3.3e8]]
[participants.ship]
fmu = "KCS"
fmi_version = "{version}"
[participants.ship.parameters]
u0 = 9.26
x0 = 20000.0
y0 = 20000.0
[participants.env]
fmu = "MetOcean"
fmi_version = "{version}"
[participants.env.parameters]
grid_file = "${{metocean.grid}}"
[outputs]
format = "csv"
"""


def test_fmi3_plant_and_environment_give_the_fmi2_trajectory(tmp_path):
    frames = {}
    for version in ("2.0", "3.0"):
        path = tmp_path / f"fmi{version[0]}.toml"
        path.write_text(textwrap.dedent(SCENARIO.format(tag=version[0], version=version)))
        report = run_scenario(path, tmp_path / "results", progress=False)
        assert report.status == "finished", report.reason
        frames[version] = pd.read_csv(report.folder / "timeseries.csv")
    two, three = frames["2.0"], frames["3.0"]
    assert len(two) == len(three) == 361
    for column in ("ship.x", "ship.y", "ship.psi", "ship.u", "ship.v", "ship.r", "env.hs", "env.wind_speed"):
        scale = max(1.0, float(np.abs(two[column]).max()))
        assert np.max(np.abs(two[column] - three[column])) <= 1e-12 * scale, column
    assert two["env.hs"].std() > 0  # the ship sailed through a varying field


def test_a_value_outside_its_declared_range_is_refused_by_the_fmu(fmus3, fmus2, tmp_path):
    from fmpy import extract
    from fmpy.fmi3 import FMU3Slave
    from fmpy.fmi1 import FMICallException

    description = read_model_description(str(fmus3["KCS"]))
    vr = {v.name: v.valueReference for v in description.modelVariables}
    messages = []
    slave = FMU3Slave(guid=description.instantiationToken, unzipDirectory=extract(str(fmus3["KCS"]), str(tmp_path / "u")),
                      modelIdentifier="KCS", instanceName="ship")
    slave.instantiate(logMessage=lambda env, status, category, message: messages.append(message.decode()))
    slave.enterInitializationMode(startTime=0.0)
    slave.exitInitializationMode()
    slave.setFloat64([vr["hs"]], [2.0])  # inside the range: accepted
    with pytest.raises(FMICallException):
        slave.setFloat64([vr["hs"]], [-0.5])
    assert messages[-1] == "fmi3SetFloat64: hs (value reference 6) = -0.5 is outside its range [0, inf]"
    slave.freeInstance()


def test_fmi3_independent_variable_reads_the_time(fmus3, tmp_path):
    from fmpy import extract
    from fmpy.fmi3 import FMU3Slave

    from orchestrator.model_description import FMI3_TIME_VR

    description = read_model_description(str(fmus3["KCS"]))
    assert [v.name for v in description.modelVariables if v.causality == "independent"] == ["time"]
    slave = FMU3Slave(guid=description.instantiationToken, unzipDirectory=extract(str(fmus3["KCS"]), str(tmp_path / "u")),
                      modelIdentifier="KCS", instanceName="ship")
    slave.instantiate()
    slave.enterInitializationMode(startTime=10.0)
    slave.exitInitializationMode()
    slave.doStep(10.0, 2.5)
    assert slave.getFloat64([FMI3_TIME_VR]) == [12.5]
    slave.freeInstance()


def test_the_time_is_not_read_before_initialisation(fmus3, tmp_path):
    from fmpy import extract
    from fmpy.fmi1 import FMICallException
    from fmpy.fmi3 import FMU3Slave

    from orchestrator.model_description import FMI3_TIME_VR

    description = read_model_description(str(fmus3["KCS"]))
    messages = []
    slave = FMU3Slave(guid=description.instantiationToken, unzipDirectory=extract(str(fmus3["KCS"]), str(tmp_path / "u")),
                      modelIdentifier="KCS", instanceName="ship")
    slave.instantiate(logMessage=lambda env, status, category, message: messages.append(message.decode()))
    with pytest.raises(FMICallException):
        slave.getFloat64([FMI3_TIME_VR])
    assert messages == ["fmi3GetFloat64: illegal call in state Instantiated"]
    slave.freeInstance()


def test_an_unknown_fmi_version_is_refused_naming_the_key(tmp_path):
    path = tmp_path / "s.toml"
    path.write_text(textwrap.dedent(SCENARIO.format(tag="x", version="1.0")))
    with pytest.raises(ScenarioError, match=r"participants\.ship\.fmi_version' must be one of 2\.0, 3\.0, got '1\.0'"):
        load_scenario(path)


def test_a_description_without_its_model_variables_is_refused_naming_the_element():
    from orchestrator.errors import FmuError
    from orchestrator.model_description import to_fmi3

    text = '<fmiModelDescription fmiVersion="2.0" modelName="M" guid="{1}"><CoSimulation modelIdentifier="M"/>' \
           '</fmiModelDescription>'
    with pytest.raises(FmuError, match=r"^modelDescription.xml: <fmiModelDescription> has no <ModelVariables>$"):
        to_fmi3(text, [], "1.0")
