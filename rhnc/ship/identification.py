"""Identify the NMPC's 3-DOF prediction model on a plant FMU (``python -m orchestrator identify``).

The plant is the scenario's ship FMU, stepped through its mapping (so in canonical SI
ports whatever its own names and units) with the weather inputs at zero.  Standard
manoeuvres are sailed from straight motion at the service speed:

- ``trim``: a PI speed controller finds the surge force holding the service speed;
- ``speed_steps``: surge force stepped to 130 %, 60 % and back to 100 % of that trim;
- ``turn_starboard``, ``turn_port``: full yaw moment either way;
- ``zigzag_10``: a 10/10 zig-zag, yaw moment 10/35 of the bound switched at +-10 deg;
- ``zigzag_20``: a 20/20 zig-zag, held out for validation.

The model of :mod:`rhnc.ship.ship_model` is linear in its eight coefficients once the
accelerations are known::

    m11 udot - m22 v r + d11 u                    = tau_u
    m22 vdot + m11 u r + d22 v + d23 r            = 0
    m33 rdot - (m11 - m22) u v + d32 v + d33 r    = tau_r

so they are fitted by one linear least-squares problem over all samples of the fitting
manoeuvres, the rows of each equation divided by its force scale (the bounds).  The
accelerations and the states in the rows come from a Savitzky-Golay filter (cubic, 21 s
window) over the FMU's 1 s outputs; samples within half a window of an input switch are
left out.  The bounds are the user's (the largest surge force and yaw moment the ship can
give: they cannot be seen in motions that stay inside them).

Validation: the fitted model is integrated open loop with the recorded inputs of the
held-out manoeuvre, from its first sample, and compared with what the plant did.

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
from rhnc.ship.prediction_error import position_error_growth
from rhnc.ship.ship_model import STATE_NAMES, ShipParameters, equations_of_motion, rk4_step

LOG = logging.getLogger(__name__)
COEFFICIENTS = ("m11", "m22", "m33", "d11", "d22", "d33", "d23", "d32")
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
        return lambda t, x: (trim, 0.0 if t < 60 else sign * tau_r_max)

    def zigzag(angle_deg):
        moment = angle_deg / 35.0 * tau_r_max
        limit = math.radians(angle_deg)
        memory = {"sign": 1.0}

        def policy(t, x):
            if t < 60:
                return trim, 0.0
            if memory["sign"] > 0 and x[2] >= limit:
                memory["sign"] = -1.0
            elif memory["sign"] < 0 and x[2] <= -limit:
                memory["sign"] = 1.0
            return trim, memory["sign"] * moment
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
    """Filtered (u, v, r), their time derivatives, and a mask of samples clear of input switches."""
    from scipy.signal import savgol_filter

    body = record.states[:, 3:6]
    values = savgol_filter(body, FILTER_WINDOW, 3, axis=0, mode="interp")
    rates = savgol_filter(body, FILTER_WINDOW, 3, deriv=1, delta=SAMPLE_S, axis=0, mode="interp")
    keep = np.ones(len(record.t), dtype=bool)
    half = FILTER_WINDOW // 2
    keep[:half + 1] = keep[-half - 1:] = False
    switches = np.flatnonzero(np.any(np.diff(record.tau, axis=0) != 0.0, axis=1))
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
    #           m11     m22     m33   d11   d22   d33   d23   d32
    surge = np.column_stack([du, -v * r, zero, u, zero, zero, zero, zero])
    sway = np.column_stack([u * r, dv, zero, zero, v, zero, r, zero])
    yaw = np.column_stack([-u * v, u * v, dr, zero, zero, r, zero, v])
    a = np.vstack([surge / scales[0], sway / scales[1], yaw / scales[2]])
    b = np.concatenate([tau[:, 0] / scales[0], zero, tau[:, 1] / scales[2]])
    return a, b, len(u)


def fit_coefficients(records: dict[str, Record], tau_u_max: float, tau_r_max: float) -> tuple[np.ndarray, dict, dict]:
    """Least-squares coefficients (in :data:`COEFFICIENTS` order), residual RMS and R² per equation."""
    scales = (tau_u_max, tau_u_max, tau_r_max)
    blocks = [regression_rows(records[name], scales) for name in FIT_MANOEUVRES]
    a = np.vstack([block[0] for block in blocks])
    b = np.concatenate([block[1] for block in blocks])
    norms = np.linalg.norm(a, axis=0)
    norms[norms == 0.0] = 1.0
    solution, *_ = np.linalg.lstsq(a / norms, b, rcond=None)
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


def refine_output_error(records: dict[str, Record], theta: np.ndarray) -> np.ndarray:
    """Coefficients improving ``theta`` on the simulation error of the fitting manoeuvres.

    The equation-error fit is biased where the plant's structure differs from the model's
    (a quadratic hull resistance, say), and a prediction model is judged by what it
    predicts over a horizon.  So each fitting manoeuvre is integrated open loop with its
    recorded inputs (RK4, the sampling step in two substeps) and the coefficients are scaled
    by factors in [0.2, 5] that minimise the errors of heading (per degree), surge and
    sway speed (per 0.1 m/s) and yaw rate (per 0.06 deg/s), with exact CasADi Jacobians
    (scipy's trust-region least squares).
    """
    import casadi as ca
    from scipy.optimize import least_squares

    factors = ca.SX.sym("k", len(COEFFICIENTS))
    scaled = SimpleNamespace(**{name: factors[i] * float(theta[i]) for i, name in enumerate(COEFFICIENTS)})
    state, tau = ca.SX.sym("X", 4), ca.SX.sym("tau", 2)   # psi, u, v, r

    def f(x):   # the ship's equations (rows psi, u, v, r) with the scaled coefficients
        full = ca.vertcat(0.0, 0.0, x)
        return equations_of_motion(full, tau, scaled, ca.cos, ca.sin, lambda rows: ca.vertcat(*rows))[2:]

    h = SAMPLE_S / 2.0
    x = state
    for _ in range(2):
        k1 = f(x)
        k2 = f(x + 0.5 * h * k1)
        k3 = f(x + 0.5 * h * k2)
        k4 = f(x + h * k3)
        x = x + h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
    step = ca.Function("step", [state, tau, factors], [x])
    weights = np.array([1.0 / math.radians(1.0), 10.0, 10.0, 1.0 / math.radians(0.06)])
    residuals = []
    for name in FIT_MANOEUVRES:
        record = records[name]
        measured = record.states[:, 2:6]
        n = len(record.t) - 1
        trajectory = step.mapaccum(n)(ca.DM(measured[0]), ca.DM(record.tau[:n].T), ca.repmat(factors, 1, n))
        error = (trajectory - ca.DM(measured[1:].T)) * ca.DM(weights)
        residuals.append(ca.vec(error) / math.sqrt(n))
    stacked = ca.vertcat(*residuals)
    evaluate = ca.Function("residual", [factors], [stacked])
    jacobian = ca.Function("jacobian", [factors], [ca.jacobian(stacked, factors)])
    result = least_squares(lambda k: np.asarray(evaluate(k)).ravel(), np.ones(len(COEFFICIENTS)),
                           jac=lambda k: np.asarray(jacobian(k)), bounds=(0.2, 5.0), x_scale=1.0,
                           max_nfev=100)
    LOG.info("output-error refinement: %s after %d evaluations, cost %.4g -> %.4g", result.message,
             result.nfev, 0.5 * float(np.sum(np.asarray(evaluate(np.ones(len(COEFFICIENTS)))) ** 2)), result.cost)
    return theta * result.x


def simulate(parameters: ShipParameters, record: Record) -> np.ndarray:
    """Open-loop states (n, 6) of the model under the record's inputs, from its first sample."""
    states = np.empty_like(record.states)
    states[0] = record.states[0]
    for k in range(len(record.t) - 1):
        states[k + 1] = rk4_step(states[k], record.tau[k], record.t[k + 1] - record.t[k], 4, parameters)
    return states


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


def identify_model(runner: PlantRunner, tau_u_max: float, tau_r_max: float, set_name: str,
                   reference: ShipParameters | None = None, refine: bool = True) -> Fit:
    """Sail the manoeuvres, fit the coefficients, validate on the held-out manoeuvre.

    ``reference`` (a model to compare with, e.g. the one the NMPC used before) is
    validated the same way under ``validation["reference: <name>"]``.

    Raises
    ------
    ToolchainError
        The plant cannot hold the service speed, or the fit gives a non-physical
        coefficient (a mass or a direct damping that is not positive).
    """
    trim, records = sail_manoeuvres(runner, tau_u_max, tau_r_max)
    equation_error, rms, r2 = fit_coefficients(records, tau_u_max, tau_r_max)
    theta = refine_output_error(records, equation_error) if refine else equation_error
    values = dict(zip(COEFFICIENTS, (float(v) for v in theta)))
    bad = [k for k in ("m11", "m22", "m33", "d11", "d22", "d33") if not values[k] > 0.0]
    if bad:
        raise ToolchainError(f"identify: the fit gives non-positive {', '.join(bad)} "
                             f"({', '.join(f'{k} = {values[k]:.4g}' for k in bad)}): the manoeuvres do not "
                             "excite the plant enough, or its dynamics are far from the 3-DOF model")
    parameters = ShipParameters(**values, tau_u_max=float(tau_u_max), tau_r_max=float(tau_r_max), name=set_name)
    predictions, validation = {}, {}
    for name, record in records.items():
        predictions[name] = simulate(parameters, record)
        key = "held_out: " + name if name == VALIDATION_MANOEUVRE else name
        validation[key] = validation_errors(record, predictions[name])
    if refine:
        ls = ShipParameters(**dict(zip(COEFFICIENTS, (float(v) for v in equation_error))), tau_u_max=float(tau_u_max),
                            tau_r_max=float(tau_r_max), name="equation error only")
        validation["held_out with the equation-error fit alone"] = validation_errors(
            records[VALIDATION_MANOEUVRE], simulate(ls, records[VALIDATION_MANOEUVRE]))
    if reference is not None:
        predicted = simulate(reference, records[VALIDATION_MANOEUVRE])
        validation[f"held_out with {reference.name}"] = validation_errors(records[VALIDATION_MANOEUVRE], predicted)
    error = position_error_growth(parameters, records)
    parameters = dataclasses.replace(parameters, extras={"position_error_growth_mps": error["growth_mps"]})
    return Fit(parameters, trim, rms, r2, validation, records, predictions, error)


def check_bounds(tau_u_max: float | None, tau_r_max: float | None) -> tuple[float, float]:
    """The bounds given on the command line, checked."""
    for name, value in (("--tau-u-max-N", tau_u_max), ("--tau-r-max-Nm", tau_r_max)):
        if value is None:
            raise ScenarioError(f"identify: give {name}, the largest force the ship can give (from its data sheet)")
        if not (math.isfinite(value) and value > 0):
            raise ScenarioError(f"identify: {name} must be a positive number, got {value}")
    return float(tau_u_max), float(tau_r_max)
