"""Two measurements of the same suites compared situation by situation (``scripts/compare_suites.py``)."""

import json
from pathlib import Path

import pytest

from script_module import module_of_file

REPO = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def compare_suites():
    return module_of_file(REPO / "scripts" / "compare_suites.py", "compare_suites")


def write_batch(root: Path, runs: dict[str, dict]) -> Path:
    """A batch folder ``root/suite`` whose runs are given per situation as
    {separation_kept, fallbacks, arrival_s (None: did not arrive)}."""
    batch = root / "suite"
    entries = []
    for index, (situation, run) in enumerate(runs.items()):
        run_id = f"run{index}-{root.name}"  # run ids differ between measurements; situations match
        entries.append({"run_id": run_id, "parameters": {"situation": f"situations/{situation}.json"}})
        folder = batch / "runs" / run_id
        folder.mkdir(parents=True)
        arrived = run.get("arrival_s")
        reason = (f"stopped at t = {arrived:.0f} s before the step of ship, env: goal.arrived > 0.5"
                  if arrived is not None else "reached the step limit")
        target = {"obstacle": 0, "encounter_class": "head_on", "started_inside": False,
                  "separation_kept": run["separation_kept"], "cpa_nm": 0.8, "required_nm": 1.0}
        (folder / "summary.json").write_text(json.dumps({
            "status": "finished", "reason": reason,
            "analyses": {"colregs": {"targets": [target]}},
            "participants": {"ctrl": {"fallback_count": run.get("fallbacks", 0)}}}))
    (batch / "batch.json").write_text(json.dumps({"runs": entries}))
    return batch


def test_changes_are_named_by_situation_with_the_arrival_change(compare_suites, tmp_path, capsys):
    write_batch(tmp_path / "before", {
        "s1": {"separation_kept": False, "arrival_s": 3000.0},
        "s2": {"separation_kept": True, "fallbacks": 2, "arrival_s": 3000.0},
        "s3": {"separation_kept": True, "arrival_s": None},
        "s4": {"separation_kept": False}})
    write_batch(tmp_path / "after", {
        "s1": {"separation_kept": True, "arrival_s": 3000.0 + 15 * 60},
        "s2": {"separation_kept": False, "arrival_s": 3000.0},
        "s3": {"separation_kept": True, "arrival_s": 3100.0},
        "s4": {"separation_kept": False}})
    assert compare_suites.main([str(tmp_path / "before"), str(tmp_path / "after"), "suite"]) == 0
    out = capsys.readouterr().out
    assert "separation: 2 -> 2 runs; now failing: s2; now passing: s1\n" in out
    assert "fallback only: 1 -> 0 runs; now passing: s2" in out
    assert "arrived: 2 -> 3; in both 2, mean change +7.5 min, later by > 10 min 1" in out
    assert "total: separation 2 -> 2, fallback 1 -> 0, fallback only 1 -> 0" in out


def test_batches_of_different_situations_are_refused(compare_suites, tmp_path):
    write_batch(tmp_path / "before", {"s1": {"separation_kept": True}})
    write_batch(tmp_path / "after", {"s9": {"separation_kept": True}})
    with pytest.raises(SystemExit, match="not the same situations"):
        compare_suites.main([str(tmp_path / "before"), str(tmp_path / "after"), "suite"])


def test_a_missing_results_root_is_named(compare_suites, tmp_path, capsys):
    assert compare_suites.main([str(tmp_path / "nowhere"), str(tmp_path), "suite"]) == 2
    assert "nowhere: no such results folder" in capsys.readouterr().err
