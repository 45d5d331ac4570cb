"""The master loop: exchange order, multi-rate stepping, recording and failures."""

import json

import numpy as np
import pandas as pd
import pytest

from orchestrator.errors import ScenarioError
from orchestrator.master import CoSimulation
from orchestrator.run import run_scenario
from orchestrator.scenario import load_scenario

TWO = """
connections = ["clock.count -> echo.value"]

[simulation]
stop_s = 10.0
dt_s = 1.0

[participants.{first}]
type = "python"
class = "sample_participants:{first_class}"
every = {first_every}

[participants.{second}]
type = "python"
class = "sample_participants:{second_class}"
every = {second_every}
"""


def scenario_text(order=("clock", "echo"), every=(1, 1)):
    classes = {"clock": "Clock", "echo": "Echo"}
    return TWO.format(first=order[0], first_class=classes[order[0]], first_every=every[0],
                      second=order[1], second_class=classes[order[1]], second_every=every[1])


def run(write_scenario, text):
    cosim = CoSimulation(load_scenario(write_scenario(text)))
    outcome = cosim.run(progress=False)
    cosim.close()
    return cosim, outcome


def test_gauss_seidel_a_later_participant_sees_this_steps_outputs(write_scenario):
    cosim, outcome = run(write_scenario, scenario_text(("clock", "echo")))
    assert outcome.status == "finished"
    # echo steps after clock at t = k: it sees clock's count of this step, k + 1
    assert cosim.participant("echo").seen[:3] == [(0.0, 1.0), (1.0, 2.0), (2.0, 3.0)]


def test_an_earlier_participant_sees_the_previous_steps_outputs(write_scenario):
    cosim, outcome = run(write_scenario, scenario_text(("echo", "clock")))
    assert outcome.status == "finished"
    # echo steps first: at t = k it still sees clock's count from step k - 1 (set-up: 0)
    assert cosim.participant("echo").seen[:3] == [(0.0, 0.0), (1.0, 1.0), (2.0, 2.0)]


def jacobi(text):
    return text.replace("dt_s = 1.0", 'dt_s = 1.0\nexchange = "jacobi"')


def test_jacobi_every_participant_sees_the_outputs_published_before_the_point(write_scenario):
    # declared first or second, echo sees clock's count of the previous step (set-up: none)
    for order in (("clock", "echo"), ("echo", "clock")):
        cosim, outcome = run(write_scenario, jacobi(scenario_text(order)))
        assert outcome.status == "finished"
        assert cosim.participant("echo").seen[:3] == [(0.0, 0.0), (1.0, 1.0), (2.0, 2.0)]


def test_jacobi_outputs_of_a_longer_step_arrive_at_its_end(write_scenario):
    cosim, outcome = run(write_scenario, jacobi(scenario_text(("clock", "echo"), every=(3, 1))))
    seen = dict(cosim.participant("echo").seen)
    # clock steps at 0, 3, 6: its count from the step at 0 reaches echo at 3, not at 1
    assert [seen[t] for t in (0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0)] == [0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 2.0]


def test_an_unknown_exchange_order_is_refused_naming_the_key(write_scenario):
    with pytest.raises(ScenarioError, match=r"'simulation.exchange' must be one of gauss-seidel, jacobi, got 'random'"):
        load_scenario(write_scenario(scenario_text().replace("dt_s = 1.0", 'dt_s = 1.0\nexchange = "random"')))


def test_multi_rate_steps_and_hold(write_scenario):
    cosim, outcome = run(write_scenario, scenario_text(("clock", "echo"), every=(3, 1)))
    clock = cosim.participant("clock")
    # 10 macro steps, clock every 3: at 0, 3, 6 with step 3 s, the last at 9 shortened to 1 s
    assert clock.calls == [(0.0, 3.0), (3.0, 3.0), (6.0, 3.0), (9.0, 1.0)]
    seen = dict(cosim.participant("echo").seen)
    assert [seen[t] for t in (0.0, 1.0, 2.0, 3.0, 4.0)] == [1.0, 1.0, 1.0, 2.0, 2.0]
    frame = outcome.recorder.to_frame()
    assert list(frame["clock.count"][:5]) == [1.0, 1.0, 1.0, 2.0, 2.0]


def test_a_connection_from_some_of_many_outputs_hands_on_the_port_it_names(write_scenario):
    # the ship gives eight outputs each step and one is connected: what the echo sees is that
    # one, the value the ship gave at the end of its step (the row of t + 1)
    text = """
connections = ["helm.tau_u -> ship.tau_u", "helm.tau_r -> ship.tau_r", "ship.r -> echo.value"]
[simulation]
stop_s = 30.0
dt_s = 1.0
[participants.helm]
type = "scripted_tau"
[participants.helm.options]
tau_u_N = 7.7e5
tau_r_steps = [[5.0, 3.3e8]]
[participants.ship]
fmu = "KCS"
[participants.ship.parameters]
u0 = 9.26
[participants.echo]
type = "python"
class = "sample_participants:Echo"
"""
    cosim, outcome = run(write_scenario, text)
    assert outcome.status == "finished"
    frame = outcome.recorder.to_frame()
    seen = [value for _, value in cosim.participant("echo").seen]
    assert len(seen) == len(frame) == 30 and seen[:-1] == list(frame["ship.r"][1:])  # (the row of 30 s: after the run)
    assert len(set(seen)) > 20  # the ship turns: the values differ from step to step


def test_an_output_not_yet_given_is_left_out_of_the_inputs_until_it_is(write_scenario):
    # the collector steps first; 'late' gives 'b' from its first step on: the collector's first
    # step has 'a' alone (from the set-up), the later ones both, in the order declared
    text = """
connections = ["late.b -> collector.b", "late.a -> collector.a"]
[simulation]
stop_s = 3.0
dt_s = 1.0
[participants.collector]
type = "python"
class = "sample_participants:Collector"
[participants.late]
type = "python"
class = "sample_participants:Late"
"""
    cosim, outcome = run(write_scenario, text)
    assert outcome.status == "finished", outcome.reason
    seen = cosim.participant("collector").seen
    assert seen == [{"a": 0.5}, {"b": -1.0, "a": 1.0}, {"b": -2.0, "a": 2.0}]
    assert [list(inputs) for inputs in seen[1:]] == [["b", "a"], ["b", "a"]]


def test_a_participant_that_does_not_say_it_checks_its_outputs_has_them_checked(write_scenario):
    # all-float outputs take the master's quick path: without ``checks_outputs_finite`` the
    # master checks them itself there too
    text = """
[simulation]
stop_s = 5.0
dt_s = 1.0
[participants.drifter]
type = "python"
class = "sample_participants:Drifter"
"""
    _, outcome = run(write_scenario, text)
    assert outcome.status == "failed"
    assert outcome.reason == "drifter: output 'value' is not finite at t = 2 s"


def test_recorder_flattens_arrays_and_stamps_times(write_scenario):
    _, outcome = run(write_scenario, scenario_text())
    frame = outcome.recorder.to_frame()
    assert list(frame["time_s"]) == [float(t) for t in range(10)]
    np.testing.assert_allclose(frame["clock.vector[1]"], 2 * frame["time_s"])
    np.testing.assert_allclose(frame["clock.time"], frame["time_s"])


def test_a_nan_output_fails_the_run_and_keeps_what_was_computed(write_scenario, tmp_path):
    text = scenario_text() + "[participants.clock.options]\nnan_at_s = 4.0\n"
    report = run_scenario(write_scenario(text), tmp_path / "results", progress=False)
    assert report.status == "failed"
    assert report.reason == "clock: output 'count' is not finite at t = 4 s"
    summary = json.loads((report.folder / "summary.json").read_text())
    assert summary["status"] == "failed"
    assert summary["simulation"]["steps_done"] == 4
    frame = pd.read_parquet(report.folder / "timeseries.parquet")
    assert frame["time_s"].iloc[-1] == 3.0
    assert not list((tmp_path / "results" / "scenario").glob(".*partial"))
    calls = pd.read_csv(report.folder / "clock_calls.csv")  # a participant's event log
    assert list(calls["time"]) == [0.0, 1.0, 2.0, 3.0, 4.0]


def test_a_participant_exception_is_a_failed_run(write_scenario, tmp_path):
    text = scenario_text() + '\n[participants.crash]\ntype = "python"\nclass = "sample_participants:Crash"\n' \
        "[participants.crash.options]\nat_s = 2.0\n"
    report = run_scenario(write_scenario(text), tmp_path, progress=False)
    assert (report.status, report.reason) == ("failed", "crash: RuntimeError: boom")  # names who raised
    assert report.summary["participants"]["clock"] == {"steps": 3}


def test_connection_to_a_missing_port_is_refused(write_scenario):
    text = scenario_text().replace("clock.count -> echo.value", "clock.speed -> echo.value")
    with pytest.raises(ScenarioError, match=r"connection 'clock.speed -> echo.value': clock has no output 'speed' "
                                            r"\(outputs: count, time, vector\)"):
        CoSimulation(load_scenario(write_scenario(text)))
    text = scenario_text().replace("clock.count -> echo.value", "echo.seen -> clock.count")
    with pytest.raises(ScenarioError, match=r"clock has no input 'count'"):
        CoSimulation(load_scenario(write_scenario(text)))


def test_unknown_type_and_class(write_scenario):
    text = scenario_text().replace('type = "python"\nclass = "sample_participants:Echo"', 'type = "warp_drive"')
    with pytest.raises(ScenarioError, match=r"participants.echo.type: unknown participant type 'warp_drive'"):
        CoSimulation(load_scenario(write_scenario(text)))
    text = scenario_text().replace("sample_participants:Echo", "no_such_module:Echo")
    with pytest.raises(ScenarioError, match=r"participants.echo.class: cannot import module 'no_such_module': "
                                            r"No module named 'no_such_module'$"):
        CoSimulation(load_scenario(write_scenario(text)))


def test_a_class_whose_module_lies_beside_the_scenario_but_off_the_import_path_is_refused_saying_so(
        write_scenario, tmp_path):
    (tmp_path / "helm_beside_the_scenario.py").write_text("raise AssertionError('must not be imported')\n")
    text = scenario_text().replace("sample_participants:Echo", "helm_beside_the_scenario:Helm")
    with pytest.raises(ScenarioError, match=r"participants.echo.class: cannot import module 'helm_beside_the_scenario': "
                                            r"No module named 'helm_beside_the_scenario' \(it lies in the scenario's "
                                            r"folder .*, which is not on the import path: start the command from that "
                                            r"folder, or install the module\)$"):
        CoSimulation(load_scenario(write_scenario(text)))


def test_unknown_participant_option(write_scenario):
    text = scenario_text() + "[participants.echo.options]\ngain = 2\n"
    with pytest.raises(ScenarioError, match=r"participants.echo.options: unknown option 'gain'"):
        CoSimulation(load_scenario(write_scenario(text)))


def test_interrupt_keeps_results(write_scenario, tmp_path, monkeypatch):
    from orchestrator import master

    original = master.CoSimulation.run

    def interrupted_run(self, progress=True, on_step=None, spool=None):
        def stop(k):
            if k == 2:
                raise KeyboardInterrupt
        return original(self, progress=False, on_step=stop, spool=spool)

    monkeypatch.setattr(master.CoSimulation, "run", interrupted_run)
    report = run_scenario(write_scenario(scenario_text()), tmp_path, progress=False)
    assert report.status == "interrupted"
    assert report.summary["simulation"]["steps_done"] == 3  # steps 0, 1, 2 completed
    assert (report.folder / "timeseries.parquet").is_file()


def test_stop_condition_ends_the_run_as_finished(write_scenario, tmp_path):
    text = scenario_text().replace("dt_s = 1.0", 'dt_s = 1.0\nstop_when = "clock.count >= 4"')
    report = run_scenario(write_scenario(text), tmp_path, progress=False)
    assert report.status == "finished"
    assert report.reason == "stopped at t = 3 s before the step of echo: clock.count >= 4"
    assert report.summary["simulation"]["steps_done"] == 4


def test_a_met_stop_condition_steps_nobody_after_it(write_scenario):
    # clock first: once its count reaches 4 (at t = 3) echo, declared after it, is not stepped
    # again (a goal monitor before the ship: the ship is not stepped past its arrival)
    text = scenario_text(("clock", "echo")).replace("dt_s = 1.0", 'dt_s = 1.0\nstop_when = "clock.count >= 4"')
    cosim, outcome = run(write_scenario, text)
    assert outcome.status == "finished"
    assert outcome.reason == "stopped at t = 3 s before the step of echo: clock.count >= 4"
    assert [t for t, _ in cosim.participant("echo").seen] == [0.0, 1.0, 2.0]


def test_jacobi_a_stop_condition_ends_the_run_before_the_next_round(write_scenario):
    text = jacobi(scenario_text(("clock", "echo"))).replace("dt_s = 1.0", 'dt_s = 1.0\nstop_when = "clock.count >= 4"')
    cosim, outcome = run(write_scenario, text)
    assert outcome.reason == "stopped at t = 4 s: clock.count >= 4"
    assert [t for t, _ in cosim.participant("echo").seen] == [0.0, 1.0, 2.0, 3.0]


def test_stop_condition_on_a_missing_output(write_scenario):
    text = scenario_text().replace("dt_s = 1.0", 'dt_s = 1.0\nstop_when = "clock.speed > 1"')
    with pytest.raises(ScenarioError, match=r"simulation.stop_when 'clock.speed > 1': no output 'speed'"):
        CoSimulation(load_scenario(write_scenario(text)))


@pytest.mark.parametrize("outputs, message", [
    ('analyses = ["speed_trial"]', r"scenario.toml: 'outputs.analyses': unknown name 'speed_trial' \(valid: .*voyage"),
    ('figures = ["radar"]', r"scenario.toml: 'outputs.figures': unknown name 'radar'"),
    ('analyses = ["voyage"]\n[outputs.options.voyage]\ngoal = [1, 2]',
     r"unknown option 'outputs.options.voyage.goal' \(valid: goal_nm, arrival_radius_nm, cii_year\)"),
])
def test_unknown_outputs_are_refused_before_the_run(write_scenario, outputs, message):
    text = scenario_text() + f"\n[outputs]\n{outputs}\n"
    with pytest.raises(ScenarioError, match=message):
        CoSimulation(load_scenario(write_scenario(text)))
