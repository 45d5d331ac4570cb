"""scripts/started_inside_reading.py: stored Rule 8/16 verdicts re-read for started-inside targets."""

import json
from pathlib import Path

import pytest
from script_module import module_of_file

REPO = Path(__file__).resolve().parents[2]


def load_script():
    return module_of_file(REPO / "scripts" / "started_inside_reading.py", "started_inside_reading")


def write_run(folder: Path, name: str, targets: list[dict]) -> None:
    run = folder / "runs" / name
    run.mkdir(parents=True)
    (run / "summary.json").write_text(json.dumps({"analyses": {"colregs": {"targets": targets}}}))


def test_only_started_inside_targets_whose_range_opened_in_time_are_turned(tmp_path):
    batch = tmp_path / "batch"
    write_run(batch, "a", [
        {"rule_8": "fail", "rule_16": "fail", "started_inside": True, "range_opened_in_time": True},
        {"rule_8": "fail", "rule_16": "fail", "started_inside": True, "range_opened_in_time": False},
        {"rule_8": "fail", "rule_16": "not applicable", "started_inside": False, "range_opened_in_time": None},
    ])
    write_run(batch, "b", [{"rule_8": "pass", "rule_16": "pass", "started_inside": False}])
    counts = load_script().count([batch])
    assert counts == {"rule_8": (1, 4, 1), "rule_16": (1, 3, 1)}


def test_a_missing_folder_is_a_one_line_error(tmp_path, capsys):
    with pytest.raises(SystemExit) as stop:
        load_script().main([str(tmp_path / "nowhere")])
    assert stop.value.code == 2
    assert "not a folder" in capsys.readouterr().err
