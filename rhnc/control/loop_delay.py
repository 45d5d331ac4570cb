"""The controller's loop delay: the measured state predicted over it with the inputs already sent.

In a master that steps every participant at once (Jacobi: OSP's libcosim and most FMI
masters), an input the controller computes at ``t`` from the state measured at ``t``
reaches the plant only at ``t + d`` (d: one communication step of the controller), while
the input sent one step earlier acts over ``[t, t + d)``.  A controller that ignores this
plans for a ship that is ``d`` behind the one its input will meet: at a 60 s interval the
yaw moment of Experiment 2 swung between its bounds for the whole voyage.

:class:`LoopDelay` keeps the inputs sent with the time each takes effect, and
:meth:`LoopDelay.predict` carries the measured state forward over ``[t, t + d)`` with
those inputs through the controller's own prediction model (RK4, no disturbance): the
controller then solves at ``t + d`` from the state its input will meet.  With ``d = 0``
(our master's default Gauss-Seidel order, the controller stepping before the plant) it
returns the measured state unchanged.

The prediction model knows no weather: in Experiment 2's wind, waves and current the
ship's speed and track differ from the model's by a steady amount, and a state carried
over the delay by the model alone was a ship faster than the real one (the controller
pushed less, and the voyage made good 1.4 % less in Jacobi order than in ours).  The
prediction is therefore corrected by the model's error over the last delay: the state
measured now less the one the model predicted for now from the measurement one delay ago
(a disturbance taken as constant over one delay, as a Smith predictor corrects its model
with the measured output).  In calm water with the plant's own model that error is zero.
"""

from __future__ import annotations

import math

import numpy as np

from orchestrator.geometry import wrap_angle
from rhnc.ship.ship_model import ShipParameters, rk4_step

#: longest RK4 step of the prediction over the delay [s]
MAX_SUBSTEP_S = 5.0
#: index of the heading in the state (x, y, psi, u, v, r)
HEADING = 2


class LoopDelay:
    """Inputs sent and when they take effect; prediction of the state over the delay.

    Parameters
    ----------
    delay_s : float
        Time from a step at ``t`` to its input acting on the plant [s], >= 0.
    params : ShipParameters
        The controller's prediction model.
    """

    def __init__(self, delay_s: float, params: ShipParameters) -> None:
        if not (math.isfinite(delay_s) and delay_s >= 0.0):
            raise ValueError(f"loop delay must be a finite number of seconds >= 0, got {delay_s!r}")
        self.delay_s = float(delay_s)
        self.params = params
        self._sent: list[tuple[float, np.ndarray]] = []  # (takes effect at [s], input [SI])
        self._expected: tuple[float, np.ndarray] | None = None  # the model's last prediction (time [s], state)
        #: the model's error over the last delay (measured less predicted), added to the prediction
        self.model_error = np.zeros(6)

    def reset(self) -> None:
        """Forget the inputs sent and the model's error."""
        self._sent = []
        self._expected = None
        self.model_error = np.zeros(6)

    def hold(self, time_s: float, tau: np.ndarray) -> None:
        """An input acting from ``time_s`` itself (the set-up's outputs, which reach the plant at once)."""
        self._sent.append((float(time_s), np.asarray(tau, dtype=float).copy()))

    def sent(self, time_s: float, tau: np.ndarray) -> None:
        """The input published at ``time_s``: it acts on the plant from ``time_s + delay_s``."""
        self._sent.append((float(time_s) + self.delay_s, np.asarray(tau, dtype=float).copy()))
        # only inputs that may still act after the next step's measurement are kept
        while len(self._sent) > 1 and self._sent[1][0] <= float(time_s):
            self._sent.pop(0)

    def acting(self, time_s: float) -> np.ndarray | None:
        """The input acting on the plant at ``time_s``, None before the first one acts."""
        acting = None
        for effective, tau in self._sent:
            if effective <= time_s + 1e-9:
                acting = tau
        return acting

    def predict(self, time_s: float, state: np.ndarray) -> tuple[float, np.ndarray]:
        """``(time_s + delay_s, state there)``: ``state`` measured at ``time_s`` carried over the delay.

        Piecewise over the sent inputs acting in ``[time_s, time_s + delay_s)``; before the
        first input sent acts, the plant is taken to hold zero forces (what the controller
        publishes at set-up).  Plus :attr:`model_error`: when the model predicted a state for
        ``time_s`` one delay ago, the measured state less that prediction (else zero).
        """
        measured = np.asarray(state, dtype=float)
        end = float(time_s) + self.delay_s
        if self.delay_s <= 0.0:
            return float(time_s), measured.copy()
        self.model_error = np.zeros(6)
        if self._expected is not None and abs(self._expected[0] - float(time_s)) < 1e-6:
            self.model_error = measured - self._expected[1]
            self.model_error[HEADING] = wrap_angle(float(self.model_error[HEADING]))
        state = measured
        switches = sorted({float(time_s), end, *(e for e, _ in self._sent if time_s < e < end)})
        for start, stop in zip(switches[:-1], switches[1:]):
            tau = self.acting(start)
            tau = np.zeros(2) if tau is None else tau
            span = stop - start
            state = rk4_step(state, tau, span, max(1, math.ceil(span / MAX_SUBSTEP_S)), self.params)
        self._expected = (end, state.copy())  # the model alone, compared with the measurement at `end`
        return end, state + self.model_error
