"""What the master hands its participants and reports: build context, sources, time grid,
output stamps, the position it reports, failures, summaries and the work folder."""

import logging
import time as wallclock

import pytest

from orchestrator import interrupts
from orchestrator.errors import ScenarioError
from orchestrator.master import CoSimulation
from orchestrator.scenario import load_scenario

PROBE = """
connections = ["clock.count -> probe.value"]

[simulation]
start_s = 10.0
stop_s = 20.0
dt_s = 2.0

[participants.clock]
type = "python"
class = "sample_participants:Clock"

[participants.probe]
type = "python"
class = "sample_participants:Probe"
every = {every}
[participants.probe.options]
{options}
"""


def probe_run(write_scenario, options="", every=1, exchange=None, work_dir=None):
    text = PROBE.format(every=every, options=options)
    if exchange:
        text = text.replace("dt_s = 2.0", f'dt_s = 2.0\nexchange = "{exchange}"')
    cosim = CoSimulation(load_scenario(write_scenario(text)), work_dir=work_dir)
    try:
        outcome = cosim.run(progress=False)
    finally:
        cosim.close()
    return cosim, cosim.participant("probe"), outcome


def test_the_build_context_and_sources_a_participant_is_given(write_scenario, tmp_path):
    cosim, probe, outcome = probe_run(write_scenario, every=3)
    context = probe.context
    assert context.where.endswith("scenario.toml: participants.probe")
    assert context.scenario_dir == tmp_path
    assert (context.step_size, context.start_time, context.stop_time) == (6.0, 10.0, 20.0)
    assert context.metocean is None
    assert probe.sources == {"value": cosim.participant("clock")}
    # 5 macro steps of 2 s from t = 10 s, every third: at 10 s (6 s), at 16 s (shortened to 4 s)
    assert probe.calls == [(10.0, 6.0), (16.0, 4.0)]
    assert (outcome.status, outcome.reason, outcome.steps_done) == ("finished", "", 5)


def test_step_end_outputs_are_stamped_at_the_end_of_their_step(write_scenario):
    for exchange in (None, "jacobi"):
        _, _, sampled = probe_run(write_scenario, exchange=exchange)
        _, _, dynamic = probe_run(write_scenario, "at_step_end = true", exchange=exchange)
        held = sampled.recorder.to_frame().set_index("time_s")["probe.value"]
        ended = dynamic.recorder.to_frame().set_index("time_s")["probe.value"]
        # the value is the step's start time: held from it, or reported at its end
        assert list(held.loc[[10.0, 12.0, 14.0]]) == [10.0, 12.0, 14.0]
        assert list(ended.loc[[12.0, 14.0, 16.0]]) == [10.0, 12.0, 14.0]


def test_jacobi_set_ups_see_no_outputs_gauss_seidel_ones_see_earlier_set_ups(write_scenario):
    _, probe, _ = probe_run(write_scenario)
    assert probe.setup_inputs == {"value": 0.0}  # the clock, set up before it
    _, probe, _ = probe_run(write_scenario, exchange="jacobi")
    assert probe.setup_inputs == {}


def test_the_position_reported_for_an_interrupt_names_phase_participant_and_time(write_scenario):
    _, probe, _ = probe_run(write_scenario)
    assert probe.positions[0] == "setting up participant 'probe' at t = 10 s"
    assert probe.positions[1:3] == ["stepping participant 'probe' at t = 10 s",
                                    "stepping participant 'probe' at t = 12 s"]


def test_a_failure_is_reported_with_the_participant_that_raised(write_scenario):
    _, _, outcome = probe_run(write_scenario, 'misbehave = "model_error"\nat_s = 14.0')
    assert (outcome.status, outcome.reason, outcome.steps_done) == ("failed", "probe: refused the step", 2)
    _, _, outcome = probe_run(write_scenario, 'misbehave = "undeclared"\nat_s = 12.0')
    assert outcome.reason == "probe: returned an undeclared output 'surprise'"


def test_an_interrupt_a_library_turned_into_an_error_is_an_interrupt(write_scenario):
    try:
        _, _, outcome = probe_run(write_scenario, 'misbehave = "interrupt_as_error"\nat_s = 12.0')
    finally:
        interrupts._state.reset()
    assert (outcome.status, outcome.reason) == ("interrupted", "interrupted by SIGTERM")


def test_a_failed_set_up_has_done_no_steps(write_scenario):
    text = PROBE.format(every=1, options="") + (
        '\n[participants.crash]\ntype = "python"\nclass = "sample_participants:Crash"\n'
        "[participants.crash.options]\nin_setup = true\n")
    cosim = CoSimulation(load_scenario(write_scenario(text)))
    outcome = cosim.run(progress=False)
    cosim.close()
    assert outcome.status == "failed" and outcome.steps_done == 0 and cosim.steps_done == 0
    assert outcome.reason.startswith("crash: LinAlgError")


@pytest.mark.parametrize("misbehave, status", [("integer", "finished"), ("numpy_scalar", "finished"),
                                               ("numpy_nan", "failed"), ("nan", "failed")])
def test_outputs_of_any_number_type_are_checked_finite(write_scenario, misbehave, status):
    _, _, outcome = probe_run(write_scenario, f'misbehave = "{misbehave}"\nat_s = 12.0')
    assert outcome.status == status
    if status == "failed":
        assert outcome.reason == "probe: output 'value' is not finite at t = 12 s"


def test_a_participant_that_checks_its_own_outputs_is_not_checked_again(write_scenario):
    _, _, outcome = probe_run(write_scenario, 'misbehave = "nan"\nat_s = 12.0\nchecks_finite = true')
    assert outcome.status == "finished"


def test_a_summary_that_raises_is_reported_in_its_place(write_scenario):
    _, _, outcome = probe_run(write_scenario, "bad_summary = true")
    assert outcome.status == "failed"  # a run whose figures cannot all be reported did not end cleanly
    assert outcome.reason == "probe: summary raised ValueError: no summary today"
    assert outcome.participant_summaries["probe"] == {"error": "summary raised ValueError: no summary today"}
    assert outcome.participant_summaries["clock"] == {"steps": 5}


def test_the_wall_time_is_that_of_the_run(write_scenario):
    before = wallclock.perf_counter()
    _, _, outcome = probe_run(write_scenario)
    assert 0.0 <= outcome.wall_time_s <= wallclock.perf_counter() - before


def test_a_given_work_folder_is_used_and_kept_a_temporary_one_is_removed(write_scenario, tmp_path):
    mine = tmp_path / "work"
    mine.mkdir()
    cosim, _, _ = probe_run(write_scenario, work_dir=mine)
    assert cosim.work_dir == mine and mine.is_dir()
    cosim = CoSimulation(load_scenario(write_scenario(PROBE.format(every=1, options=""))))
    made = cosim.work_dir
    assert made.is_dir() and made != mine
    cosim.close()
    assert not made.exists()


def test_the_met_ocean_field_reaches_python_participants_and_fmus(write_scenario, tmp_path):
    text = PROBE.format(every=1, options="") + (
        '\n[metocean]\ngenerator = "paper_default"\nx_range_nm = [0.0, 10.0]\ny_range_nm = [0.0, 10.0]\n'
        '\n[participants.env]\nfmu = "MetOcean"\n[participants.env.parameters]\ngrid_file = "${metocean.grid}"\n')
    (tmp_path / "work").mkdir()
    cosim = CoSimulation(load_scenario(write_scenario(text)), work_dir=tmp_path / "work")
    try:
        field = cosim.participant("probe").context.metocean
        assert field is cosim.metocean and field.x[-1] == pytest.approx(10 * 1852.0)
        grid = tmp_path / "work" / "metocean.grid"
        assert grid.is_file()
        assert cosim.participant("env").parameters["grid_file"] == str(grid)
    finally:
        cosim.close()


def test_participant_lookup_names_the_missing_one(write_scenario):
    cosim = CoSimulation(load_scenario(write_scenario(PROBE.format(every=1, options=""))))
    cosim.close()
    with pytest.raises(KeyError) as missing:
        cosim.participant("radar")
    assert missing.value.args == ("radar",)


@pytest.mark.parametrize("target, message", [
    ("sample_participants", r"participants.probe.class: 'sample_participants' must read 'package.module:Class'$"),
    ("sample_participants:Nowhere", r"participants.probe.class: 'sample_participants:Nowhere' is not a participant "
                                    r"class with from_options\(\)$"),
    ("sample_participants:math", r"'sample_participants:math' is not a participant class with from_options\(\)$"),
    # the module ends at the first colon: what follows is looked up in it as the class
    ("sample_participants:Probe:v2", r"participants.probe.class: 'sample_participants:Probe:v2' is not a participant "
                                     r"class with from_options\(\)$"),
    ("sample_participants:NotAParticipant", r"participants.probe: sample_participants:NotAParticipant does not "
                                            r"build an orchestrator.participant.Participant$"),
])
def test_a_class_that_is_not_a_participant_is_refused(write_scenario, target, message):
    text = PROBE.format(every=1, options="").replace("sample_participants:Probe", target)
    with pytest.raises(ScenarioError, match=message):
        CoSimulation(load_scenario(write_scenario(text)))


def test_refusals_name_the_scenario_file_and_list_the_valid_names(write_scenario):
    text = PROBE.format(every=1, options="").replace("probe.value", "probe.speed")
    with pytest.raises(ScenarioError, match=r"^.*scenario.toml: connection 'clock.count -> probe.speed': probe has "
                                            r"no input 'speed' \(inputs: value\)$"):
        CoSimulation(load_scenario(write_scenario(text)))
    text = PROBE.format(every=1, options='inputs = ["value", "heading"]').replace("probe.value", "probe.speed")
    with pytest.raises(ScenarioError, match=r"no input 'speed' \(inputs: value, heading\)$"):
        CoSimulation(load_scenario(write_scenario(text)))
    text = PROBE.format(every=1, options="").replace('type = "python"\nclass = "sample_participants:Probe"',
                                                     'type = "warp_drive"')
    with pytest.raises(ScenarioError, match=r"unknown participant type 'warp_drive' \(valid: [a-z_]+, [a-z_]+, .*, python\)"):
        CoSimulation(load_scenario(write_scenario(text)))


def test_a_met_ocean_file_is_found_beside_the_scenario_and_its_errors_name_the_table(write_scenario, tmp_path):
    text = PROBE.format(every=1, options="") + '\n[metocean]\nfile = "weather/missing.nc"\n'
    scenario = load_scenario(write_scenario(text))
    with pytest.raises(ScenarioError) as refused:
        CoSimulation(scenario)
    assert str(refused.value) == (f"{scenario.path}: metocean.file: met-ocean file not found: "
                                  f"{tmp_path / 'weather' / 'missing.nc'}")


def test_a_built_in_fmu_is_built_for_the_fmi_version_its_participant_asks_for(write_scenario, monkeypatch):
    from orchestrator import fmu_build

    asked = []

    def ensure_built(name, fmi_version="2.0"):
        asked.append((name, fmi_version))
        raise ScenarioError("stop here: the FMU itself is not needed")

    monkeypatch.setattr(fmu_build, "ensure_built", ensure_built)
    text = PROBE.format(every=1, options="") + '\n[participants.ship]\nfmu = "KCS"\nfmi_version = "3.0"\n'
    with pytest.raises(ScenarioError, match="^stop here"):
        CoSimulation(load_scenario(write_scenario(text)))
    assert asked == [("KCS", "3.0")]


def test_removing_the_files_asks_every_participant_that_has_some_and_removes_the_work_folder(write_scenario):
    cosim = CoSimulation(load_scenario(write_scenario(PROBE.format(every=1, options=""))))
    assert not hasattr(cosim.participant("clock"), "remove_files")  # skipped, not an error
    cosim.remove_files()
    assert cosim.participant("probe").removed == 1
    assert not cosim.work_dir.exists()


def test_every_participant_whose_terminate_fails_is_named_in_the_reason(run_to_end):
    text = PROBE.format(every=1, options="") + "".join(
        f'\n[participants.{name}]\ntype = "python"\nclass = "sample_participants:Misbehaving"\n'
        f'[participants.{name}.options]\nhow = "terminate"\n' for name in ("pump", "winch"))
    outcome = run_to_end(text)
    assert outcome.status == "failed"
    assert outcome.reason == ("pump: terminate() raised OSError: device busy; "
                              "winch: terminate() raised OSError: device busy")


def test_a_class_calling_sys_exit_while_being_built_is_refused_naming_it(write_scenario):
    text = PROBE.format(every=1, options="") + (
        '\n[participants.bad]\ntype = "python"\nclass = "sample_participants:Misbehaving"\n'
        '[participants.bad.options]\nhow = "exit_options"\n')
    scenario = load_scenario(write_scenario(text))
    with pytest.raises(ScenarioError) as refused:
        CoSimulation(scenario)
    assert str(refused.value) == (f"{scenario.path}: participants.bad: sample_participants:Misbehaving called "
                                  "sys.exit(4) while being built")


def test_a_failing_terminate_is_logged_with_its_traceback_at_debug(run_to_end, caplog):
    """The reason names the exception; ``-v`` shows where it was raised."""
    text = PROBE.format(every=1, options="") + (
        '\n[participants.pump]\ntype = "python"\nclass = "sample_participants:Misbehaving"\n'
        '[participants.pump.options]\nhow = "terminate"\n')
    with caplog.at_level(logging.DEBUG, logger="orchestrator.master"):
        run_to_end(text)
    logged = [r for r in caplog.records if r.name == "orchestrator.master" and r.getMessage() == "terminate raised"]
    assert len(logged) == 1 and logged[0].levelno == logging.DEBUG
    assert logged[0].exc_info is not None and isinstance(logged[0].exc_info[1], OSError)


def test_from_options_raising_is_logged_with_its_traceback_at_debug(write_scenario, caplog):
    text = PROBE.format(every=1, options="") + (
        '\n[participants.bad]\ntype = "python"\nclass = "sample_participants:Misbehaving"\n'
        '[participants.bad.options]\nhow = "options"\n')
    with caplog.at_level(logging.DEBUG, logger="orchestrator.participant_build"):
        with pytest.raises(ScenarioError, match="could not be built from its options: ValueError: gain must be positive"):
            CoSimulation(load_scenario(write_scenario(text)))
    logged = [r for r in caplog.records if r.getMessage() == "from_options raised"]
    assert len(logged) == 1 and logged[0].levelno == logging.DEBUG
    assert logged[0].exc_info is not None and str(logged[0].exc_info[1]) == "gain must be positive"


def test_closing_again_after_the_work_folder_is_gone_does_not_raise(write_scenario):
    """remove_files (a watchdog ending the process) closes the master, and the run's own clean-up
    closes it again."""
    cosim = CoSimulation(load_scenario(write_scenario(PROBE.format(every=1, options=""))))
    cosim.remove_files()
    assert not cosim.work_dir.exists()
    cosim.close()
    assert not cosim.work_dir.exists()
