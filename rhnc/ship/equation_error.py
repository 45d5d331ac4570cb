"""The equation-error fit of the identification: one bounded linear least-squares problem per model class.

The model of :mod:`rhnc.ship.ship_model` is linear in its coefficients once the
accelerations are known::

    m11 udot - (m22 v + m23 r) r + d11 u + d11q |u| u                 = tau_u
    m22 vdot + m23 rdot + m11 u r + d22 v + d23 r + d22q |v| v        = 0
    m23 vdot + m33 rdot - (m11 - m22) u v + m23 u r + d32 v + d33 r
                                                      + d33q |r| r    = tau_r

(each equation less the hull polynomial's terms, ``x_vv v^2``, ..., ``n_rrr r^3``, in the
widest class), so each model class (:data:`rhnc.ship.identification.MODEL_CLASSES`) is
fitted by one bounded linear least-squares problem over all samples of the fitting
manoeuvres (masses and direct damping positive, quadratic damping not negative, the
polynomial free; the rows of each equation divided by its force scale, the columns by their
norms).  The accelerations and the states in the rows come from a Savitzky-Golay filter
(cubic, 21 s window) over the FMU's 1 s outputs; samples within half a window of an input
switch are left out.  The bounds are the user's (the largest surge force and yaw moment the
ship can give: they cannot be seen in motions that stay inside them).
"""

from __future__ import annotations

import math

import numpy as np

from rhnc.ship.physical_bounds import MassBounds, envelope_directions, make_dissipative, power_rows
from rhnc.ship.sea_trials import FIT_MANOEUVRES, SAMPLE_S, Record
from rhnc.ship.ship_model import HULL_POLYNOMIAL, HULL_POLYNOMIAL_KEYS

COEFFICIENTS = ("m11", "m22", "m33", "d11", "d22", "d33", "d23", "d32")
#: Every coefficient a class may fit, in the order of the regression's columns.
QUADRATIC = COEFFICIENTS + ("m23", "d11q", "d22q", "d33q")
ALL_COEFFICIENTS = QUADRATIC + HULL_POLYNOMIAL_KEYS
#: Coefficients that must be positive (masses, direct damping) and not negative (quadratic damping).
POSITIVE = ("m11", "m22", "m33", "d11", "d22", "d33")
NOT_NEGATIVE = ("d11q", "d22q", "d33q")
FILTER_WINDOW = 21


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


def regression_rows(record: Record, scales: tuple[float, float, float], damping_speed: float = 0.0):
    """Rows ``A theta = b`` of the three equations for one record (scaled by ``scales``); with
    ``damping_speed`` [m/s] the linear sway-yaw damping's columns scale with ``u / damping_speed``
    (:class:`rhnc.ship.ship_model.ShipParameters`' ``damping_speed_mps``)."""
    values, rates, keep = _smoothed(record)
    u, v, r = values[keep].T
    du, dv, dr = rates[keep].T
    tau = record.tau[keep]  # the same before and after a kept sample (switches are left out)
    zero = np.zeros_like(u)
    #           m11     m22     m33   d11   d22   d33   d23   d32  m23           d11q      d22q      d33q
    surge: list[np.ndarray] = [du, -v * r, zero, u, zero, zero, zero, zero, -r * r, np.abs(u) * u, zero, zero]
    sway: list[np.ndarray] = [u * r, dv, zero, zero, v, zero, r, zero, dr, zero, np.abs(v) * v, zero]
    yaw: list[np.ndarray] = [-u * v, u * v, dr, zero, zero, r, zero, v, dv + u * r, zero, zero, np.abs(r) * r]
    if damping_speed > 0.0:
        factor = u / damping_speed
        sway[4], sway[6], yaw[5], yaw[7] = sway[4] * factor, sway[6] * factor, yaw[5] * factor, yaw[7] * factor
    equations = (surge, sway, yaw)
    for equation, v_power, r_power in HULL_POLYNOMIAL.values():   # right-hand-side forces: minus here
        for index, rows in enumerate(equations):
            rows.append(-v ** v_power * r ** r_power if index == equation else zero)
    blocks = [np.column_stack(rows) / scale for rows, scale in zip(equations, scales)]
    a = np.vstack(blocks)
    b = np.concatenate([tau[:, 0] / scales[0], zero, tau[:, 1] / scales[2]])
    return a, b, len(u)


def fit_coefficients(records: dict[str, Record], tau_u_max: float, tau_r_max: float,
                     names: tuple[str, ...] = COEFFICIENTS,
                     masses: MassBounds | None = None, damping_speed: float = 0.0) -> tuple[np.ndarray, dict, dict]:
    """Bounded least-squares coefficients (in the order of ``names``), residual RMS and R² per equation.

    Masses and direct damping are kept positive (at least 1e-6 of the scale of their
    column), quadratic damping not negative; the columns are scaled by their norms, so the
    problem is well conditioned whatever the ship's size.  With ``masses`` the mass matrix
    stays within their bounds; with the hull polynomial among ``names`` its power stays
    dissipative on the sailed envelope's directions (:mod:`rhnc.ship.physical_bounds`: linear
    inequalities, solved as a quadratic programme).  With ``damping_speed`` [m/s] the linear
    sway-yaw damping is fitted proportional to the speed (:func:`regression_rows`).
    """
    from scipy.optimize import lsq_linear

    scales = (tau_u_max, tau_u_max, tau_r_max)
    blocks = [regression_rows(records[name], scales, damping_speed) for name in FIT_MANOEUVRES if name in records]
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


