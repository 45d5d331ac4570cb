"""Wall-time limits on participant calls: a participant that sleeps, swallows every exception
or loops in native code inside an FMU cannot block a run for ever.

What must hold: status ``timed out`` with a reason naming the participant, exit code 3, the
results written (the time series up to the step that hung).
"""

import json
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from orchestrator import time_limits
from orchestrator.cli import main
from orchestrator.errors import ScenarioError
from orchestrator.scenario import load_scenario

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[1]

SLEEPER = """
[simulation]
name = "sleepy"
steps = 20
dt_s = 1.0
step_timeout_s = 1.0
[participants.clock]
type = "python"
class = "sample_participants:Clock"
[participants.nap]
type = "python"
class = "sample_participants:Sleeper"
[participants.nap.options]
at_s = 4.0
[outputs]
format = "csv"
figures = []
"""


def summary_of(out: str) -> tuple[Path, dict]:
    folder = Path(out.split("results in ")[1].split()[0])
    return folder, json.loads((folder / "summary.json").read_text())


def test_a_sleeping_python_participant_is_stopped_at_its_limit(write_scenario, tmp_path, capsys):
    path = write_scenario(SLEEPER)
    assert main(["run", str(path), "--results", str(tmp_path / "results"), "--no-progress"]) == 3
    captured = capsys.readouterr()
    assert "error: participant 'nap' did not return from its step at t = 4 s within its wall-time limit " \
           "of 1 s (step_timeout_s)" in captured.err
    folder, summary = summary_of(captured.out)
    assert "\ntimed out: results in" in captured.out
    assert summary["status"] == "timed out"
    assert summary["simulation"]["steps_done"] == 4  # the step of t = 4 s is not recorded as done
    series = (folder / "timeseries.csv").read_text().splitlines()
    assert len(series) == 1 + 5  # header, t = 0 .. 4 s (the clock stepped at 4 s before the sleeper)
    assert summary["participants"]["clock"] == {"steps": 5}


def test_a_participants_own_limit_replaces_the_simulations(write_scenario, tmp_path):
    from orchestrator.run import run_scenario

    text = SLEEPER.replace("step_timeout_s = 1.0", "step_timeout_s = 0.5").replace("at_s = 4.0", "at_s = 17.0").replace(
        "[participants.nap.options]", "step_timeout_s = 30.0\n[participants.nap.options]\nsleep_s = 1.0")
    report = run_scenario(write_scenario(text), tmp_path, progress=False)
    assert report.status == "finished"  # three 1 s sleeps under nap's own 30 s limit, over the simulation's 0.5 s
    assert load_scenario(write_scenario(text)).participant("nap").step_timeout_s == 30.0


def test_a_limit_the_participant_swallows_still_ends_the_run(write_scenario, tmp_path):
    """The master checks the time-out flag after the call: a swallowed StepTimeout does not hide it."""
    from orchestrator.run import run_scenario

    # interrupted at 1 s, it swallows the exception and sleeps 1.2 s more, then returns normally
    text = SLEEPER.replace("at_s = 4.0", "at_s = 4.0\nsleep_s = 1.2\nswallow = true")
    report = run_scenario(write_scenario(text), tmp_path, progress=False)
    assert report.status == "timed out" and "participant 'nap'" in report.reason
    assert report.summary["simulation"]["steps_done"] == 4


@pytest.mark.parametrize("table, key", [("simulation", "simulation.step_timeout_s"),
                                        ("participants.nap", "participants.nap.step_timeout_s")])
@pytest.mark.parametrize("value", [0, -1.0, "'10'", "nan"])
def test_a_bad_limit_is_refused_naming_the_key(write_scenario, table, key, value):
    text = SLEEPER.replace("step_timeout_s = 1.0\n", "")
    text = text.replace(f"[{table}]\n", f"[{table}]\nstep_timeout_s = {value}\n")
    with pytest.raises(ScenarioError, match=re.escape(f"'{key}' must be")):
        load_scenario(write_scenario(text))


def test_the_default_limit_applies_when_none_is_given(write_scenario):
    scenario = load_scenario(write_scenario(SLEEPER.replace("step_timeout_s = 1.0\n", "")))
    assert scenario.simulation.step_timeout_s == time_limits.DEFAULT_STEP_TIMEOUT_S


def run_cli(tmp_path, text, name, timeout=120):
    """Run the command line in a process whose temporary folders go to ``tmp_path / "tmp"``."""
    path = tmp_path / f"{name}.toml"
    path.write_text(text)
    (tmp_path / "tmp").mkdir()
    return subprocess.run(
        [sys.executable, "-m", "orchestrator", "run", str(path), "--results", str(tmp_path / "results"),
         "--no-progress"], capture_output=True, text=True, timeout=timeout,
        env={**__import__("os").environ, "PYTHONPATH": f"{HERE}:{REPO}", "TMPDIR": str(tmp_path / "tmp")})


@pytest.mark.slow
def test_a_participant_that_swallows_the_limit_is_ended_with_the_process(tmp_path):
    text = SLEEPER.replace("at_s = 4.0", "at_s = 4.0\nswallow = true")
    result = run_cli(tmp_path, text, "sleepy")
    assert result.returncode == time_limits.EXIT_TIMED_OUT, result.stderr
    assert "the call did not return 2 s after it was interrupted (native code), so the process was ended" \
        in result.stderr
    folder, summary = summary_of(result.stdout)
    assert summary["status"] == "timed out" and "participant 'nap'" in summary["reason"]
    assert summary["simulation"]["steps_done"] == 4
    assert len((folder / "timeseries.csv").read_text().splitlines()) == 1 + 5
    assert [p.name for p in folder.parent.iterdir() if p.name.startswith(".")] == []
    assert list((tmp_path / "tmp").iterdir()) == []  # no rhnc-run-* folder outlives the process


@pytest.fixture(scope="module")
def spinning_fmu(tmp_path_factory):
    """The KCS FMU with a busy loop in fmi2DoStep from t = 20 s on (native code that never returns)."""
    from orchestrator import fmu_build

    tree = tmp_path_factory.mktemp("models")
    for name in ("common", "KCS"):
        shutil.copytree(REPO / "models" / name, tree / name)
    model = tree / "KCS" / "model.c"
    source = model.read_text()
    anchor = "fmi2Status model_do_step(ModelInstance *comp, double t, double h) {\n"
    assert anchor in source
    model.write_text(source.replace(anchor, anchor + "    volatile int spin = t >= 20.0;\n    while (spin) {}\n"))
    return fmu_build.build_fmu("KCS", out_dir=tree / "built", models_dir=tree)


@pytest.mark.slow
def test_a_native_busy_loop_in_an_fmu_is_ended_with_its_status_and_series(tmp_path, spinning_fmu):
    text = (REPO / "scenarios" / "turning_circle.toml").read_text()
    text = text.replace('fmu = "KCS"', f'fmu = "{spinning_fmu}"\nstep_timeout_s = 1.0').replace(
        'parameter_set = "default"\n', '')
    result = run_cli(tmp_path, text, "turning_circle")
    assert result.returncode == time_limits.EXIT_TIMED_OUT, result.stderr
    assert re.search(r"error: participant 'ship' did not return from its step at t = 20 s within its wall-time "
                     r"limit of 1 s .*the process was ended", result.stderr), result.stderr
    assert "Traceback" not in result.stderr
    folder, summary = summary_of(result.stdout)
    assert summary["status"] == "timed out"
    assert summary["simulation"]["steps_done"] == 4
    series = (folder / "timeseries.csv").read_text().splitlines()
    assert series[0].startswith("time_s,") and "ship.x" in series[0]
    assert len(series) == 1 + 5
    assert list((tmp_path / "tmp").iterdir()) == []  # neither the run's folder nor the unpacked FMU


def test_a_run_on_another_thread_is_stopped_at_its_limit(write_scenario, tmp_path):
    """As in a Dask worker: no signal reaches the thread, the exception is raised in it."""
    import threading

    from orchestrator.run import run_scenario

    path = write_scenario(SLEEPER.replace("at_s = 4.0", "at_s = 4.0\nbusy = true"))
    reports = []
    worker = threading.Thread(target=lambda: reports.append(run_scenario(path, tmp_path, progress=False)))
    worker.start()
    worker.join(120.0)
    assert not worker.is_alive()
    (report,) = reports
    assert report.status == "timed out" and "participant 'nap'" in report.reason
    assert report.summary["simulation"]["steps_done"] == 4


def test_a_set_up_over_its_limit_ends_the_run_naming_the_set_up(run_to_end):
    text = SLEEPER.replace("step_timeout_s = 1.0", "step_timeout_s = 0.3").replace(
        "[participants.nap.options]", "[participants.nap.options]\nsetup_sleep_s = 5.0")
    outcome = run_to_end(text)
    assert outcome.status == "timed out"
    assert outcome.reason == ("participant 'nap' did not return from set-up at t = 0 s within its wall-time limit "
                              "of 0.3 s (step_timeout_s)")


def test_a_call_that_does_not_return_after_its_interrupt_has_the_run_written_as_timed_out(run_to_end,
                                                                                          monkeypatch):
    """What the watchdog writes before it ends the process: the run's emergency writers are
    called with the reason and the status "timed out" (the process's end is only recorded here)."""
    from orchestrator import interrupts

    written, ended = [], []
    monkeypatch.setattr(interrupts, "write_emergency", lambda why, status="interrupted": written.append((why, status)))
    monkeypatch.setattr(time_limits.os, "_exit", ended.append)
    # interrupted at 0.3 s, it swallows that and sleeps 2.5 s more: 2 s of grace run out first
    text = SLEEPER.replace("step_timeout_s = 1.0", "step_timeout_s = 0.3").replace(
        "at_s = 4.0", "at_s = 1.0\nsleep_s = 2.5\nswallow = true")
    outcome = run_to_end(text)
    assert outcome.status == "timed out" and ended == [time_limits.EXIT_TIMED_OUT]
    assert written == [("participant 'nap' did not return from its step at t = 1 s within its wall-time limit of "
                        "0.3 s (step_timeout_s); the call did not return 2 s after it was interrupted (native code), "
                        "so the process was ended", "timed out")]
