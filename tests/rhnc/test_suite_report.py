"""suite_report: the counts of a batch folder of encounter runs."""

import json

from rhnc.suite_report import markdown, summarise


def _run(folder, name, separation, side, verdict, fallbacks, solve_max_s, targets):
    path = folder / "runs" / name
    path.mkdir(parents=True)
    path.joinpath("summary.json").write_text(json.dumps({
        "status": "finished",
        "analyses": {"encounter": {"separation_respected": separation},
                     "colregs": {"side_correct": side, "verdict": verdict, "targets": targets,
                                 "rules_failed": [] if verdict != "fail" else ["rule_15"]}},
        "participants": {"ctrl": {"fallback_count": fallbacks, "solve_time_max_s": solve_max_s,
                                  "solve_time_median_s": solve_max_s / 10}},
    }))


def test_counts_of_a_batch(tmp_path):
    _run(tmp_path, "a", True, True, "pass", 0, 0.05, [{"side_correct": True}])
    _run(tmp_path, "b", False, False, "fail", 2, 0.30, [{"side_correct": False}, {"side_correct": True}])
    _run(tmp_path, "c", True, None, "not applicable", 0, 0.02, [{"side_correct": None}])
    row = summarise(tmp_path)
    assert row["runs"] == 3 and row["separation"] == 2
    assert (row["side_ok"], row["side_runs"]) == (1, 2)
    assert (row["side_targets_ok"], row["side_targets"]) == (2, 3)
    assert row["verdict_ok"] == 2 and row["fallback_runs"] == 1
    assert row["solve_max_ms"] == 300.0 and row["rules_failed"] == {"rule_15": 1}
    assert "| 2/3 | 1/2 | 2/3 | 2/3 | 1 | 5 / 300 | R15: 1 |" in markdown([row])
