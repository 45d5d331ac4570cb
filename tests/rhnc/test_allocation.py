"""Control allocation: its force model is the plant's (straight motion), its inverse gives the
demanded tau back, it respects the actuators' ranges and rates, and bad options are refused."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest

from orchestrator.errors import ScenarioError
from orchestrator.participant import BuildContext
from rhnc.control.allocation import AllocationParticipant, ForceModel, load_coefficients

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "models"))
from mmg_reference import forces, mmg_parameters  # noqa: E402  (the independent plant equations)


def context(step_size=5.0):
    return BuildContext("scenario.toml: participants.alloc", Path("."), step_size, 0.0, 100.0)


def test_force_model_is_the_plants_propeller_and_rudder_in_straight_motion():
    model = ForceModel(load_coefficients())
    p = mmg_parameters()
    for rudder_deg, rps, u in ((0.0, 1.1, 9.26), (15.0, 1.3, 8.0), (-30.0, 0.9, 11.0)):
        tau_u, tau_r = model.tau(math.radians(rudder_deg), rps, u)
        _, _, n_total, thrust, _ = forces(p, u, 0.0, 0.0, math.radians(rudder_deg), rps)
        assert tau_u == pytest.approx((1 - p["t_p"]) * thrust, rel=1e-12)
        assert tau_r == pytest.approx(n_total, rel=1e-9, abs=1.0)  # hull moment is zero at v = r = 0


@pytest.mark.parametrize("u", [6.0, 9.26, 12.0])
def test_inverse_gives_the_demanded_tau_back(u):
    """Within the actuators' reach (the rudder below 35 deg) the inverse is exact."""
    model = ForceModel(load_coefficients())
    for tau_u in (7.74e5, 1.5e6):
        rps = model.rps_for(tau_u, u)
        for tau_r in (-1e8, -3e7, 0.0, 5e6, 8e7):
            rudder = model.rudder_for(tau_r, rps, u)
            assert abs(rudder) < math.radians(35.0)
            assert model.tau(rudder, rps, u) == pytest.approx((tau_u, tau_r), rel=1e-9, abs=1e-3)


def test_commands_respect_ranges_and_rates_and_report_saturation():
    alloc = AllocationParticipant.from_options("alloc", {}, context(5.0))
    alloc.setup(0.0, {"rudder_angle": 0.0, "propeller_rps": 1.0, "u": 9.26})
    out = alloc.step(0.0, 5.0, {"tau_u": 1.8e6, "tau_r": 5e9, "u": 9.26})
    coefficients = load_coefficients()
    assert out["rudder_angle_cmd"] == pytest.approx(5.0 * coefficients["rudder_rate_max"])
    assert out["propeller_rps_cmd"] == pytest.approx(1.0 + 5.0 * coefficients["propeller_rate_max"])
    assert out["saturated"] == 1.0
    for k in range(1, 20):
        out = alloc.step(5.0 * k, 5.0, {"tau_u": -1e6, "tau_r": 5e9, "u": 9.26})
    assert out["rudder_angle_cmd"] == pytest.approx(math.radians(35.0))
    assert out["propeller_rps_cmd"] >= 0.0  # ahead only


def test_achieved_tau_comes_from_the_actuators_the_plant_reports():
    alloc = AllocationParticipant.from_options("alloc", {}, context(5.0))
    alloc.setup(0.0, {"u": 9.26})
    out = alloc.step(0.0, 5.0, {"tau_u": 7.7e5, "tau_r": 1e7, "u": 9.26, "rudder_angle": 0.0,
                                "propeller_rps": 1.08})
    assert out["tau_r_achieved"] == 0.0  # the plant's rudder has not moved yet
    assert out["tau_u_achieved"] == pytest.approx(alloc.model.tau(0.0, 1.08, 9.26)[0])


@pytest.mark.parametrize("options, message", [
    ({"rudder_maxx": 0.5}, r"participants.alloc: unknown option 'rudder_maxx'"),
    ({"rudder_max": "35"}, r"participants.alloc: option 'rudder_max' must be a finite number"),
    ({"prop_diameter": -7.9}, r"participants.alloc: option 'prop_diameter' must be positive"),
    ({"parameter_set": "tanker"}, r"participants.alloc: option 'parameter_set': no set 'tanker'"),
    ({"x_r": 0.5}, r"participants.alloc: options 'x_r', 'a_h', 'x_h' must put the rudder's lever aft"),
])
def test_bad_options_are_refused_naming_the_key(options, message):
    with pytest.raises(ScenarioError, match=message):
        AllocationParticipant.from_options("alloc", options, context())


def test_a_coefficient_given_as_an_option_replaces_the_default():
    smaller = AllocationParticipant.from_options("alloc", {"rudder_area": 20.0}, context())
    default = AllocationParticipant.from_options("alloc", {}, context())
    ratio = smaller.model.tau(0.2, 1.0, 9.0)[1] / default.model.tau(0.2, 1.0, 9.0)[1]
    assert ratio == pytest.approx(20.0 / load_coefficients()["rudder_area"])
    assert np.isfinite(ratio)


def test_first_step_starts_from_the_actuators_the_plant_reports():
    """Declared before the plant, the allocation learns the actuators only at its first step:
    it must start from them, not from zero revolutions."""
    alloc = AllocationParticipant.from_options("alloc", {}, context(5.0))
    alloc.setup(0.0, {})  # nothing known yet
    out = alloc.step(0.0, 5.0, {"tau_u": 7.7e5, "tau_r": 0.0, "u": 9.26, "rudder_angle": 0.0,
                                "propeller_rps": 1.08})
    wanted = alloc.model.rps_for(7.7e5, 9.26)
    rate = load_coefficients()["propeller_rate_max"]
    assert abs(out["propeller_rps_cmd"] - 1.08) <= 5.0 * rate + 1e-12
    assert out["propeller_rps_cmd"] == pytest.approx(wanted, abs=5.0 * rate)


# --------------------------------------------------------------------------------------
# the force model from a ship file's [actuators], with stall
# --------------------------------------------------------------------------------------

def _ship_file(tmp_path, **changes):
    import tomllib

    from rhnc.ship.ships import SHIPS_DIR

    text = (SHIPS_DIR / "KCS.toml").read_text()
    table = tomllib.loads(text)["actuators"]
    lines = []
    for key, value in {**table, **changes}.items():
        if value is not None:
            lines.append(f"{key} = {value!r}")
    path = tmp_path / "vendor_ship.toml"
    path.write_text(text.split("[actuators]")[0] + "[actuators]\n" + "\n".join(lines) + "\n")
    return path


def test_the_kcs_ship_file_gives_the_kcsmmg_allocation():
    by_set = AllocationParticipant.from_options("a", {}, context())
    by_ship = AllocationParticipant.from_options("a", {"ship": "KCS"}, context())
    for delta in (0.05, 0.3, 0.6):
        for rps in (0.8, 1.4):
            assert by_ship.model.tau(delta, rps, 9.0) == pytest.approx(by_set.model.tau(delta, rps, 9.0), rel=1e-9)
    assert by_ship.model.rudder_for(1.2e8, 1.4, 9.0) == pytest.approx(by_set.model.rudder_for(1.2e8, 1.4, 9.0))
    assert by_ship.model.c["rudder_rate_max"] == pytest.approx(math.radians(2.32))
    assert by_ship.model.c["propeller_rate_max"] == pytest.approx(0.05)


def test_a_stalling_rudder_gives_less_beyond_its_stall_and_is_never_commanded_there(tmp_path):
    path = _ship_file(tmp_path, rudder_stall_deg=22.0, rudder_post_stall_fraction=0.5)
    allocation = AllocationParticipant.from_options("a", {"ship": str(path)}, context())
    model = allocation.model
    at_stall = model.tau(math.radians(22.0), 1.4, 9.0)[1]
    hard_over = model.tau(math.radians(35.0), 1.4, 9.0)[1]
    assert hard_over < 0.6 * at_stall                                    # beyond the stall the force falls
    assert model.tau(math.radians(27.0), 1.4, 9.0)[1] < model.tau(math.radians(24.0), 1.4, 9.0)[1] < at_stall
    # the largest demand gets the stall angle, not the range's 35 deg
    assert model.rudder_for(10 * at_stall, 1.4, 9.0) == pytest.approx(math.radians(22.0))
    assert model.rudder_for(-10 * at_stall, 1.4, 9.0) == pytest.approx(-math.radians(22.0))
    # below the stall the inverse is exact
    assert model.tau(model.rudder_for(0.5 * at_stall, 1.4, 9.0), 1.4, 9.0)[1] == pytest.approx(0.5 * at_stall)


@pytest.mark.parametrize("change, message", [
    ({"rudder_area_m2": None}, r"missing key 'actuators\.rudder_area_m2' \(rudder area"),
    ({"rudder_chord_m": 5.0}, r"unknown key 'actuators\.rudder_chord_m'"),
    ({"rudder_stall_deg": -3.0}, r"'actuators\.rudder_stall_deg' must be positive"),
    ({"wake_fraction": 1.2}, r"'actuators\.wake_fraction' must be within \[0, 1\)"),
    ({"thrust_coefficients": [0.5, -0.4]}, r"'actuators\.thrust_coefficients' must be \[k0, k1, k2\]"),
])
def test_ship_actuator_mistakes_name_the_file_and_key(tmp_path, change, message):
    path = _ship_file(tmp_path, **change)
    with pytest.raises(ScenarioError, match=message) as caught:
        AllocationParticipant.from_options("a", {"ship": str(path)}, context())
    assert str(path) in str(caught.value)


def test_the_ship_option_stands_alone():
    with pytest.raises(ScenarioError, match=r"option 'ship' takes every coefficient from the ship file; give it alone "
                                            r"\(also given: rudder_max\)"):
        AllocationParticipant.from_options("a", {"ship": "KCS", "rudder_max": 0.5}, context())
