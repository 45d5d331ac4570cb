"""When every obstacle's closest approach is final: a stop condition that cannot change the judged separation.

A run is judged (``colregs`` analysis) on each obstacle's closest approach over the
recorded samples.  Once no obstacle can come closer than it already has before the run
ends, the rest of the run cannot change those figures, and ``stop_when = "watch.settled > 0.5"``
may end it there.

The bound, for an obstacle at relative position ``r = p_obstacle - p_own`` now, sailing at
its constant velocity ``v``, and an own ship that sails at most ``U`` over ground: at any
time ``tau`` from now, ``|d(tau)| >= |r + v tau| - U tau =: g(tau)``.  ``g`` is convex;
with ``|v| <= U`` it never rises (its least value is at the end of the run), else it is
least at ``tau* = (-r.v + U sqrt((|v|^2 |r|^2 - (r.v)^2) / (|v|^2 - U^2))) / |v|^2``.
An obstacle is settled when the least ``g`` over the time left is at least its closest
approach so far; the run is, when every obstacle is.

The watch does not know when each of its inputs was taken: in the master's Gauss-Seidel
order the own ship has already stepped to ``t + dt`` when the watch steps at ``t``, while
the obstacles are those of ``t``.  So it allows the own position it sees to be up to one
of its steps ``s`` off the obstacles' time, an error of at most ``U s`` in each range: it
looks ahead over the time left plus ``s``, takes ``U s`` off the bound and adds ``U s`` to
the closest approach so far (a range it saw may be ``U s`` longer than the one recorded).
Settled is then ``least g - closest - 2 U s >= 0``.

The bound holds as long as its two premises do, and the watch checks both on what it sees:
an obstacle whose velocity changes (a manoeuvre) or an own ship faster over ground than
``max_own_speed_kn`` between two samples makes the watch give up for the rest of the run
(``settled`` stays 0; its summary says why).  ``max_own_speed_kn`` is therefore a declared
limit of the own ship (its top speed with the current), not a guess that the run can break
unseen.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from orchestrator.geometry import KNOT, NM
from orchestrator.participant import BuildContext, Participant, Value, check_options
from orchestrator.toml_input import Positive, TomlTable

#: Relative change of an obstacle's velocity [m/s] below which it counts as unchanged (round-off).
VELOCITY_TOLERANCE_MPS = 1e-6


def least_future_range_m(relative_m, velocity_mps, own_speed_mps: float, time_left_s: float) -> float:
    """Lower bound [m] of the range to an obstacle over the next ``time_left_s`` [s].

    Parameters
    ----------
    relative_m : (2,) array
        Obstacle position minus own position now [m].
    velocity_mps : (2,) array
        The obstacle's constant velocity [m/s].
    own_speed_mps : float
        Most the own ship can sail over ground [m/s].
    time_left_s : float
        Time to the end of the run [s].
    """
    r = np.asarray(relative_m, dtype=float)
    v = np.asarray(velocity_mps, dtype=float)
    speed_u = float(own_speed_mps)
    left = max(float(time_left_s), 0.0)

    def bound(tau: float) -> float:
        return float(np.hypot(*(r + v * tau)) - speed_u * tau)

    a, b, c = float(v @ v), float(r @ v), float(r @ r)
    if a <= speed_u * speed_u:  # g never rises: least at the end
        return min(bound(0.0), bound(left))
    tau_star = (-b + speed_u * math.sqrt(max(a * c - b * b, 0.0) / (a - speed_u * speed_u))) / a
    return min(bound(0.0), bound(left), bound(min(max(tau_star, 0.0), left)))


class SeparationWatchOptions(TomlTable):
    """Options of ``type = "separation_watch"``."""

    max_own_speed_kn: Positive


class SeparationWatch(Participant):
    """Publishes ``settled`` = 1 once no obstacle can come closer than its closest approach so far.

    Options: ``max_own_speed_kn`` (the own ship's top speed over ground).
    Inputs: ``x``, ``y`` [m] (the own ship), ``obstacles`` ((n, 5): x, y, vx, vy, radius; SI).
    Outputs: ``settled`` (0 or 1) and ``least_future_margin_m`` (the smallest, over the
    obstacles, of the bound less the closest approach so far, less ``2 U s`` for inputs up to
    one step apart in time; negative while any can still close;
    finite, as every output must be).  A run without obstacles is never settled.
    """

    OPTIONS = tuple(SeparationWatchOptions.model_fields)

    def __init__(self, name: str, max_own_speed_mps: float, stop_time_s: float, step_s: float) -> None:
        super().__init__(name)
        self.max_own_speed_mps = max_own_speed_mps
        self.stop_time_s = stop_time_s
        self.step_s = step_s  # how far apart in time the own position and the obstacles seen may be
        self._reset()

    def _reset(self) -> None:
        self.closest_m: np.ndarray | None = None
        self.velocities: np.ndarray | None = None
        self.last: tuple[float, np.ndarray] | None = None
        self.gave_up: str | None = None
        self.settled_at_s: float | None = None

    @classmethod
    def from_options(cls, name: str, options: Mapping[str, Any], context: BuildContext) -> "SeparationWatch":
        checked = check_options(SeparationWatchOptions, options, context.where)
        return cls(name, checked.max_own_speed_kn * KNOT, context.stop_time, context.step_size)

    input_names = property(lambda self: ("x", "y", "obstacles"))
    output_names = property(lambda self: ("settled", "least_future_margin_m"))

    def setup(self, start_time: float, inputs: Mapping[str, Value]) -> dict[str, Value]:
        self._reset()
        return self._observe(start_time, inputs) if all(port in inputs for port in self.input_names) else {}

    def step(self, time: float, step_size: float, inputs: Mapping[str, Value]) -> dict[str, Value]:
        self.require_inputs(inputs)
        return self._observe(time, inputs)

    def _observe(self, time: float, inputs: Mapping[str, Value]) -> dict[str, Value]:
        own = np.array([float(inputs["x"]), float(inputs["y"])])
        obstacles = np.asarray(inputs["obstacles"], dtype=float).reshape(-1, 5)
        self._check_premises(time, own, obstacles)
        ranges = np.hypot(obstacles[:, 0] - own[0], obstacles[:, 1] - own[1])
        self.closest_m = ranges if self.closest_m is None or len(self.closest_m) != len(ranges) else np.minimum(
            self.closest_m, ranges)
        if not len(obstacles):  # nothing to watch: never settled (a run without obstacles is not ended)
            return {"settled": 0.0, "least_future_margin_m": 0.0}
        left = self.stop_time_s - time + self.step_s
        skew_m = self.max_own_speed_mps * self.step_s  # the own position seen may be a step off the obstacles'
        margin = min(least_future_range_m(row[:2] - own, row[2:4], self.max_own_speed_mps, left) - closest
                     for row, closest in zip(obstacles, self.closest_m)) - 2.0 * skew_m
        settled = margin >= 0.0 and self.gave_up is None
        if settled and self.settled_at_s is None:
            self.settled_at_s = time
        return {"settled": 1.0 if settled else 0.0, "least_future_margin_m": float(margin)}

    def _check_premises(self, time: float, own: np.ndarray, obstacles: np.ndarray) -> None:
        """Give up for the rest of the run when an obstacle changed velocity or the own ship outran its limit."""
        if self.gave_up is not None:
            return
        velocities = obstacles[:, 2:4].copy()
        if self.velocities is not None and (self.velocities.shape != velocities.shape or np.any(
                np.abs(self.velocities - velocities) > VELOCITY_TOLERANCE_MPS)):
            self.gave_up = f"an obstacle changed its velocity at t = {time:g} s"
        if self.last is not None and time > self.last[0]:
            speed = float(np.hypot(*(own - self.last[1]))) / (time - self.last[0])
            if speed > self.max_own_speed_mps:
                self.gave_up = (f"the own ship sailed {speed / KNOT:.2f} kn over ground at t = {time:g} s, more than "
                                f"max_own_speed_kn = {self.max_own_speed_mps / KNOT:g}")
        self.velocities = velocities
        self.last = (time, own)

    def summary(self) -> dict[str, Any]:
        return {"settled_at_s": self.settled_at_s, "gave_up": self.gave_up,
                "closest_nm": None if self.closest_m is None else [float(c) / NM for c in self.closest_m]}
