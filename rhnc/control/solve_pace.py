"""The processor time an NLP iteration takes on this machine, and the iteration cap it allows.

An iteration budget bounds a control step's solve in iterations; the goal is a bound in
processor time, and the time of an iteration is the machine's: the same 200 iterations took
120 ms on one machine and up to 274 ms on a slower one.  The solver (fatrop) has no clock of
its own, so the watchdog's timer ends a solve at its processor-time limit
(:mod:`rhnc.control.solver_watchdog`); such a solve leaves nothing, and the next step falls
back.  :class:`IterationPace` keeps the step from reaching the timer: it measures the
processor time per iteration of this run's long solves and caps the next solve's
iterations at what fits in ``PACE_SHARE`` of the limit, so that a long solve stops at its
cap, at an iterate the controller can still use (a feasible point, or the warm start of the
next step), as it does at the iteration budget.

Before the run has measured a long solve, the pace is taken as ``PRIOR_PACE_S`` (2 ms an
iteration, above the slowest measured on this project's machines, 1.4 ms): a run's first long
solve, often from a cold start with a target already close, then stops at its cap (85
iterations at 0.2 s), where without a prior the timer ended the first one or two steps of 4
of 110 held-out runs, and each fell back with no plan to shift.  That capped solve is the
run's first measurement.  A solve stopped at the cap of an estimated pace goes on, in the
same step, from its own iterate, capped at what the processor time left allows at the pace
measured now (:meth:`IterationPace.continuation`), keeping ``CONTINUATION_RESERVE_S``
free: with the prior alone the first solves of 6 of 34 runs stopped at 85 iterations,
infeasible, with 40-140 ms of the limit unused.  Should the timer end the going-on solve,
the point it went on from is kept for the next step as if it had not gone on.

Where the budget fits in the limit at the measured pace (a fast machine), no cap is asked
for after that first one; where it does not, the cap depends on the times measured, and so
do the results: the run summary counts the steps that stopped at
their cap (``iteration_capped_steps``) and the solves the timer ended (``timeout_count``).
"""

from __future__ import annotations

import collections
import math

#: solves with at least this many iterations measure the pace (in shorter ones the fixed cost
#: of a call, about a millisecond, weighs on the time per iteration)
PACE_MIN_ITERATIONS = 30
#: the pace is the slowest of this many latest measurements
PACE_MEMORY = 8
#: the pace before the run has measured one [s an iteration]
PRIOR_PACE_S = 2e-3
#: a solve stopped at its cap goes on within the step only for at least this many iterations
CONTINUATION_MIN_ITERATIONS = 10
#: of the time left, what a going-on solve keeps free [s]: the worker's timer is armed 20 ms
#: short of it, and a new solver object and the call cost a few ms (with 10 ms kept free, the
#: timer ended 12 going-on solves of 270 runs, each then falling back)
CONTINUATION_RESERVE_S = 0.03
#: share of the processor-time limit the capped iterations may take at that pace: the rest is
#: for the call's fixed costs and iterations slower than the slowest measured
PACE_SHARE = 0.85


class IterationPace:
    """Processor time per iteration of recent long solves, and the iteration cap it allows.

    Parameters
    ----------
    cpu_time_limit_s : float or None
        The processor-time limit of one solve [s]; None: never a cap.
    """

    def __init__(self, cpu_time_limit_s: float | None) -> None:
        self.cpu_time_limit_s = cpu_time_limit_s
        self._paces: collections.deque[float] = collections.deque(maxlen=PACE_MEMORY)
        self.capped = 0  # solves that stopped at their cap

    @property
    def pace_s(self) -> float:
        """The slowest recent processor time per iteration [s] (``PRIOR_PACE_S`` before any long solve)."""
        return max(self._paces) if self._paces else PRIOR_PACE_S

    def record(self, iterations: int, cpu_time_s: float, stopped_by_timer: bool, iterations_allowed: int,
               cap: int | None = None) -> None:
        """Measure a solve: ``iterations`` it ran in ``cpu_time_s``; one the timer ended ran
        at most ``iterations_allowed`` (its budget's share, or ``cap``) in the whole limit,
        which bounds its pace from below.  A solve that ran to its ``cap`` is counted."""
        self.capped += int(cap is not None and iterations >= cap)
        if cap is not None:
            iterations_allowed = min(iterations_allowed, cap)
        if stopped_by_timer and self.cpu_time_limit_s is not None:
            self._paces.append(self.cpu_time_limit_s / max(iterations_allowed, 1))
        elif iterations >= PACE_MIN_ITERATIONS and math.isfinite(cpu_time_s):
            self._paces.append(cpu_time_s / iterations)

    def time_left(self, cpu_spent_s: float) -> float | None:
        """The processor time [s] left of the limit after ``cpu_spent_s`` (None: no limit)."""
        return None if self.cpu_time_limit_s is None else self.cpu_time_limit_s - cpu_spent_s

    def continuation(self, iterations_left: int, cpu_spent_s: float) -> int | None:
        """The cap of a solve going on from where the last one stopped at its cap, with
        ``iterations_left`` of its budget, after ``cpu_spent_s`` [s] of the step's processor
        time: what fits in the rest at the pace measured now, None when fewer than
        ``CONTINUATION_MIN_ITERATIONS`` fit (or no limit is set)."""
        left = self.time_left(cpu_spent_s)
        if left is None or iterations_left < CONTINUATION_MIN_ITERATIONS:
            return None
        fits = math.floor(PACE_SHARE * (left - CONTINUATION_RESERVE_S) / self.pace_s)
        return None if fits < CONTINUATION_MIN_ITERATIONS else min(fits, iterations_left)

    def cap(self, iterations_allowed: int) -> int | None:
        """The iteration cap of the next solve, allowed ``iterations_allowed`` by its budget:
        None when those fit in ``PACE_SHARE`` of the limit at the measured pace."""
        if self.cpu_time_limit_s is None:
            return None
        fits = max(1, math.floor(PACE_SHARE * self.cpu_time_limit_s / self.pace_s))
        return None if fits >= iterations_allowed else fits
