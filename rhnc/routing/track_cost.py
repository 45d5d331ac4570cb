"""Cost, fuel and CO2 of a timed track, and the timing of a track sailed at constant speed.

A *track* is a polyline of waypoints (north, east [m]) with the time [s] the ship passes
each one.  Between two waypoints the ship makes good a constant speed over ground along
the leg's course.  Its speed through water is that minus the current component along the
course (the cross component only sets a drift angle, as in :func:`rhnc.ship.energy.
speed_through_water`), and the energy model gives the brake power with the leg's course
as heading, the wind and waves relative to it (:func:`rhnc.ship.energy.brake_power`).  The
accounting is that of :mod:`rhnc.voyage.voyage`: the cost rate EC includes the running cost
C_c / 24 per hour, so a later arrival is not free, and rates are integrated over time with
the trapezoid rule, here on sub-legs no longer than ``max_spacing_nm`` (0.25 nm) so that
a long leg through varying weather is costed by the weather along it.

Met-ocean fields that change in time (those with more than one entry in ``times_s``) are
sampled at the time each point is passed; static fields at their one time.
"""

from __future__ import annotations

import numpy as np

from rhnc.ship.energy import EnergyParameters, brake_power, fuel_rate_t_h
from orchestrator.geometry import NM

#: Longest sub-leg [nm] over which the rates are integrated by the trapezoid rule.
DEFAULT_SPACING_NM = 0.25


def is_time_varying(metocean) -> bool:
    """True when the field holds more than one time (``times_s``)."""
    times = getattr(metocean, "times_s", None)
    return times is not None and np.size(times) > 1


def sample_weather(metocean, x_m, y_m, t_s=None) -> dict[str, np.ndarray]:
    """The field at points (x, y) [m], at times ``t_s`` [s] when it changes in time."""
    if t_s is not None and is_time_varying(metocean):
        return metocean.sample(x_m, y_m, np.broadcast_to(np.asarray(t_s, dtype=float), np.shape(x_m)))
    return metocean.sample(x_m, y_m)


def densify(waypoints_m: np.ndarray, max_spacing_m: float) -> np.ndarray:
    """The polyline with points inserted so that no leg exceeds ``max_spacing_m``."""
    points = np.asarray(waypoints_m, dtype=float).reshape(-1, 2)
    if len(points) < 2:
        return points.copy()
    legs = np.diff(points, axis=0)
    pieces = np.maximum(np.ceil(np.hypot(*legs.T) / max_spacing_m - 1e-9).astype(int), 1)
    fractions = np.concatenate([np.arange(n) / n for n in pieces])
    starts = np.repeat(np.arange(len(legs)), pieces)
    dense = points[starts] + fractions[:, None] * legs[starts]
    return np.vstack([dense, points[-1]])


def constant_speed_times(metocean, waypoints_m: np.ndarray, speed_through_water_mps: float,
                         departure_s: float = 0.0, iterations: int = 3) -> np.ndarray:
    """Times [s] at the waypoints of a ship keeping a constant speed through water.

    Over each leg the speed over ground is the speed through water plus the current
    along the leg, averaged over the leg's two ends (give short legs: :func:`densify`).
    In a field that changes in time the currents are sampled at the times passed, found
    by ``iterations`` fixed-point passes (the current changes the times only slightly).

    Raises
    ------
    ValueError
        If a head current is as fast as the ship on some leg.
    """
    points = np.asarray(waypoints_m, dtype=float)
    legs = np.diff(points, axis=0)
    length = np.hypot(*legs.T)
    course = np.arctan2(legs[:, 1], legs[:, 0])
    times = departure_s + np.concatenate([[0.0], np.cumsum(length / speed_through_water_mps)])
    for _ in range(iterations if is_time_varying(metocean) else 1):
        weather = sample_weather(metocean, points[:, 0], points[:, 1], times)
        along_a = weather["current_north"][:-1] * np.cos(course) + weather["current_east"][:-1] * np.sin(course)
        along_b = weather["current_north"][1:] * np.cos(course) + weather["current_east"][1:] * np.sin(course)
        over_ground = speed_through_water_mps + 0.5 * (along_a + along_b)
        if np.any((over_ground <= 1e-3) & (length > 0)):
            raise ValueError(f"a head current stops the ship at {speed_through_water_mps:.2f} m/s through water")
        times = departure_s + np.concatenate([[0.0], np.cumsum(np.where(length > 0, length / np.maximum(
            over_ground, 1e-3), 0.0))])
    return times


def cost_of_track(metocean, energy: EnergyParameters, waypoints_m, times_s,
                  max_spacing_nm: float = DEFAULT_SPACING_NM) -> dict[str, float]:
    """Cost, CO2 and fuel of sailing a timed track in the met-ocean field.

    Parameters
    ----------
    metocean : MetOceanField
    energy : EnergyParameters
    waypoints_m : array_like (n, 2)
        North, east [m].
    times_s : array_like (n,)
        Non-decreasing times [s] at the waypoints.
    max_spacing_nm : float
        Longest sub-leg of the trapezoid integration [nm].

    Returns
    -------
    dict
        ``cost_usd`` (fuel plus running cost), ``fuel_t``, ``co2_t``, ``distance_nm``
        (sailed over ground), ``duration_s``, ``mean_speed_through_water_kn`` (distance
        through water over duration) and ``mean_speed_over_ground_kn``.

    Raises
    ------
    ValueError
        If the arrays disagree in length, the times decrease, or a leg of positive
        length takes no time.
    """
    points = np.asarray(waypoints_m, dtype=float).reshape(-1, 2)
    times = np.asarray(times_s, dtype=float).ravel()
    if len(points) != len(times) or len(points) < 2:
        raise ValueError("cost_of_track needs as many times as waypoints, and at least two")
    if np.any(np.diff(times) < 0):
        raise ValueError("cost_of_track: the times must not decrease")
    legs = np.diff(points, axis=0)
    length = np.hypot(*legs.T)
    if np.any((length > 0) & (np.diff(times) <= 0)):
        raise ValueError("cost_of_track: a leg of positive length takes no time")
    pieces = np.maximum(np.ceil(length / (max_spacing_nm * NM) - 1e-9).astype(int), 1)
    leg_of = np.repeat(np.arange(len(legs)), pieces)
    fractions = np.concatenate([np.arange(n) / n for n in pieces])
    dense_points = np.vstack([points[leg_of] + fractions[:, None] * legs[leg_of], points[-1]])
    dense_times = np.concatenate([times[leg_of] + fractions * np.diff(times)[leg_of], times[-1:]])
    sub_length = np.repeat(length / pieces, pieces)
    sub_duration = np.diff(dense_times)
    course = np.arctan2(legs[:, 1], legs[:, 0])[leg_of]
    over_ground = np.divide(sub_length, sub_duration, out=np.zeros_like(sub_length), where=sub_duration > 0)
    weather = sample_weather(metocean, dense_points[:, 0], dense_points[:, 1], dense_times)
    fuel_ends = []
    through_water = np.zeros_like(sub_length)
    for end in (slice(None, -1), slice(1, None)):
        along = weather["current_north"][end] * np.cos(course) + weather["current_east"][end] * np.sin(course)
        stw = np.maximum(over_ground - along, 0.0)
        through_water += 0.5 * stw
        power = brake_power(stw, course, weather["wind_north"][end], weather["wind_east"][end],
                            weather["hs"][end], energy)
        fuel_ends.append(fuel_rate_t_h(power, energy))
    hours = sub_duration / 3600.0
    fuel_t = float(np.sum(0.5 * (fuel_ends[0] + fuel_ends[1]) * hours))
    duration_s = float(times[-1] - times[0])
    cost_usd = fuel_t * energy.fuel_price_usd_t + energy.running_cost_usd_day / 24.0 * duration_s / 3600.0
    distance_nm = float(np.sum(length)) / NM
    water_nm = float(np.sum(through_water * sub_duration)) / NM
    per_hour = 3600.0 / duration_s if duration_s > 0 else float("nan")
    return {
        "cost_usd": cost_usd,
        "fuel_t": fuel_t,
        "co2_t": fuel_t * energy.co2_per_fuel_t_t,
        "distance_nm": distance_nm,
        "duration_s": duration_s,
        "mean_speed_through_water_kn": water_nm * per_hour,
        "mean_speed_over_ground_kn": distance_nm * per_hour,
    }
