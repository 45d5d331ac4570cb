"""Our autonomy in other FMI masters, judged there by the scenario's own acceptance criteria.

Each system of ``scenarios/osp/`` (Experiments 2, 3a, 3b and a COLREG crossing) is exported
with ``export --osp`` and run to its end by OSP's libcosim (its own exchange order: every
simulator of a communication point at once) with libcosim's file observer; ``check`` judges
libcosim's CSV files by the criteria that travel with the system (``scenario.toml``).  The
verdicts must be those of our own master in its default order (Gauss-Seidel).

The second master: a Jacobi loop over the exported FMUs written with plain FMPy
(``FMU2Slave``), its results written with FMPy's ``write_csv``, one file per FMU.
"""

from __future__ import annotations

import glob
from pathlib import Path

import numpy as np
import pytest

from orchestrator.cli import main
from orchestrator.run import run_scenario

REPO = Path(__file__).resolve().parents[2]
NANO = 1_000_000_000
SYSTEMS = ("exp3b_head_on", "exp3a_static", "crossing_give_way", "exp2_rhnc")


def libcosim_run(config: Path, out: Path) -> list[str]:
    """Run an OSP system to its end with libcosim's file observer; the CSV files written."""
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimObserver import CosimObserver
    from orchestrator.scenario import load_scenario

    scenario = load_scenario(config.parent / "scenario.toml")
    log_output_level(CosimLogLevel.WARNING)
    execution = CosimExecution.from_osp_config_file(str(config))
    observer = CosimObserver.create_to_dir(str(out))
    assert execution.add_observer(observer)
    assert execution.simulate_until(int(round(scenario.simulation.stop_s * NANO)))
    del execution, observer  # the observer writes its files when it is released
    return sorted(glob.glob(str(out / "*.csv")))


def verdicts_of_check(files, scenario: Path, tmp_path: Path) -> dict[str, bool]:
    import json

    summary = tmp_path / "check.json"
    code = main(["check", *files, "--scenario", str(scenario), "--summary", str(summary)])
    criteria = json.loads(summary.read_text())["acceptance"]["criteria"]
    assert code == (0 if all(c["passed"] for c in criteria) else 3)
    return {c["name"]: c["passed"] for c in criteria}


@pytest.mark.slow
@pytest.mark.parametrize("name", SYSTEMS)
def test_exported_system_in_libcosim_gets_our_masters_verdicts(name, tmp_path):
    pytest.importorskip("libcosimpy")
    scenario = REPO / "scenarios" / "osp" / f"{name}.toml"
    out = tmp_path / "osp"
    assert main(["export", str(scenario), "--osp", "--out", str(out)]) == 0
    assert (out / "scenario.toml").read_text() == scenario.read_text()  # the criteria travel with it
    files = libcosim_run(out / "OspSystemStructure.xml", tmp_path / "libcosim")
    theirs = verdicts_of_check(files, out / "scenario.toml", tmp_path)

    ours = run_scenario(scenario, tmp_path / "ours", progress=False, overrides={"simulation.exchange": "gauss-seidel"})
    assert theirs == {c["name"]: c["passed"] for c in ours.summary["acceptance"]["criteria"]}, (theirs, ours.reason)
