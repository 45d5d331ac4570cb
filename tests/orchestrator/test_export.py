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
    assert ("reference", [16, 7]) in [(entry["port"], entry["shape"]) for entry in layout["inputs"]]
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


def test_a_refused_name_among_several_leaves_no_fmu_behind(short_exp3b, tmp_path, capsys):
    """``export S ctrl bogus``: refused with exit 2 before ctrl.fmu is built, and nothing written."""
    out = tmp_path / "out"
    assert main(["export", str(short_exp3b), "ctrl", "bogus", "--out", str(out)]) == 2
    assert "no participant 'bogus' (participants: ref, traffic, ctrl, ship)" in capsys.readouterr().err
    assert not out.exists()


def test_an_export_failing_half_way_removes_what_it_wrote(short_exp3b, tmp_path, monkeypatch, capsys):
    """The second FMU fails to build: the first one is removed again, files already there stay."""
    import orchestrator.export as export

    out = tmp_path / "out"
    out.mkdir()
    (out / "keep.txt").write_text("the user's")
    real_build = export._build
    built = []

    def build_then_fail(script, files, out_dir, participant, units=None):
        if built:
            raise ScenarioError(f"{participant}: the FMU could not be built")
        built.append(real_build(script, files, out_dir, participant, units))
        return built[-1]

    monkeypatch.setattr(export, "_build", build_then_fail)
    assert main(["export", str(short_exp3b), "ctrl", "ref", "--out", str(out)]) == 2
    assert "ref: the FMU could not be built" in capsys.readouterr().err
    assert built and not built[0].exists()
    assert sorted(p.name for p in out.iterdir()) == ["keep.txt"]


@pytest.fixture(scope="module")
def exported_ctrl(short_exp3b, tmp_path_factory):
    return export_participant(short_exp3b, "ctrl", tmp_path_factory.mktemp("ctrl"))


def test_the_exported_nmpc_describes_every_variable(exported_ctrl):
    """Units (declared in UnitDefinitions), descriptions, the meaning of each array element, and
    the loop delay as a parameter of one communication step."""
    from fmpy import read_model_description
    from fmpy.validation import validate_fmu

    assert validate_fmu(str(exported_ctrl)) == []
    variables = {v.name: v for v in read_model_description(str(exported_ctrl)).modelVariables}
    assert all(v.description for v in variables.values()), [n for n, v in variables.items() if not v.description]
    assert (variables["tau_r"].unit, variables["psi"].unit, variables["x"].unit) == ("N.m", "rad", "m")
    assert [variables[f"reference[3,{j}]"].unit for j in range(7)] == ["s", "m", "m", "rad", "m/s", "m/s", "rad/s"]
    assert variables["reference[3,4]"].description.startswith("row 3, u surge [m/s]: reference trajectory")
    assert "(t [s], x [m], y [m], psi [rad], u [m/s], v [m/s], r [rad/s])" in variables["reference[0,0]"].description
    assert variables["obstacles[0,4]"].description.startswith("row 0, radius R_i [m]")
    delay = variables["loop_delay_s"]
    assert (delay.causality, delay.unit, float(delay.start)) == ("parameter", "s", 20.0)
    # start values of the inputs: the exported scenario's first step (a usable reference)
    assert float(variables["reference[1,0]"].start) - float(variables["reference[0,0]"].start) == 20.0
    assert float(variables["u"].start) == pytest.approx(9.26)


def test_the_exported_nmpc_steps_cleanly_from_its_start_values_in_plain_fmpy(exported_ctrl):
    from fmpy import simulate_fmu

    result = simulate_fmu(str(exported_ctrl), stop_time=60.0, output_interval=20.0,
                          output=["tau_u", "tau_r", "prediction[0,0]", "fallback"])
    assert list(result["time"]) == [0.0, 20.0, 40.0, 60.0]
    assert np.all(np.isfinite(result["tau_u"])) and np.all(result["fallback"] == 0.0)
    assert abs(result["tau_r"][1]) < 1.65e8  # not saturated: a usable reference
    # decided at 0 for the ship from 20 s (one communication step of delay)
    assert result["prediction[0,0]"][1] == 20.0


def _step_with(fmu_path, values: dict):
    """Instantiate with logging on, set ``values``, step once: (status or None, messages)."""
    from fmpy import calloc, extract, free, read_model_description
    from fmpy.fmi1 import FMICallException
    from fmpy.fmi2 import (FMU2Slave, fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE,
                           fmi2CallbackFunctions, fmi2CallbackLoggerTYPE)

    description = read_model_description(str(fmu_path))
    refs = {v.name: v.valueReference for v in description.modelVariables}
    messages = []
    callbacks = fmi2CallbackFunctions()
    callbacks.logger = fmi2CallbackLoggerTYPE(lambda _c, _i, status, _cat, text: messages.append((status, text.decode())))
    callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
    callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
    fmu = FMU2Slave(guid=description.guid, unzipDirectory=extract(str(fmu_path)),
                    modelIdentifier=description.coSimulation.modelIdentifier, instanceName="ctrl")
    fmu.instantiate(callbacks=callbacks, loggingOn=True)
    status = None
    try:
        fmu.setupExperiment(startTime=0.0)
        fmu.enterInitializationMode()
        fmu.exitInitializationMode()
        fmu.setReal([refs[name] for name in values], list(values.values()))
        try:
            fmu.doStep(0.0, 20.0)
        except FMICallException as exc:
            status = exc.status
        fmu.terminate()
    finally:
        fmu.freeInstance()
    return status, messages


def test_a_non_finite_input_is_refused_with_a_message_naming_it(exported_ctrl):
    status, messages = _step_with(exported_ctrl, {"x": float("nan"), "obstacles[0,1]": float("inf")})
    assert status == 2  # fmi2Discard: the step is refused, the instance lives on
    assert (3, "ctrl: inputs not finite at t = 0 s: x = nan, obstacles[0,1] = inf") in messages


def test_a_reference_of_another_layout_is_refused_with_a_message_naming_the_layout(exported_ctrl):
    from fmpy import read_model_description

    starts = {v.name: float(v.start) for v in read_model_description(str(exported_ctrl)).modelVariables
              if v.name.startswith("reference[")}
    rows = np.array([[starts[f"reference[{i},{j}]"] for j in range(7)] for i in range(16)])
    swapped = rows[:, [1, 2, 3, 4, 5, 6, 0]]  # (x, y, psi, u, v, r, t)
    status, messages = _step_with(exported_ctrl, {f"reference[{i},{j}]": swapped[i, j]
                                                  for i in range(16) for j in range(7)})
    assert status == 2
    assert any(level == 3 and "input 'reference' at t = 0.0 s: rows must be (t [s], x [m], y [m], psi [rad], "
               "u [m/s], v [m/s], r [rad/s])" in text for level, text in messages), messages
