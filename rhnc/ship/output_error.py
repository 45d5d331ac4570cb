"""The output-error refinement of the identification: coefficients moved to what the model predicts over the manoeuvres."""

from __future__ import annotations

import logging
import math
from typing import cast
from types import SimpleNamespace

import numpy as np

from rhnc.ship.equation_error import (ALL_COEFFICIENTS, COEFFICIENTS, NOT_NEGATIVE, _made_dissipative,
                                      sailed_envelope)
from rhnc.ship.physical_bounds import MassBounds, envelope_directions, power_rows
from rhnc.ship.prediction_error import STATE_ERROR_WEIGHTS
from rhnc.ship.sea_trials import FIT_MANOEUVRES, SAMPLE_S, Record
from rhnc.ship.ship_model import (HULL_POLYNOMIAL, HULL_POLYNOMIAL_KEYS, ShipParameters, equations_of_motion,
                                   rk4_states)

LOG = logging.getLogger(__name__)
#: With the hull polynomial the linear cross-coupling may change sign in the refinement:
#: a course-unstable linear part that the cubic terms steady, as in full hull forms.
SIGN_FREE_WITH_POLYNOMIAL = ("d23", "d32")
#: Weight of the polynomial's positive power (per the linear damping's) in the refinement.
POWER_PENALTY = 100.0


def _coefficient_scales(theta: dict[str, float], speed_mps: float) -> dict[str, float]:
    """Typical magnitude of every coefficient, from the linear ones: the unit of the
    refinement's variables (so all are of order one) and the floor of a zero start."""
    u = max(speed_mps, 0.1)
    sway, rate = 0.1 * u, math.radians(0.5)           # a sway of a tenth of it, half a degree per second
    units = {
        **{name: abs(theta[name]) for name in COEFFICIENTS},
        "m23": 0.05 * math.sqrt(theta["m22"] * theta["m33"]),
        "d11q": theta["d11"] / u,                     # as much drag at service speed as d11
        "d22q": theta["d22"] / sway,
        "d33q": theta["d33"] / rate,
    }
    # a polynomial term as large as the linear damping of its equation at that sway and rate
    force = (theta["d11"] * u, theta["d22"] * sway, theta["d33"] * rate)
    for name, (equation, v_power, r_power) in HULL_POLYNOMIAL.items():
        units[name] = force[equation] / (sway ** v_power * rate ** r_power)
    return units


def refine_output_error(records: dict[str, Record], theta: np.ndarray,
                        names: tuple[str, ...] = COEFFICIENTS,
                        masses: MassBounds | None = None, damping_speed: float = 0.0,
                        horizon_s: float | None = None) -> tuple[np.ndarray, str]:
    """Coefficients improving ``theta`` (in the order of ``names``) on the simulation error
    of the fitting manoeuvres, and a note on how it went.

    The equation-error fit is biased where the plant's structure differs from the model's
    (a quadratic hull resistance, say), and a prediction model is judged by what it
    predicts over a horizon.  So each fitting manoeuvre is integrated open loop with its
    recorded inputs (RK4, the sampling step in two substeps), in segments of ``horizon_s``
    each started again from the measured state (multiple shooting: the NMPC predicts over
    its horizon from each measured state, never longer; None: the whole manoeuvre in one
    run), and the coefficients are
    moved, within bounds, to minimise the errors of heading (per degree), surge and sway
    speed (per 0.1 m/s) and yaw rate (per 0.06 deg/s), with exact CasADi Jacobians
    (scipy's trust-region least squares).  The variables are the coefficients divided by
    their typical magnitudes; masses, direct and cross damping stay within a factor 5 of
    the start (sign kept), quadratic damping in [0, 5 x its typical value], m23 within half
    the geometric mean of m22 and m33.  A model that diverges on a manoeuvre counts as a
    large error there instead of stopping the fit; if the optimiser still fails the start
    is kept.  With ``masses`` the mass matrix stays within their bounds instead.  With the
    hull polynomial its power on the sailed envelope's directions is penalised where
    positive, and what is left of that afterwards is taken out by the pure cubic damping
    (:func:`rhnc.ship.physical_bounds.make_dissipative`), so the result is dissipative.
    With ``damping_speed`` [m/s] the model's linear sway-yaw damping scales with the speed
    (``damping_speed_mps`` of :class:`rhnc.ship.ship_model.ShipParameters`).
    """
    from scipy.optimize import least_squares

    start = dict(zip(names, (float(v) for v in theta)))
    full = {name: start.get(name, 0.0) for name in ALL_COEFFICIENTS}
    speed = float(np.median(np.concatenate([records[n].states[:, 3] for n in FIT_MANOEUVRES if n in records])))
    unit = _coefficient_scales(full, speed)
    sign_free = SIGN_FREE_WITH_POLYNOMIAL if set(HULL_POLYNOMIAL_KEYS) & set(names) else ()
    for name in sign_free:   # a cross-coupling near zero may still change sign: a floor for its unit
        unit[name] = max(unit[name], 0.1 * math.sqrt(full["d22"] * full["d33"]))
    z0, lower, upper = _scaled_start_and_bounds(names, start, full, unit, sign_free, masses)
    z0 = np.clip(np.array(z0), lower, upper)
    if np.any(np.array(lower) >= np.array(upper)):
        return np.asarray(theta, dtype=float), "not refined: a coefficient is zero"
    evaluate, jacobian = _simulation_error(records, names, full, unit, damping_speed, horizon_s)
    large = 1e4   # a diverged simulation: a large error, not a NaN that stops the optimiser

    def residual(z):
        return np.nan_to_num(np.asarray(evaluate(z)).ravel(), nan=large, posinf=large, neginf=-large)

    def jac(z):
        return np.nan_to_num(np.asarray(jacobian(z)), nan=0.0, posinf=0.0, neginf=0.0)

    try:
        result = least_squares(residual, z0, jac=jac, bounds=(lower, upper), x_scale=1.0, max_nfev=100)
    except (ValueError, np.linalg.LinAlgError, RuntimeError) as exc:
        return np.asarray(theta, dtype=float), f"not refined ({exc})"
    before = 0.5 * float(np.sum(residual(z0) ** 2))
    if not (np.isfinite(result.cost) and result.cost <= before):
        return np.asarray(theta, dtype=float), "not refined: the optimiser found nothing better"
    LOG.info("output-error refinement: %s after %d evaluations, cost %.4g -> %.4g", result.message,
             result.nfev, before, result.cost)
    refined = result.x * np.array([max(unit[name], 1e-12) for name in names])
    note = f"refined: cost {before:.4g} -> {result.cost:.4g} in {result.nfev} evaluations"
    if sign_free:
        refined, added = _made_dissipative(refined, names, records)
        if added > 0.0:
            note += f"; cubic damping strengthened by {added:.3g} W at the sailed amplitudes to stay dissipative"
    return refined, note


def _scaled_start_and_bounds(names, start: dict, full: dict, unit: dict, sign_free: tuple[str, ...] = (),
                             masses: MassBounds | None = None) -> tuple[list, list, list]:
    """The start and bounds of the coefficients divided by their typical magnitudes ``unit``
    (see :func:`refine_output_error`); the hull polynomial and the names in ``sign_free``
    within +-5 times the larger of their start and their unit, either sign; the masses
    within ``masses``' bounds when given."""
    z0, lower, upper = [], [], []
    for name in names:
        scale = max(unit[name], 1e-12)
        value = start[name] / scale
        z0.append(value)
        if masses is not None and name in masses.bounds:
            lower.append(masses.bounds[name][0] / scale)
            upper.append(masses.bounds[name][1] / scale)
        elif name in HULL_POLYNOMIAL or name in sign_free:
            bound = 5.0 * max(abs(value), 1.0)
            lower.append(-bound)
            upper.append(bound)
        elif name in NOT_NEGATIVE:
            lower.append(0.0)
            upper.append(5.0 * max(start[name], unit[name]) / scale)
        elif name == "m23":
            bound = 0.5 * math.sqrt(full["m22"] * full["m33"]) / scale
            lower.append(-bound)
            upper.append(bound)
        elif value >= 0.0:
            lower.append(0.2 * value)
            upper.append(5.0 * value)
        else:
            lower.append(5.0 * value)
            upper.append(0.2 * value)
    return z0, lower, upper


def _simulation_error(records: dict[str, Record], names, full: dict, unit: dict, damping_speed: float = 0.0,
                      horizon_s: float | None = None):
    """CasADi functions of the scaled coefficients: the weighted open-loop simulation errors
    over the fitting manoeuvres, in segments of ``horizon_s`` from the measured states (None:
    one segment per manoeuvre), and their Jacobian."""
    import casadi as ca

    variables = ca.SX.sym("z", len(names))
    symbolic = dict(full)
    for i, name in enumerate(names):
        symbolic[name] = variables[i] * max(unit[name], 1e-12)
    symbolic["damping_speed_mps"] = damping_speed
    scaled = SimpleNamespace(**symbolic)
    scaled.sway_yaw_accelerations = lambda fv, fr: ShipParameters.sway_yaw_accelerations(
        cast(ShipParameters, scaled), fv, fr)   # the same formula on the symbolic coefficients
    state, tau = ca.SX.sym("X", 4), ca.SX.sym("tau", 2)   # psi, u, v, r

    def f(x):   # the ship's equations (rows psi, u, v, r) with the scaled coefficients
        full_state = ca.vertcat(0.0, 0.0, x)
        return equations_of_motion(full_state, tau, scaled, ca.cos, ca.sin, lambda rows: ca.vertcat(*rows))[2:]

    x = rk4_states(f, state, SAMPLE_S / 2.0, 2)[-1]
    step = ca.Function("step", [state, tau, variables], [x])
    weights = STATE_ERROR_WEIGHTS
    residuals = []
    for name in FIT_MANOEUVRES:
        if name not in records:
            continue
        record = records[name]
        measured = record.states[:, 2:6]
        n = len(record.t) - 1
        length = n if horizon_s is None else max(1, min(n, int(round(horizon_s / SAMPLE_S))))
        errors = []
        for start in range(0, n, length):   # each segment from the measured state at its start
            m = min(length, n - start)
            trajectory = step.mapaccum(m)(ca.DM(measured[start]), ca.DM(record.tau[start:start + m].T),
                                          ca.repmat(variables, 1, m))
            errors.append(ca.vec((trajectory - ca.DM(measured[start + 1:start + m + 1].T)) * ca.DM(weights)))
        residuals.append(ca.vertcat(*errors) / math.sqrt(n))
    if set(HULL_POLYNOMIAL_KEYS) & set(names):
        # the polynomial's power where positive on the envelope's directions, per the linear
        # damping's power there: a penalty that keeps the refinement near the dissipative set
        sway, rate = sailed_envelope(records)
        rows = power_rows(tuple(names), envelope_directions(sway, rate))
        power = ca.mtimes(ca.DM(rows), ca.vertcat(*[symbolic[name] for name in names]))
        reference = abs(full["d22"]) * sway ** 2 + abs(full["d33"]) * rate ** 2
        residuals.append(POWER_PENALTY * ca.fmax(power, 0.0) / max(reference, 1e-12))
    stacked = ca.vertcat(*residuals)
    evaluate = ca.Function("residual", [variables], [stacked])
    jacobian = ca.Function("jacobian", [variables], [ca.jacobian(stacked, variables)])
    return evaluate, jacobian


