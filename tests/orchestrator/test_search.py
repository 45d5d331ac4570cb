"""Adversarial search: what it finds, its outputs, resumption, seeds, errors, and the HTML report in Chromium."""

import json
import shutil
import subprocess
import sys
import textwrap
from html.parser import HTMLParser
from pathlib import Path

import pandas as pd
import pytest

from orchestrator.batch_spec import load_batch
from orchestrator.cli import main
from orchestrator.search import run_search
from orchestrator.search_journal import JOURNAL, read_journal

REPO = Path(__file__).resolve().parents[2]

SCENARIO = """\
connections = ["helm.tau_u -> ship.tau_u", "helm.tau_r -> ship.tau_r"]

[simulation]
name = "short_turn"
stop_s = 120.0
dt_s = 5.0

[participants.helm]
type = "python"
class = "test_batch_participants:TestHelm"
[participants.helm.options]
tau_u_N = 7.7e5

[participants.ship]
fmu = "KCS"
[participants.ship.parameters]
u0 = 9.26

[outputs]
analyses = ["turning_circle"]
figures = ["track"]
"""

# the approach speed grows with u0: the failures (below 12 kn) lie at low u0 only
SEARCH = """\
[batch]
name = "small"
scenario = "short_turn.toml"

[monte_carlo]
seed = 11
runs = 4
[monte_carlo.uniform]
"participants.ship.parameters.u0" = [5.0, 9.0]
[monte_carlo.choice]
"participants.helm.options.tau_u_N" = [5.0e5, 9.0e5]

[search]
objective = "analyses.turning_circle.approach_speed_kn"
fails_below = 12.0
evaluations = 6
per_round = 3
worst = 2

[[acceptance]]
name = "finished"
metric = "status"
op = "=="
value = "finished"

[report]
series = ["ship.u", "ship.r"]
"""


@pytest.fixture
def search_file(tmp_path):
    (tmp_path / "short_turn.toml").write_text(SCENARIO)

    def write(text=SEARCH, name="small.toml"):
        path = tmp_path / name
        path.write_text(textwrap.dedent(text))
        return path

    return write


def _journal_values(folder):
    return [(e["run_id"], e["values"]) for e in read_journal(folder / JOURNAL)]


@pytest.mark.slow
def test_search_evaluates_its_budget_and_writes_what_it_found(search_file, tmp_path):
    report = run_search(search_file(), tmp_path / "res", workers=2, progress=False)
    folder = tmp_path / "res" / "small_search"
    table = report.table
    assert len(table) == 6 and set(table["status"]) == {"finished"}
    assert list(table["evaluation"]) == [1, 2, 3, 4, 5, 6]
    # the objective is the run's own figure, and a failure is an objective below the threshold
    for _, row in table.iterrows():
        summary = json.loads((folder / "runs" / row["run_id"] / "summary.json").read_text())
        assert row["objective"] == pytest.approx(summary["analyses"]["turning_circle"]["approach_speed_kn"])
        assert row["failure"] == (row["objective"] < 12.0)
    assert report.best == pytest.approx(table["objective"].min())
    failures = table[table["failure"]]
    assert report.failures == len(failures)
    assert report.first_failure == (failures["evaluation"].min() if len(failures) else None)
    saved = json.loads((folder / "search.json").read_text())
    assert saved["first_failure"] == report.first_failure and saved["evaluations_done"] == 6
    # the worst cases rerun exactly: a one-run batch of the same run id, lowest objective first
    worst = sorted((folder / "worst").glob("*.toml"))
    assert len(worst) == 2
    lowest = table.sort_values("objective")["run_id"].tolist()[:2]
    assert [load_batch(w).runs()[0].run_id for w in worst] == lowest
    assert [w.name.split("-", 1)[1][:-5] for w in worst] == lowest
    # the boundary summary: per parameter and bin, the runs and the failures there
    boundary = pd.read_csv(folder / "boundary.csv")
    u0 = boundary[boundary["parameter"] == "participants.ship.parameters.u0"]
    assert len(u0) == 8 and u0["runs"].sum() == 6 and u0["failures"].sum() == len(failures)
    for _, row in u0[u0["runs"] > 0].iterrows():
        inside = table[(table["param:participants.ship.parameters.u0"] >= row["low"])
                       & (table["param:participants.ship.parameters.u0"] <= row["high"])]
        assert row["min_objective"] == pytest.approx(inside["objective"].min())
    thrust = boundary[boundary["parameter"] == "participants.helm.options.tau_u_N"]
    assert sorted(thrust["runs"]) == sorted(table["param:participants.helm.options.tau_u_N"].value_counts().reindex(
        [5.0e5, 9.0e5], fill_value=0))
    for name in ("progress.png", "boundary.png", "report.html", "summary.parquet"):
        assert (folder / name).stat().st_size > 1000


@pytest.mark.slow
@pytest.mark.parametrize("sampler", ["tpe", "tpe-restart"])
def test_search_is_seeded_and_a_resumed_search_equals_an_uninterrupted_one(search_file, tmp_path, sampler):
    path = search_file(SEARCH.replace("worst = 2", f"worst = 2\nsampler = \"{sampler}\""))
    whole = run_search(path, tmp_path / "whole", workers=2, progress=False, report=False)
    folder = tmp_path / "part" / "small_search"
    run_search(path, tmp_path / "part", workers=1, progress=False, evaluations=3, report=False)
    assert len(read_journal(folder / JOURNAL)) == 3
    # a search killed during its second round: the round journaled, one run published, one not
    resumed = run_search(path, tmp_path / "part", workers=1, progress=False, evaluations=6, report=False)
    assert _journal_values(folder) == _journal_values(tmp_path / "whole" / "small_search")
    pd.testing.assert_frame_equal(whole.table.drop(columns="wall_time_s"), resumed.table.drop(columns="wall_time_s"))
    shutil.rmtree(folder / "runs" / resumed.table["run_id"].iloc[4])
    with open(folder / JOURNAL, "a") as journal:  # and a line torn as the next round was written
        journal.write('{"number": 6, "run_id": "abc')
    again = run_search(path, tmp_path / "part", workers=1, progress=False, report=False)
    assert again.evaluated == 1  # only the run that was lost
    pd.testing.assert_frame_equal(whole.table.drop(columns="wall_time_s"), again.table.drop(columns="wall_time_s"))
    other = run_search(path, tmp_path / "other", workers=1, progress=False, seed=12, evaluations=3, report=False)
    assert _journal_values(tmp_path / "other" / "small_search") != _journal_values(folder)[:3]
    assert len(other.table) == 3


@pytest.mark.slow
def test_until_failure_stops_after_the_round_of_the_first_failure_and_a_threshold_only_relabels(search_file,
                                                                                               tmp_path):
    path = search_file()
    whole = run_search(path, tmp_path / "whole", workers=1, progress=False, report=False)
    every = _journal_values(tmp_path / "whole" / "small_search")
    high, low = whole.table["objective"].max() + 1.0, whole.table["objective"].min() - 1.0
    # every run below the threshold: the first round (3 evaluations) holds the first failure
    stopped = run_search(path, tmp_path / "high", workers=1, progress=False, report=False, fails_below=high,
                         until_failure=True)
    assert len(stopped.table) == 3 and stopped.first_failure == 1 and stopped.failures == 3
    assert _journal_values(tmp_path / "high" / "small_search") == every[:3]
    again = run_search(path, tmp_path / "high", workers=1, progress=False, report=False, fails_below=high,
                       until_failure=True)
    assert again.evaluated == 0 and len(again.table) == 3  # the journal holds the failure: nothing more is asked
    # no run below it: the whole budget, and the optimiser asked for the same runs (it minimises either way)
    none = run_search(path, tmp_path / "low", workers=1, progress=False, report=False, fails_below=low,
                      until_failure=True)
    assert len(none.table) == 6 and none.failures == 0 and none.first_failure is None
    assert _journal_values(tmp_path / "low" / "small_search") == every
    saved = json.loads((tmp_path / "low" / "small_search" / "search.json").read_text())
    assert saved["fails_below"] == low


@pytest.mark.slow
def test_tpe_concentrates_on_the_failures_that_random_sampling_finds_by_chance(search_file, tmp_path):
    # one number to search and a cheap run: after its 10 random start-up evaluations TPE
    # samples where the objective was lowest; random sampling keeps spreading evenly
    path = search_file(SEARCH.replace("evaluations = 6", "evaluations = 16").replace("per_round = 3", "per_round = 4"))
    tpe = run_search(path, tmp_path / "tpe", workers=2, progress=False, report=False)
    uniform = run_search(path, tmp_path / "random", workers=2, progress=False, sampler="random", report=False)
    late = slice(10, None)
    assert tpe.table["failure"].iloc[late].sum() > uniform.table["failure"].iloc[late].sum()
    assert tpe.best <= uniform.best


@pytest.mark.parametrize("change, message", [
    (lambda t: t.replace('[search]\nobjective = "analyses.turning_circle.approach_speed_kn"\n', "[search]\n"),
     r"small.toml: missing key 'search.objective'"),
    (lambda t: t.replace("per_round = 3", "per_round = 3\nbudget = 4"), r"small.toml: unknown key 'search.budget'"),
    (lambda t: t.replace('sampler = "tpe"\n', "") .replace("worst = 2", 'worst = 2\nsampler = "grid"'),
     r"small.toml: 'search.sampler'"),
    (lambda t: t.replace("[search]", "[grid]\n\"simulation.dt_s\" = [5.0, 10.0]\n\n[search]"),
     r"small.toml: 'grid': a search varies \[monte_carlo\]'s ranges only"),
    (lambda t: t.replace('"participants.ship.parameters.u0" = [5.0, 9.0]', '"participants.ship.parameters.u0" = 7.0')
     .replace('"participants.helm.options.tau_u_N" = [5.0e5, 9.0e5]', '"participants.helm.options.tau_u_N" = [5.0e5]'),
     r"small.toml: 'monte_carlo': no range to search"),
    (lambda t: t.split("[search]")[0] + "[[acceptance]]" + t.split("[[acceptance]]")[1],
     r"small.toml: no \[search\] table"),
    (lambda t: t.replace('"participants.ship.parameters.u0" =', '"participants.ship.parameters.u_zero" ='),
     r"small.toml: 'monte_carlo.\"participants.ship.parameters.u_zero\"'"),
])
def test_bad_search_files_are_refused_in_one_line_and_nothing_is_written(search_file, tmp_path, capsys, change,
                                                                         message):
    import re

    path = search_file(change(SEARCH))
    assert main(["search", str(path), "--results", str(tmp_path / "res"), "--no-progress"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and re.search(message, err), err
    assert not (tmp_path / "res").exists()


def test_a_threshold_that_is_not_a_number_is_refused_before_anything_is_written(search_file, tmp_path):
    from orchestrator.errors import ScenarioError

    with pytest.raises(ScenarioError, match="--fails-below must be a finite number, got nan"):
        run_search(search_file(), tmp_path / "res", workers=1, progress=False, fails_below=float("nan"))
    assert not (tmp_path / "res").exists()


def test_resuming_with_another_seed_is_refused(search_file, tmp_path, capsys):
    path = search_file(SEARCH.replace("evaluations = 6", "evaluations = 1"))
    assert main(["search", str(path), "--results", str(tmp_path / "res"), "--no-progress", "--workers", "1"]) == 0
    capsys.readouterr()
    before = sorted(p.name for p in (tmp_path / "res" / "small_search" / "runs").iterdir())
    assert main(["search", str(path), "--results", str(tmp_path / "res"), "--no-progress", "--seed", "3"]) == 2
    err = capsys.readouterr().err
    assert "holds a search with another 'seed' (11)" in err
    assert sorted(p.name for p in (tmp_path / "res" / "small_search" / "runs").iterdir()) == before


def test_encounter_count_draws_the_first_entries():
    from orchestrator.batch_model import monte_carlo_spec
    from orchestrator.batch_spec import RandomChoices, draw_overrides

    import numpy as np

    entry = {"type": "head_on", "cpa_nm": [0.0, 0.5], "tcpa_min": 20.0, "speed_kn": 10.0, "radius_nm": 1.0}
    table = {"seed": 1, "runs": 1, "own_ship": {"start_nm": [0.0, 0.0], "course_deg": 0.0, "speed_kn": 18.0},
             "encounters": [entry, entry, entry], "encounter_count": [1, 3]}
    spec = monte_carlo_spec(table, "b.toml", {})
    counts = set()
    for index in range(40):
        overrides, parameters = draw_overrides(spec, RandomChoices(np.random.default_rng([1, index])))
        targets = overrides["participants.traffic.options.targets"]
        assert len(targets) == parameters["encounters.count"]
        assert {f"enc{k}.cpa_nm" for k in range(len(targets))} <= set(parameters)
        assert f"enc{len(targets)}.cpa_nm" not in parameters
        counts.add(len(targets))
    assert counts == {1, 2, 3}
    from orchestrator.errors import ScenarioError

    with pytest.raises(ScenarioError, match=r"b.toml: 'monte_carlo.encounter_count' must be \[low, high\] with "
                                            r"1 <= low <= high <= 3"):
        monte_carlo_spec({**table, "encounter_count": [1, 4]}, "b.toml", {})


# -- the report, as a browser shows it -------------------------------------------------------------
def _chromium():
    return shutil.which("chromium") or shutil.which("chromium-browser")


def _dom(url: str, tmp_path: Path) -> str:
    flags = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
             "--disable-component-update", "--disable-sync", "--no-first-run",
             f"--user-data-dir={tmp_path / 'chromium-profile'}", "--virtual-time-budget=3000"]
    done = subprocess.run([_chromium(), *flags, "--dump-dom", url], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr[-2000:]
    return done.stdout


class _Page(HTMLParser):
    """The rows of the runs table (their cells' text and links), the images and the inline plots."""

    def __init__(self):
        super().__init__()
        self.header, self.rows, self.images, self.series, self.links = [], [], [], [], []
        self._in_runs = self._in_head = False
        self._row = self._cell = None

    def handle_starttag(self, tag, attrs):
        attrs = dict(attrs)
        if tag == "table" and attrs.get("id") == "runs":
            self._in_runs = True
        elif self._in_runs and tag == "thead":
            self._in_head = True
        elif self._in_runs and tag == "tr" and not self._in_head:
            self._row = {"cells": [], "links": {}}
        elif self._in_runs and tag in ("td", "th"):
            self._cell = ""
        elif tag == "a":
            self.links.append(attrs.get("href"))
            if self._row is not None:
                self._row["links"][attrs.get("class")] = attrs.get("href")
        elif tag == "img":
            self.images.append(attrs.get("src"))
        elif tag == "svg" and attrs.get("data-series"):
            self.series.append(attrs["data-series"])

    def handle_data(self, data):
        if self._cell is not None:
            self._cell += data

    def handle_endtag(self, tag):
        if tag in ("td", "th") and self._cell is not None:
            (self.header if self._in_head else self._row["cells"]).append(self._cell.strip())
            self._cell = None
        elif tag == "thead":
            self._in_head = False
        elif tag == "tr" and self._row is not None:
            self.rows.append(self._row)
            self._row = None
        elif tag == "table":
            self._in_runs = False


def _parsed(html: str) -> _Page:
    page = _Page()
    page.feed(html)
    return page


@pytest.mark.slow
@pytest.mark.skipif(_chromium() is None, reason="Debian's chromium is not installed (.ci/run installs it)")
def test_search_report_in_headless_chromium_worst_first_and_a_track_two_clicks_away(search_file, tmp_path):
    report = run_search(search_file(), tmp_path / "res", workers=2, progress=False)
    folder = tmp_path / "res" / "small_search"
    page = _parsed(_dom((folder / "report.html").as_uri(), tmp_path))
    assert len(page.rows) == 6
    column = page.header.index("objective")
    shown = [float(row["cells"][column]) for row in page.rows]
    assert shown == sorted(shown)  # worst (lowest) first
    assert shown[0] == pytest.approx(report.best, rel=1e-3)
    assert [row["cells"][page.header.index("rank")] for row in page.rows] == ["1", "2", "3", "4", "5", "6"]
    assert {"progress.png", "boundary.png"} <= set(page.images)
    for image in page.images:
        assert (folder / image).is_file()
    worst = page.rows[0]
    assert worst["cells"][page.header.index("failure")] == ("yes" if report.best < 12.0 else "no")
    # click 1: the track figure itself, or the run's page with the track and the time series
    assert (folder / worst["links"]["track"]).is_file() and worst["links"]["track"].endswith("track.png")
    run_page = folder / worst["links"]["run"]
    detail = _parsed(_dom(run_page.as_uri(), tmp_path))
    tracks = [src for src in detail.images if src.endswith("track.png")]
    assert tracks and (run_page.parent / tracks[0]).resolve().is_file()
    assert detail.series == ["ship.u", "ship.r"]
    # the page's own sorting: by a header, descending, as a click on it twice does
    ordered = _parsed(_dom((folder / "report.html").as_uri() + "#sort=-objective", tmp_path))
    assert [float(row["cells"][column]) for row in ordered.rows] == sorted(shown, reverse=True)


@pytest.mark.slow
@pytest.mark.skipif(_chromium() is None, reason="Debian's chromium is not installed (.ci/run installs it)")
def test_batch_report_from_the_command_line_not_passed_first(search_file, tmp_path):
    batch = search_file(SEARCH.replace("[search]", "[unused]").split("[unused]")[0]
                        + "[[acceptance]]\nname = \"fast\"\nmetric = \"analyses.turning_circle.approach_speed_kn\"\n"
                          "op = \">=\"\nvalue = 12.0\n", name="batch.toml")
    assert main(["batch", str(batch), "--results", str(tmp_path / "res"), "--workers", "2", "--no-progress"]) in (0, 3)
    folder = tmp_path / "res" / "small"
    (folder / "report.html").unlink()
    done = subprocess.run([sys.executable, "-m", "orchestrator", "report", str(folder)], capture_output=True, text=True,
                          cwd=REPO, timeout=120)
    assert done.returncode == 0, done.stderr
    page = _parsed(_dom((folder / "report.html").as_uri(), tmp_path))
    table = pd.read_parquet(folder / "summary.parquet")
    assert len(page.rows) == len(table) == 4
    passed = [row["cells"][page.header.index("passed")] for row in page.rows]
    assert passed == sorted(passed, key=lambda p: p == "yes")  # the runs that did not pass first
    assert "overview.png" in page.images


def test_report_of_a_folder_that_is_not_a_batch_is_refused(tmp_path, capsys):
    assert main(["report", str(tmp_path)]) == 2
    assert "not a batch or search results folder" in capsys.readouterr().err


STOPPED_FROM_PYTHON = """\
import signal, sys
from orchestrator.search import run_search
if __name__ == "__main__":  # the workers are spawned: they import this file
    if sys.argv[3] == "SIGINT":
        signal.signal(signal.SIGINT, signal.SIG_IGN)  # as a shell starts a background job: Ctrl-C is not its own
    report = run_search(sys.argv[1], sys.argv[2], workers=1, progress=False, report=False)
    print("interrupted" if report.interrupted else "not interrupted", len(report.table))
"""


@pytest.mark.slow
@pytest.mark.parametrize("name", ["SIGINT", "SIGTERM"])
def test_a_signal_stops_a_search_called_from_plain_python_and_it_resumes(search_file, tmp_path, name):
    # no command line around it (a bench script, python -c): run_search installs the handlers itself
    import os
    import signal
    import time

    path = search_file(SEARCH.replace("evaluations = 6", "evaluations = 60"))
    script = tmp_path / "stopped.py"
    script.write_text(STOPPED_FROM_PYTHON)
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(REPO), str(REPO / "tests" / "orchestrator")])}
    process = subprocess.Popen([sys.executable, str(script), str(path), str(tmp_path / "res"), name], cwd=REPO, env=env,
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    journal = tmp_path / "res" / "small_search" / JOURNAL
    deadline = time.monotonic() + 120
    while len(read_journal(journal)) < 4 and process.poll() is None and time.monotonic() < deadline:
        time.sleep(0.2)  # the second round is journaled: the search is running
    os.kill(process.pid, getattr(signal, name))
    try:
        out, err = process.communicate(timeout=90)
    except subprocess.TimeoutExpired:
        process.kill()
        pytest.fail(f"{name} did not stop the search")
    assert process.returncode == 0, err
    assert out.split()[:2] == ["interrupted", str(len(read_journal(journal)))], out
    asked = len(read_journal(journal))
    assert 4 <= asked < 60
    resumed = run_search(path, tmp_path / "res", workers=1, progress=False, report=False, evaluations=asked)
    assert resumed.evaluated <= 3 and len(resumed.table) == asked and set(resumed.table["status"]) == {"finished"}


@pytest.mark.slow
def test_the_command_line_takes_a_threshold_and_stops_at_the_first_failure(search_file, tmp_path, capsys):
    path = search_file()
    args = ["search", str(path), "--results", str(tmp_path / "res"), "--no-progress", "--workers", "1"]
    assert main([*args, "--fails-below", "1000", "--until-failure"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("3 evaluations (3 run now)") and "3 failures, first at evaluation 1" in out, out
    saved = json.loads((tmp_path / "res" / "small_search" / "search.json").read_text())
    assert saved["fails_below"] == 1000.0


def test_a_threshold_that_is_not_a_number_is_refused_on_the_command_line(search_file, tmp_path, capsys):
    args = ["search", str(search_file()), "--results", str(tmp_path / "res"), "--no-progress"]
    assert main([*args, "--fails-below", "nan"]) == 2
    err = capsys.readouterr().err.strip()
    assert err == "error: --fails-below must be a finite number, got nan"
    assert not (tmp_path / "res").exists()
