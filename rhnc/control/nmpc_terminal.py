"""Terminal weight P of the NMPC: the DARE solution about straight motion at the reference speed.

The scaled model (see :mod:`rhnc.control.nmpc`) is linearised about straight motion at speed U
with the equilibrium input, and P solves the discrete algebraic Riccati equation with the
stage weights Q and R (scipy's ``solve_discrete_are``).  P lives in the reference's along-/
cross-track frame; the problem rotates the terminal error into that frame.  Values are
cached per reference speed in 0.25 m/s bins.  Below ``MIN_TERMINAL_SPEED_MPS`` (a reference
that stops at its destination) P is taken at that speed: about zero speed the cross-track
position is reached only through sway, which is unactuated, and the DARE has no solution.
"""

from __future__ import annotations

from collections.abc import Sequence

import casadi as ca
import numpy as np
from scipy.linalg import solve_discrete_are

from rhnc.control.nmpc_problem import DISTURBANCE_SIZE
from rhnc.ship.ship_model import ShipParameters

#: lowest speed [m/s] about which the terminal weight P is linearised
MIN_TERMINAL_SPEED_MPS = 1.0


class TerminalWeight:
    """P(U) for the scaled problem, cached.

    Parameters
    ----------
    step : casadi.Function
        Scaled model step ``F_s(z, w, d)``.
    params : ShipParameters
        For the equilibrium input.
    q, r : sequence of float
        Diagonals of Q (6) and R (2).
    speed_scale_mps : float
        U of the scaling [m/s].
    input_scale : numpy.ndarray
        Input scale (tau_max) [N, N m].
    enabled : bool
        False: P = Q.
    """

    def __init__(self, step: ca.Function, params: ShipParameters, q: Sequence[float], r: Sequence[float],
                 speed_scale_mps: float, input_scale: np.ndarray, enabled: bool = True) -> None:
        self.step = step
        self.params = params
        self.q = np.asarray(q, dtype=float)
        self.r = np.asarray(r, dtype=float)
        self.speed_scale = float(speed_scale_mps)
        self.input_scale = np.asarray(input_scale, dtype=float)
        self.enabled = enabled
        self._cache: dict[float, np.ndarray] = {}
        z = ca.SX.sym("z", 6)
        w = ca.SX.sym("w", 2)
        z_next = step(z, w, ca.DM.zeros(DISTURBANCE_SIZE))[0]
        self._linearised = ca.Function("linearised_step", [z, w], [ca.jacobian(z_next, z), ca.jacobian(z_next, w)])

    def __call__(self, speed_mps: float) -> np.ndarray:
        """P (6 x 6, scaled, path frame) about straight motion at ``speed_mps`` [m/s]."""
        if not self.enabled:
            return np.diag(self.q)
        key = round(max(speed_mps, MIN_TERMINAL_SPEED_MPS) * 4.0) / 4.0
        if key not in self._cache:
            z0 = np.array([0.0, 0.0, 0.0, key / self.speed_scale, 0.0, 0.0])
            w0 = self.params.equilibrium_tau(key) / self.input_scale
            A, B = (np.array(m) for m in self._linearised(z0, w0))
            P = solve_discrete_are(A, B, np.diag(self.q), np.diag(self.r))
            self._cache[key] = 0.5 * (P + P.T)
        return self._cache[key]
