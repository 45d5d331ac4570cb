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



# -- the search's rules, one by one, on scripted and affine arrivals ---------------------------
def scripted(target_s, offsets_s):
    """An arrival function that answers ``target_s + offset`` from ``offsets_s`` in turn."""
    answers = iter(offsets_s)

    def arrival_of(speed_kn):
        return target_s + next(answers), None

    return arrival_of


def affine(lag_s=600.0):
    """Arrival affine in 1/v: a fixed lag plus the distance over the speed."""
    return lambda speed_kn: (lag_s + DISTANCE_NM / speed_kn * 3600.0, None)


def test_a_baseline_without_a_trial_around_the_target_says_so():
    lonely = EqualArrival(target_s=1000.0, tolerance_s=10.0, trials=[ArrivalTrial(10.0, 5000.0)])
    with pytest.raises(ValueError, match="^the equal-arrival baseline has no trial at or around the target arrival$"):
        lonely.at_target(lambda t: 1.0)


def test_the_search_stops_at_half_the_tolerance_unless_told_otherwise():
    # tolerance 10 s: the default aim is 5 s, so 6 s off goes on and 4 s off stops
    result = match_arrival_time(scripted(20_000.0, [6.0, -4.0, 0.1, 0.0]), 20_000.0, tolerance_s=10.0,
                                first_speed_kn=12.0)
    assert len(result.trials) == 2
    # an explicit aim is the one used: 4 s off is not close enough for an aim of 1 s
    result = match_arrival_time(scripted(20_000.0, [6.0, -4.0, 0.5, 0.0]), 20_000.0, tolerance_s=10.0,
                                first_speed_kn=12.0, aim_s=1.0)
    assert len(result.trials) == 3


def test_a_trial_exactly_at_the_aim_ends_the_search():
    result = match_arrival_time(scripted(20_000.0, [5.0, 1.0]), 20_000.0, tolerance_s=10.0, first_speed_kn=12.0)
    assert len(result.trials) == 1


def jump(target_s, lag_s=600.0):
    """Affine arrival with a 600 s jump over the target at the speed that would meet it:
    no speed lands near the target, and the search bisects the jump."""
    at_kn = DISTANCE_NM * 3600.0 / (target_s - lag_s)

    def arrival_of(speed_kn):
        base = lag_s + DISTANCE_NM / speed_kn * 3600.0
        return (base - 300.0 if speed_kn >= at_kn else base + 300.0), None

    return arrival_of, at_kn


def test_eight_trials_by_default():
    arrival_of, _ = jump(30_000.0)
    result = match_arrival_time(arrival_of, 30_000.0, tolerance_s=10.0, first_speed_kn=12.0)
    assert len(result.trials) == 8


def test_bisection_ends_once_the_bracket_is_narrower_than_a_micro_knot():
    arrival_of, at_kn = jump(30_000.0)
    result = match_arrival_time(arrival_of, 30_000.0, tolerance_s=10.0, first_speed_kn=12.0, max_trials=200)
    assert len(result.trials) < 200
    early, late = result.bracket
    assert 0 < early.speed_kn - late.speed_kn < 1e-6
    assert late.speed_kn < at_kn <= early.speed_kn
    # the midpoint that would come next lies closer than a micro-knot to both: not tried
    assert len(result.trials) <= 40


def test_no_speed_is_tried_twice():
    # never arrives: a quarter faster each time up to the top bound, which is tried once
    tried = []

    def arrival_of(speed_kn):
        tried.append(speed_kn)
        return None, None

    match_arrival_time(arrival_of, 20_000.0, tolerance_s=10.0, first_speed_kn=20.0, max_trials=20)
    assert tried == pytest.approx([20.0, 25.0, 30.0])


def test_the_secant_runs_through_the_last_two_arrived_trials():
    from rhnc.voyage.equal_arrival import _next_speed

    arrival_of = affine()
    target_s = 30_000.0
    trials = [ArrivalTrial(v, arrival_of(v)[0]) for v in (25.0, 20.0, 18.0)]
    exact = DISTANCE_NM * 3600.0 / (target_s - 600.0)
    assert _next_speed(trials, target_s, trials[-1], None, 2.0, 30.0) == pytest.approx(exact, rel=1e-12)


def test_a_shallow_but_rising_secant_is_still_followed():
    from rhnc.voyage.equal_arrival import _next_speed

    # arrival grows by 0.05 s from 10 kn to 5 kn: slope 0.5 s per 1/kn, positive
    trials = [ArrivalTrial(10.0, 1000.0), ArrivalTrial(5.0, 1000.05)]
    assert _next_speed(trials, 1000.1, None, trials[-1], 2.0, 30.0) == pytest.approx(1.0 / 0.3, rel=1e-9)


def test_a_falling_secant_without_a_bracket_ends_the_search():
    from rhnc.voyage.equal_arrival import _next_speed

    trials = [ArrivalTrial(10.0, 1000.0), ArrivalTrial(9.0, 900.0)]   # slower, yet earlier
    assert _next_speed(trials, 1100.0, None, trials[-1], 2.0, 30.0) is None


def test_the_secant_is_kept_inside_the_bracket_when_it_falls_there():
    from rhnc.voyage.equal_arrival import _next_speed

    arrival_of = affine()
    target_s = 30_000.0
    early, late = ArrivalTrial(20.0, arrival_of(20.0)[0]), ArrivalTrial(12.0, arrival_of(12.0)[0])
    exact = DISTANCE_NM * 3600.0 / (target_s - 600.0)   # 17.25 kn, not the midpoint 16 kn
    assert _next_speed([early, late], target_s, early, late, 2.0, 30.0) == pytest.approx(exact, rel=1e-12)


def test_a_bracket_narrower_than_a_micro_knot_ends_the_search():
    from rhnc.voyage.equal_arrival import _next_speed

    early, late = ArrivalTrial(10.0 + 5e-7, 900.0), ArrivalTrial(10.0, 1100.0)
    assert _next_speed([early, late], 1000.0, early, late, 2.0, 30.0) is None
    wider_early = ArrivalTrial(10.0 + 5e-6, 900.0)
    assert _next_speed([wider_early, late], 1000.0, wider_early, late, 2.0, 30.0) == pytest.approx(10.0 + 2.5e-6)


def test_a_guess_of_zero_ends_the_search_and_a_small_one_is_raised_to_the_bound():
    from rhnc.voyage.equal_arrival import _next_speed

    at_once = [ArrivalTrial(10.0, 0.0)]        # arrived at departure: the one-point guess is 0 kn
    assert _next_speed(at_once, 1000.0, at_once[0], None, 2.0, 30.0) is None
    early = [ArrivalTrial(10.0, 50.0)]         # guess 10 * 50 / 1000 = 0.5 kn, below the 2 kn bound
    assert _next_speed(early, 1000.0, early[0], None, 2.0, 30.0) == 2.0


def test_a_baseline_that_arrives_at_no_speed_up_to_the_fastest_cannot_arrive():
    # a ship held back by the weather: no run arrives whatever the reference speed
    result = match_arrival_time(lambda v: (None, "held back"), 25_000.0, tolerance_s=2.0, first_speed_kn=14.85,
                                max_trials=5, speed_bounds_kn=(2.0, 30.0))
    assert [round(t.speed_kn, 2) for t in result.trials] == [14.85, 18.56, 23.2, 29.0, 30.0]
    assert result.cannot_arrive and not result.usable
    # the same search cut short before the fastest speed: it ran out of trials, nothing more
    short = match_arrival_time(lambda v: (None, "held back"), 25_000.0, tolerance_s=2.0, first_speed_kn=14.85,
                               max_trials=4, speed_bounds_kn=(2.0, 30.0))
    assert not short.cannot_arrive
    # one trial arrived, even too late: the baseline can arrive
    late = EqualArrival(25_000.0, 2.0, [ArrivalTrial(30.0, None), ArrivalTrial(29.0, 40_000.0)], top_speed_kn=30.0)
    assert not late.cannot_arrive
