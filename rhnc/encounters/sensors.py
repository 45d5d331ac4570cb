"""How the own ship sees other ships: AIS reports and radar detections, seeded.

Both sensors take the true targets (the traffic participant's ``targets`` port: x, y, vx,
vy, radius; SI) and publish what an own ship would receive; a target tracker
(:mod:`rhnc.encounters.tracker`) turns that into estimated targets.

AIS (:class:`AisParticipant`)
    Each target transmits position reports at the ITU-R M.1371-5 Class A intervals
    (:func:`reporting_interval_s`, the table in ``docs/traffic.md``): by speed over ground,
    shorter while it changes course.  A report carries the position, speed and course at
    its time of transmission with Gaussian noise (quantised as the message quantises them:
    SOG 0.1 kn, COG 0.1 deg), is lost with ``dropout_probability``, and every target
    falls silent for ``gap_duration_s`` at random instants (``gaps_per_hour``: a receiver
    out of range, a shadowed antenna, a busy channel).  A report arrives ``latency_s`` (+ a
    uniform ``latency_jitter_s``) after transmission and keeps its time stamp.  Output
    ``reports`` (n, 6): per target row (its identity, as the MMSI is), the latest report
    received: received (1, or 0 until the first one arrives), time of the position [s],
    x, y [m], SOG [m/s], COG [rad].
Radar (:class:`RadarParticipant`)
    One scan per step: each target within ``detection_range_nm`` is detected with
    ``detection_probability``; its range and bearing from the own ship carry Gaussian noise.
    No clutter, no false alarms, no identity.  Output ``detections`` (n, 6): detected (1,
    or 0 for a row without a detection), time [s], range [m], bearing [rad, clockwise from
    north], own x, own y [m] at the scan; the detections come first, sorted by bearing (a
    radar does not know which ship is which).

Same seed, same inputs: same series (one ``numpy.random.Generator`` per participant,
drawn in a fixed order).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Annotated, Any

import numpy as np

from pydantic import PlainValidator

from orchestrator.errors import ModelError
from orchestrator.geometry import DEG, KNOT, NM, wrap_angle
from orchestrator.participant import BuildContext, Participant, Value, check_options
from orchestrator.toml_input import NonNegative, NonNegativeInt, Positive, TomlTable, fail, is_finite_number, shown

#: ITU-R M.1371-5, Annex 1, Table 1 (Class A shipborne mobile equipment under way):
#: (lowest SOG [kn], interval [s], interval while changing course [s]).
CLASS_A_INTERVALS = ((0.0, 10.0, 10.0 / 3.0), (14.0, 6.0, 2.0), (23.0, 2.0, 2.0))
#: Ships at anchor or moored and not moving faster than 3 kn report every 3 min.
AT_ANCHOR_INTERVAL_S = 180.0
AT_ANCHOR_SPEED_KN = 3.0


def reporting_interval_s(speed_kn: float, changing_course: bool, at_anchor: bool = False) -> float:
    """Class A reporting interval [s] (ITU-R M.1371-5, Annex 1, Table 1)."""
    if at_anchor and speed_kn <= AT_ANCHOR_SPEED_KN:
        return AT_ANCHOR_INTERVAL_S
    interval = CLASS_A_INTERVALS[0]
    for row in CLASS_A_INTERVALS:
        if speed_kn > row[0]:
            interval = row
    return interval[2] if changing_course else interval[1]


def _probability(value: Any) -> float:
    if not is_finite_number(value) or not 0.0 <= value <= 1.0:
        raise fail(f"must be a probability within [0, 1], got {shown(value)}")
    return float(value)


Probability = Annotated[float, PlainValidator(_probability)]


class AisOptions(TomlTable):
    """Options of ``type = "ais"`` (defaults: the realistic levels of ``docs/traffic.md``)."""

    seed: NonNegativeInt = 0
    position_sigma_m: NonNegative = 10.0
    speed_sigma_kn: NonNegative = 0.2
    course_sigma_deg: NonNegative = 2.0
    dropout_probability: Probability = 0.1
    gaps_per_hour: NonNegative = 2.0
    gap_duration_s: NonNegative = 60.0
    latency_s: NonNegative = 2.0
    latency_jitter_s: NonNegative = 2.0
    changing_course_deg_min: Positive = 10.0


class AisParticipant(Participant):
    """AIS position reports of every target (module docstring).

    Inputs: ``targets`` ((n, 5) true targets).  Output: ``reports`` ((n, 6)).
    """

    OPTIONS = tuple(AisOptions.model_fields)

    def __init__(self, name: str, options: AisOptions) -> None:
        super().__init__(name)
        self.options = options
        self._reset()

    @classmethod
    def from_options(cls, name: str, options: Mapping[str, Any], context: BuildContext) -> "AisParticipant":
        return cls(name, check_options(AisOptions, options, context.where))

    input_names = property(lambda self: ("targets",))
    output_names = property(lambda self: ("reports",))

    def _reset(self) -> None:
        self._rng = np.random.default_rng(self.options.seed)
        self._previous: tuple[float, np.ndarray] | None = None
        self._next_transmission: np.ndarray | None = None
        self._silent_until: np.ndarray | None = None
        self._in_flight: list[tuple[float, int, np.ndarray]] = []  # (arrival, row, report)
        self._latest: np.ndarray | None = None
        self.sent = self.lost = 0

    def setup(self, start_time: float, inputs: Mapping[str, Value]) -> dict[str, Value]:
        self._reset()
        if "targets" not in inputs:
            return {"reports": np.zeros((0, 6))}
        return self._observe(start_time, np.asarray(inputs["targets"], dtype=float).reshape(-1, 5))

    def step(self, time: float, step_size: float, inputs: Mapping[str, Value]) -> dict[str, Value]:
        if "targets" not in inputs:
            raise ModelError(f"participant '{self.name}': input 'targets' must be connected")
        return self._observe(time, np.asarray(inputs["targets"], dtype=float).reshape(-1, 5))

    def _observe(self, time: float, targets: np.ndarray) -> dict[str, Value]:
        n = len(targets)
        if self._latest is None or len(self._latest) != n:
            self._latest = np.zeros((n, 6))
            # the first transmissions spread over an interval (the ships' slots are not aligned)
            self._next_transmission = time + self._rng.uniform(0.0, 1.0, n) * self._intervals(targets, None)
            self._silent_until = np.full(n, -np.inf)
        if self._previous is not None and self._previous[0] < time:
            self._transmit(self._previous[0], self._previous[1], time, targets)
        self._previous = (time, targets.copy())
        arrived = [entry for entry in self._in_flight if entry[0] <= time + 1e-9]
        self._in_flight = [entry for entry in self._in_flight if entry[0] > time + 1e-9]
        for _, row, report in sorted(arrived, key=lambda entry: entry[2][0]):
            if self._latest[row, 0] == 0.0 or report[0] > self._latest[row, 1]:  # not by an older, late one
                self._latest[row] = np.r_[1.0, report]
        return {"reports": self._latest.copy()}

    def _intervals(self, targets: np.ndarray, previous: np.ndarray | None, dt: float = 1.0) -> np.ndarray:
        speed_kn = np.hypot(targets[:, 2], targets[:, 3]) / KNOT
        turning = np.zeros(len(targets), dtype=bool)
        if previous is not None and len(previous) == len(targets) and dt > 0:
            change = wrap_angle(np.arctan2(targets[:, 3], targets[:, 2]) - np.arctan2(previous[:, 3], previous[:, 2]))
            turning = np.abs(change) / DEG / (dt / 60.0) > self.options.changing_course_deg_min
        return np.array([reporting_interval_s(s, bool(c)) for s, c in zip(speed_kn, turning)])

    def _transmit(self, t0: float, before: np.ndarray, t1: float, after: np.ndarray) -> None:
        """Every transmission in (t0, t1], the true state interpolated between the two samples."""
        o = self.options
        if len(before) != len(after):
            before = after
        intervals = self._intervals(after, before, t1 - t0)
        for row in range(len(after)):
            while self._next_transmission[row] <= t1 + 1e-9:
                t = float(self._next_transmission[row])
                self._next_transmission[row] = t + intervals[row]
                w = 0.0 if t1 <= t0 else min(max((t - t0) / (t1 - t0), 0.0), 1.0)
                state = before[row] + w * (after[row] - before[row])
                noise = self._rng.standard_normal(4)
                draws = self._rng.uniform(0.0, 1.0, 3)
                self.sent += 1
                if draws[0] < o.gaps_per_hour * intervals[row] / 3600.0:
                    self._silent_until[row] = t + o.gap_duration_s
                if t < self._silent_until[row] or draws[1] < o.dropout_probability:
                    self.lost += 1
                    continue
                sog = max(math.hypot(state[2], state[3]) + noise[2] * o.speed_sigma_kn * KNOT, 0.0)
                cog = math.atan2(state[3], state[2]) + noise[3] * o.course_sigma_deg * DEG
                report = np.array([t, state[0] + noise[0] * o.position_sigma_m, state[1] + noise[1] * o.position_sigma_m,
                                   round(sog / KNOT, 1) * KNOT, float(wrap_angle(round(cog / DEG, 1) * DEG))])
                arrival = t + o.latency_s + draws[2] * o.latency_jitter_s
                self._in_flight.append((arrival, row, report))

    def summary(self) -> dict[str, Any]:
        return {"reports_sent": self.sent, "reports_lost": self.lost}


class RadarOptions(TomlTable):
    """Options of ``type = "radar"`` (defaults: IMO MSC.192(79), see ``docs/traffic.md``)."""

    seed: NonNegativeInt = 0
    range_sigma_m: NonNegative = 57.0
    bearing_sigma_deg: NonNegative = 0.5
    detection_range_nm: Positive = 11.0
    detection_probability: Probability = 0.95


class RadarParticipant(Participant):
    """Radar detections of the targets within range (module docstring).

    Inputs: own ``x``, ``y`` [m], ``targets`` ((n, 5)).  Output: ``detections`` ((n, 6)).
    """

    OPTIONS = tuple(RadarOptions.model_fields)

    def __init__(self, name: str, options: RadarOptions) -> None:
        super().__init__(name)
        self.options = options
        self._rng = np.random.default_rng(options.seed)

    @classmethod
    def from_options(cls, name: str, options: Mapping[str, Any], context: BuildContext) -> "RadarParticipant":
        return cls(name, check_options(RadarOptions, options, context.where))

    input_names = property(lambda self: ("x", "y", "targets"))
    output_names = property(lambda self: ("detections",))

    def setup(self, start_time: float, inputs: Mapping[str, Value]) -> dict[str, Value]:
        self._rng = np.random.default_rng(self.options.seed)
        if not all(port in inputs for port in self.input_names):
            return {"detections": np.zeros((0, 6))}
        return self._scan(start_time, inputs)

    def step(self, time: float, step_size: float, inputs: Mapping[str, Value]) -> dict[str, Value]:
        self.require_inputs(inputs)
        return self._scan(time, inputs)

    def _scan(self, time: float, inputs: Mapping[str, Value]) -> dict[str, Value]:
        o = self.options
        own = np.array([float(inputs["x"]), float(inputs["y"])])
        targets = np.asarray(inputs["targets"], dtype=float).reshape(-1, 5)
        rows = np.zeros((len(targets), 6))
        for i, target in enumerate(targets):
            noise = self._rng.standard_normal(2)
            draw = self._rng.uniform()
            offset = target[:2] - own
            distance = float(np.hypot(*offset))
            if distance > o.detection_range_nm * NM or draw >= o.detection_probability:
                continue
            rows[i] = [1.0, time, max(distance + noise[0] * o.range_sigma_m, 0.0),
                       float(wrap_angle(math.atan2(offset[1], offset[0]) + noise[1] * o.bearing_sigma_deg * DEG)),
                       own[0], own[1]]
        order = np.argsort(np.where(rows[:, 0] > 0, rows[:, 3], np.inf), kind="stable")
        return {"detections": rows[order]}
