"""The search-vs-random comparison script: its declaration file checked, and how a count is read."""

from pathlib import Path

import pytest
from script_module import module_of_file

REPO = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def bench():
    return module_of_file(REPO / "bench" / "bench_search.py", "bench_search")


GOOD = """\
search = "{search}"
fails_below_nm = -0.5
seeds = [1, 2]
optimiser_budget = 200
baseline_budget = 1000
"""


@pytest.mark.parametrize("change, message", [
    (("baseline_budget = 1000", "baseline_budget = 1000\nbudgets = 3"), "unknown key 'budgets'"),
    (("seeds = [1, 2]", "seeds = [1, 1]"), "'seeds' must be a list of different non-negative integers"),
    (("fails_below_nm = -0.5", "fails_below_nm = nan"), "'fails_below_nm'"),
    (("optimiser_budget = 200", "optimiser_budget = 0"), "'optimiser_budget' must be a positive integer"),
    (("optimiser_budget = 200", "optimiser_budget = 200\noptimiser = \"annealing\""), "'optimiser'"),
    (("{search}", "no_such_search.toml"), "'search': no such file"),
])
def test_bad_comparison_files_are_refused_in_one_line_and_nothing_is_run(bench, tmp_path, capsys, change, message):
    text = GOOD.replace(*change).replace("{search}", str(REPO / "batches" / "search_rhnc.toml"))
    path = tmp_path / "comparison.toml"
    path.write_text(text)
    assert bench.main([str(path), "--results", str(tmp_path / "results")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and str(path) in err and message in err
    assert not (tmp_path / "results").exists()


def test_seeds_not_declared_are_refused(bench, tmp_path, capsys):
    path = tmp_path / "comparison.toml"
    path.write_text(GOOD.replace("{search}", str(REPO / "batches" / "search_rhnc.toml")))
    assert bench.main([str(path), "--seeds", "3", "--results", str(tmp_path / "results")]) == 2
    assert "--seeds [3]: not among" in capsys.readouterr().err
    assert not (tmp_path / "results").exists()


def test_the_declared_comparisons_are_valid(bench):
    table, search = bench.load_comparison(REPO / "bench" / "search_vs_random.toml")
    assert search == REPO / "batches" / "search_rhnc.toml" and table.fails_below_nm < 0
    for name, optimiser in [("watched", "tpe"), ("restart", "tpe-restart"), ("periodic", "tpe-periodic")]:
        table, search = bench.load_comparison(REPO / "bench" / f"search_vs_random_{name}.toml")
        assert search == REPO / "batches" / "search_rhnc_watched.toml" and table.fails_below_nm == -0.5
        assert table.optimiser == optimiser and table.baseline == "random"


def test_a_baseline_that_found_nothing_counts_as_its_budget_at_least(bench):
    found, censored, hit = bench.Count(10, 200, -0.6), bench.Count(None, 50, -0.2), bench.Count(30, 50, -0.7)
    assert bench.ratio(found, censored) == ">= 5.0" and censored.shown() == "> 50"
    assert bench.ratio(found, hit) == "3.0" and hit.shown() == "30"
    assert bench.ratio(bench.Count(None, 200, -0.1), hit) == "-"


def test_as_run_tables_what_the_folders_hold_and_says_which_search_was_stopped(bench, tmp_path, capsys):
    import json

    path = tmp_path / "comparison.toml"
    path.write_text(GOOD.replace("{search}", str(REPO / "batches" / "search_rhnc.toml")))
    results = tmp_path / "results"

    def saved(folder, first, done, best):
        (results / folder / "search_rhnc_search").mkdir(parents=True)
        (results / folder / "search_rhnc_search" / "search.json").write_text(
            json.dumps({"first_failure": first, "evaluations_done": done, "best": best}))

    saved("tpe-seed1", 12, 20, -0.7)      # found at 12: random may take up to 60
    saved("random-seed1", None, 33, -0.3)  # nothing in 33, stopped before 60
    saved("tpe-seed2", None, 200, -0.2)    # nothing in its whole budget
    out = tmp_path / "table.md"
    assert bench.main([str(path), "--results", str(results), "--as-run", "--write", str(out)]) == 0
    rows = [line for line in out.read_text().splitlines() if line.startswith("| 1 ") or line.startswith("| 2 ")]
    assert rows == ["| 1 | 12 | > 33, stopped | >= 2.8 | -0.700 | -0.300 |",
                    "| 2 | > 200 | > 0, stopped | - | -0.200 | none |"]
    assert "tpe found a loss on 1 of 2 seeds" in out.read_text()
    assert "random needed at least 5 times as many on 0 of 2 seeds" in out.read_text()


def test_a_readme_without_the_summary_markers_is_refused_before_anything_runs(bench, tmp_path, capsys):
    path = tmp_path / "comparison.toml"
    path.write_text(GOOD.replace("{search}", str(REPO / "batches" / "search_rhnc.toml")))
    readme = tmp_path / "README.md"
    readme.write_text("# no markers\n")
    assert bench.main([str(path), "--results", str(tmp_path / "results"), "--readme", str(readme)]) == 2
    assert "no <!-- search-summary:begin -->" in capsys.readouterr().err
    assert not (tmp_path / "results").exists() and readme.read_text() == "# no markers\n"


def test_the_readme_block_is_replaced_between_its_markers(bench, tmp_path):
    readme = tmp_path / "README.md"
    readme.write_text("a\n<!-- search-summary:begin -->\nold\n<!-- search-summary:end -->\nb\n")
    bench.replace_block(readme, "search-summary", "new")
    assert readme.read_text() == "a\n<!-- search-summary:begin -->\nnew\n<!-- search-summary:end -->\nb\n"


def test_each_declared_comparison_fills_its_own_readme_block_and_leaves_the_other(bench, tmp_path):
    import json

    path = tmp_path / "comparison.toml"
    path.write_text(GOOD.replace("{search}", str(REPO / "batches" / "search_rhnc.toml")))
    results = tmp_path / "results"
    (results / "tpe-seed1" / "search_rhnc_search").mkdir(parents=True)
    (results / "tpe-seed1" / "search_rhnc_search" / "search.json").write_text(
        json.dumps({"first_failure": 12, "evaluations_done": 20, "best": -0.7}))
    readme = tmp_path / "README.md"
    first = "<!-- search-summary:begin -->\nas measured\n<!-- search-summary:end -->\n"
    readme.write_text(f"{first}<!-- search-summary-watched:begin -->\nold\n<!-- search-summary-watched:end -->\n")
    assert bench.main([str(path), "--results", str(results), "--as-run", "--readme", str(readme),
                       "--readme-marker", "search-summary-watched"]) == 0
    text = readme.read_text()
    assert text.startswith(first) and "| 1 | 12 | > 0, stopped |" in text.split(first)[1] and "old" not in text
