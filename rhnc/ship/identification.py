"""Identify the NMPC's 3-DOF prediction model on a plant FMU (``python -m orchestrator identify``).

The plant sails the standard manoeuvres (:mod:`rhnc.ship.sea_trials`); each model class
(:data:`MODEL_CLASSES`: the paper's diagonal linear model; with the sway-yaw mass coupling
m23; with it and the quadratic damping; the same with its linear sway-yaw damping
proportional to the speed, :data:`SPEED_SCALED`; with all of these and the cubic MMG hull
polynomial of full hull forms) is fitted by least squares on the equations of motion
(:mod:`rhnc.ship.equation_error`) and refined on the simulation error
(:mod:`rhnc.ship.output_error`).

Validation: each fitted class predicts the held-out manoeuvre over the NMPC's horizon
(its ``horizon_steps`` times its control interval, from the settings the model is for)
from every control interval's measured state, with the recorded inputs, as the NMPC uses
it (:func:`rhnc.ship.prediction_error.horizon_cost`), and is compared with what the plant
did; the class with the smallest held-out error is kept (a wider class only when it is better by
more than 2 % and by more than a tenth of the weighted error's unit), and within a class the refined coefficients or the equation-error ones,
whichever predict the held-out manoeuvre better.  A fit that cannot be made (too few samples, no class that stays finite
on the held-out manoeuvre) is refused with one line saying what to change.

The class is not chosen by one open-loop run over the whole manoeuvre: a model whose
zig-zag drifts slowly out of phase scores worse there than one that barely turns, which
predicts worse over every horizon the NMPC plans.  The refinement fits the same kind of
error: segments of the horizon's length, each from the measured state.

Prediction error: from every control interval of every manoeuvre the fitted model predicts
over the horizon from the measured state, as the NMPC does; the growth of its position error with the
prediction time (:func:`position_error_growth`) goes into the set as
``position_error_growth_mps``, the NMPC's default tightening of its collision domains.
"""

from __future__ import annotations

import dataclasses
import logging
import math

import numpy as np

from orchestrator.errors import ScenarioError, ToolchainError
from orchestrator.geometry import KNOT
from rhnc.ship.equation_error import (ALL_COEFFICIENTS, COEFFICIENTS, FILTER_WINDOW, QUADRATIC, fit_coefficients,
                                      sailed_envelope)
from rhnc.ship.output_error import refine_output_error
from rhnc.ship.physical_bounds import MassBounds, is_dissipative
from rhnc.ship.prediction_error import (STATE_ERROR_WEIGHTS, horizon_cost, position_error_growth, window_starts,
                                       windowed_predictions)
from rhnc.ship.sea_trials import VALIDATION_MANOEUVRE, PlantRunner, Record, sail_manoeuvres
from rhnc.ship.ship_model import HULL_POLYNOMIAL_KEYS, ShipParameters, rk4_step

LOG = logging.getLogger(__name__)
#: Model classes, narrowest first: name -> the coefficients it fits (the others are 0).
MODEL_CLASSES = {
    "linear": COEFFICIENTS,
    "coupled mass": COEFFICIENTS + ("m23",),
    "coupled mass, quadratic damping": QUADRATIC,
    "coupled mass, quadratic damping, speed-scaled": QUADRATIC,
    "coupled mass, cubic damping": ALL_COEFFICIENTS,
}
#: Classes whose linear sway-yaw damping is proportional to the surge speed, equal to the
#: fitted values at the service speed (``damping_speed_mps``): a hull's linear forces go
#: with U^2 times derivatives in v/U and rL/U, so a ship that slows in a turn (a full hull
#: form loses a third of its speed) turns faster under the same moment than one set of
#: constant coefficients predicts.
SPEED_SCALED = ("coupled mass, quadratic damping, speed-scaled",)
#: A wider class is kept only when its held-out error is smaller by this fraction; the class
#: with the hull polynomial (eleven coefficients more) also by at least this much of the
#: weighted error (a tenth of a degree of heading, of 0.1 m/s, ...): below that, what its
#: polynomial fits is the smoothing filter's bias, not the hull (seen on a plain linear plant).
#: The narrower classes keep the fraction alone: with the margin for them, the KCS (whose
#: quadratic-damping fit predicts the held-out zig-zag to 0.01 deg) fell back to the linear
#: class (0.06 deg) and its coefficients drifted 4 % from the plant's.
WIDER_CLASS_GAIN = 0.02
WIDER_CLASS_MARGIN = 0.1


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
    #: the held-out weighted error of one open-loop run over the whole manoeuvre, per class (reported only)
    class_open_loop_errors: dict[str, float] = dataclasses.field(default_factory=dict)
    horizon: Horizon | None = None


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


@dataclasses.dataclass(frozen=True)
class Horizon:
    """The prediction the model is for: the NMPC's horizon [s] (``horizon_steps`` times the
    control interval) and how often it predicts again from a measured state [s] (the control
    interval)."""

    horizon_s: float
    interval_s: float

    def __post_init__(self) -> None:
        if not (math.isfinite(self.interval_s) and self.interval_s > 0 and math.isfinite(self.horizon_s)
                and self.horizon_s >= self.interval_s):
            raise ValueError(f"a prediction horizon of {self.horizon_s} s every {self.interval_s} s: both must be "
                             "positive, the horizon at least one interval")


#: Keys of an identified parameter set recording the NMPC set-up its class was chosen for [s].
NMPC_HORIZON_KEY = "nmpc_horizon_s"
NMPC_INTERVAL_KEY = "nmpc_control_interval_s"


def recorded_horizon(extras, where: str) -> Horizon | None:
    """The NMPC set-up a parameter set records it was identified for; None when it records none.

    Raises
    ------
    ScenarioError
        Only one of the two keys, or values that are no horizon (named by ``where``).
    """
    present = [key for key in (NMPC_HORIZON_KEY, NMPC_INTERVAL_KEY) if key in extras]
    if not present:
        return None
    if len(present) == 1:
        raise ScenarioError(f"{where}: key '{present[0]}' needs its partner "
                            f"'{NMPC_INTERVAL_KEY if present[0] == NMPC_HORIZON_KEY else NMPC_HORIZON_KEY}' "
                            "(the NMPC set-up the model was identified for); write the file again with identify")
    values = [extras[key] for key in (NMPC_HORIZON_KEY, NMPC_INTERVAL_KEY)]
    try:
        if any(isinstance(v, bool) or not isinstance(v, (int, float)) for v in values):
            raise ValueError("not numbers")
        return Horizon(float(values[0]), float(values[1]))
    except ValueError:
        raise ScenarioError(f"{where}: keys '{NMPC_HORIZON_KEY}' = {values[0]!r}, '{NMPC_INTERVAL_KEY}' = "
                            f"{values[1]!r} are no prediction horizon (seconds, the horizon at least one "
                            "interval); write the file again with identify") from None


def same_horizon(a: Horizon, b: Horizon) -> bool:
    """Whether two NMPC set-ups predict over the same horizon from the same interval (to 1e-6 relative)."""
    return math.isclose(a.horizon_s, b.horizon_s, rel_tol=1e-6) and math.isclose(a.interval_s, b.interval_s,
                                                                                   rel_tol=1e-6)


def windowed_starts(record: Record, horizon: Horizon) -> list[float]:
    """The times [s] of ``record`` from which the class choice predicts over ``horizon``
    (:func:`rhnc.ship.prediction_error.windowed_predictions`: every interval, each window whole)."""
    return [float(record.t[k]) for k in window_starts(record, horizon.horizon_s, horizon.interval_s)]


def held_out_windows_note(held_out: Record, horizon: Horizon) -> str:
    """How many predictions over the horizon the class was chosen by; with one, the choice is
    that of one open-loop run over the held-out manoeuvre, not of the NMPC's re-planning."""
    count = len(windowed_starts(held_out, horizon))
    length = float(held_out.t[-1] - held_out.t[0])
    text = (f"chosen by {count} prediction{'s' if count != 1 else ''} of the {horizon.horizon_s:g}-s horizon from the "
            f"{length:g}-s held-out {VALIDATION_MANOEUVRE}, one every {horizon.interval_s:g} s")
    if count == 1:
        text += (": the held-out manoeuvre is about one horizon long, so the class is chosen as by one open-loop "
                 "run over it, not by the NMPC's predictions from each measured state")
    return text


def open_loop_cost(record: Record, predicted: np.ndarray) -> float:
    """Weighted RMS error of one open-loop prediction over a whole record (heading per degree,
    surge and sway per 0.1 m/s, yaw rate per 0.06 deg/s); inf when it diverged.  Reported, not
    the choice: see :func:`model_cost`."""
    error = (predicted[:, 2:6] - record.states[:, 2:6]) * STATE_ERROR_WEIGHTS
    value = float(np.sqrt(np.mean(error ** 2)))
    return value if math.isfinite(value) else math.inf


def model_cost(parameters: ShipParameters, records: dict[str, Record], horizon: Horizon) -> float:
    """What the class is chosen by: the weighted error of the model's predictions of the
    held-out manoeuvre over the horizon, from every interval's measured state
    (:func:`rhnc.ship.prediction_error.horizon_cost`); inf when a prediction of the horizon's
    length from any measured state of any manoeuvre diverges (a polynomial can fit the
    samples and still run away between them)."""
    for name, record in records.items():
        if name == VALIDATION_MANOEUVRE:
            continue
        windows = windowed_predictions(parameters, record, horizon.horizon_s, horizon.interval_s)
        if windows is not None and not np.all(np.isfinite(windows[0])):
            return math.inf
    return horizon_cost(parameters, records[VALIDATION_MANOEUVRE], horizon.horizon_s, horizon.interval_s)


def choose_class(costs: dict[str, float]) -> str | None:
    """The class kept among ``costs`` (class -> held-out cost, narrowest first): a wider class
    replaces a narrower one only when its cost is smaller by :data:`WIDER_CLASS_GAIN` (the
    hull polynomial's also by :data:`WIDER_CLASS_MARGIN`); None when no cost is finite."""
    finite = [name for name, cost in costs.items() if math.isfinite(cost)]
    if not finite:
        return None
    chosen = finite[0]
    for name in finite[1:]:   # narrowest first: a wider class must earn its coefficients
        best = costs[chosen]
        margin = WIDER_CLASS_MARGIN if set(MODEL_CLASSES[name]) & set(HULL_POLYNOMIAL_KEYS) else 0.0
        if costs[name] < min((1.0 - WIDER_CLASS_GAIN) * best, best - margin):
            chosen = name
    return chosen


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


def _fit_class(records, tau_u_max, tau_r_max, names, refine, horizon: Horizon, masses=None, damping_speed=0.0):
    """One class fitted: (equation-error parameters, final parameters, rms, r2, note); a fit
    that is not :func:`physical` is None.  ``damping_speed`` [m/s]: see :data:`SPEED_SCALED`."""
    equation_error, rms, r2 = fit_coefficients(records, tau_u_max, tau_r_max, names, masses, damping_speed)
    note = "equation error only"
    theta = equation_error
    if refine:
        theta, note = refine_output_error(records, equation_error, names, masses, damping_speed, horizon.horizon_s)

    def parameters(values, label):
        coefficients = {name: 0.0 for name in ALL_COEFFICIENTS}
        coefficients.update(zip(names, (float(v) for v in values)))
        if not physical(coefficients, records, masses):
            return None
        return ShipParameters(**coefficients, tau_u_max=float(tau_u_max), tau_r_max=float(tau_r_max),
                              damping_speed_mps=float(damping_speed), name=label)

    return parameters(equation_error, "equation error only"), parameters(theta, "fitted"), rms, r2, note


def _refined_from_narrower(records: dict[str, Record], names: tuple[str, ...], candidates: dict, horizon: Horizon,
                           masses: MassBounds | None = None):
    """The class ``names`` refined from the narrower candidate with the smallest held-out cost
    (its coefficients, the others zero; its masses brought within ``masses``' bounds):
    (parameters or None, note).  A speed-scaled class is no start: the polynomial's class has
    constant damping."""
    candidates = {name: candidate for name, candidate in candidates.items() if name not in SPEED_SCALED}
    if not candidates:
        return None, "no narrower class with constant damping to start from"
    narrower_name = min(candidates, key=lambda name: candidates[name][0])
    narrower = candidates[narrower_name][2]
    if not math.isfinite(candidates[narrower_name][0]):
        return None, "no finite narrower class to start from"
    start = {name: getattr(narrower, name) for name in names}
    for name, (low, high) in (masses.bounds.items() if masses is not None else ()):
        start[name] = min(max(start[name], low), high)
    theta, note = refine_output_error(records, np.array([start[name] for name in names]), names, masses,
                                      horizon_s=horizon.horizon_s)
    parameters = dataclasses.replace(narrower, **dict(zip(names, (float(v) for v in theta))))
    if not physical({name: getattr(parameters, name) for name in ALL_COEFFICIENTS}, records, masses):
        return None, "not physical"
    return parameters, f"from the {narrower_name} model, {note}"


def _fit_candidates(records: dict[str, Record], tau_u_max: float, tau_r_max: float, classes: tuple[str, ...],
                    refine: bool, horizon: Horizon, masses: MassBounds | None = None, service_speed: float = 0.0,
                    bound_every_class: bool = False) -> dict:
    """Every class fitted and scored on the held-out manoeuvre: name -> (held-out cost,
    equation-error parameters, chosen parameters, residual RMS, R², note); a class without a
    physical fit is left out, and so is the hull polynomial's without ``masses``.
    ``bound_every_class``: ``masses`` bound the narrower classes' masses too."""
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
        equation_error, fitted, rms, r2, note = _fit_class(records, tau_u_max, tau_r_max, names, refine, horizon,
                                                           masses if polynomial or bound_every_class else None,
                                                           service_speed if class_name in SPEED_SCALED else 0.0)
        cost = model_cost(fitted, records, horizon) if fitted is not None else math.inf
        if refine and fitted is not None and equation_error is not None:
            # the refinement fits the fitting manoeuvres; where the class lacks the plant's
            # structure that can cost on others, and the held-out manoeuvre decides
            plain = model_cost(equation_error, records, horizon)
            if plain < cost:
                cost, fitted, note = plain, equation_error, f"equation error kept: held-out {plain:.4g} against " \
                                                            f"{cost:.4g} refined ({note})"
        if refine and set(HULL_POLYNOMIAL_KEYS) & set(names) and candidates:
            # the polynomial's equation-error fit extrapolates and may run away: refine also from
            # the best narrower class's model, its polynomial zero, so the class starts where
            # the narrower one ended and can only improve on it
            nested, nested_note = _refined_from_narrower(records, names, candidates, horizon, masses)
            nested_cost = model_cost(nested, records, horizon) if nested is not None else math.inf
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
                   classes: tuple[str, ...] = tuple(MODEL_CLASSES), masses: MassBounds | None = None, *,
                   horizon: Horizon, bound_every_class: bool = False) -> Fit:
    """Sail the manoeuvres, fit every model class, keep the one that predicts the held-out
    manoeuvre best over ``horizon`` (the NMPC's, :class:`Horizon`).

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
    candidates = _fit_candidates(records, tau_u_max, tau_r_max, classes, refine, horizon, masses, runner.speed_mps,
                                 bound_every_class and masses is not None)
    class_errors = {name: (candidates[name][0] if name in candidates else None) for name in classes}
    open_loop = {name: open_loop_cost(held_out, simulate(candidates[name][2], held_out)) for name in candidates}
    chosen = choose_class({name: candidate[0] for name, candidate in candidates.items()})
    if chosen is None:
        raise ToolchainError("identify: no model class predicts the held-out zig-zag without diverging (classes "
                             f"tried: {', '.join(classes)}): the manoeuvres may leave the ship's real range; give the "
                             "yaw moment of full rudder at service speed as --tau-r-max-Nm and check the probe's figures")
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
    error = position_error_growth(parameters, records, horizon.horizon_s, horizon.interval_s)
    parameters = dataclasses.replace(parameters, extras={"position_error_growth_mps": error["growth_mps"],
                                                         "model_class": chosen})
    notes = list(runner.notes) + [f"{chosen}: {note}", held_out_windows_note(held_out, horizon)]
    if len(windowed_starts(held_out, horizon)) == 1:
        LOG.warning("identify: %s", notes[-1])
    if masses is None and any(set(MODEL_CLASSES[name]) & set(HULL_POLYNOMIAL_KEYS) for name in classes):
        notes.append("the class with the hull polynomial was not fitted: it needs the ship's particulars "
                     "(identify --ship) to bound the mass matrix")
    elif masses is not None:
        bounded = "every class" if bound_every_class else "the hull-polynomial class"
        notes.append(f"mass matrix of {bounded} bounded from {masses.source}")
    return Fit(parameters, trim, rms, r2, validation, records, predictions, error, chosen, class_errors, notes,
               open_loop, horizon)


def check_bounds(tau_u_max: float | None, tau_r_max: float | None) -> tuple[float, float]:
    """The bounds given on the command line, checked."""
    for name, value in (("--tau-u-max-N", tau_u_max), ("--tau-r-max-Nm", tau_r_max)):
        if value is None:
            raise ScenarioError(f"identify: give {name}, the largest force the ship can give (from its data sheet)")
        if not (math.isfinite(value) and value > 0):
            raise ScenarioError(f"identify: {name} must be a positive number, got {value}")
    assert tau_u_max is not None and tau_r_max is not None  # refused above
    return float(tau_u_max), float(tau_r_max)
