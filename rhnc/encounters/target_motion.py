"""Targets as agents: scripted manoeuvres and recorded tracks (AIS replay from CSV or NMEA).

Two kinds of target motion beside the constant-velocity and waypoint targets of
:mod:`rhnc.encounters.traffic`, each with the same ``state(elapsed_s)`` row
(x, y, vx, vy, radius; SI, x north, y east):

:class:`ScriptedTarget`
    Starts at constant velocity and manoeuvres at given times: a course change at a turn
    rate, a speed change at an acceleration.  The track is integrated once, at 1 s
    steps, from the run's start to its end (course and speed rate-limited towards the
    commanded values; position by the trapezoid rule), and interpolated.
:class:`RecordedTarget`
    Replays timestamped positions: a CSV file (``time_s`` or ISO-8601 ``time``, and
    ``north_nm``/``east_nm`` in the scenario plane or ``lat``/``lon`` in WGS-84 degrees
    projected about ``origin_deg``), or AIS NMEA 0183 ``!AIVDM``/``!AIVDO`` sentences decoded
    with pyais (position reports, message types 1-3, 18, 19 and 27), each line led by its
    reception time in seconds (``1712345678.2 !AIVDM,...`` or a tag block ``\\c:...\\``).
    Between two reports the position is interpolated linearly and the velocity is the
    leg's; before the first report and after the last the target sails on with the first
    or last leg's velocity (a ship does not stop where a recording ends).

Errors name the file, the row or line, and the key.
"""

from __future__ import annotations

import csv
import datetime
import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from orchestrator.errors import ScenarioError
from orchestrator.geometry import DEG, KNOT, NM
from orchestrator.participant import is_finite_number, reject_unknown_options

#: Integration step of a scripted track [s].
SCRIPT_STEP_S = 1.0
#: Defaults of a manoeuvre: turn rate [deg/s] (a merchant ship at service speed turns at
#: 0.3-1 deg/s with moderate rudder) and speed change [m/s^2] (a crash stop of a large ship
#: loses about 0.05 m/s^2 at first; an engine order about a third of that).
DEFAULT_TURN_RATE_DEG_S = 0.5
DEFAULT_ACCELERATION_MPS2 = 0.02

MANOEUVRE_KEYS = ("at_s", "course_change_deg", "turn_rate_deg_s", "speed_kn", "acceleration_mps2")
#: AIS message types that carry a position report.
POSITION_MESSAGES = (1, 2, 3, 18, 19, 27)


class Manoeuvre:
    """One scripted change: a course change [rad] at a turn rate, or a new speed at an acceleration.

    Parameters
    ----------
    at_s : float
        Time of the order after the run's start [s].
    course_change_rad : float or None
        Course change, + to starboard [rad].
    turn_rate_rad_s : float
        Turn rate while altering [rad/s], > 0.
    speed_mps : float or None
        New speed [m/s], >= 0.
    acceleration_mps2 : float
        Magnitude of the speed change rate [m/s^2], > 0.
    """

    def __init__(self, at_s: float, course_change_rad: float | None, turn_rate_rad_s: float,
                 speed_mps: float | None, acceleration_mps2: float) -> None:
        self.at_s = at_s
        self.course_change_rad = course_change_rad
        self.turn_rate_rad_s = turn_rate_rad_s
        self.speed_mps = speed_mps
        self.acceleration_mps2 = acceleration_mps2


class ScriptedTarget:
    """A target that starts at constant velocity and manoeuvres on a script (SI inside).

    Parameters
    ----------
    start_m : (2,) array
        Position at the run's start [m].
    velocity_mps : (2,) array
        Initial velocity (north, east) [m/s].
    manoeuvres : sequence of Manoeuvre
        In time order.
    radius_m : float
        Hazard radius [m].
    duration_s : float
        Length of the run [s]; past it the last velocity is held.
    """

    def __init__(self, start_m, velocity_mps, manoeuvres: Sequence[Manoeuvre], radius_m: float,
                 duration_s: float) -> None:
        self.radius_m = float(radius_m)
        self.manoeuvres = list(manoeuvres)
        course = math.atan2(velocity_mps[1], velocity_mps[0])
        speed = float(math.hypot(*velocity_mps))
        n = int(math.ceil(max(duration_s, 0.0) / SCRIPT_STEP_S)) + 2
        self._t = np.arange(n) * SCRIPT_STEP_S
        courses, speeds = np.empty(n), np.empty(n)
        commanded_course, commanded_speed = course, speed
        turn_rate, acceleration = DEFAULT_TURN_RATE_DEG_S * DEG, DEFAULT_ACCELERATION_MPS2
        pending = list(self.manoeuvres)
        for k, t in enumerate(self._t):
            while pending and pending[0].at_s <= t + 1e-9:
                order = pending.pop(0)
                if order.course_change_rad is not None:
                    commanded_course = commanded_course + order.course_change_rad
                    turn_rate = order.turn_rate_rad_s
                if order.speed_mps is not None:
                    commanded_speed = order.speed_mps
                    acceleration = order.acceleration_mps2
            if k > 0:
                course += float(np.clip(commanded_course - course, -turn_rate * SCRIPT_STEP_S,
                                        turn_rate * SCRIPT_STEP_S))
                speed += float(np.clip(commanded_speed - speed, -acceleration * SCRIPT_STEP_S,
                                       acceleration * SCRIPT_STEP_S))
            courses[k], speeds[k] = course, speed
        vx, vy = speeds * np.cos(courses), speeds * np.sin(courses)
        self._velocity = np.column_stack([vx, vy])
        steps = 0.5 * (self._velocity[1:] + self._velocity[:-1]) * SCRIPT_STEP_S
        self._position = np.asarray(start_m, dtype=float) + np.vstack([[0.0, 0.0], np.cumsum(steps, axis=0)])

    def state(self, elapsed_s: float) -> np.ndarray:
        """Row (x, y, vx, vy, radius) [m, m/s] at ``elapsed_s`` [s] after the start."""
        t = self._t
        if elapsed_s <= t[0]:
            position = self._position[0] + self._velocity[0] * elapsed_s
            return np.r_[position, self._velocity[0], self.radius_m]
        if elapsed_s >= t[-1]:
            position = self._position[-1] + self._velocity[-1] * (elapsed_s - t[-1])
            return np.r_[position, self._velocity[-1], self.radius_m]
        row = [np.interp(elapsed_s, t, self._position[:, j]) for j in range(2)]
        row += [np.interp(elapsed_s, t, self._velocity[:, j]) for j in range(2)]
        return np.r_[row, self.radius_m]


class RecordedTarget:
    """A target replaying timestamped positions (SI inside).

    Parameters
    ----------
    times_s : (k,) array
        Report times after the run's start [s], strictly increasing, k >= 2.
    positions_m : (k, 2) array
        Positions (north, east) [m].
    radius_m : float
        Hazard radius [m].
    """

    def __init__(self, times_s, positions_m, radius_m: float) -> None:
        self.times_s = np.asarray(times_s, dtype=float)
        self.positions_m = np.asarray(positions_m, dtype=float)
        self.radius_m = float(radius_m)
        self._leg_velocity = np.diff(self.positions_m, axis=0) / np.diff(self.times_s)[:, None]

    def state(self, elapsed_s: float) -> np.ndarray:
        """Row (x, y, vx, vy, radius) [m, m/s] at ``elapsed_s`` [s] after the start."""
        t = self.times_s
        leg = int(np.clip(np.searchsorted(t, elapsed_s, side="right") - 1, 0, len(t) - 2))
        velocity = self._leg_velocity[leg]
        position = self.positions_m[leg] + velocity * (elapsed_s - t[leg])
        return np.r_[position, velocity, self.radius_m]


def scripted_target(start_m, velocity_mps, entries: Any, radius_m: float, duration_s: float,
                    where: str) -> ScriptedTarget:
    """A :class:`ScriptedTarget` from the ``manoeuvres`` option (a list of tables); errors name the key."""
    here = f"{where}.manoeuvres"
    if not isinstance(entries, list) or not entries or not all(isinstance(e, Mapping) for e in entries):
        raise ScenarioError(f"{here}: must be a non-empty list of tables {{ at_s = ..., course_change_deg = ... }}")
    manoeuvres = []
    for i, entry in enumerate(entries):
        at = f"{here}[{i}]"
        reject_unknown_options(entry, MANOEUVRE_KEYS, at)
        time = _number(entry, "at_s", at, low=0.0)
        assert time is not None  # a required number: _number raises where it is missing
        change = _number(entry, "course_change_deg", at, required=False)
        speed = _number(entry, "speed_kn", at, low=0.0, required=False)
        if change is None and speed is None:
            raise ScenarioError(f"{at}: give 'course_change_deg' and/or 'speed_kn'")
        if change is not None and not -180.0 <= change <= 180.0:
            raise ScenarioError(f"{at}: 'course_change_deg' must be within [-180, 180] (+ starboard), got {change!r}")
        rate = _number(entry, "turn_rate_deg_s", at, positive=True, required=False) or DEFAULT_TURN_RATE_DEG_S
        acceleration = (_number(entry, "acceleration_mps2", at, positive=True, required=False)
                        or DEFAULT_ACCELERATION_MPS2)
        if manoeuvres and time < manoeuvres[-1].at_s:
            raise ScenarioError(f"{at}: 'at_s' = {time:g} is before the previous manoeuvre's; list them in time order")
        manoeuvres.append(Manoeuvre(time, None if change is None else change * DEG, rate * DEG,
                                    None if speed is None else speed * KNOT, acceleration))
    return ScriptedTarget(start_m, velocity_mps, manoeuvres, radius_m, duration_s)


def recorded_target(entry: Mapping[str, Any], radius_m: float, scenario_dir: Path | str, where: str) -> RecordedTarget:
    """A :class:`RecordedTarget` from ``track_file`` (+ ``mmsi``, ``origin_deg``, ``time_offset_s``)."""
    value = entry.get("track_file")
    if not isinstance(value, str) or not value:
        raise ScenarioError(f"{where}: 'track_file' must be a file name (CSV or NMEA), got {value!r}")
    path = Path(value) if Path(value).is_absolute() else Path(scenario_dir) / value
    mmsi = entry.get("mmsi")
    if mmsi is not None and (isinstance(mmsi, bool) or not isinstance(mmsi, int) or mmsi <= 0):
        raise ScenarioError(f"{where}: 'mmsi' must be a positive integer, got {mmsi!r}")
    origin = entry.get("origin_deg")
    if origin is not None:
        ok = isinstance(origin, (list, tuple)) and len(origin) == 2 and all(is_finite_number(v) for v in origin)
        if not ok or not -90.0 <= origin[0] <= 90.0 or not -180.0 <= origin[1] <= 180.0:
            raise ScenarioError(f"{where}: 'origin_deg' must be [lat, lon] in degrees, got {origin!r}")
    offset = _number(entry, "time_offset_s", where, required=False)
    if not path.is_file():
        raise ScenarioError(f"{where}: 'track_file' {path} not found")
    if path.suffix.lower() == ".csv":
        times, columns, geographic = _read_csv(path, mmsi)
    else:
        times, columns, geographic = _read_nmea(path, mmsi)
    if geographic and origin is None:
        raise ScenarioError(f"{where}: {path} gives latitude and longitude; set 'origin_deg' = [lat, lon] "
                            f"of the scenario's (0, 0) nm")
    if geographic:
        from pyproj import Transformer

        transformer = Transformer.from_crs(
            "EPSG:4326", f"+proj=aeqd +lat_0={origin[0]} +lon_0={origin[1]} +datum=WGS84 +units=m", always_xy=True)
        east, north = transformer.transform(columns[:, 1], columns[:, 0])
        positions = np.column_stack([north, east])
    else:
        positions = columns * NM
    order = np.argsort(times, kind="stable")
    times, positions = times[order], positions[order]
    keep = np.r_[True, np.diff(times) > 0.0]  # a repeated report (two receivers) is kept once
    times, positions = times[keep], positions[keep]
    if len(times) < 2:
        raise ScenarioError(f"{path}: fewer than two position reports" + (f" for mmsi {mmsi}" if mmsi else ""))
    times = times - (times[0] if offset is None else offset)
    return RecordedTarget(times, positions, radius_m)


def _read_csv(path: Path, mmsi: int | None) -> tuple[np.ndarray, np.ndarray, bool]:
    """Times [s] and (north, east) [nm] or (lat, lon) [deg] rows, and whether geographic."""
    try:
        with path.open(newline="", encoding="utf-8") as handle:
            reader = csv.DictReader(handle)
            header = [name.strip() for name in (reader.fieldnames or [])]
            rows = list(reader)
    except (OSError, UnicodeDecodeError, csv.Error) as exc:
        raise ScenarioError(f"{path}: cannot read the track: {exc}") from None
    if "time_s" in header:
        time_key = "time_s"
    elif "time" in header:
        time_key = "time"
    else:
        raise ScenarioError(f"{path}: missing column 'time_s' (seconds) or 'time' (ISO 8601); header {header}")
    if {"north_nm", "east_nm"} <= set(header):
        keys, geographic = ("north_nm", "east_nm"), False
    elif {"lat", "lon"} <= set(header):
        keys, geographic = ("lat", "lon"), True
    else:
        raise ScenarioError(f"{path}: missing columns 'north_nm', 'east_nm' (or 'lat', 'lon'); header {header}")
    if mmsi is not None and "mmsi" not in header:
        raise ScenarioError(f"{path}: option 'mmsi' given but the file has no 'mmsi' column")
    times, values = [], []
    for line, row in enumerate(rows, start=2):
        row = {(k or "").strip(): (v or "").strip() for k, v in row.items()}
        if mmsi is not None and row.get("mmsi") != str(mmsi):
            continue
        times.append(_csv_time(row[time_key], path, line, time_key))
        values.append([_csv_number(row[key], path, line, key) for key in keys])
    if geographic:
        lat, lon = np.array(values, dtype=float).reshape(-1, 2).T
        for name, column, bound in (("lat", lat, 90.0), ("lon", lon, 180.0)):
            bad = np.nonzero(np.abs(column) > bound)[0]
            if bad.size:
                raise ScenarioError(f"{path}: column '{name}' out of range at a row with value {column[bad[0]]!r}")
    return np.array(times, dtype=float), np.array(values, dtype=float).reshape(-1, 2), geographic


def _csv_number(text: str, path: Path, line: int, key: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not math.isfinite(value):
        raise ScenarioError(f"{path}: line {line}: column '{key}' must be a finite number, got {text!r}")
    return value


def _csv_time(text: str, path: Path, line: int, key: str) -> float:
    if key == "time_s":
        return _csv_number(text, path, line, key)
    try:
        moment = datetime.datetime.fromisoformat(text.replace("Z", "+00:00"))
    except ValueError:
        raise ScenarioError(f"{path}: line {line}: column 'time' must be an ISO 8601 time, got {text!r}") from None
    if moment.tzinfo is None:
        moment = moment.replace(tzinfo=datetime.timezone.utc)
    return moment.timestamp()


def _read_nmea(path: Path, mmsi: int | None) -> tuple[np.ndarray, np.ndarray, bool]:
    """Reception times [s] and (lat, lon) [deg] of the position reports in an NMEA log."""
    from pyais import decode
    from pyais.exceptions import AISBaseException

    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except (OSError, UnicodeDecodeError) as exc:
        raise ScenarioError(f"{path}: cannot read the NMEA log: {exc}") from None
    times, values, ships = [], [], set()
    for number, text in enumerate(lines, start=1):
        text = text.strip()
        if not text or text.startswith("#"):
            continue
        time, sentence = _split_nmea_line(text, path, number)
        try:
            message = decode(sentence, error_if_checksum_invalid=True)
        except (AISBaseException, ValueError, IndexError) as exc:
            raise ScenarioError(f"{path}: line {number}: not a decodable AIS sentence (checksum or payload: {exc})") from None
        if message.msg_type not in POSITION_MESSAGES:
            continue
        lat, lon = getattr(message, "lat", None), getattr(message, "lon", None)
        if lat is None or lon is None or abs(lat) > 90.0 or abs(lon) > 180.0:
            continue  # 91/181 deg: "not available" in the standard
        ships.add(message.mmsi)
        if mmsi is not None and message.mmsi != mmsi:
            continue
        times.append(time)
        values.append([lat, lon])
    if mmsi is None and len(ships) > 1:
        raise ScenarioError(f"{path}: position reports from {len(ships)} ships (mmsi {sorted(ships)[:5]}...); "
                            f"set the target's 'mmsi'")
    return np.array(times, dtype=float), np.array(values, dtype=float).reshape(-1, 2), True


def _split_nmea_line(text: str, path: Path, number: int) -> tuple[float, str]:
    """(reception time [s], sentence) of ``<time> !AIVDM,...``, ``<time>,!AIVDM,...`` or ``\\c:<time>*hh\\!AIVDM``."""
    if text.startswith("\\"):
        block, _, sentence = text[1:].partition("\\")
        fields = dict(part.split(":", 1) for part in block.split("*")[0].split(",") if ":" in part)
        stamp = fields.get("c")
    else:
        start = text.find("!")
        stamp, sentence = text[:start].strip(" ,\t"), text[start:]
        if start < 0:
            stamp = None
    try:
        time = float(stamp) if stamp else math.nan
    except ValueError:
        time = math.nan
    if not math.isfinite(time):
        raise ScenarioError(f"{path}: line {number}: each sentence must be led by its reception time in seconds "
                            f"('<time> !AIVDM,...' or a tag block '\\c:<time>\\')")
    if time > 1e11:  # tag blocks may give milliseconds
        time /= 1000.0
    return time, sentence


def _number(entry: Mapping[str, Any], key: str, where: str, low: float | None = None, positive: bool = False,
            required: bool = True) -> float | None:
    value = entry.get(key)
    if value is None and not required:
        return None
    if not is_finite_number(value):
        raise ScenarioError(f"{where}: '{key}' must be a finite number, got {value!r}")
    if positive and not value > 0:
        raise ScenarioError(f"{where}: '{key}' must be > 0, got {value!r}")
    if low is not None and value < low:
        raise ScenarioError(f"{where}: '{key}' must be >= {low:g}, got {value!r}")
    return float(value)

