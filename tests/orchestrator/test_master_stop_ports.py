"""The master's set-up probe of the ``stop_when`` ports (what ``validate`` calls), part by part.

``check_stop_ports`` is otherwise reached only through the CLI's ``validate``
(``test_clean_failures.py``); these build the master and call it directly, recording which
participants it sets up, with which inputs, and which it terminates.
"""

from pathlib import Path

import pytest

from orchestrator.master import CoSimulation, StopConditionError
from orchestrator.scenario import load_scenario

THREE = """
connections = ["clock.count -> echo.value", "clock.time -> probe.when"]

[simulation]
stop_s = 5.0
dt_s = 1.0
{simulation}

[participants.clock]
type = "python"
class = "sample_participants:Clock"

[participants.echo]
type = "python"
class = "sample_participants:Echo"

[participants.probe]
type = "python"
class = "sample_participants:Probe"
[participants.probe.options]
inputs = ["when"]
"""


def probe_master(write_scenario, monkeypatch, simulation):
    """The master of clock -> echo, clock -> probe with ``simulation`` lines added, its set-ups
    and terminations recorded (in order) in the returned list."""
    monkeypatch.syspath_prepend(str(Path(__file__).parent))
    cosim = CoSimulation(load_scenario(write_scenario(THREE.format(simulation=simulation))))
    calls = []
    for participant in cosim.participants:
        def setup(start_time, inputs, participant=participant, original=participant.setup):
            calls.append(("setup", participant.name, dict(inputs)))
            return original(start_time, inputs)

        def terminate(participant=participant, original=participant.terminate):
            calls.append(("terminate", participant.name))
            return original()

        monkeypatch.setattr(participant, "setup", setup)
        monkeypatch.setattr(participant, "terminate", terminate)
    return cosim, calls


def test_an_array_port_in_a_stop_condition_is_refused_naming_it(write_scenario, monkeypatch):
    cosim, calls = probe_master(write_scenario, monkeypatch, 'stop_when = "clock.vector > 0"')
    with pytest.raises(StopConditionError, match=r"simulation.stop_when 'clock.vector > 0': output 'vector' of "
                                                 r"'clock' is an array of shape \(2,\)"):
        cosim.check_stop_ports()
    cosim.close()
    # only clock, the one the condition names, was set up, and it was terminated
    assert calls == [("setup", "clock", {}), ("terminate", "clock")]


def test_only_the_participants_up_to_the_last_one_named_are_set_up_and_all_of_them_terminated(
        write_scenario, monkeypatch):
    cosim, calls = probe_master(write_scenario, monkeypatch, 'stop_when = "echo.seen > 3"')
    cosim.check_stop_ports()
    cosim.close()
    # probe, declared after echo, is not set up; echo gets only its own connection's value, not
    # clock's time (the input of probe's connection)
    assert calls == [("setup", "clock", {}), ("setup", "echo", {"value": 0.0}),
                     ("terminate", "clock"), ("terminate", "echo")]


def test_jacobi_the_set_up_sees_no_outputs_of_the_others(write_scenario, monkeypatch):
    cosim, calls = probe_master(write_scenario, monkeypatch, 'exchange = "jacobi"\nstop_when = "echo.seen > 3"')
    cosim.check_stop_ports()
    cosim.close()
    # echo is set up without clock's count, as a Jacobi run's first round sees it
    assert calls == [("setup", "clock", {}), ("setup", "echo", {}), ("terminate", "clock"), ("terminate", "echo")]


def test_without_a_stop_condition_nobody_is_set_up(write_scenario, monkeypatch):
    cosim, calls = probe_master(write_scenario, monkeypatch, "")
    cosim.check_stop_ports()
    cosim.close()
    assert calls == []


def test_a_set_up_that_raises_still_terminates_those_set_up(write_scenario, monkeypatch):
    cosim, calls = probe_master(write_scenario, monkeypatch, 'stop_when = "probe.value > 3"')

    def refuse(start_time, inputs):
        calls.append(("setup", "echo", dict(inputs)))
        raise RuntimeError("no licence")

    monkeypatch.setattr(cosim.participant("echo"), "setup", refuse)
    with pytest.raises(RuntimeError, match="no licence"):
        cosim.check_stop_ports()
    cosim.close()
    assert calls == [("setup", "clock", {}), ("setup", "echo", {"value": 0.0}),
                     ("terminate", "clock"), ("terminate", "echo")]
