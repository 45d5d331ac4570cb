"""The speed along a route that arrives at a given time at least fuel: speed as a decision.

At a fixed arrival time the running cost is the same for every timing, so the cheapest
passage along a route burns least fuel.  Over leg i (length L_i, current c along it at its
two ends, the weather met there) a speed over ground g costs

    J_i(g) = (F_i(g) + lambda) L_i / g,   F_i(g) = (f(g - c_a) + f(g - c_b)) / 2,

f the fuel cost rate [USD/h] at that speed through water with the leg's course as heading
(the measure of :func:`rhnc.routing.track_cost.cost_of_track`), lambda the price of an
hour.  For a given lambda each leg takes its own best speed independently (the Lagrangian
of the arrival constraint separates); lambda is then found by bisection so that the
passage arrives on time, and the leg durations are scaled by the last fraction of a
percent to arrive exactly.  In a field that changes in time the weather is sampled at the
times of the previous pass.  The speeds through water searched lie within
``bounds_mps`` on a grid of ``SPEED_GRID_MPS``.

Riding a favourable current, easing through a head sea and making up the time in calm
water are all choices of this kind: a constant speed cannot make them.
"""

from __future__ import annotations

import numpy as np

from rhnc.ship.energy import EnergyParameters, brake_power, fuel_rate_t_h
from rhnc.routing.track_cost import constant_speed_times, sample_weather

#: Spacing of the speeds through water searched on every leg [m/s].
SPEED_GRID_MPS = 0.02
#: Default bounds of the speed through water [m/s]: 4 kn to 24 kn.
DEFAULT_BOUNDS_MPS = (4.0 * 1852.0 / 3600.0, 24.0 * 1852.0 / 3600.0)
#: Bisection steps on the price of an hour.
PRICE_STEPS = 60


def profile_times(metocean, energy: EnergyParameters, points: np.ndarray, departure_s: float, arrival_s: float,
                  bounds_mps: tuple[float, float] = DEFAULT_BOUNDS_MPS, passes: int = 3) -> np.ndarray:
    """Times [s] at ``points`` of the least-fuel passage that arrives at ``arrival_s``.

    Parameters
    ----------
    metocean : MetOceanField
    energy : EnergyParameters
    points : ndarray (n, 2)
        The route, north and east [m], densified (legs of a fraction of a nautical mile).
    departure_s, arrival_s : float
        Departure and required arrival [s].
    bounds_mps : (float, float)
        Lowest and highest speed through water [m/s].
    passes : int
        Re-solves with the weather at the times found (a field that changes in time).

    Raises
    ------
    ValueError
        If no speed within the bounds arrives then.
    """
    points = np.asarray(points, dtype=float)
    legs = np.diff(points, axis=0)
    length = np.hypot(*legs.T)
    course = np.arctan2(legs[:, 1], legs[:, 0])
    total = arrival_s - departure_s
    if not total > 0:
        raise ValueError(f"arrival_s {arrival_s!r} must be after the departure {departure_s!r} s")
    mean_speed = max(float(np.sum(length)) / total, bounds_mps[0])
    times = constant_speed_times(metocean, points, min(mean_speed, bounds_mps[1]), departure_s)
    low, high = bounds_mps
    stw = np.arange(low, high + 0.5 * SPEED_GRID_MPS, SPEED_GRID_MPS)
    for _ in range(passes if getattr(metocean, "times_s", None) is not None and np.size(metocean.times_s) > 1
                   else 1):
        weather = sample_weather(metocean, points[:, 0], points[:, 1], times)
        ends = []
        for end in (slice(None, -1), slice(1, None)):
            along = weather["current_north"][end] * np.cos(course) + weather["current_east"][end] * np.sin(course)
            ends.append((along, {name: weather[name][end] for name in ("wind_north", "wind_east", "hs")}))
        mean_along = 0.5 * (ends[0][0] + ends[1][0])
        over_ground = stw[None, :] + mean_along[:, None]            # (legs, speeds)
        fuel = np.zeros_like(over_ground)
        for along, w in ends:
            speed = np.maximum(over_ground - along[:, None], 0.0)
            power = brake_power(speed, course[:, None], w["wind_north"][:, None], w["wind_east"][:, None],
                                w["hs"][:, None], energy)
            fuel += 0.5 * fuel_rate_t_h(power, energy) * energy.fuel_price_usd_t
        moving = over_ground > 1e-3
        hours = np.where(moving, length[:, None] / np.maximum(over_ground, 1e-3), np.inf) / 3600.0
        fuel_cost = np.where(moving, fuel * hours, np.inf)

        def durations(price, fuel_cost=fuel_cost, moving=moving, hours=hours):
            choice = np.argmin(fuel_cost + price * np.where(moving, hours, np.inf), axis=1)
            return hours[np.arange(len(length)), choice] * 3600.0

        fastest, slowest = durations(1e9).sum(), durations(0.0).sum()
        if fastest > total + 1e-6:
            raise ValueError(f"arrival at {arrival_s:.0f} s needs more than {high:.2f} m/s through water")
        if slowest < total:
            duration = durations(0.0) * total / slowest   # the least-fuel speeds arrive early: ease them all
        else:
            lo, hi = 0.0, 1.0
            while durations(hi).sum() > total and hi < 1e9:
                hi *= 2.0
            for _ in range(PRICE_STEPS):
                mid = 0.5 * (lo + hi)
                if durations(mid).sum() > total:
                    lo = mid
                else:
                    hi = mid
            duration = durations(hi)
            duration = duration * total / duration.sum()
        times = departure_s + np.concatenate([[0.0], np.cumsum(duration)])
    return times
