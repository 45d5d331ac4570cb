"""The command line, called as main([...]) and once as a user would, in a subprocess."""

import json
import subprocess
import sys
from pathlib import Path

import pytest

from orchestrator.cli import main

REPO = Path(__file__).resolve().parents[2]


def test_run_turning_circle_writes_results_and_figures(tmp_path, capsys):
    code = main(["run", str(REPO / "scenarios" / "turning_circle.toml"), "--results", str(tmp_path), "--no-progress"])
    out = capsys.readouterr().out
    assert code == 0
    assert out.startswith("finished: results in ")
    folder = Path(out.splitlines()[0].split("results in ")[1])
    summary = json.loads((folder / "summary.json").read_text())
    figures = summary["analyses"]["turning_circle"]
    # the acceptance band for the default KCS: 2.5 to 5 ship lengths
    assert 2.5 <= figures["tactical_diameter_L"] <= 5.0
    assert figures["advance_L"] > figures["transfer_L"] > 0
    assert {"track.png", "turning_circle.png", "timeseries.parquet"} <= {p.name for p in folder.iterdir()}


def test_bad_scenario_is_one_line_and_exit_2(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text("[simulation]\ndt_s = 1.0\nsteps = 2\nwarp = 9\n[participants.a]\ntype = 'scripted_tau'\n")
    assert main(["run", str(bad), "--results", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"error: {bad}: unknown key 'simulation.warp' (valid: name, start_s, stop_s, steps, dt_s, stop_when, exchange, "
                   "step_timeout_s)"]
    assert not (tmp_path / "bad").exists()  # nothing written for a scenario that never ran


def test_failed_run_exits_3(tmp_path, capsys):
    scenario = (REPO / "scenarios" / "turning_circle.toml").read_text().replace("u0 = 9.26", "u0 = 9.26\nm11 = 1.0")
    path = tmp_path / "diverge.toml"
    path.write_text(scenario)
    assert main(["run", str(path), "--results", str(tmp_path), "--no-progress"]) == 3
    assert "error: ship (KCS.fmu): fmi2DoStep failed" in capsys.readouterr().err


def test_validate(tmp_path, capsys):
    assert main(["validate", str(REPO / "scenarios" / "zigzag_10_10.toml")]) == 0
    assert capsys.readouterr().out.startswith("ok: ")
    missing = tmp_path / "missing_fmu.toml"
    missing.write_text((REPO / "scenarios" / "zigzag_10_10.toml").read_text().replace('fmu = "KCS"', 'fmu = "x.fmu"'))
    assert main(["validate", str(missing)]) == 2
    assert "participants.ship.fmu: FMU file not found" in capsys.readouterr().err


def test_debug_lines_are_the_v_commands_only_and_looked_up_only_for_them(monkeypatch, capsys):
    import logging

    from orchestrator import cli

    scenario = str(REPO / "scenarios" / "zigzag_10_10.toml")
    assert main(["-v", "validate", scenario]) == 0
    assert {logging.getLogger(name).level for name in ("orchestrator", "rhnc")} == {logging.DEBUG}
    monkeypatch.setattr(cli, "own_loggers", lambda: pytest.fail("the loggers were looked up without -v"))
    assert main(["validate", scenario]) == 0
    assert {logging.getLogger(name).level for name in ("orchestrator", "rhnc")} == {logging.NOTSET}


def test_subprocess_as_a_user_would(tmp_path):
    result = subprocess.run(
        [sys.executable, "-m", "orchestrator", "run", str(REPO / "scenarios" / "zigzag_10_10.toml"),
         "--results", str(tmp_path), "--no-progress"],
        capture_output=True, text=True, timeout=300,
    )
    assert result.returncode == 0, result.stderr
    assert "zigzag: first_overshoot_deg" in result.stdout
    result = subprocess.run([sys.executable, "-m", "orchestrator", "run", str(tmp_path / "none.toml")],
                            capture_output=True, text=True, timeout=60)
    assert result.returncode == 2
    assert result.stderr.strip() == f"error: {tmp_path / 'none.toml'}: scenario file not found"


def test_the_command_line_exits_without_collecting_its_objects_one_by_one():
    """``python -m orchestrator`` freezes the objects still alive before it exits (the
    interpreter's last collections skip them); exit handlers still run, the exit code is kept."""
    probe = ("import atexit, gc, runpy, sys\n"
             "atexit.register(lambda: print('frozen at exit:', gc.get_freeze_count() > 0))\n"
             f"sys.argv = ['orchestrator', 'validate', {str(REPO / 'scenarios' / 'zigzag_10_10.toml')!r}]\n"
             "runpy.run_module('orchestrator', run_name='__main__')\n")
    result = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    assert result.stdout.startswith("ok: ") and result.stdout.splitlines()[-1] == "frozen at exit: True"


def test_ctrl_c_in_a_terminal_run_keeps_the_results(tmp_path):
    """SIGINT to a running `orchestrator run`: exit 130, results written, status interrupted."""
    import signal
    import time

    scenario = (REPO / "scenarios" / "turning_circle.toml").read_text().replace(
        "stop_s = 1800.0\ndt_s = 5.0", "stop_s = 360000.0\ndt_s = 0.5")  # long enough to interrupt
    path = tmp_path / "long.toml"
    path.write_text(scenario)
    process = subprocess.Popen(
        [sys.executable, "-m", "orchestrator", "run", str(path), "--results", str(tmp_path), "--no-progress"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 120
    while not list(tmp_path.glob("turning_circle/.*.partial")) and time.monotonic() < deadline:
        time.sleep(0.05)  # wait until the run has started writing
    time.sleep(1.0)
    process.send_signal(signal.SIGINT)
    out, err = process.communicate(timeout=120)
    assert process.returncode == 130, err
    assert "interrupted by the user" in err
    folder = Path(out.split("results in ")[1].split()[0])
    summary = json.loads((folder / "summary.json").read_text())
    assert summary["status"] == "interrupted"
    assert 0 < summary["simulation"]["steps_done"] < summary["simulation"]["steps_planned"]
    assert (folder / "timeseries.parquet").is_file()


def test_the_help_names_every_fmi_version_the_master_runs(capsys):
    from orchestrator.scenario_participants import FMI_VERSIONS

    with pytest.raises(SystemExit) as done:
        main(["--help"])
    assert done.value.code == 0
    out = " ".join(capsys.readouterr().out.split())
    assert f"(FMI {' and '.join(FMI_VERSIONS)} co-simulation master)" in out
    assert FMI_VERSIONS == ("2.0", "3.0")


@pytest.mark.parametrize("command", ["batch", "search"])
def test_fewer_than_one_worker_is_refused_in_one_line_and_nothing_written(tmp_path, capsys, command):
    results = tmp_path / "results"
    assert main([command, str(tmp_path / "missing.toml"), "--workers", "0", "--results", str(results)]) == 2
    assert capsys.readouterr().err == "error: --workers must be at least 1\n"
    assert not results.exists()
