"""The physical bounds of the hull-polynomial model class: the mass matrix from the ship's
particulars, and a polynomial that only takes energy out of sway and yaw."""

import dataclasses

import numpy as np
import pytest

from orchestrator.cli import main
from rhnc.ship.equation_error import ALL_COEFFICIENTS, fit_coefficients
from rhnc.ship.identification import physical, simulate
from rhnc.ship.physical_bounds import (MassBounds, is_dissipative, make_dissipative, mass_from_particulars,
                                       power_form)
from rhnc.ship.ship_model import ShipParameters, load_parameter_set
from rhnc.ship.ships import load_ship

MASSES = ("m11", "m22", "m33", "m23")
#: The KVLCC2's hull polynomial of the MMG standard (Yasukawa and Yoshimura 2015), non-dimensional.
KVLCC2_MMG = dict(y_vvv=-1.607, y_vvr=0.379, y_vrr=-0.391, y_rrr=0.008,
                  n_vvv=-0.030, n_vvr=-0.294, n_vrr=0.055, n_rrr=-0.013)


def test_the_mass_matrix_from_the_particulars_is_the_ships():
    """The KCS set of the project was built with Clarke's sway and yaw added masses: the estimate
    is its own; the KVLCC2 of the MMG standard (m_x' 0.022, m_y' 0.223, J_z' 0.011, x_G 11.2 m)
    lies within 5 % and inside the bounds, its coupling x_G m included."""
    kcs = load_parameter_set("default")
    estimate = mass_from_particulars(load_ship("KCS"))
    for name in ("m22", "m33"):
        assert estimate.estimate[name] == pytest.approx(getattr(kcs, name), rel=1e-3), name
    assert estimate.estimate["m11"] == pytest.approx(kcs.m11, rel=1e-3)
    assert estimate.contains({name: getattr(kcs, name) for name in MASSES})

    ship = load_ship("KVLCC2")
    mass, scale = 1025.0 * ship.displacement_m3, 0.5 * 1025.0 * ship.lpp_m ** 2 * ship.draught_m
    mmg = {"m11": mass + 0.022 * scale, "m22": mass + 0.223 * scale,
           "m33": mass * (0.25 * ship.lpp_m) ** 2 + 11.2 ** 2 * mass + 0.011 * scale * ship.lpp_m ** 2,
           "m23": 11.2 * mass}
    estimate = mass_from_particulars(ship)
    for name in ("m11", "m22", "m33"):
        assert estimate.estimate[name] == pytest.approx(mmg[name], rel=0.05), name
    assert estimate.contains(mmg)
    assert not estimate.contains({**mmg, "m22": 0.2 * mmg["m22"]})   # the lone equation-error fit's sway mass


def test_the_power_check_is_exact_and_the_repair_makes_it_hold():
    """The MMG KVLCC2's polynomial only brakes sway and yaw; with a yaw term that feeds energy
    in a narrow band of directions it does not, and strengthening the pure cubic damping
    (and nothing else) makes it dissipative again."""
    assert is_dissipative(KVLCC2_MMG, 0.3, 0.5)
    assert power_form(KVLCC2_MMG) == pytest.approx([-1.607, 0.349, -0.685, 0.063, -0.013])
    feeding = dict(KVLCC2_MMG, n_vrr=1.2)           # P(1, t) > 0 only for t in about (1.8, 2.9)
    assert not is_dissipative(feeding, 0.3, 0.5)
    repaired, added = make_dissipative(feeding, 0.3, 0.5)
    assert added > 0.0 and is_dissipative(repaired, 0.3, 0.5)
    changed = {name for name in feeding if repaired[name] != feeding[name]}
    assert changed == {"y_vvv", "n_rrr"} and repaired["y_vvv"] < feeding["y_vvv"]
    assert make_dissipative(KVLCC2_MMG, 0.3, 0.5) == (KVLCC2_MMG, 0.0)


#: n_vrr per d33 / (v r) at a tenth of the speed in sway and half a degree per second: enough to
#: feed energy into sway and yaw in some direction, not enough to upset the trials.
FEEDING = 3.0


def _plant() -> ShipParameters:
    """The project's KCS with coupled mass, a course-unstable linear part and a cubic polynomial
    whose yaw term feeds energy into combined sway and yaw (n_vrr > 0): it stays steady on
    the trials, but the polynomial alone is not dissipative."""
    kcs = load_parameter_set("default")
    v, r = 0.1 * 9.26, np.radians(0.5)
    return dataclasses.replace(kcs, m23=0.08 * np.sqrt(kcs.m22 * kcs.m33), d33=0.3 * kcs.d33,
                               y_vvv=-2.0 * kcs.d22 / v**2, y_vrr=-kcs.d22 / r**2,
                               n_vvr=-0.5 * kcs.d33 / v**2, n_vrr=FEEDING * kcs.d33 / (v * r),
                               n_rrr=-0.3 * kcs.d33 / r**2)


def _records(true: ShipParameters) -> dict:
    from rhnc.ship.sea_trials import Record

    def sail(name, tau_of_t, duration_s):
        t = np.arange(0.0, duration_s + 0.5, 1.0)
        tau = np.array([tau_of_t(time) for time in t])
        start = np.tile([0.0, 0.0, 0.0, 9.26, 0.0, 0.0], (len(t), 1))
        return Record(name, t, simulate(true, Record(name, t, start, tau)), tau)

    trim = true.equilibrium_tau(9.26)[0]
    return {"speed_steps": sail("speed_steps", lambda t: (trim * (1.3 if t < 600 else 0.6), 0.0), 1200),
            "turn_starboard": sail("turn_starboard", lambda t: (trim, true.tau_r_max if t >= 60 else 0.0), 600),
            "turn_port": sail("turn_port", lambda t: (trim, -true.tau_r_max if t >= 60 else 0.0), 600),
            "zigzag_10": sail("zigzag_10", lambda t: (trim, 0.3 * true.tau_r_max * np.sign(np.sin(t / 90))), 900)}


def _masses(true: ShipParameters, factor: float = 1.0) -> MassBounds:
    return MassBounds.around({name: factor * getattr(true, name) for name in MASSES}, "the known model")


def test_the_fitted_polynomial_is_dissipative_even_when_the_data_say_otherwise():
    """Fitted freely, the trials give back the plant's energy-feeding n_vrr; the fit keeps the
    polynomial's power non-positive in every direction, and such a model is not physical."""
    from rhnc.ship.equation_error import sailed_envelope

    true = _plant()
    records = _records(true)
    assert all(np.all(np.isfinite(record.states)) for record in records.values())
    envelope = sailed_envelope(records)
    assert not is_dissipative(true, *envelope)
    theta, _, r2 = fit_coefficients(records, true.tau_u_max, true.tau_r_max, ALL_COEFFICIENTS, _masses(true))
    fitted = dict(zip(ALL_COEFFICIENTS, (float(value) for value in theta)))
    assert is_dissipative(fitted, *envelope)
    assert r2["yaw"] > 0.99   # still a fit of the data, within the bounds
    assert physical(fitted, records, _masses(true))
    assert not physical({name: getattr(true, name) for name in ALL_COEFFICIENTS}, records, _masses(true))


def test_the_fit_keeps_the_mass_matrix_within_the_particulars_bounds():
    """With bounds about masses 1.6 times the plant's, the fitted masses stay at or above the
    bounds' lower ends (the data alone would give the plant's)."""
    true = dataclasses.replace(_plant(), n_vrr=0.0)
    records = _records(true)
    bounds = _masses(true, 1.6)
    theta, _, _ = fit_coefficients(records, true.tau_u_max, true.tau_r_max, ALL_COEFFICIENTS, bounds)
    fitted = dict(zip(ALL_COEFFICIENTS, (float(value) for value in theta)))
    assert bounds.contains(fitted)
    free, _, _ = fit_coefficients(records, true.tau_u_max, true.tau_r_max, ALL_COEFFICIENTS, None)
    assert free[ALL_COEFFICIENTS.index("m22")] == pytest.approx(true.m22, rel=0.03)
    assert not physical(dict(zip(ALL_COEFFICIENTS, (float(value) for value in free))), records, bounds)


def test_identify_refuses_an_unknown_ship_in_one_line(capsys, tmp_path):
    scenario = "scenarios/own_ship/exp3a_kvlcc2_force.toml"
    assert main(["identify", scenario, "--tau-u-max-N", "2.35e6", "--tau-r-max-Nm", "5.87e8", "--ship", "NoSuchShip",
                 "--results", str(tmp_path)]) == 2
    error = capsys.readouterr().err.strip()
    assert "no particulars for ship 'NoSuchShip'" in error and "KVLCC2" in error and len(error.splitlines()) == 1
    assert not any(tmp_path.iterdir())


def test_the_narrower_classes_keep_their_free_masses():
    """The particulars bound the hull-polynomial class only: a plant of the paper's linear class,
    given bounds about 1.6 times its masses, still gets its own masses from the linear class."""
    from test_identification import NMPC_HORIZON, ModelPlant

    from rhnc.ship.identification import identify_model
    from rhnc.ship.sea_trials import PlantRunner

    true = load_parameter_set("default")
    fit = identify_model(PlantRunner(lambda initial: ModelPlant(true, initial), 9.26), true.tau_u_max,
                         true.tau_r_max, "fitted", refine=False, masses=_masses(true, 1.6),
                         horizon=NMPC_HORIZON)
    assert fit.model_class == "linear"
    for name in ("m11", "m22", "m33"):
        assert getattr(fit.parameters, name) == pytest.approx(getattr(true, name), rel=0.05), name
    assert fit.class_errors["coupled mass, cubic damping"] is not None   # fitted, within its bounds
