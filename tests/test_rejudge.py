"""Judging stored runs again with today's analyses (``scripts/rejudge.py``), without running them."""

import json
import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from script_module import module_of_file

REPO = Path(__file__).resolve().parents[1]
NM = 1852.0
KNOT = NM / 3600.0


@pytest.fixture(scope="module")
def rejudge():
    return module_of_file(REPO / "scripts" / "rejudge.py", "rejudge")


def write_run(batch: Path, run_id: str = "r1") -> Path:
    """A finished run of the encounter scenario as a batch stores it: own ship north at 18 kn,
    slowing to 8 kn after 1 min, a ship crossing from starboard (its summary's colregs analysis a
    stale marker)."""
    run = batch / "runs" / run_id
    run.mkdir(parents=True)
    targets = [{"waypoints_nm": [[54.5, 54.5], [54.5, 40.0]], "speed_kn": 18.0, "radius_nm": 1.0}]
    (run / "summary.json").write_text(json.dumps({
        "run_id": run_id, "status": "finished", "scenario": str(REPO / "scenarios" / "encounter_rhnc.toml"),
        "overrides": {"participants.traffic.options.targets": targets}, "analyses": {"colregs": {"marker": "old"}}}))
    t = np.arange(0.0, 1800.0 + 1.0, 5.0)
    speed = np.where(t >= 60.0, 8.0, 18.0) * KNOT
    x = np.concatenate([[0.0], np.cumsum(speed[1:] * 5.0)])
    columns = {"time_s": t, "ship.x": x, "ship.y": np.zeros_like(t), "ship.psi": np.zeros_like(t)}
    velocity = (0.0, -18.0 * KNOT)  # 4.5 nm ahead and 4.5 nm to starboard, heading west (x north, y east)
    for j, value in enumerate((4.5 * NM + 0.0 * t, 4.5 * NM + velocity[1] * t, 0.0 * t + velocity[0],
                               0.0 * t + velocity[1], 0.0 * t + NM)):
        columns[f"traffic.obstacles[0,{j}]"] = value
    pd.DataFrame(columns).to_parquet(run / "timeseries.parquet")
    (batch / "batch.json").write_text(json.dumps({"runs": []}))
    return run


def test_a_batch_is_judged_again_into_another_folder_and_the_original_is_left_alone(rejudge, tmp_path):
    batch = tmp_path / "suite_rhnc_colregs"
    run = write_run(batch)
    before = (run / "summary.json").read_text()
    assert rejudge.main([str(batch), "--into", str(tmp_path / "again")]) == 0
    assert (run / "summary.json").read_text() == before  # never written to
    judged = tmp_path / "again" / batch.name / "runs" / run.name
    summary = json.loads((judged / "summary.json").read_text())
    target = summary["analyses"]["colregs"]["targets"][0]
    assert target["encounter_class"] == "crossing_give_way"
    assert target["manoeuvre_kind"] == "speed" and math.isclose(target["manoeuvre_time_s"], 60.0, abs_tol=5.0)
    assert summary["rejudged"]["analyses"] == ["colregs"]
    assert (judged / "timeseries.parquet").is_symlink()
    assert (tmp_path / "again" / batch.name / "batch.json").exists()


def test_a_folder_without_runs_is_refused_naming_it(rejudge, tmp_path, capsys):
    empty = tmp_path / "not_a_batch"
    empty.mkdir()
    assert rejudge.main([str(empty), "--into", str(tmp_path / "again")]) == 2
    error = capsys.readouterr().err
    assert "not_a_batch" in error and "runs/*/summary.json" in error and len(error.strip().splitlines()) == 1


def test_judging_a_batch_into_its_own_folder_is_refused(rejudge, tmp_path, capsys):
    batch = tmp_path / "suite_rhnc_colregs"
    write_run(batch)
    assert rejudge.main([str(batch), "--into", str(tmp_path)]) == 2
    assert "would overwrite" in capsys.readouterr().err
