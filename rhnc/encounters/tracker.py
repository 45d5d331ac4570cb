"""Target tracker: AIS reports and radar detections -> estimated targets, as the traffic publishes them.

Each track is a Kalman filter on (x, y, vx, vy) [m, m/s] with the constant-velocity model
driven by white-noise acceleration of spectral density ``sigma_a^2`` (``process_noise_mps2``
= sigma_a, sized for a manoeuvring ship: a ship of 18 kn turning at 0.5 deg/s accelerates
sideways at 0.08 m/s^2; 0.05 m/s^2 lets the filter follow such a turn within a few
reports).  Measurements:

* an AIS report (time of the position, x, y, SOG, COG) updates position and velocity; the
  velocity's covariance is the SOG/COG noise carried through ``(s cos c, s sin c)``.  A
  report is associated by its identity (the row of the ``reports`` input, as the MMSI is):
  to the track holding that identity, else to the nearest untagged track inside the
  gate, else it starts a tentative track.  A report older than its track's last update
  (out of sequence) is dropped; a report is processed at its own time stamp, so latency
  only delays it;
* a radar detection (range, bearing from the own ship) updates the position; its
  covariance is the range/bearing noise turned into the plane.  Detections are associated
  by gated global nearest neighbour (greedy on the Mahalanobis distance, one detection
  per track per scan, confirmed tracks first); one outside every gate starts a tentative
  track, unless it lies within four gates of a confirmed track (that track's outlier: a
  99 % gate leaves one detection in a hundred outside).

Track management: a tentative track is confirmed after ``confirm_hits`` updates (M)
within ``confirm_window_s`` of its first (N = the scans in that window), else dropped; a
confirmed track is deleted when no measurement has updated it for ``delete_after_s``.

Output ``obstacles``: one row per slot (x, y, vx, vy, radius; SI), then the static
obstacles of the ``static_obstacles`` input (charted, passed on as they are).  A track
keeps its slot, so its row, for life: the controller and the trigger identify targets by
row.  A slot without a confirmed track is a *vacant* row: 100 nm north of the own ship,
at rest, radius 0 (outside every warning range, no constraint); a new track takes the
slot vacated longest ago.  There are as many slot rows as slots used so far (at most
``max_tracks``).  ``track_valid`` ((slots,)): 1 for a confirmed track's row.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from orchestrator.errors import ModelError
from orchestrator.geometry import DEG, KNOT, NM
from orchestrator.participant import BuildContext, Participant, Value, check_options
from orchestrator.toml_input import NonNegative, Positive, PositiveInt, TomlTable

#: Chi-square 99 % gate for 2 degrees of freedom.
GATE_CHI2_2DOF = 9.21
#: A detection outside every gate but within this many gates of a confirmed track is taken
#: for that track's outlier (1 % of them fall outside a 99 % gate) and starts no track.
INITIATION_GATE_FACTOR = 4.0
#: A vacant slot's row lies this far north of the own ship [m].
VACANT_OFFSET_M = 100.0 * NM


class TrackerOptions(TomlTable):
    """Options of ``type = "tracker"``."""

    target_radius_nm: NonNegative
    max_tracks: PositiveInt = 8
    process_noise_mps2: Positive = 0.05
    confirm_hits: PositiveInt = 3
    confirm_window_s: Positive = 60.0
    delete_after_s: Positive = 90.0
    gate_chi2: Positive = GATE_CHI2_2DOF
    ais_position_sigma_m: Positive = 10.0
    ais_speed_sigma_kn: Positive = 0.2
    ais_course_sigma_deg: Positive = 2.0
    radar_range_sigma_m: Positive = 57.0
    radar_bearing_sigma_deg: Positive = 0.5
    initial_speed_sigma_mps: Positive = 5.0


class Track:
    """One Kalman filter on (x, y, vx, vy) [m, m/s] at ``time_s``, with its bookkeeping."""

    def __init__(self, time_s: float, state: np.ndarray, covariance: np.ndarray, ais_id: int | None) -> None:
        self.time_s = time_s
        self.state = state
        self.covariance = covariance
        self.ais_id = ais_id
        self.born_s = time_s
        self.hits = 1
        self.last_update_s = time_s
        self.confirmed = False
        self.slot: int | None = None

    def predicted(self, time_s: float, q: float) -> tuple[np.ndarray, np.ndarray]:
        """State and covariance predicted to ``time_s`` (CV model, white-noise acceleration ``q`` [m^2/s^3])."""
        dt = max(time_s - self.time_s, 0.0)
        F = np.eye(4)
        F[0, 2] = F[1, 3] = dt
        Q = q * np.block([[dt ** 3 / 3 * np.eye(2), dt ** 2 / 2 * np.eye(2)],
                          [dt ** 2 / 2 * np.eye(2), dt * np.eye(2)]])
        return F @ self.state, F @ self.covariance @ F.T + Q

    def update(self, time_s: float, z: np.ndarray, H: np.ndarray, R: np.ndarray, q: float) -> None:
        x, P = self.predicted(time_s, q)
        S = H @ P @ H.T + R
        K = P @ H.T @ np.linalg.inv(S)
        self.state = x + K @ (z - H @ x)
        I_KH = np.eye(4) - K @ H
        self.covariance = I_KH @ P @ I_KH.T + K @ R @ K.T  # Joseph form: stays symmetric positive
        self.time_s = time_s
        self.last_update_s = max(self.last_update_s, time_s)
        self.hits += 1


def mahalanobis2(track: Track, time_s: float, z: np.ndarray, H: np.ndarray, R: np.ndarray, q: float) -> float:
    """Squared Mahalanobis distance of a measurement from a track's prediction."""
    x, P = track.predicted(time_s, q)
    innovation = z - H @ x
    return float(innovation @ np.linalg.solve(H @ P @ H.T + R, innovation))


H_POSITION = np.hstack([np.eye(2), np.zeros((2, 2))])


class TrackerParticipant(Participant):
    """Tracks from AIS and radar, published in the traffic participant's layout (module docstring).

    Inputs (each optional): own ``x``, ``y`` [m] (needed with radar), ``ais_reports``,
    ``radar_detections``, ``static_obstacles``.  Outputs: ``obstacles``, ``track_valid``,
    ``confirmed_tracks``.
    """

    OPTIONS = tuple(TrackerOptions.model_fields)
    #: The ``obstacles`` published are estimates; the analyses judge the true targets.
    estimates_targets = True

    def __init__(self, name: str, options: TrackerOptions) -> None:
        super().__init__(name)
        self.options = options
        self._reset()

    @classmethod
    def from_options(cls, name: str, options: Mapping[str, Any], context: BuildContext) -> "TrackerParticipant":
        return cls(name, check_options(TrackerOptions, options, context.where))

    input_names = property(lambda self: ("x", "y", "ais_reports", "radar_detections", "static_obstacles"))
    output_names = property(lambda self: ("obstacles", "track_valid", "confirmed_tracks"))

    def _reset(self) -> None:
        self.tracks: list[Track] = []
        self._slots: list[Track | None] = []
        self._vacated_s: list[float] = []
        self._ais_seen: dict[int, float] = {}
        self.initiated = self.confirmed = self.deleted = 0

    @property
    def _q(self) -> float:
        return self.options.process_noise_mps2 ** 2

    def setup(self, start_time: float, inputs: Mapping[str, Value]) -> dict[str, Value]:
        self._reset()
        return self._process(start_time, inputs)

    def step(self, time: float, step_size: float, inputs: Mapping[str, Value]) -> dict[str, Value]:
        if "radar_detections" in inputs and not ("x" in inputs and "y" in inputs):
            raise ModelError(f"participant '{self.name}': inputs 'x' and 'y' must be connected with radar")
        return self._process(time, inputs)

    # -- measurements ------------------------------------------------------------------------
    def _process(self, time: float, inputs: Mapping[str, Value]) -> dict[str, Value]:
        measurements: list[tuple[float, int, Any]] = []  # (time, kind, payload)
        if "ais_reports" in inputs:
            reports = np.asarray(inputs["ais_reports"], dtype=float).reshape(-1, 6)
            for row, report in enumerate(reports):
                if report[0] > 0 and report[1] > self._ais_seen.get(row, -math.inf):
                    self._ais_seen[row] = float(report[1])
                    measurements.append((float(report[1]), 0, (row, report[1:])))
        scans: dict[float, list[np.ndarray]] = {}
        if "radar_detections" in inputs:
            for detection in np.asarray(inputs["radar_detections"], dtype=float).reshape(-1, 6):
                if detection[0] > 0:
                    scans.setdefault(float(detection[1]), []).append(detection[1:])
        measurements += [(t, 1, rows) for t, rows in scans.items()]
        for t, kind, payload in sorted(measurements, key=lambda m: (m[0], m[1])):
            if kind == 0:
                self._ais_update(t, *payload)
            else:
                self._radar_scan(t, payload)
        self._manage(time)
        own = (float(inputs.get("x", 0.0)), float(inputs.get("y", 0.0)))
        static = np.asarray(inputs.get("static_obstacles", np.zeros((0, 5))), dtype=float).reshape(-1, 5)
        rows, valid = self._published(time, own)
        return {"obstacles": np.vstack([rows, static]), "track_valid": valid, "confirmed_tracks": float(valid.sum())}

    def _ais_update(self, t: float, row: int, report: np.ndarray) -> None:
        o = self.options
        sog, cog = float(report[3]), float(report[4])
        z = np.array([report[1], report[2], sog * math.cos(cog), sog * math.sin(cog)])
        J = np.array([[math.cos(cog), -sog * math.sin(cog)], [math.sin(cog), sog * math.cos(cog)]])
        R = np.zeros((4, 4))
        R[:2, :2] = np.eye(2) * o.ais_position_sigma_m ** 2
        R[2:, 2:] = J @ np.diag([(o.ais_speed_sigma_kn * KNOT) ** 2, (o.ais_course_sigma_deg * DEG) ** 2]) @ J.T
        R[2:, 2:] += np.eye(2) * 1e-6
        track = next((tr for tr in self.tracks if tr.ais_id == row), None)
        if track is None:
            candidates = [(mahalanobis2(tr, t, z[:2], H_POSITION, R[:2, :2], self._q), k)
                          for k, tr in enumerate(self.tracks) if tr.ais_id is None and tr.time_s <= t]
            candidates = [c for c in candidates if c[0] <= o.gate_chi2]
            if candidates:
                track = self.tracks[min(candidates)[1]]
                track.ais_id = row
        if track is None:
            self.tracks.append(Track(t, z.copy(), R.copy(), row))
            self.initiated += 1
            return
        if t < track.time_s:
            return  # out of sequence: an older report than the track's last update
        track.update(t, z, np.eye(4), R, self._q)

    def _radar_scan(self, t: float, detections: list[np.ndarray]) -> None:
        o = self.options
        measured = []
        for detection in detections:
            r, b, ox, oy = detection[1:]
            z = np.array([ox + r * math.cos(b), oy + r * math.sin(b)])
            J = np.array([[math.cos(b), -r * math.sin(b)], [math.sin(b), r * math.cos(b)]])
            R = J @ np.diag([o.radar_range_sigma_m ** 2, (o.radar_bearing_sigma_deg * DEG) ** 2]) @ J.T
            measured.append((z, R + np.eye(2) * 1e-6))
        pairs, near_confirmed = [], set()
        for k, track in enumerate(self.tracks):
            if track.time_s > t:
                continue
            for j, (z, R) in enumerate(measured):
                d2 = mahalanobis2(track, t, z, H_POSITION, R, self._q)
                if d2 <= o.gate_chi2:
                    pairs.append((not track.confirmed, d2, k, j))
                if track.confirmed and d2 <= INITIATION_GATE_FACTOR * o.gate_chi2:
                    near_confirmed.add(j)
        used_tracks, used_detections = set(), set()
        for _, _distance, k, j in sorted(pairs):  # confirmed tracks choose first
            if k in used_tracks or j in used_detections:
                continue
            used_tracks.add(k)
            used_detections.add(j)
            self.tracks[k].update(t, measured[j][0], H_POSITION, measured[j][1], self._q)
        for j, (z, R) in enumerate(measured):
            if j not in used_detections and j not in near_confirmed:
                P = np.zeros((4, 4))
                P[:2, :2] = R
                P[2:, 2:] = np.eye(2) * o.initial_speed_sigma_mps ** 2
                self.tracks.append(Track(t, np.r_[z, 0.0, 0.0], P, None))
                self.initiated += 1

    # -- track management ---------------------------------------------------------------------
    def _manage(self, time: float) -> None:
        o = self.options
        kept = []
        for track in self.tracks:
            if not track.confirmed:
                if track.hits >= o.confirm_hits:
                    track.confirmed = True
                    self.confirmed += 1
                    self._assign_slot(track, time)
                elif time - track.born_s > o.confirm_window_s:
                    continue  # not confirmed in its window: dropped
            elif time - track.last_update_s > o.delete_after_s:
                self.deleted += 1
                if track.slot is not None:
                    self._slots[track.slot] = None
                    self._vacated_s[track.slot] = time
                continue
            kept.append(track)
        self.tracks = kept

    def _assign_slot(self, track: Track, time: float) -> None:
        vacant = [k for k, occupant in enumerate(self._slots) if occupant is None]
        if len(self._slots) < self.options.max_tracks:
            self._slots.append(track)
            self._vacated_s.append(-math.inf)
            track.slot = len(self._slots) - 1
        elif vacant:
            slot = min(vacant, key=lambda k: self._vacated_s[k])
            self._slots[slot] = track
            track.slot = slot
        # else: every slot taken; the track is kept but not published

    def _published(self, time: float, own: tuple[float, float]) -> tuple[np.ndarray, np.ndarray]:
        radius = self.options.target_radius_nm * NM
        rows = np.zeros((len(self._slots), 5))
        valid = np.zeros(len(self._slots))
        for k, track in enumerate(self._slots):
            if track is None:
                rows[k] = [own[0] + VACANT_OFFSET_M, own[1], 0.0, 0.0, 0.0]
                continue
            state, _ = track.predicted(time, self._q)
            rows[k] = [*state, radius]
            valid[k] = 1.0
        return rows, valid

    def summary(self) -> dict[str, Any]:
        return {"tracks_initiated": self.initiated, "tracks_confirmed": self.confirmed,
                "tracks_deleted": self.deleted}
