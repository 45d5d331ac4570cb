"""Acceptance criteria of a batch, evaluated on a run's summary.json; a missing figure fails, never raises."""

from __future__ import annotations

import json
import operator
import re
from dataclasses import dataclass
from typing import Any

from pydantic import model_validator

from orchestrator.errors import ScenarioError
from orchestrator.toml_input import TomlTable, checked, fail_whole, is_finite_number, shown

_OPERATORS = {"<": operator.lt, "<=": operator.le, "==": operator.eq, "!=": operator.ne,
              ">=": operator.ge, ">": operator.gt}
_ORDERING = ("<", "<=", ">=", ">")
_TERMS = re.compile(r"\s+([+-])\s+")


#: Comparison operators of a criterion.
OPERATORS = ("<", "<=", "==", "!=", ">=", ">")


@dataclass(frozen=True)
class Criterion:
    """``[[acceptance]]``: ``metric op value`` or ``metric op ref``, paths into summary.json."""

    name: str
    metric: str
    op: str
    value: Any = None
    ref: str | None = None

    def describe(self) -> str:
        return f"{self.metric} {self.op} {self.ref if self.ref is not None else json.dumps(self.value)}"


class CriterionTable(TomlTable):
    """One ``[[acceptance]]`` table of a scenario or batch file."""

    name: Any = None
    metric: Any = None
    op: Any = None
    value: Any = None
    ref: Any = None

    @model_validator(mode="after")
    def _checks(self):
        if not isinstance(self.metric, str) or not self.metric:
            raise fail_whole("'{prefix}metric' must be a dotted path into summary.json")
        if self.op not in OPERATORS:
            raise fail_whole(f"'{{prefix}}op' must be one of {' '.join(OPERATORS)}, got {shown(self.op)}")
        if ("value" in self.model_fields_set) == ("ref" in self.model_fields_set):
            raise fail_whole("'{prefix}': give exactly one of 'value' (a literal) or 'ref' "
                             "(figures of the summary joined by ' + ' / ' - ')")
        if self.ref is not None and (not isinstance(self.ref, str) or not self.ref.strip()):
            raise fail_whole("'{prefix}ref' must be a string such as \"a.b + c.d + 0.1\"")
        if isinstance(self.value, float) and not is_finite_number(self.value):
            raise fail_whole(f"'{{prefix}}value' must be finite, got {shown(self.value)}")
        name = self.metric if self.name is None else self.name
        if not isinstance(name, str) or not name:
            raise fail_whole(f"'{{prefix}}name' must be a unique non-empty string, got {shown(name)}")
        return self


def parse_acceptance(entries: Any, where: str) -> tuple[Criterion, ...]:
    """``[[acceptance]]`` entries of a batch or scenario file, checked; errors name file and key."""
    if not isinstance(entries, list) or not all(isinstance(e, dict) for e in entries):
        raise ScenarioError(f"{where}: 'acceptance' must be an array of tables ([[acceptance]])")
    criteria, names = [], set()
    for k, entry in enumerate(entries):
        table = checked(CriterionTable, entry, where, ("acceptance", k))
        name = table.name if table.name is not None else table.metric
        if name in names:
            raise ScenarioError(f"{where}: 'acceptance[{k}].name' must be a unique non-empty string, got {shown(name)}")
        names.add(name)
        criteria.append(Criterion(name=name, metric=table.metric, op=table.op, value=table.value, ref=table.ref))
    return tuple(criteria)


class MissingFigure(LookupError):
    """A dotted path that does not lead to a value of the summary."""


@dataclass(frozen=True)
class Verdict:
    """One criterion on one run: passed or not, and why not."""

    name: str
    passed: bool
    value: Any
    reason: str = ""


def lookup(summary: dict, dotted: str):
    """The value at ``dotted`` in a run summary.

    Keys may contain dots themselves (the ``overrides`` table is keyed by dotted scenario
    keys), so at each level the longest matching key wins; integers index lists
    (``overrides.participants.traffic.options.targets.0.radius_nm``).

    Raises
    ------
    MissingFigure
        When the path leads nowhere; the message names the part that is missing.
    """
    parts = dotted.split(".")
    node, done = summary, 0
    while done < len(parts):
        if isinstance(node, dict):
            for end in range(len(parts), done, -1):
                key = ".".join(parts[done:end])
                if key in node:
                    node, done = node[key], end
                    break
            else:
                raise MissingFigure(f"'{dotted}' not in summary.json (no '{parts[done]}' at "
                                    f"'{'.'.join(parts[:done]) or '<top>'}')")
        elif isinstance(node, list) and parts[done].lstrip("-").isdigit() and -len(node) <= int(parts[done]) < len(node):
            node, done = node[int(parts[done])], done + 1
        else:
            raise MissingFigure(f"'{dotted}' not in summary.json ('{'.'.join(parts[:done])}' is a value)")
    return node


def reference_value(summary: dict, ref: str) -> float:
    """Evaluate ``"a.b + c.d - 0.1"``: figures of the summary and numbers joined by ' + ' / ' - '."""
    tokens = _TERMS.split(ref.strip())
    total, sign = 0.0, 1.0
    for position, token in enumerate(tokens):
        if position % 2:
            sign = 1.0 if token == "+" else -1.0
            continue
        try:
            term = float(token)
        except ValueError:
            term = lookup(summary, token)
            if not is_finite_number(term):
                raise MissingFigure(f"'{token}' in ref '{ref}' is {term!r}, not a number") from None
        total += sign * float(term)
    return total


def evaluate(criteria: tuple[Criterion, ...], summary: dict) -> list[Verdict]:
    """Each criterion's verdict on ``summary`` (a run's summary.json as a dict)."""
    verdicts = []
    for criterion in criteria:
        try:
            value = lookup(summary, criterion.metric)
            bound = reference_value(summary, criterion.ref) if criterion.ref is not None else criterion.value
        except MissingFigure as exc:
            verdicts.append(Verdict(criterion.name, False, None, str(exc)))
            continue
        if criterion.op in _ORDERING and not (is_finite_number(value) and is_finite_number(bound)):
            verdicts.append(Verdict(criterion.name, False, value,
                                    f"'{criterion.metric}' = {value!r} is not a number to compare with {bound!r}"))
            continue
        passed = bool(_OPERATORS[criterion.op](value, bound))
        reason = "" if passed else f"{criterion.metric} = {_show(value)}, not {criterion.op} {_show(bound)}"
        verdicts.append(Verdict(criterion.name, passed, value, reason))
    return verdicts


def _show(value) -> str:
    return f"{value:.6g}" if is_finite_number(value) else repr(value)
