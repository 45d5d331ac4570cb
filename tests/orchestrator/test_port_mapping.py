"""Mapping a third-party plant's variables onto the canonical ports: units, offsets,
geodetic positions, polar vectors, initial conditions, and every mapping mistake refused
with one line (exit 2)."""

import math
import shutil

import numpy as np
import pandas as pd
import pytest

from orchestrator import fmu_build
from orchestrator.cli import main
from orchestrator.errors import ModelError, ScenarioError
from orchestrator.fmu_participant import FmuParticipant, resolve_fmu
from orchestrator.port_mapping import VectorBinding
from orchestrator.run import run_scenario
from orchestrator.scenario import load_scenario
from orchestrator.units import resolve_unit

from fmu_copies import copy_with_description

KNOT = 1852 / 3600
NM = 1852.0

VENDOR_B_MAPPING = """[participants.ship.mapping]
x = { variable = "north_m", start = "north0_m" }
y = "east_m"
psi = { variable = "heading_deg", start = "heading0_deg" }
u = { variable = "surge_speed_kn", start = "surge0_kn" }
v = "sway_speed_kn"
r = "yaw_rate_deg_s"
tau_u = "thrust_kN"
tau_r = "yaw_moment_kNm"
"""

S175_MAPPING = """
[participants.ship.geodetic]
origin_deg = [35.0, 140.0]
[participants.ship.mapping]
x = { variable = "lat", geodetic = "latitude", start = "start_lat" }
y = { variable = "lon", geodetic = "longitude", start = "start_lon" }
psi = { variable = "heading", start = "start_heading" }
u = { variable = "stw", start = "start_stw" }
v = "sway_speed"
r = "rot"
sog = "sog"
cog = "cog"
tau_u = "propeller_thrust"
tau_r = "rudder_moment"
current = { speed = "current_drift", direction = "current_set", direction_is = "towards" }
wind = { speed = "wind_speed_true", direction = "wind_from", direction_is = "from" }
hs = "wave_height"
"""


def s175_scenario(initial="", mapping=S175_MAPPING, extra_ship="", fmu='"S175"', helm="tau_u_N = 4.7e5"):
    return f"""
connections = ["helm.tau_u -> ship.tau_u", "helm.tau_r -> ship.tau_r"]
[simulation]
stop_s = 600.0
dt_s = 10.0
[participants.helm]
type = "scripted_tau"
[participants.helm.options]
{helm}
[participants.ship]
fmu = {fmu}
{extra_ship}
[participants.ship.initial]
{initial}
{mapping}
"""


def build(path, name="ship"):
    scenario = load_scenario(path)
    spec = scenario.participant(name)
    where = f"{path}: participants.{name}"
    return FmuParticipant(spec, resolve_fmu(spec.fmu, scenario.directory, where), where)


def test_units_are_read_from_the_model_description_and_pint():
    assert resolve_unit("kn").factor == pytest.approx(KNOT)
    rot = resolve_unit("deg/min")
    assert rot.factor == pytest.approx(math.pi / 180 / 60) and rot.dimension[-1] == 1
    assert resolve_unit("kN.m").factor == 1000.0
    assert resolve_unit("kg.m2").dimension[:3] == (1, 2, 0)


def test_initial_state_in_canonical_units_through_the_geodetic_mapping(write_scenario):
    ship = build(write_scenario(s175_scenario("x_nm = 3.0\ny_nm = -2.0\npsi_deg = 270.0\nu_kn = 18.0")))
    assert ship.parameters["start_heading"] == pytest.approx(270.0)
    assert ship.parameters["start_stw"] == pytest.approx(18.0)
    assert ship.parameters["start_lat"] == pytest.approx(35.0 + 3.0 / 60.0, abs=0.01)  # 1 nm ~ 1' of latitude
    try:
        out = ship.setup(0.0, {})
        assert out["x"] == pytest.approx(3 * NM, abs=1e-6)
        assert out["y"] == pytest.approx(-2 * NM, abs=1e-6)
        assert out["psi"] == pytest.approx(-math.pi / 2)
        assert out["u"] == pytest.approx(18 * KNOT)
        # 10 min due west at 18 kn: the projected distance is the FMU's own to 1 m; the
        # parallel sailed bends 3 m north of the grid line (meridian convergence)
        for k in range(60):
            out = ship.step(10.0 * k, 10.0, {"tau_u": 4.7e5, "tau_r": 0.0})
        sailed = math.hypot(out["x"] - 3 * NM, out["y"] + 2 * NM)
        assert sailed == pytest.approx(1000 * math.hypot(out["north_km"], out["east_km"]), abs=1.0)
        assert out["y"] + 2 * NM == pytest.approx(1000 * out["east_km"], abs=1.0)
        assert 0.0 < out["x"] - 3 * NM < 5.0
        assert out["y"] + 2 * NM < -5000.0
    finally:
        ship.terminate()


def test_current_given_as_set_and_drift_and_compass_course_wrapped(write_scenario):
    ship = build(write_scenario(s175_scenario("psi_deg = 0.0\nu_kn = 10.0")))
    try:
        ship.setup(0.0, {})
        out = ship.step(0.0, 1.0, {"current_north": 0.0, "current_east": -0.5, "tau_u": 0.0})
        assert ship.parameters["start_stw"] == pytest.approx(10.0)
        # a current setting west (270 deg) pushes the ship to port: course over ground negative
        # (to 1e-4: the apparent wind of the current turns the ship a little)
        assert out["cog"] == pytest.approx(math.atan2(-0.5, out["u"]), abs=1e-4)
        assert out["sog"] == pytest.approx(math.hypot(out["u"], 0.5), rel=1e-4)
    finally:
        ship.terminate()


def test_vector_binding_forms():
    to_fmu = VectorBinding(("wind_speed", "wind_direction"), "polar_from", ("wn", "we"), "cartesian",
                           ((1.0, 0.0), (1.0, 0.0))).to_fmu
    wind = to_fmu({"wind_speed": 10.0, "wind_direction": math.pi / 2})   # from the east: blows west
    assert wind["wn"] == pytest.approx(0.0, abs=1e-12) and wind["we"] == pytest.approx(-10.0)
    to_fmu = VectorBinding(("current_north", "current_east"), "cartesian", ("drift", "set"), "polar_towards",
                           ((KNOT, 0.0), (math.pi / 180, 0.0))).to_fmu
    current = to_fmu({"current_north": -0.5 * KNOT, "current_east": 0.0})   # setting south
    assert current["drift"] == pytest.approx(0.5) and current["set"] == pytest.approx(180.0)


def test_vendor_b_by_declared_units_alone_matches_the_kcs(tmp_path):
    """No scale anywhere: the declared units do the conversions, [initial] the start values."""
    frames = []
    for fmu, mapping, initial in (
        ("KCS", "", "x_nm = 1.0\npsi_deg = 30.0\nu_kn = 18.0"),
        ("KCSVendorB", VENDOR_B_MAPPING, "x_nm = 1.0\npsi_deg = 30.0\nu_kn = 18.0"),
    ):
        path = tmp_path / f"{fmu}.toml"
        text = s175_scenario(initial, mapping=mapping, fmu=f'"{fmu}"',
                             helm="tau_u_N = 7.7e5\ntau_r_steps = [[100.0, 1.5e8]]")
        path.write_text(text.replace("stop_s = 600.0", "stop_s = 400.0"))
        report = run_scenario(path, tmp_path / "results", progress=False)
        assert report.ok, report.reason
        frames.append(pd.read_parquet(report.folder / "timeseries.parquet"))
    for port in ("x", "y", "psi", "u", "v", "r"):
        np.testing.assert_allclose(frames[1][f"ship.{port}"], frames[0][f"ship.{port}"], rtol=1e-9, atol=1e-9)
    assert frames[0]["ship.x"].iloc[0] == pytest.approx(NM)


def test_offset_after_the_declared_unit(write_scenario):
    mapping = S175_MAPPING.replace('x = { variable = "lat", geodetic = "latitude", start = "start_lat" }',
                                   'x = { variable = "north_km", offset = 5000.0 }')
    mapping = mapping.replace('y = { variable = "lon", geodetic = "longitude", start = "start_lon" }', 'y = "east_km"')
    ship = build(write_scenario(s175_scenario("u_kn = 18.0", mapping=mapping)))
    try:
        assert ship.setup(0.0, {})["x"] == pytest.approx(5000.0)
        out = ship.step(0.0, 100.0, {"tau_u": 4.7e5})
        # km converted to m, then the offset: 100 s north at a little under 18 kn
        assert out["x"] - 5000.0 == pytest.approx(18 * KNOT * 100, rel=0.02)
    finally:
        ship.terminate()


@pytest.fixture
def s175_without_heading_unit(tmp_path):
    """A copy of the S175 FMU whose heading declares no unit (as some vendors ship them)."""
    def without_heading_unit(text: str) -> str:
        start = text.index('name="heading"')
        end = text.index("</ScalarVariable>", start)
        return text[:start] + text[start:end].replace('declaredType="Bearing"', "") + text[end:]

    return copy_with_description(fmu_build.ensure_built("S175"), tmp_path / "S175_nounit.fmu", without_heading_unit)


MISTAKES = {
    "unit of another dimension": (
        lambda m: m.replace('psi = { variable = "heading", start = "start_heading" }', 'psi = "stw"')
        .replace('u = { variable = "stw", start = "start_stw" }', 'u = "sog"').replace('sog = "sog"\n', ""),
        "", r"mapping\.psi: port 'psi' is in rad but FMU variable 'stw' is in 'kn'"),
    "one variable to two ports": (
        lambda m: m.replace('v = "sway_speed"', 'v = "stw"'), "",
        r"mapping\.v: FMU variable 'stw' already feeds port 'u'"),
    "geodetic without an origin": (
        lambda m: m.replace("[participants.ship.geodetic]\norigin_deg = [35.0, 140.0]\n", ""), "",
        r"geodetic: give origin_deg"),
    "initial value without a start parameter": (
        lambda m: m, "v_kn = 1.0", r"initial: 'v' has no start parameter in the FMU"),
    "unknown unit": (
        lambda m: m.replace('v = "sway_speed"', 'v = { variable = "sway_speed", unit = "furlongs/fortnite" }'), "",
        r"mapping\.v: FMU variable 'sway_speed': unknown unit 'furlongs/fortnite'"),
    "unknown initial key": (lambda m: m, "u_mph = 3.0", r"unknown key 'participants\.ship\.initial\.u_mph'"),
    "a port mapped twice": (
        lambda m: m.replace('current = { speed = "current_drift", direction = "current_set", direction_is = "towards" }',
                            'wind_direction = "current_set"'), "",
        r"mapping: port 'wind_direction' is mapped twice"),
    "m/s stated on a variable declared in knots": (
        lambda m: m.replace('u = { variable = "stw", start = "start_stw" }',
                            'u = { variable = "stw", unit = "m/s", start = "start_stw" }'), "",
        r"mapping\.u: unit 'm/s' contradicts the unit 'kn' that the FMU declares for variable 'stw'"),
    "rad stated on a heading declared in degrees (through its type)": (
        lambda m: m.replace('psi = { variable = "heading", start = "start_heading" }',
                            'psi = { variable = "heading", unit = "rad", start = "start_heading" }'), "",
        r"mapping\.psi: unit 'rad' contradicts the unit 'deg' that the FMU declares for variable 'heading'"),
    "deg/s stated on a rate of turn declared in deg/min": (
        lambda m: m.replace('r = "rot"', 'r = { variable = "rot", unit = "deg/s" }'), "",
        r"mapping\.r: unit 'deg/s' contradicts the unit 'deg/min' that the FMU declares for variable 'rot'"),
    "a vector part's unit against the declared one": (
        lambda m: m.replace('direction_is = "towards" }', 'direction_is = "towards", units = { speed = "m/s" } }'),
        "", r"mapping\.current\.speed: unit 'm/s' contradicts the unit 'kn'"),
    "sphere radius without the sphere": (
        lambda m: m.replace("origin_deg = [35.0, 140.0]", "origin_deg = [35.0, 140.0]\nsphere_radius_m = 6.371e6"),
        "", r"geodetic\.sphere_radius_m' needs earth = \"sphere\""),
    "unknown earth model": (
        lambda m: m.replace("origin_deg = [35.0, 140.0]", "origin_deg = [35.0, 140.0]\nearth = \"flat\""),
        "", r"geodetic\.earth"),
}


@pytest.mark.parametrize("mistake", list(MISTAKES))
def test_mapping_mistakes_are_one_line_and_exit_2(mistake, write_scenario, capsys):
    edit, initial, message = MISTAKES[mistake]
    path = write_scenario(s175_scenario(initial or "u_kn = 18.0", mapping=edit(S175_MAPPING)))
    with pytest.raises(ScenarioError, match=message):
        build(path)
    assert main(["validate", str(path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and str(path) in err[0]


def test_angle_without_unit_or_scale_is_refused(s175_without_heading_unit, write_scenario, capsys):
    """The case that once ran to "finished": a heading in degrees taken for radians."""
    path = write_scenario(s175_scenario("u_kn = 18.0", fmu=f'"{s175_without_heading_unit}"'))
    with pytest.raises(ScenarioError, match=r"mapping\.psi: port 'psi' is an angle \(rad\) and FMU variable "
                                            r"'heading' declares no unit"):
        build(path)
    assert main(["run", str(path), "--results", str(path.parent / "results"), "--no-progress"]) == 2
    assert not (path.parent / "results").exists() or not any((path.parent / "results").rglob("summary.json"))
    # stating the unit in the mapping fixes it
    fixed = S175_MAPPING.replace('psi = { variable = "heading", start = "start_heading" }',
                                 'psi = { variable = "heading", unit = "deg", start = "start_heading" }')
    path.write_text(s175_scenario("u_kn = 18.0\npsi_deg = 90.0", mapping=fixed, fmu=f'"{s175_without_heading_unit}"'))
    ship = build(path)
    try:
        assert ship.setup(0.0, {})["psi"] == pytest.approx(math.pi / 2)
    finally:
        ship.terminate()


def test_a_unit_named_otherwise_but_meaning_the_declared_one_is_accepted(write_scenario):
    mapping = S175_MAPPING.replace('u = { variable = "stw", start = "start_stw" }',
                                   'u = { variable = "stw", unit = "knot", start = "start_stw" }')
    ship = build(write_scenario(s175_scenario("u_kn = 18.0", mapping=mapping)))
    try:
        assert ship.setup(0.0, {})["u"] == pytest.approx(18.0 * KNOT)
    finally:
        ship.terminate()


def test_geodetic_mapping_on_a_sphere(write_scenario):
    """A plant integrating on a sphere: one degree of latitude is R pi / 180 along the meridian,
    where the WGS84 projection would make it 0.1-0.4 % longer or shorter."""
    from orchestrator.port_mapping import GeodeticBinding

    radius = 6.371e6
    sphere = GeodeticBinding(("lat", "lon"), ((1.0, 0.0), (1.0, 0.0)), (35.0, 140.0), ("sphere", radius))
    wgs84 = GeodeticBinding(("lat", "lon"), ((1.0, 0.0), (1.0, 0.0)), (35.0, 140.0))
    north = sphere.to_canonical({"lat": 36.0, "lon": 140.0})
    assert north["x"] == pytest.approx(radius * math.pi / 180.0, rel=1e-9) and north["y"] == pytest.approx(0.0, abs=1e-6)
    assert abs(wgs84.to_canonical({"lat": 36.0, "lon": 140.0})["x"] / north["x"] - 1.0) > 1e-3
    # small offsets east: a sphere's parallel at 35 deg has radius R cos(35 deg)
    east = sphere.to_canonical({"lat": 35.0, "lon": 140.01})
    assert east["y"] == pytest.approx(radius * math.cos(math.radians(35.0)) * math.radians(0.01), rel=1e-6)
    assert sphere.latitude_longitude(north["x"], 0.0) == pytest.approx((36.0, 140.0), abs=1e-12)
    # the scenario chooses it; the mean earth radius unless given
    path = write_scenario(s175_scenario("u_kn = 18.0", mapping=S175_MAPPING.replace(
        "origin_deg = [35.0, 140.0]", 'origin_deg = [35.0, 140.0]\nearth = "sphere"\nsphere_radius_m = 6.371e6')))
    assert load_scenario(path).participant("ship").geodetic_earth == ("sphere", 6.371e6)
    path.write_text(s175_scenario("u_kn = 18.0", mapping=S175_MAPPING.replace(
        "origin_deg = [35.0, 140.0]", 'origin_deg = [35.0, 140.0]\nearth = "sphere"')))
    assert load_scenario(path).participant("ship").geodetic_earth == ("sphere", 6371008.8)
    path.write_text(s175_scenario("u_kn = 18.0"))
    assert load_scenario(path).participant("ship").geodetic_earth == ("wgs84", None)


def test_initial_state_given_twice_is_refused(write_scenario):
    path = write_scenario(s175_scenario("u_kn = 18.0", mapping="", fmu='"KCS"',
                                        extra_ship="[participants.ship.parameters]\nu0 = 9.26"))
    with pytest.raises(ScenarioError, match=r"parameters\.u0: the initial state is already given in \[initial\]"):
        build(path)


def test_unmapped_ports_keep_working(tmp_path):
    shutil.copy(fmu_build.ensure_built("KCS"), tmp_path / "k.fmu")
    path = tmp_path / "s.toml"
    path.write_text(s175_scenario("u_kn = 18.0", mapping="", fmu='"k.fmu"'))
    ship = build(path)
    assert {"x", "psi", "tau_u", "wind_direction"} <= set(ship.output_names) | set(ship.input_names)



@pytest.mark.parametrize("fmu, mapping", [
    ('"KCSVendorB"', VENDOR_B_MAPPING),
    # every input given at a step scaled by 2 exactly: the loop's quick path is for a scale of 1 alone
    ('"KCS"', '[participants.ship.mapping]\ntau_u = { variable = "tau_u", scale = 2.0 }\n'
              'tau_r = { variable = "tau_r", scale = 2.0 }\n'),
], ids=["vendor-b-units", "scale-2"])
def test_a_plant_of_one_variable_per_port_steps_as_the_bindings_convert(write_scenario, fmu, mapping):
    """Where every port is one scaled variable the participant converts them in one loop: the
    same doubles as each binding's own conversion, the heading wrapped, through a full turn."""
    path = write_scenario(s175_scenario("psi_deg = 170.0\nu_kn = 18.0", mapping=mapping, fmu=fmu))
    ships = [build(path), build(path)]
    assert ships[0]._scalar_inputs is not None and ships[0]._scalar_outputs is not None
    ships[1]._scalar_inputs = ships[1]._scalar_outputs = None  # each binding's own conversion
    try:
        outputs = [ship.setup(0.0, {}) for ship in ships]
        assert outputs[0] == outputs[1]
        for k in range(40):
            inputs = {"tau_u": 7.7e5 + 1e3 * k, "tau_r": 3.0e8}
            outputs = [ship.step(10.0 * k, 10.0, inputs) for ship in ships]
            assert list(outputs[0].items()) == list(outputs[1].items())
        assert all(-math.pi < psi <= math.pi for psi in (outputs[0]["psi"],))
    finally:
        for ship in ships:
            ship.terminate()


def test_a_non_finite_input_to_a_mapped_plant_is_refused_naming_the_port(write_scenario):
    """The general input path (ports that are no single variable, here the polar current):
    the refusal names the participant, the port and the value."""
    ship = build(write_scenario(s175_scenario("psi_deg = 0.0\nu_kn = 10.0")))
    try:
        ship.setup(0.0, {})
        with pytest.raises(ModelError, match=r"^ship: input 'current_east' received a non-finite value \(inf\)$"):
            ship.step(0.0, 1.0, {"current_north": 0.0, "current_east": math.inf, "tau_u": 0.0})
    finally:
        ship.terminate()
