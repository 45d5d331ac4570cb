"""The closed RHNC loop in the moving storm: the environment FMU and the navigation read the
same time-varying field, each at the times sailed (shortened scenarios/moving_storm_demo.toml)."""

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from orchestrator.run import run_scenario
from rhnc.energy import EnergyParameters, brake_power, cost_rate
from rhnc.metocean import MetOceanField

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
    return frame, MetOceanField.from_netcdf(report.folder / "metocean.nc")


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
