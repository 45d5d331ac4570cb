"""Identify the NMPC's 3-DOF prediction model on a plant FMU (``python -m orchestrator identify``).

The plant is the scenario's ship FMU, stepped through its mapping (so in canonical SI
ports whatever its own names and units) with the weather inputs at zero.  Standard
manoeuvres are sailed from straight motion at the service speed:

- ``trim``: a PI speed controller finds the surge force holding the service speed;
- ``speed_steps``: surge force stepped to 130 %, 60 % and back to 100 % of that trim;
- ``turn_starboard``, ``turn_port``: turning circles at full helm either way;
- ``zigzag_10``: a 10/10 zig-zag, helm 10/35 of full switched at +-10 deg;
- ``zigzag_20``: a 20/20 zig-zag, held out to choose the model class and to validate.

These are the trials a captain runs, and they stay in the ship's real range: the helm
is a fraction of the largest yaw moment *at the service speed*, and like a rudder's it
falls with the square of the speed the ship keeps (:func:`helm_moment`), so a turning
circle does not spin a ship that has slowed in it under the moment its rudder gave at
full speed.  A manoeuvre is cut short, not failed, when the plant leaves the range the
model is for (non-finite states, the ship slower than a fifth of the service speed).

The model of :mod:`rhnc.ship.ship_model` is linear in its coefficients once the
accelerations are known::

    m11 udot - (m22 v + m23 r) r + d11 u + d11q |u| u                 = tau_u
    m22 vdot + m23 rdot + m11 u r + d22 v + d23 r + d22q |v| v        = 0
    m23 vdot + m33 rdot - (m11 - m22) u v + m23 u r + d32 v + d33 r
                                                      + d33q |r| r    = tau_r

(each equation less the hull polynomial's terms, ``x_vv v^2``, ..., ``n_rrr r^3``, in the
widest class), so each model class (:data:`MODEL_CLASSES`: the paper's diagonal linear
model; with the sway-yaw mass coupling m23; with it and the quadratic damping; with all of
these and the cubic MMG hull polynomial of full hull forms) is fitted by one bounded linear
least-squares problem over all samples of the fitting manoeuvres (masses and direct
damping positive, quadratic damping not negative, the polynomial free; the rows of each
equation divided by its force scale, the columns by their norms).  The
accelerations and the states in the rows come from a Savitzky-Golay filter (cubic, 21 s
window) over the FMU's 1 s outputs; samples within half a window of an input switch are
left out.  The bounds are the user's (the largest surge force and yaw moment the ship can
give: they cannot be seen in motions that stay inside them).

Validation: each fitted class is integrated open loop with the recorded inputs of the
held-out manoeuvre, from its first sample, and compared with what the plant did; the
class with the smallest held-out error is kept (a wider class only when it is better by
more than 2 % and by more than a tenth of the weighted error's unit), and within a class the refined coefficients or the equation-error ones,
whichever predict the held-out manoeuvre better.  A fit that cannot be made (too few samples, no class that stays finite
on the held-out manoeuvre) is refused with one line saying what to change.

Prediction error: from every 20 s of every manoeuvre the fitted model predicts 300 s ahead
from the measured state, as the NMPC does; the growth of its position error with the
prediction time (:func:`position_error_growth`) goes into the set as
``position_error_growth_mps``, the NMPC's default tightening of its collision domains.
"""

from __future__ import annotations

import dataclasses
import logging
import math
from collections.abc import Callable
from types import SimpleNamespace

import numpy as np

from orchestrator.errors import ScenarioError, ToolchainError
from orchestrator.geometry import KNOT
from rhnc.ship.physical_bounds import (MassBounds, envelope_directions, is_dissipative, make_dissipative,
                                       power_rows)
from rhnc.ship.prediction_error import position_error_growth
from rhnc.ship.ship_model import (HULL_POLYNOMIAL, HULL_POLYNOMIAL_KEYS, STATE_NAMES, ShipParameters,
                                   equations_of_motion, rk4_states, rk4_step)

LOG = logging.getLogger(__name__)
COEFFICIENTS = ("m11", "m22", "m33", "d11", "d22", "d33", "d23", "d32")
#: Every coefficient a class may fit, in the order of the regression's columns.
QUADRATIC = COEFFICIENTS + ("m23", "d11q", "d22q", "d33q")
ALL_COEFFICIENTS = QUADRATIC + HULL_POLYNOMIAL_KEYS
#: Model classes, narrowest first: name -> the coefficients it fits (the others are 0).
MODEL_CLASSES = {
    "linear": COEFFICIENTS,
    "coupled mass": COEFFICIENTS + ("m23",),
    "coupled mass, quadratic damping": QUADRATIC,
    "coupled mass, cubic damping": ALL_COEFFICIENTS,
}
#: With the hull polynomial the linear cross-coupling may change sign in the refinement:
#: a course-unstable linear part that the cubic terms steady, as in full hull forms.
SIGN_FREE_WITH_POLYNOMIAL = ("d23", "d32")
#: Coefficients that must be positive (masses, direct damping) and not negative (quadratic damping).
POSITIVE = ("m11", "m22", "m33", "d11", "d22", "d33")
NOT_NEGATIVE = ("d11q", "d22q", "d33q")
#: A wider class is kept only when its held-out error is smaller by this fraction; the class
#: with the hull polynomial (eleven coefficients more) also by at least this much of the
#: weighted error (a tenth of a degree of heading, of 0.1 m/s, ...): below that, what its
#: polynomial fits is the smoothing filter's bias, not the hull (seen on a plain linear plant).
#: The narrower classes keep the fraction alone: with the margin for them, the KCS (whose
#: quadratic-damping fit predicts the held-out zig-zag to 0.01 deg) fell back to the linear
#: class (0.06 deg) and its coefficients drifted 4 % from the plant's.
WIDER_CLASS_GAIN = 0.02
#: Weight of the polynomial's positive power (per the linear damping's) in the refinement.
POWER_PENALTY = 100.0
WIDER_CLASS_MARGIN = 0.1
#: A manoeuvre stops when the ship is slower than this fraction of the service speed.
SLOWEST_FRACTION = 0.2
WEATHER_PORTS = ("current_north", "current_east", "wind_speed", "wind_direction", "hs")
FIT_MANOEUVRES = ("speed_steps", "turn_starboard", "turn_port", "zigzag_10")
VALIDATION_MANOEUVRE = "zigzag_20"
SAMPLE_S = 1.0
FILTER_WINDOW = 21


@dataclasses.dataclass
class Record:
    """One sailed manoeuvre: times (n,), states (n, 6) and the inputs held after each sample (n, 2)."""

    name: str
    t: np.ndarray
    states: np.ndarray
    tau: np.ndarray


@dataclasses.dataclass
class Fit:
    """The identified coefficients and how well they explain the data."""

    parameters: ShipParameters
    trim_tau_u: float
    residual_rms: dict[str, float]
    r_squared: dict[str, float]
    validation: dict[str, dict[str, float]]
    records: dict[str, Record]
    predictions: dict[str, np.ndarray]
    prediction_error: dict[str, float] = dataclasses.field(default_factory=dict)
    model_class: str = "linear"
    class_errors: dict[str, float | None] = dataclasses.field(default_factory=dict)
    notes: list[str] = dataclasses.field(default_factory=list)


class PlantRunner:
    """Sails manoeuvres on a fresh instance of the plant FMU participant each time.

    Parameters
    ----------
    build : callable
        ``build(initial) -> FmuParticipant`` with ``initial`` the ``[initial]`` table
        (canonical units) the manoeuvre starts from.
    speed_mps : float
        Service speed the manoeuvres start at [m/s].
    """

    def __init__(self, build: Callable, speed_mps: float) -> None:
        self.build = build
        self.speed_mps = speed_mps
        self.notes: list[str] = []

    def sail(self, name: str, duration_s: float, policy: Callable[[float, np.ndarray], tuple[float, float]]) -> Record:
        plant = self.build({"x_m": 0.0, "y_m": 0.0, "psi_rad": 0.0, "u_mps": self.speed_mps})
        weather = {port: 0.0 for port in WEATHER_PORTS if port in plant.input_names}
        times, states, taus = [], [], []
        try:
            outputs = plant.setup(0.0, weather)
            steps = int(round(duration_s / SAMPLE_S))
            for k in range(steps + 1):
                t = k * SAMPLE_S
                state = np.array([outputs[port] for port in STATE_NAMES], dtype=float)
                if not np.all(np.isfinite(state)) or state[3] < SLOWEST_FRACTION * self.speed_mps:
                    self.notes.append(f"{name}: stopped after {t:.0f} s (the ship "
                                      + ("reported non-finite states)" if not np.all(np.isfinite(state)) else
                                         f"slowed to {state[3]:.2f} m/s)"))
                    break
                tau = policy(t, state)
                times.append(t)
                states.append(state)
                taus.append(tau)
                if k < steps:
                    outputs = plant.step(t, SAMPLE_S, {"tau_u": tau[0], "tau_r": tau[1], **weather})
        finally:
            plant.terminate()
        states = np.array(states)
        states[:, 2] = np.unwrap(states[:, 2])
        return Record(name, np.array(times), states, np.array(taus, dtype=float))


def helm_moment(helm: float, u: float, service_speed: float, tau_r_max: float) -> float:
    """Yaw moment [N m] of a helm order as a rudder gives it: ``helm`` (1 = hard over) of the
    largest moment at the service speed, falling with the square of the surge speed ``u``
    [m/s] (a rudder's lift goes with its inflow speed squared), never above the largest."""
    return helm * tau_r_max * min((max(u, 0.0) / service_speed) ** 2, 1.0)


def sail_manoeuvres(runner: PlantRunner, tau_u_max: float, tau_r_max: float) -> tuple[float, dict[str, Record]]:
    """The trim search and the standard manoeuvres; returns the trim surge force [N] and the records."""
    speed = runner.speed_mps
    gain = tau_u_max / 2.0                      # N per m/s: full force for 2 m/s of error
    state = {"integral": 0.5 * tau_u_max}

    def hold_speed(t, x):
        error = speed - x[3]
        state["integral"] = min(max(state["integral"] + gain / 100.0 * error * SAMPLE_S, 0.0), tau_u_max)
        return min(max(state["integral"] + gain * error, -tau_u_max), tau_u_max), 0.0

    trim_record = runner.sail("trim", 1500.0, hold_speed)
    trim = float(np.mean(trim_record.tau[trim_record.t >= 1200.0, 0]))
    if abs(trim_record.states[-1, 3] - speed) > 0.05 * speed:
        raise ToolchainError(f"identify: the plant does not hold {speed / KNOT:.1f} kn with a surge force up to "
                             f"{tau_u_max:g} N (reached {trim_record.states[-1, 3] / KNOT:.1f} kn)")

    def steps(t, x):
        factor = 1.0 if t < 60 else 1.3 if t < 660 else 0.6 if t < 1260 else 1.0
        return min(factor * trim, tau_u_max), 0.0

    def turn(sign):
        return lambda t, x: (trim, 0.0 if t < 60 else sign * helm_moment(1.0, x[3], speed, tau_r_max))

    def zigzag(angle_deg):
        helm = angle_deg / 35.0
        limit = math.radians(angle_deg)
        memory = {"sign": 1.0}

        def policy(t, x):
            if t < 60:
                return trim, 0.0
            if memory["sign"] > 0 and x[2] >= limit:
                memory["sign"] = -1.0
            elif memory["sign"] < 0 and x[2] <= -limit:
                memory["sign"] = 1.0
            return trim, memory["sign"] * helm_moment(helm, x[3], speed, tau_r_max)
        return policy

    records = {
        "speed_steps": runner.sail("speed_steps", 1860.0, steps),
        "turn_starboard": runner.sail("turn_starboard", 660.0, turn(1.0)),
        "turn_port": runner.sail("turn_port", 660.0, turn(-1.0)),
        "zigzag_10": runner.sail("zigzag_10", 900.0, zigzag(10.0)),
        VALIDATION_MANOEUVRE: runner.sail(VALIDATION_MANOEUVRE, 900.0, zigzag(20.0)),
    }
    return trim, records


def _smoothed(record: Record) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Filtered (u, v, r), their time derivatives, and a mask of samples clear of input steps."""
    from scipy.signal import savgol_filter

    body = record.states[:, 3:6]
    values = savgol_filter(body, FILTER_WINDOW, 3, axis=0, mode="interp")
    rates = savgol_filter(body, FILTER_WINDOW, 3, deriv=1, delta=SAMPLE_S, axis=0, mode="interp")
    keep = np.ones(len(record.t), dtype=bool)
    half = FILTER_WINDOW // 2
    keep[:half + 1] = keep[-half - 1:] = False
    # a step of the input (not the slow change of a helm moment with speed): 5 % of its range
    size = np.maximum(np.max(np.abs(record.tau), axis=0), 1e-9)
    switches = np.flatnonzero(np.any(np.abs(np.diff(record.tau, axis=0)) > 0.05 * size, axis=1))
    for index in switches:  # tau[index] acts over (t[index], t[index + 1]]
        keep[max(0, index + 1 - half - 1):index + 1 + half + 1] = False
    return values, rates, keep


def regression_rows(record: Record, scales: tuple[float, float, float]):
    """Rows ``A theta = b`` of the three equations for one record (scaled by ``scales``)."""
    values, rates, keep = _smoothed(record)
    u, v, r = values[keep].T
    du, dv, dr = rates[keep].T
    tau = record.tau[keep]  # the same before and after a kept sample (switches are left out)
    zero = np.zeros_like(u)
    #           m11     m22     m33   d11   d22   d33   d23   d32  m23           d11q      d22q      d33q
    surge = [du, -v * r, zero, u, zero, zero, zero, zero, -r * r, np.abs(u) * u, zero, zero]
    sway = [u * r, dv, zero, zero, v, zero, r, zero, dr, zero, np.abs(v) * v, zero]
    yaw = [-u * v, u * v, dr, zero, zero, r, zero, v, dv + u * r, zero, zero, np.abs(r) * r]
    equations = (surge, sway, yaw)
    for equation, v_power, r_power in HULL_POLYNOMIAL.values():   # right-hand-side forces: minus here
        for index, rows in enumerate(equations):
            rows.append(-v ** v_power * r ** r_power if index == equation else zero)
    surge, sway, yaw = (np.column_stack(rows) for rows in equations)
    a = np.vstack([surge / scales[0], sway / scales[1], yaw / scales[2]])
    b = np.concatenate([tau[:, 0] / scales[0], zero, tau[:, 1] / scales[2]])
    return a, b, len(u)


def fit_coefficients(records: dict[str, Record], tau_u_max: float, tau_r_max: float,
                     names: tuple[str, ...] = COEFFICIENTS,
                     masses: MassBounds | None = None) -> tuple[np.ndarray, dict, dict]:
    """Bounded least-squares coefficients (in the order of ``names``), residual RMS and R² per equation.

    Masses and direct damping are kept positive (at least 1e-6 of the scale of their
    column), quadratic damping not negative; the columns are scaled by their norms, so the
    problem is well conditioned whatever the ship's size.  With ``masses`` the mass matrix
    stays within their bounds; with the hull polynomial among ``names`` its power stays
    dissipative on the sailed envelope's directions (:mod:`rhnc.ship.physical_bounds`: linear
    inequalities, solved as a quadratic programme).
    """
    from scipy.optimize import lsq_linear

    scales = (tau_u_max, tau_u_max, tau_r_max)
    blocks = [regression_rows(records[name], scales) for name in FIT_MANOEUVRES if name in records]
    columns = [ALL_COEFFICIENTS.index(name) for name in names]
    a = np.vstack([block[0] for block in blocks])[:, columns]
    b = np.concatenate([block[1] for block in blocks])
    norms = np.linalg.norm(a, axis=0)
    norms[norms == 0.0] = 1.0
    lower = np.array([1e-6 if n in POSITIVE else 0.0 if n in NOT_NEGATIVE else -np.inf for n in names])
    upper = np.full(len(names), np.inf)
    for name, (low, high) in (masses.bounds.items() if masses is not None else ()):
        if name in names:
            lower[names.index(name)], upper[names.index(name)] = low * norms[names.index(name)], \
                high * norms[names.index(name)]
    solution = lsq_linear(a / norms, b, bounds=(lower, upper), method="bvls").x
    if set(HULL_POLYNOMIAL_KEYS) & set(names):
        solution = _dissipative_solution(a / norms, b, solution, (lower, upper),
                                         power_rows(names, envelope_directions(*sailed_envelope(records))) / norms)
        theta, _ = _made_dissipative(solution / norms, names, records)   # exact, between the grid's directions too
    else:
        theta = solution / norms
    residual = a @ theta - b
    counts = [block[2] for block in blocks]
    # rows are stacked per record as [surge, sway, yaw]; gather each equation's rows
    per_equation = {"surge": [], "sway": [], "yaw": []}
    target = {"surge": [], "sway": [], "yaw": []}
    start = 0
    for n in counts:
        for j, equation in enumerate(per_equation):
            per_equation[equation].append(residual[start + j * n:start + (j + 1) * n])
            target[equation].append(b[start + j * n:start + (j + 1) * n])
        start += 3 * n
    rms, r2 = {}, {}
    for equation, scale in zip(per_equation, ("N", "N", "N m")):
        res = np.concatenate(per_equation[equation])
        factor = scales[list(per_equation).index(equation)]
        rms[f"{equation}_{scale.replace(' ', '')}"] = float(np.sqrt(np.mean(res ** 2)) * factor)
        tgt = np.concatenate(target[equation])
        spread = float(np.sum((tgt - tgt.mean()) ** 2))
        r2[equation] = float(1.0 - np.sum(res ** 2) / spread) if spread > 0 else None
    return theta, rms, r2


def sailed_envelope(records: dict[str, Record]) -> tuple[float, float]:
    """The largest sway speed [m/s] and yaw rate [rad/s] of the fitting manoeuvres (floors:
    1 cm/s, 0.01 deg/s): the amplitudes the hull polynomial's power is judged at."""
    states = np.vstack([records[name].states for name in FIT_MANOEUVRES if name in records])
    return max(float(np.max(np.abs(states[:, 4]))), 0.01), max(float(np.max(np.abs(states[:, 5]))),
                                                              math.radians(0.01))


def _made_dissipative(theta: np.ndarray, names: tuple[str, ...], records: dict[str, Record]) -> tuple[np.ndarray, float]:
    """``theta`` with its polynomial made dissipative on the sailed envelope
    (:func:`rhnc.ship.physical_bounds.make_dissipative`) and the power that took [W]."""
    values, added = make_dissipative(dict(zip(names, (float(value) for value in theta))), *sailed_envelope(records))
    return np.array([values[name] for name in names]), added


def _dissipative_solution(a: np.ndarray, b: np.ndarray, start: np.ndarray, bounds: tuple, power: np.ndarray):
    """``min |a z - b|^2`` within ``bounds`` and with ``power @ z <= 0`` (a quadratic programme,
    scipy's SLSQP on the normal equations), from ``start``; the start itself when it already
    keeps the power's sign."""
    from scipy.optimize import minimize

    rows = power / np.maximum(np.linalg.norm(power, axis=1, keepdims=True), 1e-300)
    if np.all(rows @ start <= 0.0):
        return start
    hessian, gradient = a.T @ a, a.T @ b
    lower, upper = bounds
    feasible = start.copy()
    feasible[np.any(rows != 0.0, axis=0)] = 0.0          # the polynomial zero: dissipative
    feasible = np.clip(feasible, lower, upper)
    result = minimize(lambda z: 0.5 * z @ hessian @ z - gradient @ z, feasible, jac=lambda z: hessian @ z - gradient,
                      method="SLSQP", bounds=list(zip(lower, upper)),
                      constraints=[{"type": "ineq", "fun": lambda z: -rows @ z, "jac": lambda z: -rows}],
                      options={"maxiter": 1000, "ftol": 1e-14})
    return result.x if np.all(np.isfinite(result.x)) else feasible


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
                        masses: MassBounds | None = None) -> tuple[np.ndarray, str]:
    """Coefficients improving ``theta`` (in the order of ``names``) on the simulation error
    of the fitting manoeuvres, and a note on how it went.

    The equation-error fit is biased where the plant's structure differs from the model's
    (a quadratic hull resistance, say), and a prediction model is judged by what it
    predicts over a horizon.  So each fitting manoeuvre is integrated open loop with its
    recorded inputs (RK4, the sampling step in two substeps) and the coefficients are
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
    evaluate, jacobian = _simulation_error(records, names, full, unit)
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


def _simulation_error(records: dict[str, Record], names, full: dict, unit: dict):
    """CasADi functions of the scaled coefficients: the weighted open-loop simulation errors
    over the fitting manoeuvres, and their Jacobian."""
    import casadi as ca

    variables = ca.SX.sym("z", len(names))
    symbolic = dict(full)
    for i, name in enumerate(names):
        symbolic[name] = variables[i] * max(unit[name], 1e-12)
    scaled = SimpleNamespace(**symbolic)
    scaled.sway_yaw_accelerations = lambda fv, fr: ShipParameters.sway_yaw_accelerations(scaled, fv, fr)
    state, tau = ca.SX.sym("X", 4), ca.SX.sym("tau", 2)   # psi, u, v, r

    def f(x):   # the ship's equations (rows psi, u, v, r) with the scaled coefficients
        full_state = ca.vertcat(0.0, 0.0, x)
        return equations_of_motion(full_state, tau, scaled, ca.cos, ca.sin, lambda rows: ca.vertcat(*rows))[2:]

    x = rk4_states(f, state, SAMPLE_S / 2.0, 2)[-1]
    step = ca.Function("step", [state, tau, variables], [x])
    weights = np.array([1.0 / math.radians(1.0), 10.0, 10.0, 1.0 / math.radians(0.06)])
    residuals = []
    for name in FIT_MANOEUVRES:
        if name not in records:
            continue
        record = records[name]
        measured = record.states[:, 2:6]
        n = len(record.t) - 1
        trajectory = step.mapaccum(n)(ca.DM(measured[0]), ca.DM(record.tau[:n].T), ca.repmat(variables, 1, n))
        error = (trajectory - ca.DM(measured[1:].T)) * ca.DM(weights)
        residuals.append(ca.vec(error) / math.sqrt(n))
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


def simulate(parameters: ShipParameters, record: Record) -> np.ndarray:
    """Open-loop states (n, 6) of the model under the record's inputs, from its first sample
    (NaN from the first step where a diverging model leaves the finite numbers)."""
    states = np.full_like(record.states, np.nan)
    states[0] = record.states[0]
    with np.errstate(over="ignore", invalid="ignore"):
        for k in range(len(record.t) - 1):
            states[k + 1] = rk4_step(states[k], record.tau[k], record.t[k + 1] - record.t[k], 4, parameters)
            if not np.all(np.isfinite(states[k + 1])):
                states[k + 1:] = np.nan
                break
    return states


def held_out_cost(record: Record, predicted: np.ndarray) -> float:
    """Weighted RMS open-loop error of a prediction (heading per degree, surge and sway per
    0.1 m/s, yaw rate per 0.06 deg/s: the refinement's weights); inf when it diverged."""
    weights = np.array([1.0 / math.radians(1.0), 10.0, 10.0, 1.0 / math.radians(0.06)])
    error = (predicted[:, 2:6] - record.states[:, 2:6]) * weights
    value = float(np.sqrt(np.mean(error ** 2)))
    return value if math.isfinite(value) else math.inf


def _model_cost(parameters: ShipParameters, records: dict[str, Record]) -> float:
    """The held-out cost of a fitted model (:func:`held_out_cost`); inf when it diverges on the
    held-out manoeuvre or on any fitting one (a polynomial can fit the samples and still
    run away between them)."""
    for name, record in records.items():
        if name != VALIDATION_MANOEUVRE and not np.all(np.isfinite(simulate(parameters, record))):
            return math.inf
    return held_out_cost(records[VALIDATION_MANOEUVRE], simulate(parameters, records[VALIDATION_MANOEUVRE]))


def validation_errors(record: Record, predicted: np.ndarray) -> dict[str, float]:
    """RMS and largest errors of a simulated record: heading [deg], speed [kn], yaw rate [deg/min], position [m]."""
    measured = record.states
    heading = np.degrees(predicted[:, 2] - measured[:, 2])
    speed = (predicted[:, 3] - measured[:, 3]) / KNOT
    rate = np.degrees(predicted[:, 5] - measured[:, 5]) * 60.0
    position = np.hypot(predicted[:, 0] - measured[:, 0], predicted[:, 1] - measured[:, 1])
    return {
        "heading_rms_deg": float(np.sqrt(np.mean(heading ** 2))),
        "heading_max_deg": float(np.max(np.abs(heading))),
        "speed_rms_kn": float(np.sqrt(np.mean(speed ** 2))),
        "yaw_rate_rms_deg_min": float(np.sqrt(np.mean(rate ** 2))),
        "position_end_m": float(position[-1]),
    }


def physical(coefficients: dict, records: dict[str, Record], masses: MassBounds | None = None) -> bool:
    """True for coefficients a prediction model may have: finite, a positive definite mass
    matrix; with the hull polynomial also masses within ``masses``' bounds and a dissipative
    polynomial on the sailed envelope (:mod:`rhnc.ship.physical_bounds`)."""
    if not all(math.isfinite(value) for value in coefficients.values()):
        return False
    if coefficients["m22"] * coefficients["m33"] <= coefficients.get("m23", 0.0) ** 2:
        return False
    if not any(coefficients.get(name, 0.0) != 0.0 for name in HULL_POLYNOMIAL_KEYS):
        return True
    return masses is not None and masses.contains(coefficients) and is_dissipative(coefficients,
                                                                                 *sailed_envelope(records))


def _fit_class(records, tau_u_max, tau_r_max, names, refine, masses=None):
    """One class fitted: (equation-error parameters, final parameters, rms, r2, note); a fit
    that is not :func:`physical` is None."""
    equation_error, rms, r2 = fit_coefficients(records, tau_u_max, tau_r_max, names, masses)
    note = "equation error only"
    theta = equation_error
    if refine:
        theta, note = refine_output_error(records, equation_error, names, masses)

    def parameters(values, label):
        coefficients = {name: 0.0 for name in ALL_COEFFICIENTS}
        coefficients.update(zip(names, (float(v) for v in values)))
        if not physical(coefficients, records, masses):
            return None
        return ShipParameters(**coefficients, tau_u_max=float(tau_u_max), tau_r_max=float(tau_r_max), name=label)

    return parameters(equation_error, "equation error only"), parameters(theta, "fitted"), rms, r2, note


def _refined_from_narrower(records: dict[str, Record], names: tuple[str, ...], candidates: dict,
                           masses: MassBounds | None = None):
    """The class ``names`` refined from the narrower candidate with the smallest held-out cost
    (its coefficients, the others zero; its masses brought within ``masses``' bounds):
    (parameters or None, note)."""
    narrower_name = min(candidates, key=lambda name: candidates[name][0])
    narrower = candidates[narrower_name][2]
    if not math.isfinite(candidates[narrower_name][0]):
        return None, "no finite narrower class to start from"
    start = {name: getattr(narrower, name) for name in names}
    for name, (low, high) in (masses.bounds.items() if masses is not None else ()):
        start[name] = min(max(start[name], low), high)
    theta, note = refine_output_error(records, np.array([start[name] for name in names]), names, masses)
    parameters = dataclasses.replace(narrower, **dict(zip(names, (float(v) for v in theta))))
    if not physical({name: getattr(parameters, name) for name in ALL_COEFFICIENTS}, records, masses):
        return None, "not physical"
    return parameters, f"from the {narrower_name} model, {note}"


def _fit_candidates(records: dict[str, Record], tau_u_max: float, tau_r_max: float, classes: tuple[str, ...],
                    refine: bool, masses: MassBounds | None = None) -> dict:
    """Every class fitted and scored on the held-out manoeuvre: name -> (held-out cost,
    equation-error parameters, chosen parameters, residual RMS, R², note); a class without a
    physical fit is left out, and so is the hull polynomial's without ``masses``."""
    candidates = {}
    for class_name in classes:
        names = MODEL_CLASSES[class_name]
        polynomial = bool(set(HULL_POLYNOMIAL_KEYS) & set(names))
        if masses is None and polynomial:
            LOG.info("model class %s: not fitted without the ship's particulars (the mass matrix's bounds)",
                     class_name)
            continue
        # the narrower classes keep their free masses: without the polynomial's structure an
        # effective mass is part of what they fit (bounded, the KVLCC2's held-out errors grew)
        equation_error, fitted, rms, r2, note = _fit_class(records, tau_u_max, tau_r_max, names, refine,
                                                           masses if polynomial else None)
        cost = _model_cost(fitted, records) if fitted is not None else math.inf
        if refine and fitted is not None and equation_error is not None:
            # the refinement fits the fitting manoeuvres; where the class lacks the plant's
            # structure that can cost on others, and the held-out manoeuvre decides
            plain = _model_cost(equation_error, records)
            if plain < cost:
                cost, fitted, note = plain, equation_error, f"equation error kept: held-out {plain:.4g} against " \
                                                            f"{cost:.4g} refined ({note})"
        if refine and set(HULL_POLYNOMIAL_KEYS) & set(names) and candidates:
            # the polynomial's equation-error fit extrapolates and may run away: refine also from
            # the best narrower class's model, its polynomial zero, so the class starts where
            # the narrower one ended and can only improve on it
            nested, nested_note = _refined_from_narrower(records, names, candidates, masses)
            nested_cost = _model_cost(nested, records) if nested is not None else math.inf
            if nested_cost < cost:
                cost, fitted, note = nested_cost, nested, nested_note
        if fitted is None:
            LOG.info("model class %s: no physical fit", class_name)
            continue
        LOG.info("model class %s: held-out cost %.4g (%s)", class_name, cost, note)
        candidates[class_name] = (cost, equation_error, fitted, rms, r2, note)
    return candidates


def identify_model(runner: PlantRunner, tau_u_max: float, tau_r_max: float, set_name: str,
                   reference: ShipParameters | None = None, refine: bool = True,
                   classes: tuple[str, ...] = tuple(MODEL_CLASSES), masses: MassBounds | None = None) -> Fit:
    """Sail the manoeuvres, fit every model class, keep the one best on the held-out manoeuvre.

    ``masses`` (the mass matrix the ship's particulars give, :mod:`rhnc.ship.physical_bounds`)
    bound the class with the hull polynomial; without them that class is not fitted.

    ``reference`` (a model to compare with, e.g. the one the NMPC used before) is
    validated the same way under ``validation["held_out with <name>"]``.

    Raises
    ------
    ToolchainError
        The plant cannot hold the service speed, the manoeuvres leave too few samples,
        or no model class stays finite on the held-out manoeuvre (one line saying what to
        change).
    """
    trim, records = sail_manoeuvres(runner, tau_u_max, tau_r_max)
    short = [name for name, record in records.items() if len(record.t) < 3 * FILTER_WINDOW]
    if VALIDATION_MANOEUVRE in short or len(short) > 1:
        raise ToolchainError(f"identify: the manoeuvres {', '.join(short)} ended after less than "
                             f"{3 * FILTER_WINDOW} s ({'; '.join(runner.notes) or 'the plant stopped'}): give a "
                             "smaller --tau-r-max-Nm (the yaw moment at full rudder and service speed) or a lower "
                             "--speed-kn")
    records = {name: record for name, record in records.items() if name not in short}
    held_out = records[VALIDATION_MANOEUVRE]
    candidates = _fit_candidates(records, tau_u_max, tau_r_max, classes, refine, masses)
    class_errors = {name: (candidates[name][0] if name in candidates else None) for name in classes}
    finite = [name for name in candidates if math.isfinite(candidates[name][0])]
    if not finite:
        raise ToolchainError("identify: no model class predicts the held-out zig-zag without diverging (classes "
                             f"tried: {', '.join(classes)}): the manoeuvres may leave the ship's real range; give the "
                             "yaw moment of full rudder at service speed as --tau-r-max-Nm and check the probe's figures")
    chosen = finite[0]
    for name in finite[1:]:   # narrowest first: a wider class must earn its coefficients
        best = candidates[chosen][0]
        margin = WIDER_CLASS_MARGIN if set(MODEL_CLASSES[name]) & set(HULL_POLYNOMIAL_KEYS) else 0.0
        if candidates[name][0] < min((1.0 - WIDER_CLASS_GAIN) * best, best - margin):
            chosen = name
    _, equation_error, parameters, rms, r2, note = candidates[chosen]
    parameters = dataclasses.replace(parameters, name=set_name)
    predictions, validation = {}, {}
    for name, record in records.items():
        predictions[name] = simulate(parameters, record)
        key = "held_out: " + name if name == VALIDATION_MANOEUVRE else name
        validation[key] = validation_errors(record, predictions[name])
    if refine and equation_error is not None:
        validation["held_out with the equation-error fit alone"] = validation_errors(
            held_out, simulate(equation_error, held_out))
    if reference is not None:
        predicted = simulate(reference, held_out)
        validation[f"held_out with {reference.name}"] = validation_errors(held_out, predicted)
    error = position_error_growth(parameters, records)
    parameters = dataclasses.replace(parameters, extras={"position_error_growth_mps": error["growth_mps"],
                                                         "model_class": chosen})
    notes = list(runner.notes) + [f"{chosen}: {note}"]
    if masses is None and any(set(MODEL_CLASSES[name]) & set(HULL_POLYNOMIAL_KEYS) for name in classes):
        notes.append("the class with the hull polynomial was not fitted: it needs the ship's particulars "
                     "(identify --ship) to bound the mass matrix")
    elif masses is not None:
        notes.append(f"mass matrix of the hull-polynomial class bounded from {masses.source}")
    return Fit(parameters, trim, rms, r2, validation, records, predictions, error, chosen, class_errors, notes)


def check_bounds(tau_u_max: float | None, tau_r_max: float | None) -> tuple[float, float]:
    """The bounds given on the command line, checked."""
    for name, value in (("--tau-u-max-N", tau_u_max), ("--tau-r-max-Nm", tau_r_max)):
        if value is None:
            raise ScenarioError(f"identify: give {name}, the largest force the ship can give (from its data sheet)")
        if not (math.isfinite(value) and value > 0):
            raise ScenarioError(f"identify: {name} must be a positive number, got {value}")
    return float(tau_u_max), float(tau_r_max)
