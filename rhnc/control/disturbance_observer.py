"""Offset-free NMPC: an estimate of the current and the body-frame loads the model does not see.

The NMPC predicts with the calm-water model; wind, waves, current and model error then
leave a steady cross-track offset and a speed loss that no tracking weight removes.  This
observer treats the missing terms as an unknown constant disturbance

    d = [c_n, c_e, w_u, w_v, w_r]   (current north, east [m/s]; surge, sway force [N]; yaw moment [N m])

entering the model as in :func:`rhnc.control.nmpc_problem.disturbed_derivatives`, i.e. the state
augmented with a random-walk disturbance.  At each control step it predicts the measured
state from the previous one under the input actually applied and the current estimate,
and corrects the estimate by a fraction ``gain`` of the least-squares (Gauss-Newton) step
that would explain the prediction error:

    e = x_k - F(x_{k-1}, tau_{k-1}, d),   J = dF/dd,   d <- d + gain * (S J)^+ (S e),

with ``S`` the NMPC's state scaling, so that metres, radians and m/s weigh alike.  With
``gain = 1`` a constant disturbance on a linear model is found in one step; a smaller gain
filters the step-to-step changes (waves, turning).  The NMPC then predicts with ``d``, so
its plans already contain the drift and the force needed against it: the steady offsets
vanish (integral action through the estimate).  The estimate is clipped to physical
bounds (``max_current_mps``, the input bounds for the forces).
"""

from __future__ import annotations

import logging
import math

import casadi as ca
import numpy as np

from orchestrator.geometry import wrap_angle
from rhnc.control.nmpc_problem import DISTURBANCE_SIZE, disturbed_rk4
from rhnc.ship.ship_model import ShipParameters, hull_forces

LOG = logging.getLogger(__name__)

#: longest prediction substep [s] of the observer's integrator
MAX_SUBSTEP_S = 15.0


class DisturbanceObserver:
    """Estimate ``d`` from successive measured states and the applied inputs.

    Parameters
    ----------
    params : ShipParameters
        Prediction model (the NMPC's).
    state_scale : numpy.ndarray
        Scale of each state component (weights of the least-squares fit).
    gain : float
        Fraction of the Gauss-Newton correction applied per step, in (0, 1].
    max_current_mps : float
        Bound of each current component [m/s].
    max_gap_s : float
        A step longer than this (a pause, a restart) resets the prediction without update [s].
    """

    def __init__(self, params: ShipParameters, state_scale: np.ndarray, gain: float = 0.5,
                 max_current_mps: float = 3.0, max_gap_s: float = 600.0) -> None:
        if not 0.0 < gain <= 1.0:
            raise ValueError(f"disturbance observer gain must be in (0, 1], got {gain}")
        self.params = params
        self.state_scale = np.asarray(state_scale, dtype=float)
        self.gain = float(gain)
        self.max_gap_s = float(max_gap_s)
        force = max(params.tau_u_max, params.tau_r_max / float(params.extras.get("lpp", 230.0)))
        self.bound = np.array([max_current_mps, max_current_mps, params.tau_u_max, 2.0 * force, params.tau_r_max])
        self.estimate = np.zeros(DISTURBANCE_SIZE)
        self._previous: tuple[float, np.ndarray, np.ndarray] | None = None
        self._models: dict[float, tuple[ca.Function, ca.Function]] = {}

    def reset(self) -> None:
        """Forget the estimate and the previous sample."""
        self.estimate = np.zeros(DISTURBANCE_SIZE)
        self._previous = None

    def _model(self, dt_s: float) -> tuple[ca.Function, ca.Function]:
        key = round(dt_s, 6)
        if key not in self._models:
            substeps = max(1, math.ceil(dt_s / MAX_SUBSTEP_S))
            F = disturbed_rk4(self.params, dt_s, substeps)
            x = ca.SX.sym("x", 6)
            tau = ca.SX.sym("tau", 2)
            d = ca.SX.sym("d", DISTURBANCE_SIZE)
            x_next = F(x, tau, d)[0]
            self._models[key] = (ca.Function("observer_step", [x, tau, d], [x_next]),
                                 ca.Function("observer_jacobian", [x, tau, d], [ca.jacobian(x_next, d)]))
        return self._models[key]

    def update(self, time_s: float, state: np.ndarray) -> np.ndarray:
        """Correct the estimate with the state measured at ``time_s``; return the estimate.

        Call :meth:`applied` with the input chosen at this time before the next update.
        """
        state = np.asarray(state, dtype=float)
        previous = self._previous
        if previous is not None and previous[2] is not None:
            dt = time_s - previous[0]
            if 0.0 < dt <= self.max_gap_s:
                step, jacobian = self._model(dt)
                predicted = np.array(step(previous[1], previous[2], self.estimate)).ravel()
                error = state - predicted
                error[2] = wrap_angle(float(error[2]))
                J = np.array(jacobian(previous[1], previous[2], self.estimate)) / self.state_scale[:, None]
                correction = np.linalg.lstsq(J, error / self.state_scale, rcond=1e-9)[0]
                if np.all(np.isfinite(correction)):
                    self.estimate = np.clip(self.estimate + self.gain * correction, -self.bound, self.bound)
                else:
                    LOG.warning("disturbance observer at t = %.1f s: non-finite correction ignored", time_s)
        self._previous = (float(time_s), state.copy(), None)
        return self.estimate.copy()

    def applied(self, tau: np.ndarray) -> None:
        """Record the input applied from the last measured state on."""
        if self._previous is not None:
            self._previous = (self._previous[0], self._previous[1], np.asarray(tau, dtype=float).copy())

    def ready(self) -> bool:
        """True when the previous sample has its input (an update will correct the estimate)."""
        return self._previous is not None and self._previous[2] is not None


def trimmed_reference(reference: np.ndarray, disturbance: np.ndarray, dt_s: float,
                      params: ShipParameters) -> tuple[np.ndarray, np.ndarray]:
    """The reference made consistent with the estimated disturbance, and its feed-forward input.

    A reference with the heading along the track and no sway (the paper's Eq. 19) cannot be
    followed in a cross current or a beam wind: holding the track needs a drift angle.
    Left as it is, the heading weight (Q = 10 per rad²) outbids the cross-track weight and
    the ship settles off the track however well the disturbance is known.  So each node
    keeps its position and yaw rate and gets the body velocity that yields the reference's
    velocity over ground under the estimate: the water-relative velocity is the ground
    velocity minus the current, the sway speed is the steady one under the sway load
    (``v = w_v / d22``), and the heading turns by the drift angle ``atan2(v, u)``.  The
    feed-forward input balances the surge and yaw equations at that state.

    Parameters
    ----------
    reference : (N+1, 6) array
        Reference states [SI].
    disturbance : (5,) array
        Current north, east [m/s], w_u, w_v [N], w_r [N m].
    dt_s : float
        Spacing of the reference nodes [s].
    params : ShipParameters

    Returns
    -------
    reference : (N+1, 6) array
        Trimmed reference states [SI].
    tau : (N, 2) array
        Feed-forward input [N, N m], clipped to the bounds.
    """
    reference = np.array(reference, dtype=float)
    c_n, c_e, w_u, w_v, w_r = np.asarray(disturbance, dtype=float)
    psi, u, v, r = reference[:, 2], reference[:, 3], reference[:, 4], reference[:, 5]
    ground_n = u * np.cos(psi) - v * np.sin(psi)
    ground_e = u * np.sin(psi) + v * np.cos(psi)
    water_n, water_e = ground_n - c_n, ground_e - c_e
    water_speed = np.hypot(water_n, water_e)
    sway = np.full_like(u, w_v / params.d22)
    sway = np.clip(sway, -0.5 * water_speed, 0.5 * water_speed)
    surge = np.sqrt(np.maximum(water_speed**2 - sway**2, 0.0))
    heading = np.arctan2(water_e, water_n) - np.arctan2(sway, np.maximum(surge, 1e-9))
    # keep the heading's turns as the reference had them
    heading = psi + wrap_angle(heading - psi)
    trimmed = reference.copy()
    trimmed[:, 2], trimmed[:, 3], trimmed[:, 4] = heading, surge, sway
    p = params
    udot = np.diff(surge) / dt_s
    rdot = np.diff(r) / dt_s
    su, sv, sr = surge[:-1], sway[:-1], r[:-1]
    surge_force, _, yaw_moment = hull_forces(p, su, sv, sr)
    tau_u = p.m11 * udot - surge_force - w_u
    tau_r = p.m33 * rdot - yaw_moment - w_r
    tau = np.clip(np.column_stack([tau_u, tau_r]), -p.tau_max, p.tau_max)
    return trimmed, tau
