"""Actuator ports among the canonical plant ports: a vendor's actuator-level FMU (rudder
angle, propeller revolutions under its own names and units) is mapped like a force-level one
and driven through the allocation participant."""

import math
import zipfile

import numpy as np
import pandas as pd
import pytest

from orchestrator import fmu_build
from orchestrator.errors import FmuError, ScenarioError
from orchestrator.plant_ports import PLANT_PORTS
from orchestrator.port_mapping import scalar_conversion
from orchestrator.run import run_scenario
from orchestrator.scenario import VariableMapping
from orchestrator.units import resolve_unit

#: KCSMMG variable -> (vendor name, vendor unit): the same quantities under the vendor's
#: names and units; revolutions declared as an angle per time (2 pi rad each)
VENDOR_NAMES = {
    "rudder_angle_cmd": ("RudderOrder", "radian"),
    "propeller_rps_cmd": ("ShaftSpeedOrder", "Hz"),
    "rudder_angle": ("RudderAngle", "radian"),
    "propeller_rps": ("ShaftSpeed", "rev/s"),
    "propeller_rps0": ("ShaftSpeed0", "rev/s"),
    "thrust": ("PropellerThrust", "newton"),
    "delivered_power": ("ShaftPower", "J/s"),
}
VENDOR_UNITS = """    <Unit name="radian"><BaseUnit rad="1"/></Unit>
    <Unit name="Hz"><BaseUnit s="-1"/></Unit>
    <Unit name="rev/s"><BaseUnit s="-1" rad="1" factor="6.283185307179586"/></Unit>
    <Unit name="newton"><BaseUnit kg="1" m="1" s="-2"/></Unit>
    <Unit name="J/s"><BaseUnit kg="1" m="2" s="-3"/></Unit>
"""

SCENARIO = """
connections = [
  "helm.tau_u -> alloc.tau_u",
  "helm.tau_r -> alloc.tau_r",
  "ship.u -> alloc.u",
  "ship.rudder_angle -> alloc.rudder_angle",
  "ship.propeller_rps -> alloc.propeller_rps",
  "alloc.rudder_angle_cmd -> ship.rudder_angle_cmd",
  "alloc.propeller_rps_cmd -> ship.propeller_rps_cmd",
]
[simulation]
stop_s = 300.0
dt_s = 5.0
[participants.helm]
type = "scripted_tau"
[participants.helm.options]
tau_u_N = 7.7e5
tau_r_steps = [[60.0, 1.2e8]]
[participants.alloc]
type = "allocation"
[participants.ship]
fmu = "{fmu}"
[participants.ship.initial]
u_kn = 18.0
psi_deg = 30.0
{initial}
{mapping}
"""

VENDOR_MAPPING = """[participants.ship.mapping]
rudder_angle_cmd = "RudderOrder"
propeller_rps_cmd = "ShaftSpeedOrder"
rudder_angle = "RudderAngle"
propeller_rps = { variable = "ShaftSpeed", start = "ShaftSpeed0" }
thrust = "PropellerThrust"
delivered_power = "ShaftPower"
"""


@pytest.fixture
def vendor_mmg(tmp_path):
    """A copy of the KCSMMG FMU whose actuator variables carry a vendor's names and units."""
    source = fmu_build.ensure_built("KCSMMG")
    target = tmp_path / "VendorMMG.fmu"
    with zipfile.ZipFile(source) as zin, zipfile.ZipFile(target, "w") as zout:
        for item in zin.infolist():
            data = zin.read(item.filename)
            if item.filename == "modelDescription.xml":
                text = data.decode().replace("  </UnitDefinitions>", VENDOR_UNITS + "  </UnitDefinitions>")
                for name, (vendor, unit) in VENDOR_NAMES.items():
                    start = text.index(f'name="{name}"')
                    end = text.index("</ScalarVariable>", start)
                    element = text[start:end].replace(f'name="{name}"', f'name="{vendor}"', 1)
                    element = element.replace(' displayUnit="deg"', "")
                    head, _, rest = element.partition(' unit="')
                    element = head + f' unit="{unit}"' + rest[rest.index('"'):][1:]
                    text = text[:start] + element + text[end:]
                data = text.encode()
            zout.writestr(item, data)
    return target


def test_actuator_ports_are_canonical():
    assert PLANT_PORTS["rudder_angle_cmd"].causality == "input" and PLANT_PORTS["rudder_angle_cmd"].is_angle
    assert PLANT_PORTS["propeller_rps_cmd"].causality == "input" and PLANT_PORTS["propeller_rps"].causality == "output"
    assert PLANT_PORTS["propeller_rps"].revolutions and not PLANT_PORTS["rudder_angle"].revolutions


@pytest.mark.parametrize("unit, factor", [("rpm", 1 / 60), ("revolution/second", 1.0), ("Hz", 1.0), ("1/min", 1 / 60),
                                          ("rad/s", 1 / (2 * math.pi))])
def test_revolution_units_convert_to_revolutions_per_second(unit, factor):
    variable = type("Variable", (), {"name": "shaft", "unit": unit, "declaredType": None})()
    scale, offset = scalar_conversion("propeller_rps", VariableMapping(variable="shaft"), variable, None, "w")
    assert scale == pytest.approx(factor) and offset == 0.0


def test_rudder_in_degrees_converts_and_a_speed_is_refused():
    variable = type("Variable", (), {"name": "rudder", "unit": "deg", "declaredType": None})()
    scale, _ = scalar_conversion("rudder_angle_cmd", VariableMapping(variable="rudder"), variable, None, "w")
    assert scale == pytest.approx(math.pi / 180)
    wrong = type("Variable", (), {"name": "shaft", "unit": "m/s", "declaredType": None})()
    with pytest.raises(ScenarioError, match=r"w: port 'propeller_rps_cmd' is in 1/s but FMU variable 'shaft' is in 'm/s'"):
        scalar_conversion("propeller_rps_cmd", VariableMapping(variable="shaft"), wrong, None, "w")
    assert resolve_unit("rpm").factor == pytest.approx(2 * math.pi / 60)  # pint: an angle per time


@pytest.mark.slow
def test_vendor_actuator_fmu_through_the_allocation_matches_the_kcsmmg(tmp_path, vendor_mmg):
    """Mapped under other names and unit spellings, the vendor copy sails exactly as the KCSMMG."""
    frames = []
    for fmu, mapping in (("KCSMMG", ""), (vendor_mmg.as_posix(), VENDOR_MAPPING)):
        path = tmp_path / f"{len(frames)}.toml"
        path.write_text(SCENARIO.format(fmu=fmu, mapping=mapping, initial="propeller_rps = 1.08568"))
        report = run_scenario(path, tmp_path / "results", progress=False)
        assert report.ok, report.reason
        frames.append(pd.read_parquet(report.folder / "timeseries.parquet"))
    kcsmmg, vendor = frames
    assert np.degrees(np.abs(kcsmmg["ship.rudder_angle"]).max()) > 5.0       # the rudder did move
    assert kcsmmg["ship.propeller_rps"].iloc[0] == pytest.approx(1.08568)     # [initial] reached the FMU
    for port in ("x", "y", "psi", "u", "r", "rudder_angle", "propeller_rps", "thrust", "delivered_power",
                 "alloc.rudder_angle_cmd"):
        column = port if "." in port else f"ship.{port}"
        np.testing.assert_allclose(vendor[column], kcsmmg[column], rtol=1e-12, atol=1e-9)


@pytest.mark.parametrize("mapping, error, message", [
    (VENDOR_MAPPING.replace('rudder_angle_cmd = "RudderOrder"\npropeller_rps_cmd = "ShaftSpeedOrder"',
                            'propeller_rps_cmd = "RudderOrder"'), ScenarioError,
     r"mapping\.propeller_rps_cmd: port 'propeller_rps_cmd' is in 1/s but FMU variable 'RudderOrder' is in 'radian'"),
    (VENDOR_MAPPING.replace('propeller_rps_cmd = "ShaftSpeedOrder"', 'propeller_rps_cmd = "RudderOrder"'), ScenarioError,
     r"mapping\.propeller_rps_cmd: FMU variable 'RudderOrder' already feeds port 'rudder_angle_cmd'"),
    (VENDOR_MAPPING.replace('rudder_angle = "RudderAngle"', 'rudder_angle = "RudderOrder"')
     .replace('rudder_angle_cmd = "RudderOrder"\n', ""), FmuError,
     r"mapping\.rudder_angle: 'rudder_angle' is a plant output but FMU variable 'RudderOrder' is an input"),
])
def test_vendor_actuator_mapping_mistake_is_refused(tmp_path, vendor_mmg, mapping, error, message):
    path = tmp_path / "bad.toml"
    path.write_text(SCENARIO.format(fmu=vendor_mmg.as_posix(), initial="", mapping=mapping))
    with pytest.raises(error, match=message):
        run_scenario(path, tmp_path / "results", progress=False)
