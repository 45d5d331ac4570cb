"""Ctrl-C and SIGTERM on a running `orchestrator run`: the run stops at once, wherever it is.

Each test starts the command line in a subprocess, as a user would, and sends the signal
once the run is stepping.  What must hold: exit code 130, ``status: interrupted`` in the
published ``summary.json`` with the steps done so far, no ``.partial`` staging folder left.
"""

import json
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

HERE = Path(__file__).resolve().parent

# NMPC-heavy tracking run: a 120-interval IPOPT problem solved every 20 s step from the plan
# alone (no multipliers carried over, which would halve the iterations), far more steps than
# the test waits for; almost all of its time is spent inside CasADi solves (the test reads
# the beacon's line from a pipe and may read it late, so the other participants' share of a
# step must be negligible for the signal to land in the NMPC's step).
NMPC_SCENARIO = """
connections = [
  "ref.reference -> ctrl.reference",
  "ship.x -> ctrl.x", "ship.y -> ctrl.y", "ship.psi -> ctrl.psi",
  "ship.u -> ctrl.u", "ship.v -> ctrl.v", "ship.r -> ctrl.r",
  "ctrl.tau_u -> ship.tau_u", "ctrl.tau_r -> ship.tau_r",
]
[simulation]
name = "long_nmpc"
steps = 5000
dt_s = 20.0
[participants.ref]
type = "reference_path"
[participants.ref.options]
start_nm = [0.0, 0.0]
course_deg = 30.0
speed_kn = 16.0
turn_radius_nm = 2.0
horizon_steps = 120
[participants.beacon]
type = "python"
class = "sample_participants:Beacon"
[participants.beacon.options]
from_s = 100.0
[participants.ctrl]
type = "control"
[participants.ctrl.options]
horizon_steps = 120
solver = "ipopt"
warm_start_duals = false
[participants.ship]
fmu = "KCS"
[participants.ship.parameters]
y0 = 300.0
u0 = 8.0
[outputs]
analyses = []
figures = ["track"]
"""

STUBBORN_SCENARIO = """
[simulation]
name = "stubborn"
steps = 100
dt_s = 1.0
[participants.clock]
type = "python"
class = "sample_participants:Clock"
[participants.hang]
type = "python"
class = "sample_participants:Stubborn"
[participants.hang.options]
at_s = 5.0
[outputs]
figures = []
"""


def start_run(tmp_path, text, name):
    path = tmp_path / f"{name}.toml"
    path.write_text(text)
    results = tmp_path / "results"
    process = subprocess.Popen(
        [sys.executable, "-m", "orchestrator", "run", str(path), "--results", str(results), "--no-progress"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        env={**__import__("os").environ, "PYTHONPATH": f"{HERE}:{HERE.parents[1]}"})
    return process, results / name


def wait_for_line(process, expected: str) -> None:
    """Read the run's stdout until ``expected`` (a participant's message) appears."""
    for line in process.stdout:
        if line.strip() == expected:
            return
    raise AssertionError(f"the run ended before printing {expected!r}: {process.communicate()}")


def published_summary(group: Path) -> dict:
    folders = [p for p in group.iterdir() if p.is_dir()]
    assert [p.name for p in folders if p.name.startswith(".")] == []  # no staging folder left
    assert len(folders) == 1
    return json.loads((folders[0] / "summary.json").read_text())


@pytest.mark.slow
@pytest.mark.parametrize("number", [signal.SIGINT, signal.SIGTERM])
def test_a_signal_during_nmpc_solves_stops_the_run_within_the_step(tmp_path, number):
    process, group = start_run(tmp_path, NMPC_SCENARIO, "long_nmpc")
    wait_for_line(process, "beacon: t = 100 s")  # after the first steps; the NMPC solves next
    time.sleep(0.05)  # let the beacon's step return: the process is then inside the NMPC's solve
    process.send_signal(number)
    out, err = process.communicate(timeout=120)
    assert process.returncode == 130, err
    name = signal.Signals(number).name
    match = re.search(rf"{name} received while stepping participant '(\w+)' at t = ([\d.]+) s", err)
    assert match, err
    assert match.group(1) == "ctrl"  # it arrived inside the NMPC's step (its CasADi solve)
    summary = published_summary(group)
    assert summary["status"] == "interrupted"
    assert summary["reason"] == ("interrupted by the user (Ctrl-C)" if name == "SIGINT" else "interrupted by SIGTERM")
    # stopped at the first participant boundary after the signal: the step it arrived in
    # is not completed, and no later one is begun
    assert summary["simulation"]["steps_done"] * 20.0 == float(match.group(2))
    assert 0 < summary["simulation"]["steps_done"] < summary["simulation"]["steps_planned"]
    assert (group / summary["run_id"] / "timeseries.parquet").is_file()
    assert "Traceback" not in err
    assert f"interrupted: results in {group / summary['run_id']}" in out


@pytest.mark.slow
def test_a_call_that_never_returns_is_ended_by_the_watchdog_with_its_status(tmp_path):
    process, group = start_run(tmp_path, STUBBORN_SCENARIO, "stubborn")
    wait_for_line(process, "stubborn: blocking")
    process.send_signal(signal.SIGINT)
    out, err = process.communicate(timeout=60)
    assert process.returncode == 130, err
    assert "SIGINT received while stepping participant 'hang' at t = 5 s" in err
    summary = published_summary(group)
    assert summary["status"] == "interrupted"
    assert "a call did not return within 1 s of the signal" in summary["reason"]
    assert summary["simulation"]["steps_done"] == 5
    assert (group / summary["run_id"] / "timeseries.csv").is_file()


def test_an_interrupt_a_participant_swallowed_still_stops_the_run(write_scenario, tmp_path):
    """The master checks the stop request between participant steps, not only for the exception."""
    from orchestrator import interrupts
    from orchestrator.run import run_scenario

    path = write_scenario(STUBBORN_SCENARIO.replace("Stubborn", "Swallower").replace('name = "stubborn"',
                                                                                    'name = "swallow"'))
    with interrupts.handle_signals():
        report = run_scenario(path, tmp_path, progress=False)
    assert (report.status, report.reason) == ("interrupted", "interrupted by the user (Ctrl-C)")
    # the swallower steps last: the step of t = 5 s completes, the next is not begun
    assert report.summary["simulation"]["steps_done"] == 6
    assert [p.name for p in (tmp_path / "swallow").iterdir()] == [report.folder.name]


def test_a_handled_interrupt_does_not_stop_the_next_run_in_the_process(write_scenario, tmp_path):
    from orchestrator import interrupts
    from orchestrator.run import run_scenario

    path = write_scenario(STUBBORN_SCENARIO.replace("Stubborn", "Swallower").replace('name = "stubborn"',
                                                                                    'name = "swallow"'))
    with interrupts.handle_signals():
        assert run_scenario(path, tmp_path, progress=False).status == "interrupted"
    assert interrupts.stop_requested() is None
    calm = write_scenario(STUBBORN_SCENARIO.replace("at_s = 5.0", "at_s = 1.0e9"), "calm.toml")
    assert run_scenario(calm, tmp_path, progress=False).status == "finished"


def test_an_interrupted_comparison_exits_130_and_stops_its_later_runs(write_scenario, tmp_path, capsys):
    from orchestrator.cli import main

    turning = (HERE.parents[1] / "scenarios" / "turning_circle.toml").read_text()
    write_scenario(turning + '[participants.hang]\ntype = "python"\nclass = "sample_participants:Swallower"\n'
                   "[participants.hang.options]\nat_s = 50.0\n", "first.toml")
    write_scenario(turning, "second.toml")
    comparison = write_scenario('name = "pair"\nanalysis = "none"\nmetrics = ["x"]\n'
                                '[[runs]]\nlabel = "A"\nscenario = "first.toml"\n'
                                '[[runs]]\nlabel = "B"\nscenario = "second.toml"\n', "pair.toml")
    assert main(["compare", str(comparison), "--results", str(tmp_path / "results"), "--no-progress"]) == 130
    captured = capsys.readouterr()
    assert "error: interrupted by the user (Ctrl-C)" in captured.err
    folder = Path(captured.out.split("results in ")[1].split()[0])
    summaries = [json.loads(p.read_text()) for p in sorted(folder.glob("runs/*/*/summary.json"))]
    assert [s["status"] for s in summaries] == ["interrupted", "interrupted"]
    steps = {s["scenario"].rsplit("/", 1)[-1]: s["simulation"]["steps_done"] for s in summaries}
    assert steps == {"first.toml": 11, "second.toml": 0}  # stopped after t = 50 s; the second never stepped


@pytest.mark.slow
def test_a_native_call_holding_the_interpreter_lock_is_ended_by_the_last_resort_timer(tmp_path):
    """Neither the master nor the watchdog thread can run: SIGALRM at its default action ends it."""
    process, group = start_run(tmp_path, STUBBORN_SCENARIO.replace("Stubborn", "Hog"), "stubborn")
    wait_for_line(process, "hog: blocking")
    process.send_signal(signal.SIGINT)
    out, err = process.communicate(timeout=60)
    assert process.returncode == -signal.SIGALRM, err
    assert "SIGINT received while stepping participant 'hang' at t = 5 s" in err
