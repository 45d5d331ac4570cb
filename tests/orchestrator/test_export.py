"""Export of participants as FMUs, and a whole scenario as an OSP system run in libcosim.

The libcosim run of the exported Experiment 3b (reference, traffic and NMPC as Python-backed
FMUs, the KCS FMU) must give the trajectory of our own run of the same scenario with
libcosim's exchange order (``exchange = "jacobi"``).
"""

from __future__ import annotations

import zipfile
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from orchestrator.cli import main
from orchestrator.errors import ScenarioError
from orchestrator.export import export_participant, exported_layout
from orchestrator.run import run_scenario

REPO = Path(__file__).resolve().parents[2]
STEPS = 40


@pytest.fixture(scope="module")
def short_exp3b(tmp_path_factory):
    """Experiment 3b cut to 40 macro steps (200 s, ten NMPC solves), in libcosim's exchange order."""
    text = (REPO / "scenarios" / "exp3b_head_on.toml").read_text()
    text = text.replace("steps = 320", f"steps = {STEPS}").replace("dt_s = 5.0", 'dt_s = 5.0\nexchange = "jacobi"')
    path = tmp_path_factory.mktemp("scenario") / "exp3b_short.toml"
    path.write_text(text)
    return path


def test_exported_nmpc_offers_its_ports_as_fmi_variables(short_exp3b, tmp_path):
    from fmpy import read_model_description
    from fmpy.validation import validate_fmu

    fmu = export_participant(short_exp3b, "ctrl", tmp_path)
    assert fmu == tmp_path / "ctrl.fmu"
    assert validate_fmu(str(fmu)) == []
    description = read_model_description(str(fmu))
    causality = {v.name: v.causality for v in description.modelVariables}
    for name in ("x", "y", "psi", "u", "v", "r", "reference[0,0]", "reference[15,6]", "obstacles[0,4]"):
        assert causality[name] == "input", name
    for name in ("tau_u", "tau_r", "prediction[15,6]", "solve_time_s", "iterations", "fallback"):
        assert causality[name] == "output", name
    layout = exported_layout(fmu)
    assert {"port": "reference", "shape": [16, 7]} in layout["inputs"]
    assert description.coSimulation.needsExecutionTool is True or description.coSimulation is not None
    assert not list(tmp_path.glob(".*partial*"))  # nothing half-written left behind


def test_exporting_an_fmu_or_an_unknown_participant_is_refused(short_exp3b, tmp_path):
    with pytest.raises(ScenarioError, match=r"participants.ship is an FMU already \(KCS\)"):
        export_participant(short_exp3b, "ship", tmp_path)
    with pytest.raises(ScenarioError, match=r"no participant 'nav' \(participants: ref, traffic, ctrl, ship\)"):
        export_participant(short_exp3b, "nav", tmp_path)
    assert main(["export", str(short_exp3b), "--out", str(tmp_path)]) == 2
    assert not list(tmp_path.glob("*.fmu"))


@pytest.mark.slow
def test_osp_system_in_libcosim_gives_our_trajectory(short_exp3b, tmp_path):
    libcosimpy = pytest.importorskip("libcosimpy")
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimObserver import CosimObserver

    assert main(["export", str(short_exp3b), "--osp", "--out", str(tmp_path / "osp")]) == 0
    config = tmp_path / "osp" / "OspSystemStructure.xml"
    assert {p.name for p in (tmp_path / "osp").glob("*.fmu")} == {"ref.fmu", "traffic.fmu", "ctrl.fmu", "ship.fmu"}

    log_output_level(CosimLogLevel.WARNING)
    execution = CosimExecution.from_osp_config_file(str(config))
    slaves = {s.name.decode(): s.index for s in execution.slave_infos()}
    references = {v.name.decode(): v.reference for v in execution.slave_variables(slaves["ship"])}
    observer = CosimObserver.create_last_value()
    assert execution.add_observer(observer)
    names = ("x", "y", "psi", "u", "v", "r")
    theirs = []
    for _ in range(STEPS):
        assert execution.step()
        theirs.append(observer.last_real_values(slaves["ship"], [references[n] for n in names]))
    theirs = np.array(theirs)

    report = run_scenario(short_exp3b, tmp_path / "results", progress=False)
    assert report.status == "finished", report.reason
    ours = pd.read_parquet(report.folder / "timeseries.parquet")
    ours = ours[[f"ship.{n}" for n in names]].to_numpy()[1:STEPS + 1]
    scale = np.maximum(np.abs(ours).max(axis=0), 1e-3)
    assert np.max(np.abs(theirs - ours) / scale) <= 1e-6
    assert np.hypot(*ours[-1, :2]) > 1000.0 and np.ptp(ours[:, 3]) > 0.05  # it sailed and the NMPC acted
