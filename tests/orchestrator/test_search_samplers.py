"""The restarting TPE: when an epoch ends, what the next epoch sees, and its boundary-value draws."""

import optuna
import pytest

from orchestrator.search import make_sampler
from orchestrator.search_samplers import RestartingTPE, epoch_start

optuna.logging.set_verbosity(optuna.logging.WARNING)


def test_an_epoch_ends_after_stall_evaluations_without_a_new_best():
    assert epoch_start([], 3) == 0
    assert epoch_start([5.0, 4.0, 4.5, 4.0, 6.0], 3) == 5  # three in a row not below 4.0
    assert epoch_start([5.0, 4.0, 4.5, 4.0], 3) == 0
    assert epoch_start([5.0, 4.5, 3.0, 4.0, 3.5], 3) == 0  # each new best starts the count again
    assert epoch_start([None, None, None, 1.0], 3) == 3  # evaluations without an objective count as stalled
    # a new epoch's best starts afresh: 9.0 is its best though worse than the last epoch's
    assert epoch_start([1.0, 2.0, 2.0, 9.0, 8.0, 9.0], 2) == 3
    assert epoch_start([1.0, 2.0, 2.0, 9.0, 8.0, 9.0, 9.0], 2) == 7
    # periodic: every period evaluations, new bests or not
    assert epoch_start([-float(i) for i in range(7)], 2, period=3) == 6
    assert epoch_start([-float(i) for i in range(6)], 2, period=3) == 6
    assert epoch_start([1.0] * 5, 2, period=3) == 3


def _study_with(values, xs):
    study = optuna.create_study(direction="minimize")
    dist = optuna.distributions.FloatDistribution(0.0, 1.0)
    for value, x in zip(values, xs):  # two parameters, so that the TPE's joint (relative) sampling is used
        study.add_trial(optuna.trial.create_trial(value=value, params={"x": x, "y": (x * 7.0) % 1.0},
                                                  distributions={"x": dist, "y": dist}))
    return study


def _asked(values, xs, sampler, seeds, joint=False):
    """The next x asked after the evaluations (values, xs), by a fresh sampler of each seed."""
    asked, asked_y = [], []
    for seed in seeds:
        study = _study_with(values, xs)
        study.sampler = sampler(seed)
        trial = study.ask()
        asked.append(trial.suggest_float("x", 0.0, 1.0))
        asked_y.append(trial.suggest_float("y", 0.0, 1.0))
    return asked if not joint else list(zip(asked, asked_y))


def _tpe(seed):
    return optuna.samplers.TPESampler(seed=seed, multivariate=True, group=True, constant_liar=True,
                                      n_startup_trials=10)


def test_within_an_epoch_it_asks_what_the_tpe_asks_of_that_epoch_alone():
    xs = [(0.37 * i) % 1.0 for i in range(40)]
    improving = [-float(i) if i % 2 == 0 else 100.0 for i in range(16)]  # a new best every other one
    restarting = _asked(improving, xs, lambda s: RestartingTPE(seed=s, stall=5, startup=10), range(20), joint=True)
    assert restarting == _asked(improving, xs, _tpe, range(20), joint=True)
    assert not any(x in (0.0, 1.0) for x, _ in restarting)
    # the best first, then 11 without a new best: a new epoch from evaluation 12 (stall 11), 14 long
    stalled = [-100.0] + [1.0] * 11 + improving[:14]
    restarting = _asked(stalled, xs, lambda s: RestartingTPE(seed=s, stall=11, startup=10), range(20), joint=True)
    assert restarting == _asked(improving[:14], xs[12:], _tpe, range(20), joint=True)  # the first epoch unseen
    assert restarting != _asked(stalled, xs, _tpe, range(20), joint=True)


def test_an_epoch_opens_with_boundary_values():
    stalled = [-100.0] + [1.0] * 14  # a new epoch from evaluation 11 (stall 10): its start-up
    fresh = _asked(stalled, [0.3] * 15, lambda s: RestartingTPE(seed=s, stall=10, startup=10), range(200))
    at_bounds = sum(x in (0.0, 1.0) for x in fresh)
    assert 70 <= at_bounds <= 130  # half of them, a quarter at each end
    inside = [x for x in fresh if x not in (0.0, 1.0)]
    assert sum(x < 0.5 for x in inside) == pytest.approx(len(inside) / 2, abs=20)  # the rest uniform
    assert not any(x in (0.0, 1.0) for x in _asked(stalled, [0.3] * 15, _tpe, range(200)))


def test_the_search_knows_the_sampler_and_a_fresh_one_asks_the_same():
    first = _asked([0.0] + [1.0] * 14, [0.5] * 15, lambda s: make_sampler("tpe-restart", 3, s), [16, 17])
    assert _asked([0.0] + [1.0] * 14, [0.5] * 15, lambda s: make_sampler("tpe-restart", 3, s), [16, 17]) == first
    assert isinstance(make_sampler("tpe-restart", 1, 0), RestartingTPE)
    # periodic: 45 evaluations improving every time, a new epoch at 40 with 5 done: still its start-up
    periodic = _asked([-float(i) for i in range(45)], [0.3] * 45, lambda s: make_sampler("tpe-periodic", 3, s),
                      range(100))
    assert sum(x in (0.0, 1.0) for x in periodic) >= 30
    assert not any(x in (0.0, 1.0) for x in _asked([-float(i) for i in range(45)], [0.3] * 45,
                                                      lambda s: make_sampler("tpe-restart", 3, s), range(100)))


@pytest.mark.parametrize("edge", [0.0, 0.5])
def test_integers_and_choices_follow_the_design(edge):
    study = optuna.create_study(direction="minimize")
    counts, kinds = [], []
    for seed in range(100):
        study.sampler = RestartingTPE(seed=seed, edge=edge)
        trial = study.ask()
        counts.append(trial.suggest_int("n", 1, 3))
        kinds.append(trial.suggest_categorical("kind", ["a", "b", "c"]))
        study.tell(trial, state=optuna.trial.TrialState.FAIL)
    assert set(kinds) == {"a", "b", "c"}
    middle = counts.count(2)
    assert (middle == 0) if edge == 0.5 else (middle > 20)
