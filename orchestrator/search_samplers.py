"""A restarting TPE for searches whose failures lie in a small corner of the space.

optuna's TPE (multivariate, grouped) models where the lowest objectives were found and
samples near them.  Once it has found a basin it stays there: a basin that is a local
minimum, not a failure, holds it for the rest of the budget.  :class:`RestartingTPE`
starts it afresh when its best has not improved for ``stall`` evaluations (as CMA-ES is
restarted): each epoch's TPE sees only that epoch's evaluations.  Each epoch opens with
``startup`` evaluations drawn from a boundary-value design: every numeric parameter at its
lower bound, at its upper bound, or uniform between them (``edge``, ``edge``,
``1 - 2 edge``), each choice uniform.  The extremes of the declared ranges (the fastest
target, the smallest CPA, the most targets) are where test design looks first; uniform
draws almost never reach them exactly.

optuna's CMA-ES and GP samplers model only the parameters every evaluation has (the
intersection of the search spaces); in a search over 1-3 targets that is the first target
alone, the other targets' parameters being drawn at random.  TPE's group decomposition
models each target's parameters where they exist, which is why the restarts wrap TPE.

On an objective that keeps improving by small amounts (the paper's loop rides its collision
constraint, and its margins near 0 nm differ by thousandths of a mile from run to run), the
stall never comes: ``tpe-periodic`` restarts every ``PERIOD`` evaluations instead.

The sampler is made afresh for every evaluation (:func:`orchestrator.search.make_sampler`);
the epoch is computed from the finished evaluations in order, so a resumed search asks
what an uninterrupted one asks.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from optuna.samplers import BaseSampler as _BaseSampler

#: The declared settings of ``tpe-restart``: epochs end after 20 evaluations without a new
#: best; each opens with 10 boundary-value draws; a numeric value is at each bound 1/4 of the time.
STALL = 20
STARTUP = 10
EDGE = 0.25
#: ``tpe-periodic``: the same, its epochs 40 evaluations long whatever the objective does.
PERIOD = 40


def epoch_start(values: list[float | None], stall: int = STALL, period: int | None = None) -> int:
    """The number of the first evaluation of the current epoch.

    ``values`` are the finished evaluations' objectives in order (None: no objective).  An
    epoch ends after ``stall`` evaluations in a row that do not lower its best, or, with
    ``period``, after ``period`` evaluations.
    """
    if period is not None:
        return len(values) // period * period
    start, best, since = 0, math.inf, 0
    for number, value in enumerate(values):
        if value is not None and value < best:
            best, since = value, 0
        else:
            since += 1
        if since >= stall:
            start, best, since = number + 1, math.inf, 0
    return start


class _EpochView:
    """The study as the current epoch's TPE sees it: only the trials numbered from ``start`` on."""

    def __init__(self, study, start: int) -> None:
        self._study, self._start = study, start

    def __getattr__(self, name: str) -> Any:
        return getattr(self._study, name)

    def _get_trials(self, *args, **kwargs):
        return [t for t in self._study._get_trials(*args, **kwargs) if t.number >= self._start]

    def get_trials(self, *args, **kwargs):
        return [t for t in self._study.get_trials(*args, **kwargs) if t.number >= self._start]


class RestartingTPE(_BaseSampler):
    """optuna's multivariate grouped TPE, restarted after ``stall`` evaluations without a new best;
    each epoch's first ``startup`` evaluations drawn from a boundary-value design (module docstring)."""

    def __init__(self, seed: int, stall: int = STALL, startup: int = STARTUP, edge: float = EDGE,
                 period: int | None = None) -> None:
        import optuna

        self._tpe = optuna.samplers.TPESampler(seed=seed, multivariate=True, group=True, constant_liar=True,
                                               n_startup_trials=startup)
        self._random = optuna.samplers.RandomSampler(seed=seed)
        self._rng = np.random.default_rng(seed)
        self._stall, self._startup, self._edge, self._period = stall, startup, edge, period

    # optuna's sampler interface ------------------------------------------------------------
    def infer_relative_search_space(self, study, trial):
        view = self._view(study)
        return {} if self._starting(view) else self._tpe.infer_relative_search_space(view, trial)

    def sample_relative(self, study, trial, search_space):
        view = self._view(study)
        return {} if self._starting(view) else self._tpe.sample_relative(view, trial, search_space)

    def sample_independent(self, study, trial, param_name, param_distribution):
        view = self._view(study)
        if self._starting(view):
            return self._boundary_value(study, trial, param_name, param_distribution)
        return self._tpe.sample_independent(view, trial, param_name, param_distribution)

    def before_trial(self, study, trial) -> None:
        self._tpe.before_trial(study, trial)

    def after_trial(self, study, trial, state, values) -> None:
        self._tpe.after_trial(study, trial, state, values)

    def reseed_rng(self) -> None:
        self._tpe.reseed_rng()
        self._random.reseed_rng()

    # ----------------------------------------------------------------------------------------
    def _view(self, study) -> _EpochView:
        from optuna.trial import TrialState

        finished = [t for t in study._get_trials(deepcopy=False, use_cache=True)
                    if t.state in (TrialState.COMPLETE, TrialState.FAIL)]
        finished.sort(key=lambda t: t.number)
        values = [t.value if t.state == TrialState.COMPLETE else None for t in finished]
        start = epoch_start(values, self._stall, self._period)
        return _EpochView(study, finished[start].number if start < len(finished) else
                          (finished[-1].number + 1 if finished else 0))

    def _starting(self, view: _EpochView) -> bool:
        from optuna.trial import TrialState

        return len(view._get_trials(deepcopy=False, states=(TrialState.COMPLETE,), use_cache=True)) < self._startup

    def _boundary_value(self, study, trial, name: str, distribution):
        from optuna.distributions import FloatDistribution, IntDistribution

        if isinstance(distribution, (FloatDistribution, IntDistribution)):
            u = self._rng.random()
            if u < self._edge:
                return distribution.low
            if u < 2 * self._edge:
                return distribution.high
        return self._random.sample_independent(study, trial, name, distribution)


__all__ = ["EDGE", "PERIOD", "STALL", "STARTUP", "RestartingTPE", "epoch_start"]
