"""Acceptance criteria of a batch, evaluated on a run's summary.json; a missing figure fails, never raises."""

from __future__ import annotations

import operator
import re
from dataclasses import dataclass
from typing import Any

from orchestrator.batch_spec import Criterion
from orchestrator.participant import is_finite_number

_OPERATORS = {"<": operator.lt, "<=": operator.le, "==": operator.eq, "!=": operator.ne,
              ">=": operator.ge, ">": operator.gt}
_ORDERING = ("<", "<=", ">=", ">")
_TERMS = re.compile(r"\s+([+-])\s+")


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
