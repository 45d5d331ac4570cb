"""Folders of runs whose process died (killed, crashed in native code, os._exit) are removed
by a later run; those of runs still going, in another process, are never touched."""

import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pytest

from orchestrator import leftovers
from orchestrator.cli import main

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[1]


def scenario(tmp_path, name, extra) -> Path:
    """The turning circle (an FMU: its unpacked folder too), cut short, plus ``extra`` participants."""
    text = (REPO / "scenarios" / "turning_circle.toml").read_text()
    text = text.replace('name = "turning_circle"', f'name = "{name}"').replace("stop_s = 1800.0", "stop_s = 60.0")
    text = text.replace('analyses = ["turning_circle"]', "analyses = []\nfigures = []")
    path = tmp_path / f"{name}.toml"
    path.write_text(text + extra)
    return path


def start(path, results, tmp) -> subprocess.Popen:
    env = {**os.environ, "TMPDIR": str(tmp), "PYTHONPATH": os.pathsep.join([str(HERE), str(REPO)])}
    return subprocess.Popen([sys.executable, "-m", "orchestrator", "run", str(path), "--results", str(results),
                             "--no-progress"], env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)


def owned(tmp: Path, results: Path, group: str) -> set[str]:
    """Names of the run folders of ``group`` not published: temporary folders and staging folders."""
    names = {p.name for p in tmp.iterdir() if p.name.startswith(leftovers.TEMP_PREFIXES)}
    return names | {p.name for p in (results / group).glob(".*.partial")}


@pytest.mark.parametrize("how", ["SIGKILL", "os._exit"])
def test_a_later_run_removes_what_dead_runs_left_and_keeps_a_live_runs_folders(tmp_path, monkeypatch, capsys, how):
    tmp, results = tmp_path / "tmp", tmp_path / "results"
    tmp.mkdir()
    killer = ('\n[participants.killer]\ntype = "python"\nclass = "sample_participants:SelfKiller"\n'
              f'[participants.killer.options]\nat_s = 20.0\nexit = {"true" if how == "os._exit" else "false"}\n')
    dead = start(scenario(tmp_path, "dead", killer), results, tmp)
    assert dead.wait(timeout=120) != 0, dead.stderr.read()
    dead_left = owned(tmp, results, "dead")
    assert {name.split("-")[1] for name in dead_left if name.startswith("rhnc-")} == {"run", "fmu"}
    assert any(name.endswith(".partial") for name in dead_left)

    sleeper = ('\n[participants.sleeper]\ntype = "python"\nclass = "sample_participants:Sleeper"\n'
               "[participants.sleeper.options]\nat_s = 10.0\nsleep_s = 600.0\n")
    live = start(scenario(tmp_path, "live", sleeper), results, tmp)
    try:
        deadline = time.monotonic() + 120
        while not ((results / "live").is_dir() and len(owned(tmp, results, "live") - dead_left) >= 3):
            assert time.monotonic() < deadline and live.poll() is None, live.stderr.read() if live.poll() else ""
            time.sleep(0.1)
        live_left = owned(tmp, results, "live") - dead_left

        monkeypatch.setattr(tempfile, "tempdir", str(tmp))
        assert main(["run", str(scenario(tmp_path, "later", "")), "--results", str(results), "--no-progress"]) == 0
        assert owned(tmp, results, "dead") & dead_left == set()  # the dead run's folders are gone
        assert live_left <= owned(tmp, results, "live")  # the live run's are all there
        assert live.poll() is None
    finally:
        live.kill()
        live.wait()


def test_a_folder_without_a_lock_file_is_kept_while_its_process_lives(tmp_path):
    mine = tmp_path / f"rhnc-run-{os.getpid()}-abc"
    gone = tmp_path / "rhnc-run-999999999-abc"  # beyond any process id
    for folder in (mine, gone):
        folder.mkdir()
        os.utime(folder, (time.time() - 3600, time.time() - 3600))
    young = tmp_path / "rhnc-fmu-999999999-ship-abc"
    young.mkdir()
    assert leftovers.remove_abandoned_temp_folders(tmp_path) == [gone]
    assert mine.is_dir() and young.is_dir()  # alive; and too young to judge without a lock


def test_a_held_lock_keeps_the_folder_even_under_a_dead_process_id(tmp_path):
    folder = tmp_path / "rhnc-run-999999999-abc"
    folder.mkdir()
    lock = leftovers.OwnerLock(folder)
    try:
        assert leftovers.remove_abandoned_temp_folders(tmp_path) == []
    finally:
        lock.release(remove_file=False)
    assert leftovers.remove_abandoned_temp_folders(tmp_path) == [folder]
