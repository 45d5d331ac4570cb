"""The constant speed at which a reference voyage arrives at a given time.

A fair baseline for a navigation system sails the straight (or shortest obstacle-free)
route at the one constant speed that brings it to the goal when the system under test
arrived.  The arrival time of a co-simulated voyage is a decreasing function of the
reference speed, close to ``T(v) = lag + distance / v`` and known only by running it (the
crossing of the arrival radius, interpolated between samples).  It is searched for with the
secant method in ``1 / v`` (in which ``T`` is nearly linear, so the secant lands within a
second in three or four runs), guarded
by bisection once a too-early and a too-late speed bracket the target; a speed whose run
does not arrive at all counts as too slow.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

log = logging.getLogger(__name__)

#: Two trials arriving this close around the target [s] (one 1 min macro step) may stand
#: in for a trial at it (:attr:`EqualArrival.interpolated`).
MAX_BRACKET_S = 60.0


@dataclass(frozen=True)
class ArrivalTrial:
    """One run of the reference voyage: its speed, its arrival (None: did not arrive), the run."""

    speed_kn: float
    arrival_s: float | None
    run: Any = None


@dataclass
class EqualArrival:
    """The outcome of :func:`match_arrival_time`."""

    target_s: float
    tolerance_s: float
    trials: list[ArrivalTrial] = field(default_factory=list)
    #: the fastest reference speed the search may try [kn]
    top_speed_kn: float = math.inf

    @property
    def best(self) -> ArrivalTrial | None:
        """The arrived trial nearest the target (None when no trial arrived)."""
        arrived = [t for t in self.trials if t.arrival_s is not None]
        return min(arrived, key=lambda t: abs(t.arrival_s - self.target_s)) if arrived else None

    @property
    def cannot_arrive(self) -> bool:
        """True when no trial arrived and one was sailed at the fastest speed allowed: the
        reference voyage arrives at no speed the search may try (a weather it cannot make
        way in, say), an outcome of its own rather than a search that ran out of trials."""
        return (bool(self.trials) and all(t.arrival_s is None for t in self.trials)
                and max(t.speed_kn for t in self.trials) >= self.top_speed_kn)

    @property
    def matched(self) -> bool:
        """True when the best trial arrives within the tolerance of the target."""
        best = self.best
        return best is not None and abs(best.arrival_s - self.target_s) <= self.tolerance_s

    @property
    def bracket(self) -> tuple[ArrivalTrial, ArrivalTrial] | None:
        """The arrived trials nearest the target before and after it (None unless both exist)."""
        arrived = [(t.arrival_s, t) for t in self.trials if t.arrival_s is not None]
        early = [(arrival_s, t) for arrival_s, t in arrived if arrival_s <= self.target_s]
        late = [(arrival_s, t) for arrival_s, t in arrived if arrival_s > self.target_s]
        if not early or not late:
            return None
        return max(early, key=lambda pair: pair[0])[1], min(late, key=lambda pair: pair[0])[1]

    @property
    def interpolated(self) -> bool:
        """True when no trial arrived within the tolerance but two bracket the target within
        ``MAX_BRACKET_S``: the arrival jumps with the speed there (the last control steps
        before the goal), and the baseline's figures are read between the two."""
        if self.matched:
            return False
        pair = self.bracket
        return pair is not None and pair[1].arrival_s - pair[0].arrival_s <= MAX_BRACKET_S

    @property
    def usable(self) -> bool:
        return self.matched or self.interpolated

    def at_target(self, figure: Callable[[ArrivalTrial], float]) -> float:
        """``figure`` of the baseline at the target arrival: the best trial's when matched,
        else linear in the arrival time between the bracketing trials."""
        best = self.best
        if self.matched and best is not None:
            return float(figure(best))
        if not self.interpolated:
            raise ValueError("the equal-arrival baseline has no trial at or around the target arrival")
        early, late = self.bracket
        weight = (self.target_s - early.arrival_s) / (late.arrival_s - early.arrival_s)
        return float(figure(early) + weight * (figure(late) - figure(early)))


def match_arrival_time(arrival_of: Callable[[float], tuple[float | None, Any]], target_s: float,
                       tolerance_s: float, first_speed_kn: float, max_trials: int = 8,
                       speed_bounds_kn: tuple[float, float] = (2.0, 30.0), aim_s: float | None = None) -> EqualArrival:
    """Find the reference speed whose voyage arrives within ``tolerance_s`` of ``target_s``.

    Parameters
    ----------
    arrival_of : callable
        ``arrival_of(speed_kn) -> (arrival_s or None, run)``: sails the reference voyage at
        that speed [kn] and returns its arrival time [s] since departure (None if it did
        not arrive) and whatever describes the run.
    target_s : float
        Arrival time to match [s since departure].
    tolerance_s : float
        Accepted difference [s].
    first_speed_kn : float
        The first speed to try [kn], e.g. distance / target time.
    max_trials : int
        Runs allowed.
    speed_bounds_kn : (float, float)
        Speeds outside this range [kn] are not tried.
    aim_s : float, optional
        The search goes on until a trial lands this close to the target [s] (default half
        the tolerance), or the trials
        run out; ``matched`` still only asks for ``tolerance_s``.

    Returns
    -------
    EqualArrival
        Every trial; ``best`` and ``matched`` say how close it came.
    """
    low_kn, high_kn = speed_bounds_kn
    result = EqualArrival(target_s, tolerance_s, top_speed_kn=high_kn)
    early: ArrivalTrial | None = None   # fastest-needed bound: arrived too early (speed too high)
    late: ArrivalTrial | None = None    # arrived too late or not at all (speed too low)
    aim_s = 0.5 * tolerance_s if aim_s is None else aim_s
    speed = min(max(first_speed_kn, low_kn), high_kn)
    for _ in range(max_trials):
        arrival, run = arrival_of(speed)
        trial = ArrivalTrial(speed, arrival, run)
        result.trials.append(trial)
        log.info("equal arrival: %.4f kn arrives at %s s (target %.0f s)", speed, arrival, target_s)
        if arrival is not None and abs(arrival - target_s) <= aim_s:
            break
        if arrival is not None and arrival < target_s:
            early = trial if early is None or trial.speed_kn < early.speed_kn else early
        else:
            late = trial if late is None or trial.speed_kn > late.speed_kn else late
        speed = _next_speed(result.trials, target_s, early, late, low_kn, high_kn)
        if speed is None:
            break
    return result


def _next_speed(trials, target_s, early, late, low_kn, high_kn) -> float | None:
    """Secant in 1/v through the last two arrived trials, kept inside the bracket."""
    arrived = [t for t in trials if t.arrival_s is not None]
    if len(arrived) >= 2 and arrived[-1].speed_kn != arrived[-2].speed_kn:
        a, b = arrived[-2], arrived[-1]
        slope = (b.arrival_s - a.arrival_s) / (1.0 / b.speed_kn - 1.0 / a.speed_kn)
        guess = 1.0 / (1.0 / b.speed_kn + (target_s - b.arrival_s) / slope) if slope > 0 else math.nan
    elif arrived:
        # one point: assume the arrival time scales with 1 / v
        last = arrived[-1]
        guess = last.speed_kn * last.arrival_s / target_s
    else:
        guess = trials[-1].speed_kn * 1.25
    if early is not None and late is not None:
        inside = late.speed_kn < guess < early.speed_kn
        if not (math.isfinite(guess) and inside):
            guess = 0.5 * (late.speed_kn + early.speed_kn)
        if early.speed_kn - late.speed_kn < 1e-6:
            return None
    if not math.isfinite(guess) or guess <= 0:
        return None
    guess = min(max(guess, low_kn), high_kn)
    if any(abs(t.speed_kn - guess) < 1e-9 for t in trials):
        return None
    return guess
