"""The FMU participant's lifecycle on the KCS FMU: inputs given at set-up, messages the FMU
logs, failures named by their FMI function and time, and what terminate leaves behind."""

import logging
import math
from pathlib import Path

import pytest
from fmpy.fmi1 import FMICallException

from orchestrator.errors import ModelError
from orchestrator.fmi_slave import FmiSlave
from orchestrator.master import CoSimulation
from orchestrator.scenario import load_scenario

from test_fmu_participant import STRAIGHT


@pytest.fixture
def ship(write_scenario):
    cosim = CoSimulation(load_scenario(write_scenario(STRAIGHT)))
    participant = cosim.participant("ship")
    yield participant
    participant.terminate()
    cosim.close()


def test_inputs_given_at_set_up_drive_the_first_step(ship):
    ship.setup(0.0, {"tau_u": 7.7e5, "tau_r": 1.0e9})
    turning = ship.step(0.0, 10.0, {})  # no new inputs: those of the set-up hold
    assert turning["r"] > 0.0


def test_each_step_sets_the_inputs_it_is_given_in_any_order_and_the_others_hold(ship):
    refs = [ship.variables[name].valueReference for name in ("tau_u", "tau_r")]
    ship.setup(0.0, {"tau_u": 7.7e5, "tau_r": 1.0e8})
    ship.step(0.0, 1.0, {"tau_r": 2.0e8})
    assert ship._slave.get_reals(refs) == [7.7e5, 2.0e8]
    ship.step(1.0, 1.0, {"tau_r": 3.0e8, "tau_u": 6.6e5})
    assert ship._slave.get_reals(refs) == [6.6e5, 3.0e8]
    ship.step(2.0, 1.0, {"tau_u": 5.5e5, "tau_r": 4.0e8})
    assert ship._slave.get_reals(refs) == [5.5e5, 4.0e8]


def test_outputs_are_read_at_the_end_of_the_step(ship, monkeypatch):
    ship.setup(0.0, {"tau_u": 7.7e5, "tau_r": 0.0})
    monkeypatch.setattr(ship, "_read_reals", lambda: [math.nan] * len(ship._output_refs))  # what the FMU gives
    with pytest.raises(ModelError, match=r"^ship \(KCS.fmu\): output '\w+' is nan at t = 10 s$"):
        ship.step(0.0, 10.0, {})


def test_a_non_finite_output_at_set_up_names_the_start_time(ship, monkeypatch):
    monkeypatch.setattr(FmiSlave, "real_reader", lambda self, refs: lambda: [math.inf] * len(refs))
    with pytest.raises(ModelError, match=r"^ship \(KCS.fmu\): output '\w+' is inf at t = 0 s$"):
        ship.setup(0.0, {"tau_u": 7.7e5, "tau_r": 0.0})


def refuse(self, *args, **kwargs):
    raise FMICallException(function="any", status=3)


@pytest.mark.parametrize("method, function, replacement", [
    ("enter_initialization", "fmi2EnterInitializationMode", refuse),
    ("real_reader", "fmi2GetReal", lambda self, refs: lambda: refuse(self)),  # the reader it makes refuses
])
def test_a_refused_call_is_named_by_its_fmi_function(ship, monkeypatch, method, function, replacement):
    monkeypatch.setattr(FmiSlave, method, replacement)
    with pytest.raises(ModelError, match=rf"^ship \(KCS.fmu\): {function} failed: "):
        ship.setup(0.0, {"tau_u": 7.7e5, "tau_r": 0.0})


def test_fmu_warnings_are_logged_as_warnings_and_kept_for_the_error(ship, caplog):
    with caplog.at_level(logging.DEBUG, logger="orchestrator.fmu_participant"):
        for status, text in ((0, "fine"), (1, "a warning"), (2, "discarded"), (3, "an error")):
            ship._on_message(status, "category", text)
    levels = {record.getMessage(): record.levelno for record in caplog.records}
    assert levels == {"ship [category]: fine": logging.DEBUG, "ship [category]: a warning": logging.WARNING,
                      "ship [category]: discarded": logging.WARNING, "ship [category]: an error": logging.DEBUG}
    assert ship._messages == ["a warning", "discarded", "an error"]  # what a failed call reports


def test_terminate_frees_the_fmu_and_removes_its_unpacked_files(ship):
    ship.setup(0.0, {"tau_u": 7.7e5, "tau_r": 0.0})
    unpacked = Path(ship._unzip_dir)
    slave = ship._slave
    freed = []
    original_free = slave.free
    slave.free = lambda: (freed.append(True), original_free())
    assert unpacked.is_dir()
    ship.terminate()
    assert freed == [True] and ship._slave is None
    assert not unpacked.exists() and ship._unzip_dir is None
    ship.terminate()  # a second terminate does nothing


def test_a_step_before_the_set_up_is_refused_saying_so(ship):
    with pytest.raises(RuntimeError, match="^an FMU participant was stepped before its set-up$"):
        ship.step(0.0, 10.0, {})


def test_the_fmu_is_unpacked_where_a_later_run_finds_it_if_this_process_dies(ship):
    """A killed run removes nothing: the next one sweeps the temporary folder for ``rhnc-fmu-<pid>-*``
    (orchestrator.leftovers), so the unpacked FMU must carry that name and its owner's lock."""
    import os
    import tempfile

    from orchestrator import leftovers

    ship.setup(0.0, {"tau_u": 7.7e5, "tau_r": 0.0})
    unpacked = Path(ship._unzip_dir)
    assert unpacked.parent == Path(tempfile.gettempdir())
    assert unpacked.name.startswith(f"rhnc-fmu-{os.getpid()}-")
    assert (unpacked / leftovers.LOCK_NAME).is_file()
