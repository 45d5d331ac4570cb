"""A solve bounded in processor time: the worker's timer ends a solve at its limit, and the
iteration cap from the measured pace keeps solves from reaching it."""

import math
import signal
import time

import numpy as np
import pytest

import rhnc.control.solver_watchdog as watchdog
from rhnc.control.solve_pace import (CONTINUATION_MIN_ITERATIONS, CONTINUATION_RESERVE_S, PACE_MEMORY,
                                     PACE_MIN_ITERATIONS, PACE_SHARE, PRIOR_PACE_S, IterationPace)
from rhnc.control.solver_watchdog import WALL_TIME_STATUS, BoundedSolver, _serve


def busy(cpu_s):
    """Spend ``cpu_s`` of this process's processor time, nearly all of it user time (as a solver
    does: the clock is read by a system call, so only every 20,000 sines)."""
    end = time.process_time() + cpu_s
    x = 0.0
    while time.process_time() < end:
        for _ in range(20_000):
            x = math.sin(x + 1.0)


class Burning:
    """A solver that spends ``cpu_s`` of processor time, then returns x0 (success)."""

    def __init__(self, cpu_s, cap=None):
        self.cpu_s, self.cap = cpu_s, cap

    def __call__(self, **arguments):
        busy(self.cpu_s)
        return {"x": np.asarray(arguments["x0"]), "g": np.zeros(1), "f": 0.0}

    def stats(self):
        return {"success": True, "iter_count": 1 if self.cap is None else self.cap, "return_status": "Solve_Succeeded"}


def test_the_workers_timer_ends_a_solve_at_its_processor_time_limit(monkeypatch):
    # the parent's own check every POLL_S is put off beyond the solve: only the timer can stop it
    monkeypatch.setattr(watchdog, "POLL_S", 60.0)
    bounded = BoundedSolver({"slow": Burning(8.0), "under": Burning(0.3), "quick": Burning(0.0)}, {},
                            wall_time_s=120.0, cpu_time_s=0.5)
    try:
        assert bounded.solve("under", x0=np.zeros(3)).success  # 0.3 s: under the limit
        stopped = bounded.solve("slow", x0=np.zeros(3))
        assert stopped.timed_out and stopped.stopped_by == "cpu" and stopped.status == WALL_TIME_STATUS
        assert not stopped.success and np.isnan(stopped.x).all()
        # this call's processor time, ended about the limit (the worker had used 0.3 s before it)
        assert 0.3 < stopped.cpu_time_s < 0.6
        assert bounded.timeouts == 1
        after = bounded.solve("quick", x0=np.ones(3))  # a new worker serves the next call
        assert after.success and not after.timed_out
    finally:
        bounded.close()


def test_the_timer_is_disarmed_between_calls():
    """A worker waiting for its next request is not ended by a timer left running."""
    bounded = BoundedSolver({"nlp": Burning(0.05)}, {}, wall_time_s=60.0, cpu_time_s=0.2)
    try:
        for _ in range(6):  # 0.3 s of processor time over the calls: only each call's own counts
            assert bounded.solve("nlp", x0=np.zeros(1)).success
        assert bounded.timeouts == 0
    finally:
        bounded.close()


class ScriptedEnd:
    def __init__(self, requests):
        self.requests, self.sent = list(requests), []

    def recv(self):
        if not self.requests:
            raise EOFError
        return self.requests.pop(0)

    def send(self, message):
        self.sent.append(message)


def test_the_worker_serves_a_cap_with_an_object_built_for_it_and_renews_it_with_the_cap():
    built = []

    def factory(cap=None):
        built.append(cap)
        return Burning(0.0, cap)

    end = ScriptedEnd([("nlp", {"x0": np.zeros(1)}, None, None), ("nlp", {"x0": np.zeros(1)}, 40, None),
                       ("nlp", {"x0": np.zeros(1)}, 40, None), ("nlp", {"x0": np.zeros(1)}, None, None)])
    before = signal.getsignal(signal.SIGINT), signal.getsignal(signal.SIGPROF)
    try:
        _serve(end, {"nlp": Burning(0.0)}, {"nlp": factory}, renew=lambda outcome: True)
    finally:  # the worker's loop sets its process's handlers: here that is the test's
        signal.signal(signal.SIGINT, before[0])
        signal.signal(signal.SIGPROF, before[1])
    assert [outcome.iteration_cap for outcome in end.sent] == [None, 40, 40, None]
    assert [outcome.iterations for outcome in end.sent] == [1, 40, 40, 1]
    # renewed after each answer with the cap just served; a change of cap is built at the call
    assert built == [None, 40, 40, 40, None, None]


def test_building_an_object_for_a_new_cap_is_not_the_solves_time(monkeypatch):
    # building a solver object takes 0.5-1 s interpreted: for a new cap the worker builds it
    # before the timer is armed, the parent's check counts from the solver call's start, and the
    # building is reported apart; a solve of its own under the limit is then not ended
    monkeypatch.setattr(watchdog, "POLL_S", 0.01)  # the parent checks all through the building

    def slow_to_build(cap=None):
        busy(0.4)
        return Burning(0.02, cap)

    bounded = BoundedSolver({"nlp": Burning(0.02)}, {"nlp": slow_to_build}, wall_time_s=60.0, cpu_time_s=0.2)
    try:
        outcome = bounded.solve("nlp", x0=np.zeros(1), iteration_cap=40)
        assert outcome.success and not outcome.timed_out and bounded.timeouts == 0
        assert outcome.build_cpu_s >= 0.38 and outcome.cpu_time_s < 0.15
        again = bounded.solve("nlp", x0=np.zeros(1), iteration_cap=40)
        assert again.success and again.build_cpu_s == 0.0  # kept while the cap stays: no building
    finally:
        bounded.close()

    def slow_to_build_and_to_solve(cap=None):
        busy(0.4)
        return Burning(8.0, cap)

    # a solve that does go over the limit is still ended, its building left out of its time
    bounded = BoundedSolver({"nlp": Burning(0.0)}, {"nlp": slow_to_build_and_to_solve}, wall_time_s=60.0,
                            cpu_time_s=0.2)
    try:
        stopped = bounded.solve("nlp", x0=np.zeros(1), iteration_cap=30)
        assert stopped.timed_out and stopped.stopped_by == "cpu" and 0.1 < stopped.cpu_time_s < 0.3
    finally:
        bounded.close()


def test_the_same_in_this_process():
    built = []

    def factory(cap=None):
        built.append(cap)
        return Burning(0.0, cap)

    bounded = BoundedSolver({"nlp": Burning(0.0)}, {"nlp": factory}, wall_time_s=None)
    outcomes = [bounded.solve("nlp", x0=np.zeros(1), iteration_cap=cap) for cap in (None, 40, 40, None)]
    assert [outcome.iterations for outcome in outcomes] == [1, 40, 40, 1]
    assert [outcome.iteration_cap for outcome in outcomes] == [None, 40, 40, None]
    assert built == [40, None]  # kept while the cap stays (no renewal rule here)


def test_before_a_long_solve_the_prior_pace_caps_and_without_a_limit_nothing_does():
    pace = IterationPace(0.2)
    pace.record(PACE_MIN_ITERATIONS - 1, 1.0, False, 200)  # short: its fixed costs would weigh
    assert pace.pace_s == PRIOR_PACE_S
    assert pace.cap(200) == math.floor(PACE_SHARE * 0.2 / PRIOR_PACE_S)
    unlimited = IterationPace(None)
    unlimited.record(100, 1.0, False, 200)
    assert unlimited.cap(200) is None


def test_the_cap_is_what_fits_in_a_share_of_the_limit_at_the_slowest_recent_pace():
    pace = IterationPace(0.2)
    pace.record(100, 0.1, False, 200)   # 1 ms an iteration
    pace.record(50, 0.06, False, 200)   # 1.2 ms
    pace.record(200, 0.16, False, 200)  # 0.8 ms
    assert pace.pace_s == pytest.approx(1.2e-3)
    assert pace.cap(200) == math.floor(PACE_SHARE * 0.2 / 1.2e-3)
    assert pace.cap(100) is None  # the budget fits: the steps are the budget's


def test_only_solves_that_ran_to_their_cap_count_as_capped():
    pace = IterationPace(0.2)
    pace.record(12, 0.01, False, 200, cap=150)  # converged below its cap
    pace.record(150, 0.18, False, 200, cap=150)  # stopped at it
    pace.record(200, 0.18, False, 200)  # at the budget, no cap
    assert pace.capped == 1


def test_the_pace_forgets_all_but_its_latest_measurements():
    pace = IterationPace(0.2)
    pace.record(100, 0.3, False, 200)  # 3 ms, then faster ones
    for _ in range(PACE_MEMORY):
        pace.record(100, 0.05, False, 200)
    assert pace.pace_s == pytest.approx(0.5e-3)
    assert pace.cap(400) == math.floor(PACE_SHARE * 0.2 / 0.5e-3)


def test_a_solve_the_timer_ended_lowers_the_cap_below_what_it_was_allowed():
    pace = IterationPace(0.2)
    pace.record(-1, float("nan"), True, 200)  # ended before 200 iterations: slower than 1 ms each
    assert pace.cap(200) == math.floor(PACE_SHARE * 200)
    pace.record(-1, float("nan"), True, 200, cap=pace.cap(200))  # ended again, at its cap
    assert pace.cap(200) == math.floor(PACE_SHARE * math.floor(PACE_SHARE * 200))


def test_a_continuation_gets_what_the_time_left_allows_within_the_iterations_left():
    pace = IterationPace(0.2)
    pace.record(100, 0.1, False, 200)  # 1 ms an iteration
    assert pace.continuation(150, 0.1) == math.floor(PACE_SHARE * (0.1 - CONTINUATION_RESERVE_S) / 1e-3)  # 0.1 s left
    assert pace.continuation(40, 0.1) == 40  # the budget's rest is the smaller
    assert pace.continuation(CONTINUATION_MIN_ITERATIONS - 1, 0.0) is None  # too few left to go on
    assert pace.continuation(150, 0.2 - CONTINUATION_RESERVE_S - 0.005) is None  # 5 ms beyond the reserve
    assert IterationPace(None).continuation(150, 0.0) is None
