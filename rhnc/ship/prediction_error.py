"""How far a fitted prediction model predicts wrong, as the NMPC uses it.

The NMPC predicts from each measured state over its horizon; a model's error therefore
shows in the distance between the positions it predicts from a measured state and those the
plant reached.  :func:`position_error_growth` measures that on recorded manoeuvres
(:class:`rhnc.ship.sea_trials.Record`) and reduces it to one growth rate [m/s]: the NMPC
widens its collision domains by growth times prediction time, so that a plan grazing a
domain does not take the plant into it (constraint tightening).
"""

from __future__ import annotations

import numpy as np

from orchestrator.errors import ToolchainError
from rhnc.ship.ship_model import ShipParameters, derivatives, rk4_states

#: prediction time over which the position error's growth is measured [s] (15 NMPC intervals of 20 s)
PREDICTION_HORIZON_S = 300.0
#: spacing of the prediction windows [s]
WINDOW_STRIDE_S = 20.0


def position_error_growth(parameters: ShipParameters, records: dict,
                          horizon_s: float = PREDICTION_HORIZON_S, stride_s: float = WINDOW_STRIDE_S) -> dict[str, float]:
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
        Prediction time and spacing of the windows [s].

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
        dt = float(record.t[1] - record.t[0])
        steps = int(round(horizon_s / dt))
        times = dt * np.arange(1, steps + 1)
        starts = np.arange(0, len(record.t) - steps, max(1, int(round(stride_s / dt))))
        if not len(starts):
            continue
        state = record.states[starts].T.copy()          # (6, windows)
        errors = np.empty((steps, len(starts)))
        for j in range(steps):
            tau = record.tau[starts + j].T
            state = rk4_states(derivatives, state, dt / 2.0, 2, tau, parameters)[-1]
            measured = record.states[starts + j + 1]
            errors[j] = np.hypot(state[0] - measured[:, 0], state[1] - measured[:, 1])
        ratios.append(np.max(errors / times[:, None]))
        for mark in marks:
            marks[mark].append(np.max(errors[min(steps, int(round(mark / dt))) - 1]))
    if not ratios:
        raise ToolchainError(f"identify: no manoeuvre lasts the {horizon_s:g} s prediction horizon")
    return {"growth_mps": float(max(ratios)), "horizon_s": float(horizon_s),
            **{f"max_error_{int(mark)}s_m": float(max(values)) for mark, values in marks.items()}}
