"""A scripted helm: stepped or zig-zag surge force and yaw moment, for manoeuvring trials.

It lets the co-simulation spine be proven (turning circle, zig-zag) before navigation
and control exist.  Options (``[participants.<name>.options]``):

``tau_u_N``
    Constant surge force [N].
``tau_r_steps``
    List of ``[time_s, yaw_moment_Nm]`` pairs: the yaw moment from each time on
    (``mode = "steps"``, the default; before the first time it is 0).
``mode = "zigzag"``
    Yaw-moment zig-zag: starting at ``execute_s``, apply ``+tau_r_Nm`` until the heading
    has changed by ``+angle_deg`` from the heading at execute, then ``-tau_r_Nm`` until it
    has changed by ``-angle_deg``, and so on (the yaw-moment analogue of the IMO
    rudder zig-zag).  Needs the ``psi`` input connected.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

from orchestrator.errors import ScenarioError
from orchestrator.participant import BuildContext, Participant, is_finite_number, reject_unknown_options

OPTIONS = ("mode", "tau_u_N", "tau_r_steps", "tau_r_Nm", "angle_deg", "execute_s")


class ScriptedTau(Participant):
    """Open-loop tau = [surge force, yaw moment] from a script."""

    #: Option keys (the schema docs/participants.md is checked against).
    OPTIONS = OPTIONS

    def __init__(self, name: str, tau_u: float, steps=(), zigzag=None) -> None:
        super().__init__(name)
        self.tau_u = tau_u
        self.steps = sorted(steps)
        self.zigzag = zigzag  # (execute_s, tau_r, angle_rad) or None
        self._sign = 1.0
        self._psi_execute = None

    @classmethod
    def from_options(cls, name: str, options: Mapping, context: BuildContext) -> "ScriptedTau":
        where = context.where + ".options"
        reject_unknown_options(options, OPTIONS, where)
        mode = options.get("mode", "steps")
        tau_u = _number(options, "tau_u_N", where, 0.0)
        if mode == "steps":
            steps = options.get("tau_r_steps", [])
            if not isinstance(steps, list) or not all(
                isinstance(s, list) and len(s) == 2 and all(isinstance(v, (int, float)) for v in s) for s in steps
            ):
                raise ScenarioError(f"{where}.tau_r_steps: must be a list of [time_s, yaw_moment_Nm] pairs")
            return cls(name, tau_u, steps=[(float(t), float(v)) for t, v in steps])
        if mode == "zigzag":
            zigzag = (_number(options, "execute_s", where, 0.0), _number(options, "tau_r_Nm", where),
                      math.radians(_number(options, "angle_deg", where, 10.0)))
            return cls(name, tau_u, zigzag=zigzag)
        raise ScenarioError(f"{where}.mode: must be 'steps' or 'zigzag', got {mode!r}")

    @property
    def input_names(self):
        return ["psi"] if self.zigzag else []

    @property
    def output_names(self):
        return ["tau_u", "tau_r"]

    def setup(self, start_time, inputs):
        self._sign, self._psi_execute = 1.0, None
        return {"tau_u": self.tau_u, "tau_r": self._yaw_moment(start_time, inputs)}

    def step(self, time, step_size, inputs):
        return {"tau_u": self.tau_u, "tau_r": self._yaw_moment(time, inputs)}

    def _yaw_moment(self, time: float, inputs) -> float:
        if self.zigzag is None:
            value = 0.0
            for start, moment in self.steps:
                if time >= start - 1e-9:
                    value = moment
            return value
        execute_s, moment, angle = self.zigzag
        if time < execute_s - 1e-9:
            return 0.0
        if "psi" not in inputs:
            raise ScenarioError(f"{self.name}: zigzag mode needs the 'psi' input connected")
        psi = float(inputs["psi"])
        if self._psi_execute is None:
            self._psi_execute = psi
        change = math.remainder(psi - self._psi_execute, 2 * math.pi)
        if self._sign > 0 and change >= angle:
            self._sign = -1.0
        elif self._sign < 0 and change <= -angle:
            self._sign = 1.0
        return self._sign * moment


def _number(options, key, where, default=None) -> float:
    if key not in options:
        if default is None:
            raise ScenarioError(f"{where}: missing option '{key}'")
        return float(default)
    value = options[key]
    if not is_finite_number(value):
        raise ScenarioError(f"{where}.{key}: must be a finite number, got {value!r}")
    return float(value)


RUDDER_OPTIONS = ("mode", "propeller_rps", "rudder_steps", "rudder_deg", "angle_deg", "execute_s")


class ScriptedRudder(ScriptedTau):
    """Open-loop rudder angle and propeller revolutions, for plants at actuator level.

    Options: ``propeller_rps`` (constant revolutions [1/s]); ``rudder_steps``, a list of
    ``[time_s, angle_deg]`` (``mode = "steps"``, positive to starboard); or
    ``mode = "zigzag"`` with ``rudder_deg``, ``angle_deg`` and ``execute_s``: the IMO zig-zag,
    +rudder until the heading has changed by +angle, then -rudder until -angle, and so on.
    Outputs ``rudder_angle_cmd`` [rad] and ``propeller_rps_cmd`` [1/s].
    """

    OPTIONS = RUDDER_OPTIONS

    @classmethod
    def from_options(cls, name: str, options: Mapping, context: BuildContext) -> "ScriptedRudder":
        where = context.where + ".options"
        reject_unknown_options(options, RUDDER_OPTIONS, where)
        mode = options.get("mode", "steps")
        rps = _number(options, "propeller_rps", where)
        if mode == "steps":
            steps = options.get("rudder_steps", [])
            if not isinstance(steps, list) or not all(
                isinstance(s, list) and len(s) == 2 and all(is_finite_number(v) for v in s) for s in steps
            ):
                raise ScenarioError(f"{where}.rudder_steps: must be a list of [time_s, angle_deg] pairs")
            return cls(name, rps, steps=[(float(t), math.radians(v)) for t, v in steps])
        if mode == "zigzag":
            zigzag = (_number(options, "execute_s", where, 0.0), math.radians(_number(options, "rudder_deg", where)),
                      math.radians(_number(options, "angle_deg", where, 10.0)))
            return cls(name, rps, zigzag=zigzag)
        raise ScenarioError(f"{where}.mode: must be 'steps' or 'zigzag', got {mode!r}")

    @property
    def output_names(self):
        return ["rudder_angle_cmd", "propeller_rps_cmd"]

    def setup(self, start_time, inputs):
        self._sign, self._psi_execute = 1.0, None
        return {"rudder_angle_cmd": self._yaw_moment(start_time, inputs), "propeller_rps_cmd": self.tau_u}

    def step(self, time, step_size, inputs):
        return {"rudder_angle_cmd": self._yaw_moment(time, inputs), "propeller_rps_cmd": self.tau_u}
