"""scripts/make_trafficgen55.py: the committed trafficgen55 inputs are the script's, and its refusals."""

import sys
from pathlib import Path

import pytest
from script_module import module_of_file

REPO = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def script():
    return module_of_file(REPO / "scripts" / "make_trafficgen55.py", "make_trafficgen55")


def test_the_committed_inputs_are_the_ones_the_script_writes(script, tmp_path):
    assert script.main(["--inputs-only", "--folder", str(tmp_path)]) == 0
    committed = REPO / "scenarios" / "situations" / "trafficgen55" / "input"
    written = sorted(path.relative_to(tmp_path / "input") for path in (tmp_path / "input").rglob("*.json"))
    assert written == sorted(path.relative_to(committed) for path in committed.rglob("*.json"))
    assert len([path for path in written if path.parts[0] == "situations"]) == 55
    for relative in written:
        assert (tmp_path / "input" / relative).read_text() == (committed / relative).read_text(), relative


def test_no_seed_to_try_is_one_line_exit_2_and_nothing_written(script, tmp_path, capsys):
    assert script.main(["--attempts", "0", "--folder", str(tmp_path / "suite")]) == 2
    error = capsys.readouterr().err
    assert error.count("\n") == 1 and "--attempts 0" in error
    assert not (tmp_path / "suite").exists()


def test_without_trafficgen_it_says_how_to_install_it_exit_2_and_nothing_written(script, tmp_path, capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "trafficgen.cli", None)  # import fails as if not installed
    assert script.main(["--folder", str(tmp_path / "suite")]) == 2
    error = capsys.readouterr().err
    assert error.count("\n") == 1 and "pip install trafficgen==0.9.1" in error
    assert not (tmp_path / "suite").exists()
