"""The closed RHNC loop in the moving storm: the environment FMU and the navigation read the
same time-varying field, each at the times sailed (shortened scenarios/moving_storm_demo.toml)."""

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from orchestrator.run import run_scenario
from rhnc.ship.energy import EnergyParameters, brake_power, cost_rate
from rhnc.weather.metocean_sources import from_netcdf

pytestmark = pytest.mark.slow

SCENARIO = Path(__file__).parents[2] / "scenarios" / "moving_storm_demo.toml"
# 100 min at 60 s; the storm starts beside the first 30 nm of the route so that the ship meets
# it in this short run; its steps end at 60 min, so the last 40 min read the held field
SHORT = {"simulation.steps": 100, "metocean.resolution_nm": 2.0, "metocean.duration_h": 1.0,
         "metocean.time_step_h": 0.25, "metocean.centre_nm": [10.0, 30.0], "outputs.figures": []}


@pytest.fixture(scope="module")
def demo(tmp_path_factory):
    report = run_scenario(SCENARIO, tmp_path_factory.mktemp("storm"), progress=False, overrides=SHORT)
    assert report.ok, report.reason
    frame = pd.read_parquet(report.folder / "timeseries.parquet")
    return frame, from_netcdf(report.folder / "metocean.nc")


def test_run_keeps_the_moving_field(demo):
    _, field = demo
    np.testing.assert_array_equal(field.times_s, np.arange(5) * 900.0)


def test_environment_fmu_gives_the_fields_values_at_the_places_and_times_sailed(demo):
    frame, field = demo
    t = frame["time_s"].to_numpy()
    expected = field.sample(frame["ship.x"].to_numpy(), frame["ship.y"].to_numpy(), t_s=t)
    for name in ("wind_speed", "hs", "current_north", "current_east", "wind_north", "wind_east"):
        np.testing.assert_allclose(frame[f"env.{name}"], expected[name], rtol=1e-12, atol=1e-12, err_msg=name)
    # the weather did change under the ship: the same places a quarter of an hour later differ
    later = field.sample(frame["ship.x"].to_numpy(), frame["ship.y"].to_numpy(), t_s=t + 900.0)
    assert np.max(np.abs(later["wind_speed"] - expected["wind_speed"])[t < 3600.0]) > 0.2  # m/s in 15 min


def test_navigation_rates_use_the_same_weather_at_its_planning_instants(demo):
    frame, field = demo
    # the navigation plans every 4 min from the measured state then (not at the last sample)
    rows = frame.iloc[:-1:4]
    local = field.sample(rows["ship.x"].to_numpy(), rows["ship.y"].to_numpy(), t_s=rows["time_s"].to_numpy())
    power = brake_power(np.maximum(rows["ship.u"].to_numpy(), 0.0), rows["ship.psi"].to_numpy(),
                        local["wind_north"], local["wind_east"], local["hs"], EnergyParameters())
    np.testing.assert_allclose(rows["nav.ec_rate"], cost_rate(power, EnergyParameters()), rtol=1e-12)
    # and that is the FMU's weather there and then
    np.testing.assert_allclose(rows["env.hs"], local["hs"], rtol=1e-12, atol=1e-12)


def test_voyage_accounting_without_an_environment_samples_the_field_at_the_times(tmp_path):
    """No weather FMU: the voyage analysis takes the scenario's field at each sample's place and time."""
    import json

    from rhnc.voyage.voyage import account_voyage

    scenario = tmp_path / "no_env.toml"
    scenario.write_text("""
connections = ["helm.tau_u -> ship.tau_u", "helm.tau_r -> ship.tau_r"]
[simulation]
stop_s = 3600.0
dt_s = 60.0
[metocean]
generator = "moving_storm"
resolution_nm = 2.0
duration_h = 2.0
centre_nm = [0.0, 20.0]
[participants.helm]
type = "scripted_tau"
[participants.helm.options]
tau_u_N = 7.7377e5
[participants.ship]
fmu = "KCS"
[participants.ship.parameters]
u0 = 9.26
psi0 = 0.785398
[outputs]
analyses = ["voyage"]
figures = []
""")
    report = run_scenario(scenario, tmp_path / "results", progress=False)
    assert report.ok, report.reason
    frame = pd.read_parquet(report.folder / "timeseries.parquet")
    field = from_netcdf(report.folder / "metocean.nc")
    t, x, y = frame["time_s"].to_numpy(), frame["ship.x"].to_numpy(), frame["ship.y"].to_numpy()
    weather = field.sample(x, y, t_s=t)
    expected = account_voyage(t, x, y, frame["ship.u"], frame["ship.psi"], weather["wind_north"],
                              weather["wind_east"], weather["hs"])
    at_departure = field.sample(x, y, t_s=0.0)
    frozen = account_voyage(t, x, y, frame["ship.u"], frame["ship.psi"], at_departure["wind_north"],
                            at_departure["wind_east"], at_departure["hs"])
    summary = json.loads((report.folder / "summary.json").read_text())
    cost = summary["analyses"]["voyage"]["cost_usd"]
    assert cost == pytest.approx(expected.cost_usd, rel=1e-9)
    assert abs(frozen.cost_usd - expected.cost_usd) > 1e-3 * expected.cost_usd  # the time mattered
