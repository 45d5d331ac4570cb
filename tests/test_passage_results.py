"""The passages' results table: a baseline that never arrived is listed with how far it got, never hidden."""

import json
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from script_module import module_of_file

SCRIPT = Path(__file__).resolve().parents[1] / "scripts" / "passage_results.py"


@pytest.fixture(scope="module")
def script():
    yield module_of_file(SCRIPT, "passage_results_under_test")
    del sys.modules["passage_results_under_test"]


def trial(folder: Path, arrival_s, north_nm):
    """A baseline trial sailing north along the goal's meridian (Biscay's goal, [38.196, 123.44] nm)."""
    folder.mkdir(parents=True)
    (folder / "summary.json").write_text(json.dumps({"participants": {"goal": {"arrival_time_s": arrival_s}}}))
    count = len(north_nm)
    pd.DataFrame({"time_s": 60.0 * np.arange(count), "ship.x": np.asarray(north_nm) * 1852.0,
                  "ship.y": np.full(count, 123.44 * 1852.0), "ship.psi": np.zeros(count), "ship.u": np.full(count, 3.0),
                  "env.hs": np.full(count, 10.0), "env.wind_speed": np.full(count, 20.0),
                  "env.wind_direction": np.full(count, np.radians(30.0)),
                  "route.reference[0,4]": np.full(count, 15.0 * 0.514444),
                  "ctrl.tau_u": 1.8e6 * np.minimum(1.0, 0.95 * np.arange(count))}).to_parquet(folder / "timeseries.parquet")


def test_a_baseline_that_arrived_in_no_trial_is_listed_with_its_progress(script, tmp_path):
    runs = tmp_path / "passage_biscay_crossing" / "20260101T000000Z-x" / "runs" / "RHNC_equal-arrival_baseline"
    trial(runs / "a", None, [-20.0, -10.0, -8.0, -9.0])  # 58.2 nm from the goal, ends 47.2 nm away
    lines = script.stalled_baseline_lines(tmp_path, "biscay_crossing")
    assert "the sea-route baseline arrived in no trial" in lines[1]
    assert ("- reference 15.00 kn: made good 11.0 nm of 58.2 in 0.1 h (least 46.2 nm from the goal); at the ship, "
            "median Hs 10.0 m, wind 20.0 m/s from 30 deg off the bow, speed through water 5.8 kn; surge force "
            "within 1 % of the plant's bound (1.8 MN) in 50 % of the samples") in lines


def test_no_progress_lines_when_a_trial_arrived(script, tmp_path):
    runs = tmp_path / "passage_biscay_crossing" / "20260101T000000Z-x" / "runs" / "RHNC_equal-arrival_baseline"
    trial(runs / "a", None, [-20.0, -10.0])
    trial(runs / "b", 3600.0, [-20.0, 38.0])
    assert script.stalled_baseline_lines(tmp_path, "biscay_crossing") == []


def test_the_table_says_how_each_baseline_search_ended(script):
    assert script.baseline_outcome({"baseline_outcome": "cannot arrive"}) == "cannot arrive"
    # comparisons written before the outcome was recorded: from how the baseline was read
    assert script.baseline_outcome({"baseline_interpolated": True}) == "interpolated"
    assert script.baseline_outcome({"baseline_interpolated": False}) == "matched"
    assert script.baseline_outcome({}) == "-"


def test_the_readme_lines_state_a_baseline_that_cannot_arrive_without_a_saving(script, monkeypatch):
    clear = {"min_clearance_nm": 55.17, "required_clearance_nm": 2.0, "kept": True}
    figures = {
        "biscay_crossing": {"system": {"arrival_min": 417.5, "baseline_outcome": "cannot arrive"}, "rhnc": clear},
        "gibraltar_strait": {"system": {"arrival_min": 267.7, "baseline_outcome": "matched",
                                        "saving_cost_percent": 4.23, "saving_co2_percent": 5.28},
                             "rhnc": {**clear, "min_clearance_nm": 1.017, "required_clearance_nm": 1.0},
                             "distance_alone": -0.4, "baseline_min": 0.996, "baseline_kept": False},
    }
    monkeypatch.setattr(script, "PASSAGES", tuple(figures) + ("cyclades_islands",))
    monkeypatch.setattr(script, "passage_figures", lambda results, name: figures.get(name))
    lines = script.readme_lines(Path("results"))
    assert lines[0] == ("- `biscay_crossing` (open sea, a gale): RHNC arrives at 417.5 min, 55.170 nm from land and "
                        "no-go areas (kept, 2.0 nm declared); the sea-route baseline arrives at no speed up to 30 kn "
                        "in this weather: no saving to give.")
    assert lines[1].endswith("against the sea route at equal arrival time it saves 4.23 % of cost and 5.28 % of CO2 "
                             "(the shorter track alone: -0.4 %); the baseline's clearance 0.996 nm (NOT kept).")
    assert lines[2] == "- `cyclades_islands` (among islands): not compared yet."


def comparison(results: Path, name: str, trial_arrivals) -> None:
    """A comparison folder as compare writes it: RHNC's run and the baseline's trials."""
    folder = results / f"passage_{name}" / "20260101T000000Z-x"
    (folder / "rhnc").mkdir(parents=True)
    clearance = {"min_clearance_nm": 2.5, "required_clearance_nm": 2.0, "kept": True}
    (folder / "summary.json").write_text(json.dumps({"voyage": {"systems": {"RHNC": {"arrival_min": 400.0}}},
                                                     "runs": {"RHNC": "rhnc"}}))
    (folder / "rhnc" / "summary.json").write_text(json.dumps(
        {"analyses": {"clearance": clearance, "voyage": {"distance_nm": 98.0}}}))
    for k, arrival_s in enumerate(trial_arrivals):
        trial = folder / "runs" / "RHNC_equal-arrival_baseline" / f"t{k}"
        trial.mkdir(parents=True)
        trial.joinpath("summary.json").write_text(json.dumps(
            {"participants": {"goal": {"arrival_time_s": arrival_s}},
             "analyses": {"clearance": clearance, "voyage": {"distance_nm": 90.0 + k}}}))


def test_a_baseline_that_never_arrived_has_no_distance_beside_rhncs(script, tmp_path):
    comparison(tmp_path, "stalled", [None, None])
    figures = script.passage_figures(tmp_path, "stalled")
    assert figures["baseline_nm"] is None and figures["distance_alone"] is None
    comparison(tmp_path, "arrived", [None, 24_000.0])
    figures = script.passage_figures(tmp_path, "arrived")
    assert figures["baseline_nm"] == 91.0
    assert figures["distance_alone"] == pytest.approx(100.0 * (1.0 - (98.0 / 91.0) ** 3))


def test_the_readmes_passage_lines_agree_with_the_committed_results_table():
    """Both are written by passage_results.py from the same comparisons: a README block left
    behind by a merge (older savings, an older baseline clearance) is caught here."""
    repo = SCRIPT.parents[1]
    readme = (repo / "README.md").read_text(encoding="utf-8")
    block = readme.split("<!-- passages-summary:begin -->")[1].split("<!-- passages-summary:end -->")[0]
    rows = {}
    for line in (repo / "docs" / "passages-results.md").read_text(encoding="utf-8").splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) == 13 and cells[0].endswith(("_crossing", "_islands", "_strait")):
            rows[cells[0]] = cells
    assert rows, "no passage rows in docs/passages-results.md"
    for name, cells in rows.items():
        line = next(x for x in block.splitlines() if x.startswith(f"- `{name}`"))
        assert f"RHNC arrives at {cells[1]} min, {cells[10].split(' / ')[0]} nm from land" in line, name
        if cells[5] != "-":
            assert f"saves {cells[5]} % of cost and {cells[6]} % of CO2" in line, name
            assert f"the baseline's clearance {cells[11].split(' ')[0]} nm" in line, name
        else:
            assert "no saving" in line, name
