"""suite_report: the counts of a batch folder of encounter runs."""

import json

import pytest

from rhnc.encounters.suite_report import BEGIN, END, main, markdown, summarise


def _run(folder, name, separation, side, verdict, fallbacks, solve_max_s, targets, started_inside=(),
         inside_kept=None):
    path = folder / "runs" / name
    path.mkdir(parents=True)
    path.joinpath("summary.json").write_text(json.dumps({
        "status": "finished", "reason": "stopped at t = 100 s: goal.arrived > 0.5" if name != "b" else "",
        "analyses": {"encounter": {"separation_respected": separation and not started_inside},
                     "colregs": {"side_correct": side, "verdict": verdict, "targets": targets,
                                 "separation_kept": separation, "started_inside": list(started_inside),
                                 "started_inside_range_kept": inside_kept,
                                 "rules_failed": [] if verdict != "fail" else ["rule_15"]}},
        "participants": {"ctrl": {"fallback_count": fallbacks, "solve_time_max_s": solve_max_s,
                                  "solve_time_median_s": solve_max_s / 10, "solve_cpu_time_max_s": solve_max_s / 2}},
    }))


def test_counts_of_a_batch(tmp_path):
    _run(tmp_path, "a", True, True, "pass", 0, 0.05, [{"side_correct": True, "rule_8": "pass", "rule_14": "pass",
                                                       "separation_kept": True}])
    _run(tmp_path, "b", False, False, "fail", 2, 0.30, [{"side_correct": False, "rule_15": "fail", "rule_8": "fail",
                                                         "separation_kept": False},
                                                        {"side_correct": True, "rule_8": "not applicable",
                                                         "separation_kept": True, "borderline": "head-on: ..."}])
    # a target that started inside R + R_i: the separation over the others holds, and the
    # run is counted apart by its own criterion
    _run(tmp_path, "c", True, None, "not applicable", 0, 0.02,
         [{"side_correct": None, "started_inside": True, "range_opened_in_time": True, "separation_kept": False}],
         started_inside=[0], inside_kept=True)
    row = summarise(tmp_path)
    assert row["runs"] == 3 and row["separation"] == 2 and row["stopped"] == 2
    assert (row["inside_kept"], row["inside_runs"]) == (1, 1)
    assert (row["inside_targets_opened"], row["inside_targets"]) == (1, 1)
    assert (row["outside_targets_kept"], row["outside_targets"]) == (2, 3) and row["borderline_targets"] == 1
    assert (row["side_ok"], row["side_runs"]) == (1, 2)
    assert (row["side_targets_ok"], row["side_targets"]) == (2, 3)
    assert row["verdict_ok"] == 2 and row["fallback_runs"] == 1 and row["fallbacks"] == 2
    assert row["rules"]["rule_8"] == (1, 2) and row["rules"]["rule_15"] == (0, 1) and row["rules"]["rule_13"] == (0, 0)
    assert row["solve_max_ms"] == 300.0 and row["solve_cpu_max_ms"] == 150.0 and row["rules_failed"] == {"rule_15": 1}
    assert ("| 2/3 | 2/3 | 2/3 | 1/1 | 1/1 | 1/2 | 2/3 | 2/3 | 1/2 | - | 1/1 | 0/1 | - | - | 1 | 1 (2) | 5 / 300 | 150 |"
            in markdown([row]))


def test_table_is_written_between_the_markers(tmp_path, capsys):
    _run(tmp_path / "suite", "a", True, True, "pass", 0, 0.05, [{"side_correct": True}])
    doc = tmp_path / "doc.md"
    doc.write_text(f"intro\n{BEGIN}\nold table\n{END}\nafter\n")
    assert main([str(tmp_path / "suite"), "--write", str(doc)]) == 0
    text = doc.read_text()
    assert "old table" not in text and text.startswith("intro\n") and text.endswith(f"{END}\nafter\n")
    assert "| suite | 1 | 1/1 | 1/1 |" in text
    plain = tmp_path / "plain.md"
    plain.write_text("no markers\n")
    assert main([str(tmp_path / "suite"), "--write", str(plain)]) == 2
    assert plain.read_text() == "no markers\n"
    assert "plain.md: no '<!-- suite-table:begin -->'" in capsys.readouterr().err
    assert main([str(tmp_path / "nothing")]) == 2


@pytest.mark.parametrize("text", [f"{BEGIN}\nold\n", f"old\n{END}\n", f"{END}\nold\n{BEGIN}\n"])
def test_a_file_with_one_marker_or_them_reversed_is_refused_and_left_as_it_was(tmp_path, capsys, text):
    _run(tmp_path / "suite", "a", True, True, "pass", 0, 0.05, [{"side_correct": True}])
    doc = tmp_path / "doc.md"
    doc.write_text(text)
    assert main([str(tmp_path / "suite"), "--write", str(doc)]) == 2
    assert doc.read_text() == text
    assert capsys.readouterr().err.startswith(f"suite_report: {doc}: no '{BEGIN}' ... '{END}' lines")


def test_the_table_goes_to_every_file_named_or_to_none(tmp_path, capsys):
    _run(tmp_path / "suite", "a", True, True, "pass", 0, 0.05, [{"side_correct": True}])
    doc, readme, plain = tmp_path / "doc.md", tmp_path / "README.md", tmp_path / "plain.md"
    for path in (doc, readme):
        path.write_text(f"{BEGIN}\nold\n{END}\n")
    plain.write_text("no markers\n")
    # a file without markers refuses the whole write: the others keep their old table
    assert main([str(tmp_path / "suite"), "--write", str(doc), "--write", str(plain), "--write", str(readme)]) == 2
    assert "old" in doc.read_text() and "old" in readme.read_text()
    assert main([str(tmp_path / "suite"), "--write", str(doc), "--write", str(readme)]) == 0
    assert doc.read_text() == readme.read_text() and "| suite | 1 | 1/1 | 1/1 |" in readme.read_text()


def test_failures_lists_every_failing_target_by_class(tmp_path, capsys):
    _run(tmp_path, "a", True, True, "pass", 0, 0.05, [{"side_correct": True, "rule_8": "pass",
                                                       "separation_kept": True}])
    _run(tmp_path, "b", False, False, "fail", 2, 0.30,
         [{"obstacle": 0, "encounter_class": "crossing_give_way", "side_correct": False, "rule_15": "fail",
           "separation_kept": False, "cpa_nm": 0.5, "required_nm": 1.0, "reasons": {"rule_15": "crossed ahead"}},
          {"obstacle": 1, "encounter_class": "overtaken", "started_inside": True, "range_opened_in_time": False,
           "range_opening_s": 90.0, "initial_range_nm": 0.8, "separation_kept": False}])
    _run(tmp_path, "c", True, True, "pass", 3, 0.05, [{"side_correct": True, "separation_kept": True}])
    assert main(["--failures", str(tmp_path)]) == 0
    lines = capsys.readouterr().out.splitlines()
    classes = [line.split("\t")[0] for line in lines]
    assert sorted(classes) == ["fallback", "fallback", "inside", "rule_15", "separation", "side"]
    assert any(line.startswith("rule_15") and line.endswith("crossed ahead") for line in lines)
    assert any(line.startswith("fallback") and "\tc\t" in line and line.endswith("only") for line in lines)
    assert any(line.startswith("fallback") and "\tb\t" in line and "inside, rule_15, separation, side" in line
               for line in lines)
