"""Swapping the plant FMU for another vendor's model by editing only the scenario,
and the environment FMU returning the planner's met-ocean values."""

import numpy as np
import pandas as pd
import pytest

from orchestrator.run import run_scenario
from rhnc.weather.metocean_sources import from_netcdf

KNOT = 1852 / 3600
DEG = np.pi / 180

# A turn at 18 kn through the paper's weather: wind, waves and current all act.
BASE = """
connections = [
  "helm.tau_u -> ship.tau_u",
  "helm.tau_r -> ship.tau_r",
  "env.current_north -> ship.current_north",
  "env.current_east -> ship.current_east",
  "env.wind_speed -> ship.wind_speed",
  "env.wind_direction -> ship.wind_direction",
  "env.hs -> ship.hs",
  "ship.x -> env.x",
  "ship.y -> env.y",
]

[simulation]
name = "{name}"
stop_s = 1800.0
dt_s = 10.0

[metocean]
generator = "paper_default"
resolution_nm = 2.0

[participants.helm]
type = "scripted_tau"
[participants.helm.options]
tau_u_N = 7.7377e5
tau_r_steps = [[300.0, 1.5e8], [900.0, -1.5e8]]

{ship}

[participants.env]
fmu = "MetOcean"
[participants.env.parameters]
grid_file = "${{metocean.grid}}"
"""

KCS = """
[participants.ship]
fmu = "KCS"
parameter_set = "default"
[participants.ship.parameters]
x0 = 92600.0
y0 = 92600.0
u0 = 9.26
psi0 = 0.785398
"""

# The same ship from "vendor B": other names, kN, knots and degrees. Only this table changes.
VENDOR_B = f"""
[participants.ship]
fmu = "KCSVendorB"
[participants.ship.parameters]
north0_m = 92600.0
east0_m = 92600.0
surge0_kn = {9.26 / KNOT!r}
heading0_deg = {0.785398 / DEG!r}
[participants.ship.mapping]
tau_u = {{ variable = "thrust_kN", scale = 1000.0 }}
tau_r = {{ variable = "yaw_moment_kNm", scale = 1000.0 }}
current_north = {{ variable = "current_n_kn", scale = {KNOT!r} }}
current_east = {{ variable = "current_e_kn", scale = {KNOT!r} }}
wind_speed = {{ variable = "wind_speed_kn", scale = {KNOT!r} }}
wind_direction = {{ variable = "wind_from_deg", scale = {DEG!r} }}
hs = "sig_wave_height_m"
x = "north_m"
y = "east_m"
psi = {{ variable = "heading_deg", scale = {DEG!r} }}
u = {{ variable = "surge_speed_kn", scale = {KNOT!r} }}
v = {{ variable = "sway_speed_kn", scale = {KNOT!r} }}
r = {{ variable = "yaw_rate_deg_s", scale = {DEG!r} }}
"""


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    folder = tmp_path_factory.mktemp("swap")
    frames = {}
    for name, ship in (("kcs", KCS), ("vendor_b", VENDOR_B)):
        path = folder / f"{name}.toml"
        path.write_text(BASE.format(name=name, ship=ship))
        report = run_scenario(path, folder / "results", progress=False)
        assert report.ok, report.reason
        frames[name] = (pd.read_parquet(report.folder / "timeseries.parquet"), report)
    return frames


def test_vendor_b_plant_gives_the_same_trajectory(runs):
    kcs, vendor = runs["kcs"][0], runs["vendor_b"][0]
    for port in ("x", "y", "psi", "u", "v", "r"):
        np.testing.assert_allclose(vendor[f"ship.{port}"], kcs[f"ship.{port}"], rtol=1e-9, atol=1e-9,
                                   err_msg=port)
    # and the run really turned through the weather
    assert kcs["ship.psi"].max() - kcs["ship.psi"].min() > 0.5


def test_environment_fmu_returns_the_planners_values_at_the_ships_positions(runs):
    frame, report = runs["kcs"]
    field = from_netcdf(report.folder / "metocean.nc")
    expected = field.sample(frame["ship.x"].to_numpy(), frame["ship.y"].to_numpy())
    for name in ("wind_speed", "wind_direction", "hs", "current_north", "current_east", "wind_north", "wind_east"):
        np.testing.assert_allclose(frame[f"env.{name}"], expected[name], rtol=1e-12, atol=1e-12, err_msg=name)
