"""A helm that holds a surge force and swings the yaw moment as a sine.

Options (``[participants.<name>.options]``):

``tau_u_N``
    Constant surge force [N].
``tau_r_amplitude_Nm``
    Amplitude of the yaw moment [N m].
``period_s``
    Period of the sine [s], > 0.
"""

from __future__ import annotations

import math

from orchestrator.errors import ScenarioError
from orchestrator.participant import Participant, is_finite_number, reject_unknown_options

OPTIONS = ("tau_u_N", "tau_r_amplitude_Nm", "period_s")


class SineHelm(Participant):
    """tau_u constant, tau_r = amplitude sin(2 pi t / period)."""

    def __init__(self, name: str, tau_u_N: float, tau_r_amplitude_Nm: float, period_s: float) -> None:
        super().__init__(name)
        self.tau_u_N, self.tau_r_amplitude_Nm, self.period_s = tau_u_N, tau_r_amplitude_Nm, period_s

    @classmethod
    def from_options(cls, name, options, context) -> "SineHelm":
        where = context.where + ".options"
        reject_unknown_options(options, OPTIONS, where)
        values = {}
        for key in OPTIONS:
            value = options.get(key)
            if not is_finite_number(value):
                raise ScenarioError(f"{where}.{key}: must be a finite number, got {value!r}")
            values[key] = float(value)
        if values["period_s"] <= 0:
            raise ScenarioError(f"{where}.period_s: must be positive, got {values['period_s']:g}")
        return cls(name, **values)

    @property
    def input_names(self):
        return []

    @property
    def output_names(self):
        return ["tau_u", "tau_r"]

    def _outputs(self, time_s: float) -> dict[str, float]:
        return {"tau_u": self.tau_u_N,
                "tau_r": self.tau_r_amplitude_Nm * math.sin(2.0 * math.pi * time_s / self.period_s)}

    def setup(self, start_time, inputs):
        return self._outputs(start_time)

    def step(self, time, step_size, inputs):
        return self._outputs(time)
