"""Experiment 1 runner on a shortened scenario: outputs and strict keys."""

import csv
import json

import pytest

from orchestrator.errors import ScenarioError
from rhnc.navigation.offline_planning import run_offline_planning

SCENARIO = """
name = "exp1_short"
[metocean]
generator = "paper_default"
x_range_nm = [0.0, 20.0]
y_range_nm = [0.0, 20.0]
resolution_nm = 1.0
[planner]
start_nm = [0.0, 0.0]
goal_nm = [20.0, 20.0]
step_nm = 1.2
horizon_steps = 30
speed_kn = 18.0
resolution_nm = 0.5
[[cases]]
name = "cost_only"
k1 = 1.0
k2 = 0.0
k3 = 16.0
[[cases]]
name = "cost_and_emission"
k1 = 1.0
k2 = 1.0
k3 = 16.0
"""


def test_writes_figures_table_and_summary(tmp_path):
    scenario = tmp_path / "exp1.toml"
    scenario.write_text(SCENARIO)
    folder = run_offline_planning(scenario, tmp_path / "results")
    assert folder.parent == tmp_path / "results" / "exp1_short"
    for name in ("figure8_paths.png", "figure9_field_energy.png", "paths.csv", "table.csv", "summary.json"):
        assert (folder / name).stat().st_size > 0
    assert not any(p.name.startswith(".") for p in folder.parent.iterdir())
    with open(folder / "table.csv") as handle:
        rows = {row["case"]: row for row in csv.DictReader(handle)}
    assert set(rows) == {"cost_only", "cost_and_emission"}
    for row in rows.values():
        assert row["reached_goal"] == "True"
        # the path is at least the straight distance and not much longer
        assert 28.28 <= float(row["path_length_nm"]) < 1.1 * 28.29
        assert float(row["voyage_ec_usd"]) > 0 and float(row["voyage_em_t"]) > 0
    summary = json.loads((folder / "summary.json").read_text())
    assert summary["planner"]["delta_s"] == pytest.approx(240.0)
    assert [c["case"] for c in summary["cases"]] == ["cost_only", "cost_and_emission"]


def test_unknown_keys_name_file_and_key(tmp_path):
    scenario = tmp_path / "bad.toml"
    scenario.write_text(SCENARIO.replace("step_nm = 1.2", "step_nmi = 1.2"))
    with pytest.raises(ScenarioError, match=r"bad.toml: planner: unknown key 'step_nmi' \(valid: .*step_nm"):
        run_offline_planning(scenario, tmp_path / "results")
    scenario.write_text(SCENARIO.replace("k3 = 16.0\n[[cases]]", "k4 = 16.0\n[[cases]]"))
    with pytest.raises(ScenarioError, match=r"bad.toml: cases\[0\]: unknown key 'k4'"):
        run_offline_planning(scenario, tmp_path / "results")
    assert not (tmp_path / "results").exists()
