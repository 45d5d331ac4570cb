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
from typing import Annotated, Any

from pydantic import PlainValidator, model_validator

from orchestrator.errors import ScenarioError
from orchestrator.geometry import wrap_angle
from orchestrator.participant import BuildContext, Participant, check_options, is_finite_number
from orchestrator.toml_input import Finite, TomlTable, fail, fail_whole, shown


def _schedule(value: Any) -> tuple[tuple[float, float], ...]:
    if not isinstance(value, list) or not all(
            isinstance(s, list) and len(s) == 2 and all(is_finite_number(v) for v in s) for s in value):
        raise fail(f"must be a list of [time_s, value] pairs of finite numbers, got {shown(value)}")
    return tuple((float(t), float(v)) for t, v in value)


def _mode(value: Any) -> str:
    if value not in ("steps", "zigzag"):
        raise fail(f"must be 'steps' or 'zigzag', got {shown(value)}")
    return value


Schedule = Annotated[tuple[tuple[float, float], ...], PlainValidator(_schedule)]
Mode = Annotated[str, PlainValidator(_mode)]


class ScriptedTauOptions(TomlTable):
    """Options of ``type = "scripted_tau"``."""

    mode: Mode = "steps"
    tau_u_N: Finite = 0.0
    tau_r_steps: Schedule = ()  # [time_s, yaw_moment_Nm]
    tau_r_Nm: Finite | None = None
    angle_deg: Finite = 10.0
    execute_s: Finite = 0.0

    @model_validator(mode="after")
    def _zigzag_moment(self):
        if self.mode == "zigzag" and self.tau_r_Nm is None:
            raise fail_whole("missing option '{prefix}tau_r_Nm' (the zig-zag's yaw moment [N m])")
        return self


class ScriptedRudderOptions(TomlTable):
    """Options of ``type = "scripted_rudder"``."""

    mode: Mode = "steps"
    propeller_rps: Finite
    rudder_steps: Schedule = ()  # [time_s, angle_deg]
    rudder_deg: Finite | None = None
    angle_deg: Finite = 10.0
    execute_s: Finite = 0.0

    @model_validator(mode="after")
    def _zigzag_rudder(self):
        if self.mode == "zigzag" and self.rudder_deg is None:
            raise fail_whole("missing option '{prefix}rudder_deg' (the zig-zag's rudder angle [deg])")
        return self


class ScriptedTau(Participant):
    """Open-loop tau = [surge force, yaw moment] from a script."""

    #: Option keys (the schema docs/participants.md is checked against).
    OPTIONS = tuple(ScriptedTauOptions.model_fields)

    def __init__(self, name: str, tau_u: float, steps=(), zigzag=None) -> None:
        super().__init__(name)
        self.tau_u = tau_u
        self.steps = sorted(steps)
        self.zigzag = zigzag  # (execute_s, tau_r, angle_rad) or None
        self._sign = 1.0
        self._psi_execute: float | None = None  # heading [rad] when the zigzag began

    @classmethod
    def from_options(cls, name: str, options: Mapping, context: BuildContext) -> "ScriptedTau":
        checked = check_options(ScriptedTauOptions, options, context.where)
        if checked.mode == "steps":
            return cls(name, checked.tau_u_N, steps=list(checked.tau_r_steps))
        return cls(name, checked.tau_u_N, zigzag=(checked.execute_s, checked.tau_r_Nm, math.radians(checked.angle_deg)))

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
        change = float(wrap_angle(psi - self._psi_execute))
        if self._sign > 0 and change >= angle:
            self._sign = -1.0
        elif self._sign < 0 and change <= -angle:
            self._sign = 1.0
        return self._sign * moment


class ScriptedRudder(ScriptedTau):
    """Open-loop rudder angle and propeller revolutions, for plants at actuator level.

    Options: ``propeller_rps`` (constant revolutions [1/s]); ``rudder_steps``, a list of
    ``[time_s, angle_deg]`` (``mode = "steps"``, positive to starboard); or
    ``mode = "zigzag"`` with ``rudder_deg``, ``angle_deg`` and ``execute_s``: the IMO zig-zag,
    +rudder until the heading has changed by +angle, then -rudder until -angle, and so on.
    Outputs ``rudder_angle_cmd`` [rad] and ``propeller_rps_cmd`` [1/s].
    """

    OPTIONS = tuple(ScriptedRudderOptions.model_fields)

    @classmethod
    def from_options(cls, name: str, options: Mapping, context: BuildContext) -> "ScriptedRudder":
        checked = check_options(ScriptedRudderOptions, options, context.where)
        if checked.mode == "steps":
            return cls(name, checked.propeller_rps,
                       steps=[(t, math.radians(angle)) for t, angle in checked.rudder_steps])
        return cls(name, checked.propeller_rps, zigzag=(checked.execute_s, math.radians(checked.rudder_deg),
                                                        math.radians(checked.angle_deg)))

    @property
    def output_names(self):
        return ["rudder_angle_cmd", "propeller_rps_cmd"]

    def setup(self, start_time, inputs):
        self._sign, self._psi_execute = 1.0, None
        return {"rudder_angle_cmd": self._yaw_moment(start_time, inputs), "propeller_rps_cmd": self.tau_u}

    def step(self, time, step_size, inputs):
        return {"rudder_angle_cmd": self._yaw_moment(time, inputs), "propeller_rps_cmd": self.tau_u}
