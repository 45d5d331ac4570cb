"""The processor-time bound's figures of encounter batches (``scripts/solve_time_bound.py``)."""

import json
from pathlib import Path

import pytest

from script_module import module_of_file

REPO = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def script():
    return module_of_file(REPO / "scripts" / "solve_time_bound.py", "solve_time_bound")


def write_batch(folder: Path, controls: list[dict]) -> Path:
    for index, control in enumerate(controls):
        run = folder / "runs" / f"run{index}"
        run.mkdir(parents=True)
        (run / "summary.json").write_text(json.dumps({"participants": {"ctrl": control}}))
    return folder


def test_a_batch_row_sums_solves_caps_and_timer_stops_and_takes_the_largest_times(tmp_path, script, capsys):
    folder = write_batch(tmp_path / "measured" / "suite", [
        {"solves": 100, "iteration_capped_steps": 3, "timeout_count": 0, "solve_cpu_time_max_s": 0.150,
         "step_cpu_time_max_s": 0.180},
        {"solves": 50, "iteration_capped_steps": 1, "timeout_count": 2, "solve_cpu_time_max_s": 0.1987,
         "step_cpu_time_max_s": 0.240},
        {"solves": 10},  # a run of the code before the bound: no caps counted
    ])
    assert script.main([str(folder)]) == 0
    rows = capsys.readouterr().out.splitlines()
    assert rows[-1] == "| measured/suite | 3 | 160 | 4 | 2 (1) | 199 | 240 |"


def test_a_folder_without_runs_is_refused_naming_it(tmp_path, script, capsys):
    assert script.main([str(tmp_path / "nothing")]) == 2
    assert "nothing: no runs/ folder" in capsys.readouterr().err
