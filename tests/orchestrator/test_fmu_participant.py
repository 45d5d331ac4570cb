"""FMU participants: resolution, parameters, canonical mapping and model failures."""

import math

import numpy as np
import pytest

from orchestrator.errors import FmuError, ModelError, ScenarioError
from orchestrator.master import CoSimulation
from orchestrator.run import run_scenario
from orchestrator.scenario import load_scenario

STRAIGHT = """
connections = [
  "helm.tau_u -> ship.tau_u",
  "helm.tau_r -> ship.tau_r",
]

[simulation]
stop_s = 600.0
dt_s = 10.0

[participants.helm]
type = "scripted_tau"
[participants.helm.options]
tau_u_N = 7.7e5
tau_r_steps = [[100.0, 1.0e8]]

[participants.ship]
fmu = "KCS"
parameter_set = "default"
[participants.ship.parameters]
u0 = 9.0
"""


def build(write_scenario, text):
    return CoSimulation(load_scenario(write_scenario(text)))


def test_kcs_runs_and_outputs_canonical_state(write_scenario, tmp_path):
    report = run_scenario(write_scenario(STRAIGHT), tmp_path, progress=False)
    assert report.ok, report.reason
    import pandas as pd

    frame = pd.read_parquet(report.folder / "timeseries.parquet")
    # first 100 s: straight north at about 9 m/s
    assert frame["ship.x"].iloc[10] == pytest.approx(900, rel=0.02)
    assert abs(frame["ship.y"].iloc[10]) < 1e-6
    assert frame["ship.r"].iloc[-1] > 0  # turning to starboard under a positive yaw moment
    assert frame["ship.y"].iloc[-1] > 100
    assert (report.folder / "track.png").is_file()


def test_missing_fmu_file(write_scenario):
    text = STRAIGHT.replace('fmu = "KCS"', 'fmu = "vendor/ship.fmu"')
    with pytest.raises(FmuError, match=r"participants.ship.fmu: FMU file not found: .*vendor/ship.fmu"):
        build(write_scenario, text)


def test_unknown_builtin_model(write_scenario):
    with pytest.raises(FmuError, match=r"participants.ship.fmu: no built-in model 'NoSuchShip' \(valid: .*KCS"):
        build(write_scenario, STRAIGHT.replace('fmu = "KCS"', 'fmu = "NoSuchShip"'))


def test_a_file_that_is_not_an_fmu(write_scenario, tmp_path):
    (tmp_path / "broken.fmu").write_bytes(b"not a zip archive")
    text = STRAIGHT.replace('fmu = "KCS"', 'fmu = "broken.fmu"').replace('parameter_set = "default"\n', "")
    with pytest.raises(FmuError, match=r"broken.fmu is not a valid FMU"):
        build(write_scenario, text)


def test_unknown_parameter_and_non_parameter(write_scenario):
    with pytest.raises(FmuError, match=r"participants.ship.parameters.draught: FMU KCS.fmu has no variable 'draught'"):
        build(write_scenario, STRAIGHT.replace("u0 = 9.0", "draught = 10.8"))
    with pytest.raises(FmuError, match=r"parameters.x: variable 'x' is a output, not a parameter"):
        build(write_scenario, STRAIGHT.replace("u0 = 9.0", "x = 1.0"))


def test_unknown_parameter_set(write_scenario):
    with pytest.raises(ScenarioError, match=r"participants.ship.parameter_set: no set 'ballast' .*valid: default, paper_table2"):
        build(write_scenario, STRAIGHT.replace('parameter_set = "default"', 'parameter_set = "ballast"'))


def test_mapping_to_a_missing_variable(write_scenario):
    text = STRAIGHT + '[participants.ship.mapping]\nx = "north_m"\n'
    with pytest.raises(FmuError, match=r"participants.ship.mapping.x: FMU KCS.fmu has no variable 'north_m'"):
        build(write_scenario, text)


def test_mapping_with_the_wrong_causality(write_scenario):
    text = STRAIGHT + '[participants.ship.mapping]\ntau_u = "x"\n'
    with pytest.raises(FmuError, match=r"mapping.tau_u: 'tau_u' is a plant input but FMU variable 'x' is an output"):
        build(write_scenario, text)
    text = STRAIGHT + '[participants.ship.mapping]\nheading = "m11"\n'
    with pytest.raises(FmuError, match=r"mapping.heading: variable 'm11' has causality 'parameter'"):
        build(write_scenario, text)


def test_mapping_renames_and_scales_ports(write_scenario, tmp_path):
    text = STRAIGHT + '[participants.ship.mapping]\nnorth_km = { variable = "x", scale = 0.001 }\n'
    report = run_scenario(write_scenario(text), tmp_path, progress=False)
    assert report.ok
    import pandas as pd

    frame = pd.read_parquet(report.folder / "timeseries.parquet")
    np.testing.assert_allclose(frame["ship.north_km"].iloc[10], 0.9, rtol=0.02)
    assert "ship.x" not in frame.columns


def test_outputs_said_to_be_floats_are_python_floats_scaled_and_wrapped_too(write_scenario):
    """The master publishes the outputs of a participant with ``outputs_are_floats`` without
    looking at their types: every value of every step must be a Python float."""
    text = STRAIGHT + '[participants.ship.mapping]\nnorth_km = { variable = "x", scale = 0.001 }\n'
    cosim = build(write_scenario, text)
    ship = cosim.participant("ship")
    assert ship.outputs_are_floats is True
    outputs = [ship.setup(0.0, {"tau_u": 7.7e5, "tau_r": 0.0})]
    try:
        for k in range(3):
            outputs.append(ship.step(10.0 * k, 10.0, {"tau_u": 7.7e5, "tau_r": 1.0e8}))
    finally:
        ship.terminate()
        cosim.close()
    assert {"north_km", "psi"} <= set(outputs[-1])  # scaled, wrapped
    assert {type(value) for values in outputs for value in values.values()} == {float}


def test_a_negative_zero_read_from_the_fmu_is_output_as_zero(write_scenario):
    """``scale * value + offset`` with 1 and 0 turns -0.0 into 0.0; the outputs of ports that are
    the variable unscaled are the same bits."""
    cosim = build(write_scenario, STRAIGHT)
    ship = cosim.participant("ship")
    ship.setup(0.0, {"tau_u": 7.7e5, "tau_r": 0.0})
    try:
        ship._read_reals = lambda: [-0.0] * len(ship.output_names)
        outputs = ship._read_outputs(0.0)
    finally:
        ship.terminate()
        cosim.close()
    assert [math.copysign(1.0, value) for value in outputs.values()] == [1.0] * len(ship.output_names)


def test_an_invalid_parameter_value_is_refused_by_the_fmu(write_scenario, tmp_path):
    text = STRAIGHT.replace("u0 = 9.0", "u0 = 9.0\nm11 = 0.0")
    report = run_scenario(write_scenario(text), tmp_path, progress=False)
    assert report.status == "failed"
    assert report.reason == ("ship (KCS.fmu): fmi2ExitInitializationMode failed: "
                             "parameter m11 has an invalid value")
    assert report.summary["simulation"]["steps_done"] == 0


def test_a_diverging_model_fails_the_run_with_its_name(write_scenario, tmp_path):
    text = STRAIGHT.replace("u0 = 9.0", "u0 = 9.0\nm11 = 1.0")  # stiff: d11/m11 far beyond what RK4 at h_int can integrate
    report = run_scenario(write_scenario(text), tmp_path, progress=False)
    assert report.status == "failed"
    assert report.reason == ("ship (KCS.fmu): fmi2DoStep failed: "
                             "the state became non-finite in the step from t = 0 s")
    assert (report.folder / "summary.json").is_file()


def test_non_finite_input_is_refused_before_reaching_the_fmu(write_scenario):
    """The FMU participant's own check, reached directly (the master's output check is upstream)."""
    cosim = build(write_scenario, STRAIGHT)
    ship = cosim.participant("ship")
    try:
        ship.setup(0.0, {"tau_u": 7.7e5, "tau_r": 0.0})
        ship.step(0.0, 10.0, {"tau_u": 7.7e5, "tau_r": 0.0})
        with pytest.raises(ModelError, match=r"^ship: input 'tau_u' received a non-finite value \(nan\)$"):
            ship.step(10.0, 10.0, {"tau_u": float("nan"), "tau_r": 0.0})
    finally:
        ship.terminate()
        cosim.close()


def test_a_non_finite_output_upstream_fails_the_run_before_the_fmu(write_scenario, tmp_path):
    text = STRAIGHT.replace(
        'type = "scripted_tau"', 'type = "python"\nclass = "sample_participants:Clock"').replace(
        "[participants.helm.options]\ntau_u_N = 7.7e5\ntau_r_steps = [[100.0, 1.0e8]]",
        "[participants.helm.options]\nnan_at_s = 50.0").replace(
        '"helm.tau_u -> ship.tau_u",\n  "helm.tau_r -> ship.tau_r",', '"helm.count -> ship.tau_u",')
    report = run_scenario(write_scenario(text), tmp_path, progress=False)
    assert report.status == "failed"
    assert report.reason == "helm: output 'count' is not finite at t = 50 s"
    assert math.isclose(report.summary["simulation"]["steps_done"], 5)