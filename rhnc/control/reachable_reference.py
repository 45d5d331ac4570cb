"""A reference the ship can catch: its lead over the ship no more than the speed reserve makes up.

The reference of Experiments 2 and 3 is a timed schedule: a virtual ship that sails the path
at the reference speed whatever the real one does.  A ship that has lost ground on it (it
slowed down and sailed the longer way round an obstacle) is asked by the NMPC's tracking
cost to make up the along-track lag as much as the cross-track error, since both are
position errors of the same weight.  A ship with a speed reserve does so within minutes
(the KCS, 24 kn at full power, tracks 18 kn).  A ship whose reference is its service speed,
a large tanker or bulk carrier at sea speed, has almost none: the lag stays for the rest of
the voyage, and every plan splits its heading between catching up along the track and
coming back to it, so it returns to the track at a shallow angle.

With ``reachable_reference`` on, the reference is moved back along its own headings until it
leads the ship by no more than the model's speed reserve makes up over the horizon:
``(u_top - u_ref) * T``, with ``u_top`` the surge speed at which the largest surge force
(plus the estimated surge load) balances the model's resistance.  A lag the ship can make
up is tracked as before; the rest, which no plan within the horizon can change, no longer
bends the course.  Nothing here is a tuned number: the reserve is the prediction model's.
"""

from __future__ import annotations

import math

import numpy as np

from rhnc.ship.ship_model import ShipParameters

#: bisection steps of the top speed (the bracket shrinks to 2^-60 of its width)
BISECTION_STEPS = 60
#: the top-speed search starts below this speed [m/s] and doubles it until the resistance wins
FIRST_BRACKET_MPS = 10.0
#: largest speed [m/s] the search goes to (a model whose resistance never catches up: this)
LAST_BRACKET_MPS = 1000.0


def top_speed_mps(params: ShipParameters, surge_load_N: float = 0.0) -> float:
    """Surge speed [m/s] at which the largest surge force plus ``surge_load_N`` balances the
    model's resistance in straight motion (bisection; 0 if the force never moves the ship)."""
    def excess(u: float) -> float:
        return params.tau_max[0] + surge_load_N - float(params.equilibrium_tau(u)[0])

    low, high = 0.0, FIRST_BRACKET_MPS
    if excess(low) <= 0.0:
        return 0.0
    while excess(high) > 0.0 and high < LAST_BRACKET_MPS:
        low, high = high, 2.0 * high
    for _ in range(BISECTION_STEPS):
        middle = 0.5 * (low + high)
        low, high = (middle, high) if excess(middle) > 0.0 else (low, middle)
    return low


def reachable_lead_m(params: ShipParameters, reference: np.ndarray, horizon_s: float,
                     surge_load_N: float = 0.0) -> float:
    """Along-track distance [m] the ship gains on ``reference`` (N+1, 6) [SI] over ``horizon_s``
    at its top speed: ``max(0, u_top - mean reference speed) * horizon_s``."""
    reference_speed = float(np.mean(reference[:, 3]))
    return max(0.0, top_speed_mps(params, surge_load_N) - reference_speed) * horizon_s


def reachable_reference(reference: np.ndarray, position_m: np.ndarray, lead_m: float) -> np.ndarray:
    """``reference`` (N+1, 6) [SI] moved back along each node's heading so that its first node
    leads ``position_m`` (north, east) along the track by at most ``lead_m`` [m]; unchanged
    when it leads by less (a ship ahead of its schedule is never pulled forward)."""
    heading = float(reference[0, 2])
    offset = np.asarray(reference[0, :2], dtype=float) - np.asarray(position_m, dtype=float)[:2]
    lead = offset[0] * math.cos(heading) + offset[1] * math.sin(heading)
    excess = lead - lead_m
    if not excess > 0.0:
        return reference
    moved = np.array(reference, dtype=float)
    moved[:, 0] -= excess * np.cos(moved[:, 2])
    moved[:, 1] -= excess * np.sin(moved[:, 2])
    return moved
