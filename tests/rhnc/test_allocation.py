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
