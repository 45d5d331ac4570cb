"""The equal-arrival speed search against arrival functions solvable by hand."""

import math

import pytest

from rhnc.voyage.equal_arrival import ArrivalTrial, EqualArrival, match_arrival_time

DISTANCE_NM = 140.9


def voyage(lag_s=300.0, step_s=60.0, slowest_arriving_kn=0.0):
    """Arrival on a macro-step grid of a ship that lags its reference by ``lag_s``."""
    runs = []

    def arrival_of(speed_kn):
        runs.append(speed_kn)
        if speed_kn < slowest_arriving_kn:
            return None, "did not arrive"
        arrival = lag_s + DISTANCE_NM / speed_kn * 3600.0 + 40.0 * math.sin(speed_kn)
        return math.ceil(arrival / step_s) * step_s, f"run at {speed_kn:.3f} kn"

    return arrival_of, runs


def test_secant_lands_on_the_target_step_in_a_few_runs():
    arrival_of, runs = voyage()
    target = 29_160.0
    result = match_arrival_time(arrival_of, target, tolerance_s=60.0, first_speed_kn=DISTANCE_NM / (target / 3600))
    assert result.matched
    assert abs(result.best.arrival_s - target) <= 30.0   # the same 60 s sample, not merely the next
    assert len(runs) <= 4
    assert result.best.run == f"run at {result.best.speed_kn:.3f} kn"


def test_a_run_that_does_not_arrive_counts_as_too_slow():
    arrival_of, runs = voyage(slowest_arriving_kn=15.0)
    result = match_arrival_time(arrival_of, 29_160.0, tolerance_s=60.0, first_speed_kn=10.0)
    assert result.trials[0].arrival_s is None
    assert result.matched and result.best.speed_kn > 15.0


def test_unreachable_target_is_reported_not_matched():
    # arrival does not depend on the speed (a ship that cannot keep up): no trial gets there
    result = match_arrival_time(lambda v: (40_000.0, None), 29_160.0, tolerance_s=60.0, first_speed_kn=17.0,
                                max_trials=5)
    assert not result.matched
    assert 1 <= len(result.trials) <= 5
    assert result.best.arrival_s == 40_000.0


def test_speed_stays_within_bounds():
    arrival_of, runs = voyage()
    match_arrival_time(arrival_of, 10_000.0, tolerance_s=60.0, first_speed_kn=50.0, speed_bounds_kn=(2.0, 30.0))
    assert all(2.0 <= v <= 30.0 for v in runs)


@pytest.mark.parametrize("target_s", [20_000.0, 29_160.0, 40_000.0])
def test_matches_across_targets(target_s):
    arrival_of, _ = voyage()
    result = match_arrival_time(arrival_of, target_s, tolerance_s=60.0, first_speed_kn=DISTANCE_NM / (target_s / 3600))
    assert result.matched


@pytest.mark.parametrize("target_s", [29_700.0, 30_000.0])
def test_target_inside_a_jump_is_bracketed_and_reported(target_s):
    # arrival jumps by 15 min at 17.5 kn (say, a turn the slower ship misses): no speed
    # arrives at the target; once trials lie on both sides the search must stay between
    # them and close in on the jump instead of wandering
    def arrival_of(speed_kn):
        arrival = 300.0 + DISTANCE_NM / speed_kn * 3600.0 + (900.0 if speed_kn < 17.5 else 0.0)
        return math.ceil(arrival / 60.0) * 60.0, None

    result = match_arrival_time(arrival_of, target_s, tolerance_s=60.0, first_speed_kn=17.0)
    assert not result.matched
    assert all(abs(t.speed_kn - 17.5) < 0.1 for t in result.trials[-3:])


def test_a_baseline_whose_arrival_jumps_over_the_target_is_read_between_the_two_trials():
    # the arrival jumps 22 s between two speeds 0.0002 kn apart: no trial lands within 2 s
    trials = [ArrivalTrial(17.6778, 28686.7, 100.0), ArrivalTrial(17.6776, 28708.8, 90.0),
              ArrivalTrial(17.6831, 28680.6, 130.0)]
    equal = EqualArrival(target_s=28689.6, tolerance_s=2.0, trials=trials)
    assert not equal.matched and equal.interpolated and equal.usable
    assert equal.bracket == (trials[0], trials[1])
    weight = (28689.6 - 28686.7) / (28708.8 - 28686.7)
    assert equal.at_target(lambda t: t.run) == pytest.approx(100.0 - 10.0 * weight)
    # the speed read at the target: 0.13 of the way from the early trial's to the late one's
    assert equal.at_target(lambda t: t.speed_kn) == pytest.approx(17.6778 - 0.0002 * weight, abs=1e-9)
    assert 0.1 < weight < 0.2
    # the same reading whatever order the trials were run in
    shuffled = EqualArrival(target_s=28689.6, tolerance_s=2.0, trials=trials[::-1])
    assert shuffled.at_target(lambda t: t.run) == pytest.approx(100.0 - 10.0 * weight)
    # a bracket wider than a macro step does not stand in for a trial at the target
    wide = EqualArrival(target_s=28689.6, tolerance_s=2.0, trials=[trials[2], ArrivalTrial(17.5, 28760.0, 80.0)])
    assert not wide.interpolated and not wide.usable
    with pytest.raises(ValueError, match="no trial at or around the target"):
        wide.at_target(lambda t: t.run)
    # matched: the best trial's own figure
    exact = EqualArrival(target_s=28686.0, tolerance_s=2.0, trials=trials)
    assert exact.matched and not exact.interpolated and exact.at_target(lambda t: t.run) == 100.0


def test_the_speeds_tried_follow_the_secant_in_one_over_v():
    # an arrival affine in 1/v (a fixed lag plus distance over speed): the first guess scales
    # the first trial's speed by its arrival over the target (arrival taken as 1/v alone);
    # the secant in 1/v through two trials is then exact, and the third trial lands on it
    lag_s, target_s = 600.0, 30_000.0

    def arrival_of(speed_kn):
        return lag_s + DISTANCE_NM / speed_kn * 3600.0, None

    first = 16.0
    result = match_arrival_time(arrival_of, target_s, tolerance_s=1.0, first_speed_kn=first, aim_s=1e-6)
    speeds = [t.speed_kn for t in result.trials]
    first_arrival = arrival_of(first)[0]
    exact = DISTANCE_NM * 3600.0 / (target_s - lag_s)
    assert speeds == pytest.approx([first, first * first_arrival / target_s, exact], rel=1e-12)
    assert result.matched and abs(result.trials[-1].arrival_s - target_s) < 1e-6


def test_a_trial_that_does_not_arrive_is_followed_by_a_quarter_faster_one():
    tried = []

    def arrival_of(speed_kn):
        tried.append(speed_kn)
        return (None, None) if speed_kn < 20.0 else (DISTANCE_NM / speed_kn * 3600.0, None)

    match_arrival_time(arrival_of, 25_000.0, tolerance_s=60.0, first_speed_kn=12.0, max_trials=3)
    assert tried[:3] == pytest.approx([12.0, 15.0, 18.75])

