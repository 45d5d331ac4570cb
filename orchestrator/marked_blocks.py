"""Generated text kept between two marker lines of a hand-written file (a README's figures)."""

from __future__ import annotations


def replace_between(text: str, begin: str, end: str, body: str) -> str | None:
    """``text`` with ``body`` between the markers ``begin`` and ``end`` (the first ``end`` after
    ``begin``), the markers kept; ``None`` when either is missing, for the caller to say which
    file and what it was writing."""
    head, found, rest = text.partition(begin)
    _, found_end, tail = rest.partition(end)
    if not found or not found_end:
        return None
    return f"{head}{begin}\n{body}\n{end}{tail}"
