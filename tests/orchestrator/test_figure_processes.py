"""A run's figures drawn in processes of their own: at the same time, and a figure that fails
(raises, or its process dies) loses only itself, never the results or a half-written file."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pandas as pd
import psutil
import pytest

from orchestrator import figure_processes, plugins
from orchestrator.run import run_scenario

REPO = Path(__file__).resolve().parents[2]

PROBES = '''
import os, signal, time
from pathlib import Path

SHARED = Path(os.environ["FIGURE_PROBE_DIR"])


def _wait_for(path, seconds=20.0):
    deadline = time.monotonic() + seconds
    while not path.exists():
        if time.monotonic() > deadline:
            raise TimeoutError(f"{path.name} never appeared: the figures were not drawn at the same time")
        time.sleep(0.01)


def good(frame, scenario, cosim, out_dir):
    (out_dir / "good.txt").write_text(f"{os.getpid()} {len(frame)}")
    return ["good.txt"]


def first(frame, scenario, cosim, out_dir):
    (SHARED / "first-started").touch()
    _wait_for(SHARED / "second-started")
    (out_dir / "first.txt").write_text(str(os.getpid()))
    return ["first.txt"]


def second(frame, scenario, cosim, out_dir):
    (SHARED / "second-started").touch()
    _wait_for(SHARED / "first-started")
    (out_dir / "second.txt").write_text(str(os.getpid()))
    return ["second.txt"]


def raises(frame, scenario, cosim, out_dir):
    (out_dir / "partial.txt").write_text("half a figure")
    raise RuntimeError("no ink")


def dies(frame, scenario, cosim, out_dir):
    (out_dir / "half.txt").write_text("half a figure")
    os.kill(os.getpid(), signal.SIGKILL)


def stops_the_run(frame, scenario, cosim, out_dir):
    """Ctrl-C twice while this figure is drawn: the run ends at once, this process with it."""
    (SHARED / "drawing.pid").write_text(str(os.getpid()))
    (out_dir / "half.txt").write_text("half a figure")
    for _ in range(2):
        os.killpg(os.getpgid(0), signal.SIGINT)  # as a terminal's Ctrl-C: to every process of the run
        time.sleep(0.3)
    time.sleep(30.0)
    return ["half.txt"]


def fills_the_disk(frame, scenario, cosim, out_dir):
    import errno
    (out_dir / "half.png").write_text("half a figure")
    raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))


def interrupted_once(frame, scenario, cosim, out_dir):
    """Ctrl-C once while this figure is drawn: the results are completed all the same."""
    os.killpg(os.getpgid(0), signal.SIGINT)
    time.sleep(0.5)
    (out_dir / "drawn.txt").write_text("a whole figure")
    return ["drawn.txt"]
'''
NAMES = ("good", "first", "second", "raises", "dies", "stops_the_run", "interrupted_once", "fills_the_disk")


@pytest.fixture
def probes(tmp_path, monkeypatch):
    """The probe figures registered by a package of their own (on sys.path and PYTHONPATH)."""
    site = tmp_path / "site"
    info = site / "figure_probes-1.0.dist-info"
    info.mkdir(parents=True)
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: figure-probes\nVersion: 1.0\n")
    (info / "entry_points.txt").write_text("[rhnc_cosim.figures]\n" + "".join(
        f"{name} = figure_probes:{name}\n" for name in NAMES))
    (site / "figure_probes.py").write_text(PROBES)
    shared = tmp_path / "shared"
    shared.mkdir()
    monkeypatch.setattr(sys, "path", [str(site), *sys.path])
    monkeypatch.setenv("FIGURE_PROBE_DIR", str(shared))
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join(filter(None, [str(site), str(REPO),
                                                                   os.environ.get("PYTHONPATH")])))
    plugins.registrations.cache_clear()
    yield shared
    plugins.registrations.cache_clear()
    sys.modules.pop("figure_probes", None)


def _scenario(tmp_path, figures) -> Path:
    path = tmp_path / "figures.toml"
    path.write_text(textwrap.dedent(f"""\
        [simulation]
        name = "figures"
        stop_s = 10.0
        dt_s = 5.0
        [participants.helm]
        type = "scripted_tau"
        [outputs]
        figures = {json.dumps(figures)}
        """))
    return path


def _summary(folder: Path) -> dict:
    return json.loads((folder / "summary.json").read_text())


def test_figures_are_drawn_at_the_same_time_in_processes_of_their_own(tmp_path, probes):
    report = run_scenario(_scenario(tmp_path, ["first", "second", "good"]), tmp_path / "results", progress=False)
    summary = _summary(report.folder)
    assert summary["figure_errors"] == {}  # each waited for the other to start: not one after the other
    assert summary["figures"] == ["first.txt", "second.txt", "good.txt"]
    pids = {int((report.folder / name).read_text().split()[0]) for name in summary["figures"]}
    assert len(pids) == 3 and os.getpid() not in pids
    rows = len(pd.read_parquet(report.folder / "timeseries.parquet"))
    assert (report.folder / "good.txt").read_text().split()[1] == str(rows)  # the whole series, read there
    assert not (report.folder / figure_processes.FIGURE_SPOOL).exists()


def test_a_figure_named_twice_is_drawn_twice(tmp_path, probes):
    report = run_scenario(_scenario(tmp_path, ["good", "good"]), tmp_path / "results", progress=False)
    assert _summary(report.folder)["figures"] == ["good.txt", "good.txt"]
    assert _summary(report.folder)["figure_errors"] == {}


@pytest.mark.parametrize("fork", [True, False], ids=["forked", "here"])
def test_a_figure_that_fails_loses_itself_only_and_leaves_no_half_written_file(tmp_path, probes, monkeypatch,
                                                                               fork):
    monkeypatch.setattr(figure_processes, "FORK", fork)
    failing = ["raises", "dies"] if fork else ["raises"]  # a process that dies: only a forked one
    report = run_scenario(_scenario(tmp_path, [*failing, "good"]), tmp_path / "results", progress=False)
    summary = _summary(report.folder)
    assert report.status == "finished" and summary["status"] == "finished"
    assert summary["figures"] == ["good.txt"]
    assert summary["figure_errors"]["raises"] == "RuntimeError: no ink"
    if fork:
        assert summary["figure_errors"]["dies"] == "the process drawing it was ended by SIGKILL"
    assert sorted(p.name for p in report.folder.iterdir()) == ["good.txt", "summary.json", "timeseries.parquet"]


@pytest.mark.parametrize("fork", [True, False], ids=["forked", "here"])
def test_a_full_disk_while_a_figure_is_written_keeps_nothing(tmp_path, probes, monkeypatch, capsys, fork):
    """Exit 4 and no run folder, as for a full disk while the time series is written: a folder
    without its figures must not be published as a finished run."""
    from orchestrator.cli import main

    monkeypatch.setattr(figure_processes, "FORK", fork)
    code = main(["run", str(_scenario(tmp_path, ["good", "fills_the_disk"])), "--results", str(tmp_path / "results"),
                 "--no-progress"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 4
    assert len(err) == 1 and err[0].endswith("the results could not be written (No space left on device (figure "
                                             "'fills_the_disk')); nothing was kept (the run itself: finished)")
    assert not (tmp_path / "results").exists()


def test_a_full_disk_while_a_figure_is_written_is_redone_by_a_batch_resume(tmp_path, probes):
    from orchestrator.batch_run import RunTask, execute_run, needs_redo, read_summary

    task = RunTask(str(_scenario(tmp_path, ["fills_the_disk"])), str(tmp_path / "batch"), "run-0", {})
    record = execute_run(task)
    assert record["status"] == "failed" and record["infrastructure"] is True
    assert needs_redo(read_summary(tmp_path / "batch" / "runs" / "run-0"))


def _command(tmp_path, figures) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "orchestrator", "run", str(_scenario(tmp_path, figures)),
                             "--results", str(tmp_path / "results"), "--no-progress"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True)  # a process group of its own, as in a terminal


def test_ctrl_c_while_figures_are_drawn_completes_the_results(tmp_path, probes):
    process = _command(tmp_path, ["interrupted_once", "good"])
    out, err = process.communicate(timeout=120)
    assert err.count("SIGINT received") == 1, err  # by the run only: the figure processes ignore it
    folder = Path(out.split("results in ")[1].split()[0])
    summary = _summary(folder)
    assert summary["figures"] == ["drawn.txt", "good.txt"] and summary["figure_errors"] == {}
    assert (folder / "drawn.txt").read_text() == "a whole figure"
    assert summary["status"] == "finished" and summary["simulation"]["steps_done"] == 2
    assert process.returncode == 130  # the command was interrupted, whatever the results hold
    assert err.strip().splitlines()[-1] == ("error: interrupted by the user (Ctrl-C) while the results were "
                                            "written; they were completed first")


def test_a_second_ctrl_c_while_figures_are_drawn_stops_at_once_and_ends_the_drawing(tmp_path, probes):
    process = _command(tmp_path, ["stops_the_run", "good"])
    process.wait(timeout=60)  # the figure would take 30 s
    drawing = int((probes / "drawing.pid").read_text())
    deadline = time.monotonic() + 10
    while _alive(drawing) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not _alive(drawing)  # ended with the run (the kernel's parent-death signal)
    out, err = process.communicate(timeout=10)
    assert process.returncode == 130, err
    assert err.count("SIGINT received") == 1 and "SIGINT again: stopping at once" in err, err
    folder = Path(out.split("results in ")[1].split()[0])
    assert _summary(folder)["status"] == "interrupted"
    assert not (folder / figure_processes.FIGURE_SPOOL).exists() and not (folder / "half.txt").exists()


def _alive(pid: int) -> bool:
    try:
        return psutil.Process(pid).status() != psutil.STATUS_ZOMBIE
    except psutil.Error:  # gone
        return False
