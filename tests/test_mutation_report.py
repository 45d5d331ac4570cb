"""The mutation report marks a module's verdicts stale when a mutated file changed since its run."""

import signal
import subprocess
import sys
from pathlib import Path

import pytest
from script_module import module_of_file

SCRIPT = Path(__file__).resolve().parents[1] / "scripts" / "mutation_report.py"


@pytest.fixture(scope="module")
def report():
    yield module_of_file(SCRIPT, "mutation_report_under_test")
    del sys.modules["mutation_report_under_test"]


def verdicts(report, commit="", hashes=None):
    settings = {"tests": ["tests/test_a.py"]} | ({"source_hashes": hashes} if hashes is not None else {})
    return report.Verdicts(module="a", sources=["pkg/a.py", "pkg/b.py"], counts={"killed": 9, "survived": 1},
                           survivors=[], seconds=60.0, commit=commit, date="today", settings=settings)


def test_a_file_changed_since_the_run_makes_its_verdicts_stale(report, tmp_path, monkeypatch):
    (tmp_path / "pkg").mkdir()
    (tmp_path / "pkg" / "a.py").write_text("x = 1\n")
    (tmp_path / "pkg" / "b.py").write_text("y = 2\n")
    hashes = {name: report.content_hash((tmp_path / name).read_bytes()) for name in ("pkg/a.py", "pkg/b.py")}
    v = verdicts(report, hashes=hashes)
    assert report.stale_sources(v, tmp_path) == []
    (tmp_path / "pkg" / "b.py").write_text("y = 3\n")
    assert report.stale_sources(v, tmp_path) == ["pkg/b.py"]
    (tmp_path / "pkg" / "a.py").unlink()
    assert report.stale_sources(v, tmp_path) == ["pkg/a.py", "pkg/b.py"]
    # and the rendered section says so, naming the file
    monkeypatch.setattr(report, "REPO", tmp_path)
    text = report.section(v)
    assert "**Stale**: `pkg/a.py`, `pkg/b.py` changed since this run" in text
    (tmp_path / "pkg" / "a.py").write_text("x = 1\n")
    (tmp_path / "pkg" / "b.py").write_text("y = 2\n")
    assert "Stale" not in report.section(v)


def test_a_run_stored_without_hashes_is_judged_by_its_commit(report, tmp_path):
    def git(*args):
        return subprocess.run(["git", *args], cwd=tmp_path, check=True, capture_output=True, text=True).stdout.strip()

    git("init", "-q")
    (tmp_path / "pkg").mkdir()
    (tmp_path / "pkg" / "a.py").write_text("x = 1\n")
    (tmp_path / "pkg" / "b.py").write_text("y = 2\n")
    git("add", "-A")
    git("-c", "user.name=t", "-c", "user.email=t@t", "commit", "-qm", "first")
    v = verdicts(report, commit=git("rev-parse", "--short", "HEAD"))
    assert report.stale_sources(v, tmp_path) == []
    (tmp_path / "pkg" / "a.py").write_text("x = 10\n")
    assert report.stale_sources(v, tmp_path) == ["pkg/a.py"]
    # a file the run's commit did not have (moved since), or no commit at all: not known, stale
    moved = report.Verdicts(**{**verdicts(report, commit=v.commit).__dict__, "sources": ["pkg/b.py", "pkg/c.py"]})
    (tmp_path / "pkg" / "c.py").write_text("z = 3\n")
    assert report.stale_sources(moved, tmp_path) == ["pkg/c.py"]
    assert report.stale_sources(verdicts(report), tmp_path) == ["pkg/a.py", "pkg/b.py"]


C_SCRIPT = SCRIPT.parent / "mutation_c.py"


@pytest.fixture(scope="module")
def c_mutation():
    yield module_of_file(C_SCRIPT, "mutation_c_under_test")
    del sys.modules["mutation_c_under_test"]


C_SOURCE = """/* a comment: a < b && c */
#include <math.h>
static int check(int a, int b) {
    log_error(comp, "a < b");
    if (a < b && b != 0) return fmi2Error;  /* x == y */
    return a * b + 1;
    set_name(comp, "a == b");
}
"""


def test_c_mutants_change_one_operator_of_a_code_line_never_a_comment_string_or_log_call(c_mutation):
    mutants = c_mutation.mutants_of("m.c", C_SOURCE)
    changed = {(m.line, m.mutated.strip()) for m in mutants}
    assert changed == {
        (5, "if (a <= b && b != 0) return fmi2Error;  /* x == y */"),
        (5, "if (a < b || b != 0) return fmi2Error;  /* x == y */"),
        (5, "if (a < b && b == 0) return fmi2Error;  /* x == y */"),
        (5, "if (a < b && b != 0) return fmi2OK;  /* x == y */"),
        (5, "if (!(a < b && b != 0)) return fmi2Error;  /* x == y */"),
        (6, "return a / b + 1;"),
        (6, "return a * b - 1;"),
    }
    # names are stable across processes (the report matches a survivor by its name)
    assert len({m.name for m in mutants}) == len(mutants)
    assert all(m.name.startswith("m_c:") for m in mutants)


def test_a_c_mutant_that_does_not_compile_is_told_from_one_the_tests_kill(c_mutation):
    assert c_mutation.verdict_of(1, "FmuError: building model KCS failed: kcs.c:3: error: ...") == "not compiled"
    assert c_mutation.verdict_of(1, "FAILED tests/models/test_kcs_fmu.py::test_x") == "killed"
    assert c_mutation.verdict_of(0, "") == "survived"
    assert c_mutation.verdict_of(None, "") == "timeout"
    assert c_mutation.verdict_of(-signal.SIGXCPU, "") == "timeout"  # past its processor-time limit


def test_a_c_mutants_test_run_is_stopped_by_its_processor_time_not_by_the_clock(c_mutation, tmp_path):
    (tmp_path / "test_spin.py").write_text("import time\n\ndef test_spin():\n    while True:\n        pass\n\n\n"
                                           "def test_wait():\n    time.sleep(5.0)\n")
    status, _ = c_mutation._pytest(tmp_path, ("test_spin.py::test_spin",), 4.0)
    assert status == -signal.SIGXCPU and c_mutation.verdict_of(status, "") == "timeout"
    # a run that waits longer than its processor-time limit, using none, is not stopped
    status, _ = c_mutation._pytest(tmp_path, ("test_spin.py::test_wait",), 4.0)
    assert status == 0


def test_a_mutant_whose_test_run_crashed_counts_as_killed_and_is_not_listed_open(report, tmp_path, monkeypatch):
    (tmp_path / "pkg").mkdir()
    (tmp_path / "pkg" / "a.py").write_text("x = 1\n")
    monkeypatch.setattr(report, "REPO", tmp_path)
    crashed = {"name": "pkg.a.x_f__mutmut_1", "source": "pkg/a.py", "status": "segfault", "diff": "-x = 1\n+x = 2"}
    v = report.Verdicts(module="a", sources=["pkg/a.py"], counts={"killed": 3, "segfault": 1}, survivors=[crashed],
                        seconds=1.0, settings={"tests": []})
    assert v.killed == 4 and v.score() == 100.0
    assert v.explained() == []
    assert "not yet killed" not in report.section(v)


def test_the_readmes_mutation_scores_are_those_of_the_stored_verdicts(report):
    text = report.README.read_text()
    block = text.split(report.README_BEGIN, 1)[1].split(report.README_END, 1)[0]
    assert block.strip() == report.readme_summary(report.load_verdicts()), (
        "README's mutation scores differ from docs/mutation-verdicts.json: run "
        "python scripts/mutation_report.py --report-only")


def test_the_readme_block_is_replaced_between_its_markers_only(report, tmp_path):
    readme = tmp_path / "README.md"
    readme.write_text(f"before\n{report.README_BEGIN}\nold scores\n{report.README_END}\nafter\n")
    v = verdicts(report)
    report.write_readme({"trigger": v}, readme)
    text = readme.read_text()
    assert text.startswith(f"before\n{report.README_BEGIN}\nScores (") and text.endswith(f"{report.README_END}\nafter\n")
    assert "trigger 90 % (10)" in text and "old scores" not in text
    assert "Not run yet: reference," in text
    readme.write_text("no markers\n")
    report.write_readme({"trigger": v}, readme)
    assert readme.read_text() == "no markers\n"


def test_a_c_modules_survivors_retested_take_their_new_verdicts_and_the_others_keep_theirs(report):
    def survivor(name):
        return {"name": name, "source": "m.c", "status": "survived", "diff": "-a\n+b"}

    run = report.Verdicts(module="c", sources=["m.c"], counts={"killed": 7, "survived": 3},
                          survivors=[survivor("m_c:1:a"), survivor("m_c:2:b"), survivor("m_c:3:c")], seconds=60.0,
                          commit="abc", date="then", settings={"sample": {"size": 10, "of": 99, "seed": 1}})
    retest = report.Verdicts(module="c", sources=["m.c"], counts={"killed": 1, "survived": 1},
                             survivors=[survivor("m_c:2:b")], seconds=30.0, commit="def", date="now", settings={})
    merged = report.merged_retest(run, retest, {"m_c:1:a", "m_c:2:b"})  # m_c:3:c's line has changed since
    assert merged.counts == {"killed": 8, "survived": 2} and merged.total == 10
    assert [s["name"] for s in merged.survivors] == ["m_c:2:b", "m_c:3:c"]
    assert (merged.commit, merged.settings["sample"]["size"]) == ("abc", 10)  # the run's, not the retest's
    assert merged.settings["survivors_retested"]["commit"] == "def"
