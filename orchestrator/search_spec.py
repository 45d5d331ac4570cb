"""A search file: a batch file whose ``[monte_carlo]`` ranges are searched instead of drawn.

The ``[search]`` table names the objective (a dotted path into a run's ``summary.json``,
minimised), the budget, the optimiser and its seed.  Every range of ``[monte_carlo]``
(the encounters' CPA, TCPA, speed, course offset, type and passing side, their number,
the obstacles, ``uniform``, ``choice`` and ``scale`` keys) is a parameter of the search;
``[set]`` applies to every evaluation, ``[[acceptance]]`` and ``[report]`` as in a batch.
Every error names the file and the key (exit code 2, nothing run).
"""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import dataclass
from typing import Annotated, Any

from pydantic import PlainValidator

from orchestrator.batch_model import MonteCarloSpec, Range
from orchestrator.batch_spec import BatchSpec, draw_overrides, load_batch
from orchestrator.errors import ScenarioError
from orchestrator.toml_input import (Finite, FolderName, NonNegativeInt, PositiveInt, TomlTable, checked, fail,
                                     one_of)

#: Optimisers (optuna samplers): TPE (default), CMA-ES, TPE restarted when it stalls or
#: periodically (:mod:`orchestrator.search_samplers`), and uniform random sampling of the same ranges.
SAMPLERS = ("tpe", "cmaes", "tpe-restart", "tpe-periodic", "random")
#: Most evaluations one search may ask for.
MAX_EVALUATIONS = 100_000


def _metric(value: Any) -> str:
    if not isinstance(value, str) or not value or not all(value.split(".")):
        raise fail("must be a dotted path into a run's summary.json, e.g. \"analyses.colregs.separation_margin_nm\"")
    return value


def _evaluations(value: Any) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or not 1 <= value <= MAX_EVALUATIONS:
        raise fail(f"must be a positive integer (at most {MAX_EVALUATIONS})")
    return value


class SearchTable(TomlTable):
    """``[search]``."""

    name: FolderName | None = None
    objective: Annotated[str, PlainValidator(_metric)]
    fails_below: Finite | None = None
    evaluations: Annotated[int, PlainValidator(_evaluations)]
    sampler: Annotated[str, one_of(SAMPLERS)] = "tpe"
    seed: NonNegativeInt | None = None
    per_round: PositiveInt = 4
    worst: NonNegativeInt = 10


@dataclass(frozen=True)
class SearchSpec:
    """A loaded, checked search: the batch it searches and the ``[search]`` settings."""

    batch: BatchSpec
    name: str
    objective: str
    fails_below: float | None
    evaluations: int
    sampler: str
    seed: int
    per_round: int
    worst: int
    space: dict

    @property
    def monte_carlo(self) -> MonteCarloSpec:
        """The batch's ``[monte_carlo]`` ranges, the space searched (:func:`load_search` refuses a
        file without them)."""
        if self.batch.monte_carlo is None:
            raise ScenarioError("a search needs [monte_carlo]: its ranges are the parameters searched")
        return self.batch.monte_carlo

    def identity(self) -> dict:
        """What must not change between a search and its resumption (the budget may)."""
        space = json.dumps(self.space, sort_keys=True, default=str)
        return {"scenario_sha256": self.batch.scenario_sha256, "objective": self.objective, "sampler": self.sampler,
                "seed": self.seed, "per_round": self.per_round, "fixed": self.batch.fixed,
                "space_sha256": hashlib.sha256(space.encode()).hexdigest()}

    def is_failure(self, value: float | None, passed: bool) -> bool:
        """A run that lost what the objective measures (below ``fails_below``), or, without it, did not pass."""
        if self.fails_below is None:
            return not passed
        return value is not None and value < self.fails_below


class _SpaceRecorder:
    """Walks the ``[monte_carlo]`` space once, noting every parameter that varies (conditional ones included)."""

    def __init__(self) -> None:
        self.space: dict[str, Any] = {}

    def number(self, name: str, span: Range) -> float:
        if span.high > span.low:
            self.space[name] = [span.low, span.high]
        return span.low

    def index(self, name: str, options) -> int:
        if len(options) > 1:
            self.space[name] = list(options)
        return 0

    def integer(self, name: str, low: int, high: int) -> int:
        if high > low:
            self.space[name] = [low, high]
        return high  # the largest count: every conditional parameter is visited

    def normal(self, name: str, mean: float, sd: float) -> float:
        return mean


def search_space(mc: MonteCarloSpec) -> dict[str, Any]:
    """Every searched parameter: ``[low, high]`` for a number or count, the options of a choice."""
    recorder = _SpaceRecorder()
    draw_overrides(mc, recorder)
    return recorder.space


def load_search(path, evaluations: int | None = None, sampler: str | None = None,
                seed: int | None = None, fails_below: float | None = None) -> SearchSpec:
    """Read and check a search file; ``evaluations``, ``sampler``, ``seed`` and ``fails_below`` replace the file's.

    ``fails_below`` changes which runs count as failures, not what the optimiser is told
    (it minimises the objective either way), so a search may be read again with another
    threshold.

    Raises
    ------
    ScenarioError
        For a malformed file, a missing ``[search]`` or ``[monte_carlo]``, a table a search
        cannot vary (``[grid]``, ``[situations]``, ``[monte_carlo.normal]``), or a space
        without a range.
    """
    batch = load_batch(path)
    where = str(batch.path)
    if batch.search is None:
        raise ScenarioError(f"{where}: no [search] table (objective, evaluations, ...): see docs/search.md")
    table = checked(SearchTable, batch.search, where, ("search",))
    if batch.monte_carlo is None:
        raise ScenarioError(f"{where}: a search needs [monte_carlo]: its ranges are the parameters searched")
    for name, present in (("grid", bool(batch.grid)), ("situations", bool(batch.situations)),
                          ("monte_carlo.normal", bool(batch.monte_carlo.normal))):
        if present:
            raise ScenarioError(f"{where}: '{name}': a search varies [monte_carlo]'s ranges only; "
                                "give a range ([low, high]) or a choice instead")
    space = search_space(batch.monte_carlo)
    if not space:
        raise ScenarioError(f"{where}: 'monte_carlo': no range to search (every value is fixed)")
    if evaluations is not None and not 1 <= evaluations <= MAX_EVALUATIONS:
        raise ScenarioError(f"--evaluations must be between 1 and {MAX_EVALUATIONS}, got {evaluations}")
    if sampler is not None and sampler not in SAMPLERS:
        raise ScenarioError(f"--sampler must be one of {', '.join(SAMPLERS)}, got {sampler!r}")
    if seed is not None and seed < 0:
        raise ScenarioError(f"--seed must be >= 0, got {seed}")
    if fails_below is not None and not math.isfinite(fails_below):
        raise ScenarioError(f"--fails-below must be a finite number, got {fails_below}")
    return SearchSpec(batch=batch, name=table.name or f"{batch.name}_search", objective=table.objective,
                      fails_below=fails_below if fails_below is not None else table.fails_below,
                      evaluations=evaluations if evaluations is not None else table.evaluations,
                      sampler=sampler or table.sampler,
                      seed=seed if seed is not None else table.seed if table.seed is not None
                      else batch.monte_carlo.seed,
                      per_round=table.per_round, worst=table.worst, space=space)


__all__ = ["MAX_EVALUATIONS", "SAMPLERS", "SearchSpec", "SearchTable", "load_search", "search_space"]
