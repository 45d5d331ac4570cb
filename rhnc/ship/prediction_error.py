"""How far a fitted prediction model predicts wrong, as the NMPC uses it.

The NMPC predicts from each measured state over its horizon; a model's error therefore
shows in the distance between the positions it predicts from a measured state and those the
plant reached.  :func:`position_error_growth` measures that on recorded manoeuvres
(:class:`rhnc.ship.sea_trials.Record`) and reduces it to one growth rate [m/s]: the NMPC
widens its collision domains by growth times prediction time, so that a plan grazing a
domain does not take the plant into it (constraint tightening).
"""

from __future__ import annotations

import math

import numpy as np

from orchestrator.errors import ToolchainError
from rhnc.ship.ship_model import ShipParameters, derivatives, rk4_states

def window_starts(record, horizon_s: float, stride_s: float) -> np.ndarray:
    """Sample indices of ``record`` from which a prediction over ``horizon_s`` starts, one every
    ``stride_s``, each window within the record."""
    dt = float(record.t[1] - record.t[0])
    return np.arange(0, len(record.t) - int(round(horizon_s / dt)), max(1, int(round(stride_s / dt))))


def windowed_predictions(parameters: ShipParameters, record, horizon_s: float,
                         stride_s: float) -> tuple[np.ndarray, np.ndarray] | None:
    """The model's predictions over ``horizon_s`` from every ``stride_s`` of a record, as the
    NMPC predicts from each measured state (multiple shooting: each window starts again from
    the plant's state, with the recorded inputs).

    Returns
    -------
    (predicted, measured) : ndarray (steps, 6, windows)
        States after 1..steps samples of each window; None when the record is shorter than
        the horizon.  A window whose model leaves the finite numbers holds NaN or inf.
    """
    dt = float(record.t[1] - record.t[0])
    steps = int(round(horizon_s / dt))
    starts = window_starts(record, horizon_s, stride_s)
    if steps < 1 or not len(starts):
        return None
    state = record.states[starts].T.copy()          # (6, windows)
    predicted = np.empty((steps, 6, len(starts)))
    with np.errstate(over="ignore", invalid="ignore"):
        for j in range(steps):
            state = rk4_states(derivatives, state, dt / 2.0, 2, record.tau[starts + j].T, parameters)[-1]
            predicted[j] = state
    measured = np.stack([record.states[starts + j + 1].T for j in range(steps)])
    return predicted, measured


#: Weights of the state errors in the prediction cost: heading per degree, surge and sway
#: speed per 0.1 m/s, yaw rate per 0.06 deg/s (the output-error refinement's weights).
STATE_ERROR_WEIGHTS = np.array([1.0 / math.radians(1.0), 10.0, 10.0, 1.0 / math.radians(0.06)])


def horizon_cost(parameters: ShipParameters, record, horizon_s: float, stride_s: float) -> float:
    """Weighted RMS error of the model's predictions over the NMPC's horizon, from every
    ``stride_s`` of ``record`` (:func:`windowed_predictions`; heading, surge, sway and yaw rate
    weighted by :data:`STATE_ERROR_WEIGHTS`): how well the model predicts over the time the
    NMPC uses it, not over one long run whose error grows with the phase of a zig-zag.  inf
    when a window diverges or the record is shorter than the horizon."""
    windows = windowed_predictions(parameters, record, horizon_s, stride_s)
    if windows is None:
        return math.inf
    predicted, measured = windows
    error = (predicted[:, 2:6] - measured[:, 2:6]) * STATE_ERROR_WEIGHTS[None, :, None]
    with np.errstate(over="ignore", invalid="ignore"):
        value = float(np.sqrt(np.mean(error ** 2)))
    return value if math.isfinite(value) else math.inf


def position_error_growth(parameters: ShipParameters, records: dict, horizon_s: float,
                          stride_s: float) -> dict[str, float]:
    """How fast the model's predicted position drifts from the plant's: the NMPC's margin growth.

    From every ``stride_s`` of every record the model is integrated open loop over
    ``horizon_s`` with the recorded inputs, starting from the measured state, as the NMPC
    predicts from each measured state.  The position error e(t) grows with the prediction
    time t; its largest ratio e(t) / t over all windows and times is a growth rate [m/s]
    such that a collision domain widened by ``growth * t`` covers the prediction error of
    every window (the NMPC's ``clearance_margin_growth``: constraint tightening, so that a
    plan grazing the domain does not take the plant into it).

    Parameters
    ----------
    parameters : ShipParameters
        The model.
    records : dict of Record
        Manoeuvres at a constant sampling step (times, states (n, 6), inputs held (n, 2)).
    horizon_s, stride_s : float
        Prediction time and spacing of the windows [s]: the NMPC's horizon and control interval.

    Returns
    -------
    dict
        ``growth_mps`` [m/s], ``horizon_s``, and ``max_error_20s_m``, ``max_error_60s_m``,
        ``max_error_<horizon>s_m`` [m]: the largest position errors after those times.

    Raises
    ------
    ToolchainError
        No record lasts the horizon.
    """
    ratios: list[float] = []
    marks: dict[float, list[float]] = {20.0: [], 60.0: [], float(horizon_s): []}
    for record in records.values():
        windows = windowed_predictions(parameters, record, horizon_s, stride_s)
        if windows is None:
            continue
        predicted, measured = windows
        dt = float(record.t[1] - record.t[0])
        steps = predicted.shape[0]
        times = dt * np.arange(1, steps + 1)
        errors = np.hypot(predicted[:, 0] - measured[:, 0], predicted[:, 1] - measured[:, 1])
        ratios.append(np.max(errors / times[:, None]))
        for mark in marks:
            marks[mark].append(np.max(errors[min(steps, int(round(mark / dt))) - 1]))
    if not ratios:
        raise ToolchainError(f"identify: no manoeuvre lasts the {horizon_s:g} s prediction horizon")
    return {"growth_mps": float(max(ratios)), "horizon_s": float(horizon_s),
            **{f"max_error_{int(mark)}s_m": float(max(values)) for mark, values in marks.items()}}
