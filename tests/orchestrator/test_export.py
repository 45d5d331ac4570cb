"""Export of participants as FMUs, and a whole scenario as an OSP system run in libcosim.

The libcosim run of the exported Experiment 3b (reference, traffic and NMPC as Python-backed
FMUs, the KCS FMU) must give the trajectory of our own run of the same scenario with
libcosim's exchange order (``exchange = "jacobi"``).
"""

from __future__ import annotations

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
    text = (REPO / "scenarios" / "osp" / "exp3b_head_on.toml").read_text()
    text = text.replace("steps = 320", f"steps = {STEPS}")
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


def _libcosim_ship_track(config: Path, steps: int) -> np.ndarray:
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimObserver import CosimObserver

    log_output_level(CosimLogLevel.WARNING)
    execution = CosimExecution.from_osp_config_file(str(config))
    slaves = {s.name.decode(): s.index for s in execution.slave_infos()}
    references = {v.name.decode(): v.reference for v in execution.slave_variables(slaves["ship"])}
    observer = CosimObserver.create_last_value()
    assert execution.add_observer(observer)
    track = []
    for _ in range(steps):
        assert execution.step()
        track.append(observer.last_real_values(slaves["ship"], [references[n] for n in SHIP_STATE]))
    return np.array(track)


SHIP_STATE = ("x", "y", "psi", "u", "v", "r")


@pytest.mark.slow
@pytest.mark.parametrize("name, fmus, steps_key", [
    ("exp3b_head_on", {"ref", "traffic", "ctrl", "ship"}, "steps = 320"),
    ("exp2_rhnc", {"nav", "ctrl", "goal", "ship", "env"}, "steps = 480"),
])
@pytest.mark.slow
def test_osp_system_in_libcosim_gives_our_trajectory(name, fmus, steps_key, tmp_path):
    """The committed OspSystemStructure.xml is what export writes, and libcosim running it gives
    our own run's trajectory (first 40 macro steps) to 1e-6."""
    pytest.importorskip("libcosimpy")
    scenario = REPO / "scenarios" / "osp" / f"{name}.toml"
    out = tmp_path / "osp"
    assert main(["export", str(scenario), "--osp", "--out", str(out)]) == 0
    assert (out / "OspSystemStructure.xml").read_text() == \
        (REPO / "scenarios" / "osp" / name / "OspSystemStructure.xml").read_text()
    assert {p.stem for p in out.glob("*.fmu")} == fmus
    theirs = _libcosim_ship_track(out / "OspSystemStructure.xml", STEPS)

    short = tmp_path / f"{name}.toml"
    text = scenario.read_text()
    assert steps_key in text
    short.write_text(text.replace(steps_key, f"steps = {STEPS}").replace('"../', f'"{REPO / "scenarios"}/'))
    report = run_scenario(short, tmp_path / "results", progress=False)
    assert report.status == "finished", report.reason
    ours = pd.read_parquet(report.folder / "timeseries.parquet")
    ours = ours[[f"ship.{n}" for n in SHIP_STATE]].to_numpy()[1:STEPS + 1]
    scale = np.maximum(np.abs(ours).max(axis=0), 1e-3)
    assert np.max(np.abs(theirs - ours) / scale) <= 1e-6
    assert np.hypot(*ours[-1, :2]) > 1000.0 and np.ptp(ours[:, 3]) > 0.01  # it sailed and the NMPC acted


def test_an_fmu_behind_a_mapping_is_not_exported_as_an_osp_system(tmp_path, capsys):
    """OSP would connect the canonical names to variables the vendor FMU does not have."""
    scenario = REPO / "scenarios" / "own_ship" / "exp3b_s175_identified.toml"
    out = tmp_path / "osp"
    assert main(["export", str(scenario), "--osp", "--out", str(out)]) == 2
    assert "participants.ship.mapping: an OSP system connects FMU variables directly" in capsys.readouterr().err
    assert not out.exists()


def test_an_option_json_cannot_hold_is_refused_before_anything_is_built(short_exp3b, tmp_path):
    bad = tmp_path / "nan_option.toml"
    bad.write_text(short_exp3b.read_text().replace("et_default = 1.0", "et_default = nan"))
    with pytest.raises(ScenarioError, match=r"participants\.ctrl\.options: the options cannot be written into the FMU: "
                                             r"Out of range float values"):
        export_participant(bad, "ctrl", tmp_path)
    assert not list(tmp_path.glob("*.fmu"))
