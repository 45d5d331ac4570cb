"""The script that compares full runs with runs ended by the separation watch: how it pairs and judges them."""

import json
from pathlib import Path

import pytest
from script_module import module_of_file

REPO = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def bench():
    return module_of_file(REPO / "bench" / "bench_separation_watch.py", "bench_separation_watch")


def _search(folder: Path, runs: list[tuple[dict, float, list[float], int]]) -> Path:
    """A search folder: per evaluation its values, margin, closest approaches and steps."""
    (folder / "runs").mkdir(parents=True)
    lines = []
    for number, (values, margin, cpas, steps) in enumerate(runs):
        run_id = f"{folder.name}-{number}"
        lines.append(json.dumps({"number": number, "run_id": run_id, "values": values}))
        (folder / "runs" / run_id).mkdir()
        (folder / "runs" / run_id / "summary.json").write_text(json.dumps({
            "simulation": {"steps_done": steps},
            "analyses": {"colregs": {"separation_margin_nm": margin, "targets": [{"cpa_nm": c} for c in cpas]}}}))
    (folder / "trials.jsonl").write_text("\n".join(lines) + "\n")
    return folder


def test_pairs_compares_the_evaluations_both_searches_asked_and_stops_where_they_part(bench, tmp_path, capsys):
    full = _search(tmp_path / "full", [({"a": 1}, -0.2, [0.8], 150), ({"a": 2}, 0.1, [1.1, 2.0], 150),
                                       ({"a": 3}, 0.3, [1.3], 150), ({"a": 4}, 0.3, [1.3], 150)])
    ended = _search(tmp_path / "ended", [({"a": 1}, -0.2, [0.8], 50), ({"a": 2}, 0.1, [1.1, 2.0], 100),
                                         ({"a": 9}, 0.3, [1.3], 40), ({"a": 4}, 0.3, [1.3], 40)])
    assert bench.main(["--pairs", str(full), str(ended)]) == 0
    out = capsys.readouterr().out
    assert out.strip().splitlines()[-1] == "2 runs: 2 judged alike, 0 otherwise; steps 300 -> 150 (50 % fewer)"


@pytest.mark.parametrize("other", [(-0.2, [0.8, 2.0]), (-0.19, [0.8, 2.0]), (-0.2, [0.8, 2.1])])
def test_a_run_judged_otherwise_is_shown_and_fails_the_script(bench, tmp_path, capsys, other):
    full = _search(tmp_path / "full", [({"a": 1}, -0.2, [0.8, 1.9], 150)])
    ended = _search(tmp_path / "ended", [({"a": 1}, other[0], other[1], 50)])
    assert bench.main(["--pairs", str(full), str(ended)]) == 1
    out = capsys.readouterr().out
    assert "JUDGED OTHERWISE" in out and "1 runs: 0 judged alike, 1 otherwise" in out


@pytest.mark.parametrize("args, message", [
    (["--rerun", "FOLDER"], "error: --rerun needs --watched SEARCH.toml and -n of at least 1"),
    (["--rerun", "FOLDER", "--watched", "s.toml", "-n", "0"], "error: --rerun needs --watched SEARCH.toml"),
    (["--pairs", "FOLDER", "FOLDER"], "error: {tmp}/FOLDER: no search journal (trials.jsonl)"),
])
def test_bad_input_is_refused_in_one_line(bench, tmp_path, capsys, args, message):
    args = [a.replace("FOLDER", str(tmp_path / "FOLDER")) for a in args]
    assert bench.main(args) == 2
    err = capsys.readouterr().err.strip()
    assert err == message.format(tmp=tmp_path) or (err.startswith(message) and "\n" not in err)
