"""The per-step FMU calls of :class:`orchestrator.fmi_slave.FmiSlave` on FMPy's C functions.

They skip FMPy's per-call Python layer, so they must refuse what it refuses (a status above
a warning, as :class:`fmpy.fmi1.FMICallException` naming the function) and leave a call
logger its calls.
"""

from __future__ import annotations

import shutil

import pytest
from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException

from orchestrator.fmi_slave import FmiSlave
from orchestrator.fmu_build import ensure_built


@pytest.fixture
def kcs():
    """A KCS instance in step mode at t = 0 and the value reference of its output ``x``."""
    fmu = ensure_built("KCS")
    description = read_model_description(str(fmu))
    unzip = extract(str(fmu))
    messages = []
    slave = FmiSlave(description, unzip, "ship", lambda *message: messages.append(message))
    slave.instantiate()
    slave.enter_initialization(0.0)
    slave.exit_initialization()
    refs = {v.name: v.valueReference for v in description.modelVariables}
    yield slave, refs
    slave.terminate()
    slave.free()
    shutil.rmtree(unzip, ignore_errors=True)


UNKNOWN = 987654  # a value reference the KCS does not have


def test_a_refused_get_real_raises_what_fmpy_raises(kcs):
    slave, refs = kcs
    assert slave.real_reader([refs["x"]])() == [0.0]
    with pytest.raises(FMICallException, match="^fmi2GetReal failed with status 3") as raised:
        slave.real_reader([UNKNOWN])()
    assert raised.value.function == "fmi2GetReal"


def test_a_refused_set_real_raises_what_fmpy_raises(kcs):
    slave, refs = kcs
    slave.real_writer([refs["tau_u"]])([1.0e5])
    with pytest.raises(FMICallException, match="^fmi2SetReal failed with status 3"):
        slave.real_writer([UNKNOWN])([1.0])


def test_a_refused_do_step_raises_what_fmpy_raises(kcs):
    slave, _ = kcs
    step = slave.stepper()
    step(0.0, 1.0)
    with pytest.raises(FMICallException, match="^fmi2DoStep failed with status 3"):
        step(5.0, 1.0)  # not the communication point the FMU is at (1 s)


def test_a_call_logger_is_given_every_per_step_call(kcs):
    slave, refs = kcs
    logged = []
    slave._fmu.fmiCallLogger = logged.append
    slave.real_writer([refs["tau_u"]])([1.0e5])
    slave.stepper()(0.0, 1.0)
    slave.real_reader([refs["x"]])()
    assert [line.split("(")[0] for line in logged] == ["fmi2SetReal", "fmi2DoStep", "fmi2GetReal"]


def test_the_reader_gives_what_fmpy_reads_after_every_step(kcs):
    slave, refs = kcs
    outputs = [refs[name] for name in ("x", "y", "psi", "u", "v", "r")]
    read, step = slave.real_reader(outputs), slave.stepper()
    slave.real_writer([refs["tau_u"], refs["tau_r"]])([7.7e5, 3.3e8])
    seen = []
    for k in range(3):
        step(float(k), 1.0)
        seen.append(read())
        assert seen[-1] == slave.get_reals(outputs)
    assert seen[0] != seen[1] != seen[2]
