"""NavigationParticipant: options, Interface I start, outputs and the trigger log."""

from pathlib import Path

import numpy as np
import pytest

from orchestrator.errors import ScenarioError
from orchestrator.participant import BuildContext
from orchestrator.geometry import KNOT, NM
from rhnc.weather.weather_generators import paper_default
from rhnc.navigation.navigation_participant import NavigationParticipant

DELTA = 240.0


@pytest.fixture(scope="module")
def metocean():
    return paper_default(resolution_nm=2.0)


def context(metocean):
    return BuildContext("exp.toml: participants.nav", Path("."), DELTA, 0.0, 3600.0, metocean=metocean)


def build(metocean, **options):
    """The paper's method unless ``method`` is given."""
    return NavigationParticipant.from_options("nav", {"goal_nm": [100, 100], "method": "paper", **options},
                                              context(metocean))


def test_unknown_option_names_the_key_and_the_valid_ones(metocean):
    with pytest.raises(ScenarioError, match=r"exp.toml: participants.nav.options: unknown option 'speed_knots' "
                                            r"\(valid: .*speed_kn.*\)"):
        build(metocean, speed_knots=18)


def test_bad_values_are_scenario_errors(metocean):
    with pytest.raises(ScenarioError, match=r"nav.options.start_from: 'predicted' is not valid"):
        build(metocean, start_from="predicted")
    with pytest.raises(ScenarioError, match=r"nav.options.energy: unknown energy parameter 'Cw'"):
        build(metocean, energy={"Cw": 1.0})
    with pytest.raises(ScenarioError, match=r"goal_nm: the goal lies outside"):
        NavigationParticipant.from_options("nav", {"goal_nm": [150, 10]}, context(metocean))
    with pytest.raises(ScenarioError, match=r"needs the scenario's \[metocean\]"):
        NavigationParticipant.from_options("nav", {"goal_nm": [1, 1]}, context(None))


def test_setup_and_step_outputs(metocean):
    nav = build(metocean, start_nm=[0, 0], horizon_steps=16, resolution_nm=2.0)
    out = nav.setup(0.0, {})
    ref = out["reference"]
    assert ref.shape == (17, 7)
    assert np.allclose(ref[:, 0], DELTA * np.arange(17))
    assert np.allclose(np.linalg.norm(np.diff(ref[:, 1:3], axis=0), axis=1), 18 * KNOT * DELTA)
    assert out["et"] == 0.0
    assert out["goal_distance_m"] == pytest.approx(np.hypot(100, 100) * NM)
    assert 1000 < out["ec_rate"] < 5000 and out["em_rate"] > 1000

    # Interface I: the start is the prediction interpolated at t, not the measurement
    prediction = ref.copy()
    prediction[:, 2] += 500.0
    t = 1.5 * DELTA
    step = nav.step(t, DELTA, {"x": 0.0, "y": 0.0, "psi": 0.0, "u": 9.0, "prediction": prediction})
    expected = np.interp(t, prediction[:, 0], prediction[:, 1]), np.interp(t, prediction[:, 0], prediction[:, 2])
    assert step["reference"][0, 1:3] == pytest.approx(expected)
    assert step["reference"][0, 0] == t
    measured = build(metocean, start_nm=[0, 0], start_from="measured")
    measured.setup(0.0, {})
    step = measured.step(t, DELTA, {"x": 10.0, "y": 20.0, "psi": 0.0, "u": 9.0, "prediction": prediction})
    assert tuple(step["reference"][0, 1:3]) == (10.0, 20.0)


def test_obstacle_switches_to_avoidance_and_is_logged(metocean):
    nav = build(metocean, eps_static_nm=6.0)
    nav.setup(0.0, {"x": 0.0, "y": 0.0, "psi": 0.8, "u": 9.26})
    island = np.array([[4 * NM, 4 * NM, 0.0, 0.0, 3 * NM]])
    out = nav.step(DELTA, DELTA, {"x": 0.0, "y": 0.0, "psi": 0.8, "u": 9.26, "obstacles": island})
    assert out["et"] == 1.0
    # in the avoidance state the path follows G alone: the straight line to the goal
    assert np.allclose(out["reference"][:, 1], out["reference"][:, 2])
    summary = nav.summary()
    assert summary["et_activations"] == 1 and summary["avoidance_plans"] == 1
    assert summary["et_transitions"][0]["range_m"] == pytest.approx(np.hypot(4, 4) * NM)


def test_setup_without_position_needs_start(metocean):
    nav = build(metocean)
    with pytest.raises(ScenarioError, match="start_nm"):
        nav.setup(0.0, {})


def test_plans_in_the_weather_of_each_planning_instant():
    """With a moving storm the fields and the local rates use the weather at the plan's time."""
    from rhnc.ship.energy import EnergyParameters, brake_power, cost_rate
    from rhnc.navigation.fields import resample_weather
    from rhnc.weather.weather_generators import moving_storm

    field = moving_storm(resolution_nm=2.0, duration_h=6.0)
    nav = build(field, start_nm=[0, 0], resolution_nm=2.0, start_from="measured")
    nav.setup(0.0, {})
    state = {"x": 40.0 * NM, "y": 45.0 * NM, "psi": np.pi / 4, "u": 9.0}
    for t in (3600.0, 3.5 * 3600.0):
        out = nav.step(t, DELTA, state)
        expected = resample_weather(field, 2.0, t_s=t)
        np.testing.assert_allclose(nav.field.weather.hs, expected.hs, rtol=1e-12)
        np.testing.assert_allclose(nav.field.ec, energy_at(expected, nav), rtol=1e-12)
        local = field.sample(state["x"], state["y"], t_s=t)
        power = brake_power(9.0, np.pi / 4, local["wind_north"], local["wind_east"], local["hs"], EnergyParameters())
        assert out["ec_rate"] == pytest.approx(float(cost_rate(power, EnergyParameters())), rel=1e-12)
    early = resample_weather(field, 2.0, t_s=3600.0)
    assert np.max(np.abs(nav.field.weather.hs - early.hs)) > 0.5  # the storm did move meanwhile


def energy_at(weather, nav):
    from rhnc.navigation.fields import energy_rate_fields

    return energy_rate_fields(weather, nav.goal, nav.speed, nav.energy)[0]


@pytest.mark.parametrize("method", ["paper", "routing"])
def test_a_delayed_reference_is_planned_for_the_instant_it_reaches_the_controller(metocean, method):
    """Jacobi order: the reference of a step at t reaches the controller at t + delta; it starts
    there, from the controller's prediction at t + delta (the set-up's arrives at once)."""
    jacobi = BuildContext("exp.toml: participants.nav", Path("."), DELTA, 0.0, 3600.0, metocean=metocean,
                          output_delay_s=DELTA)
    nav = NavigationParticipant.from_options("nav", {"goal_nm": [100, 100], "method": method, "start_nm": [0, 0]},
                                             jacobi)
    assert nav.output_delay_s == DELTA
    assert nav.fmu_parameters()["output_delay_s"]["start"] == DELTA
    first = nav.setup(0.0, {})["reference"]
    assert first[0, 0] == 0.0
    prediction = first.copy()
    prediction[:, 2] += 500.0  # the controller predicts the ship 500 m east of the plan
    t = DELTA
    step = nav.step(t, DELTA, {"x": 0.0, "y": 0.0, "psi": 0.8, "u": 9.0, "prediction": prediction})["reference"]
    assert step[0, 0] == t + DELTA
    expected = [np.interp(t + DELTA, prediction[:, 0], prediction[:, j]) for j in (1, 2)]
    assert step[0, 1:3] == pytest.approx(expected)
    # no prediction: the measurement carried over the delay at its course and speed
    alone = nav.step(t, DELTA, {"x": 10.0, "y": 20.0, "psi": 0.0, "u": 9.0})["reference"]
    assert alone[0, 1:3] == pytest.approx([10.0 + 9.0 * DELTA, 20.0])
    assert build(metocean).output_delay_s == 0.0  # Gauss-Seidel: the context's delay is 0


def test_a_negative_reference_delay_is_refused_naming_the_key(metocean):
    with pytest.raises(ScenarioError, match=r"participants.nav.options.output_delay_s: must not be negative, got -1"):
        build(metocean, output_delay_s=-1.0)
