"""A search's journal (``trials.jsonl``) and what each journaled evaluation gives: its run and its objective."""

from __future__ import annotations

import json
import os
from pathlib import Path

from orchestrator import acceptance
from orchestrator.batch_run import read_summary
from orchestrator.batch_spec import RunSpec

JOURNAL = "trials.jsonl"


# -- the journal --------------------------------------------------------------------------------
def read_journal(path: Path) -> list[dict]:
    """The journaled evaluations in order; a torn last line (the search killed while writing) is dropped."""
    entries = []
    try:
        lines = path.read_text().splitlines()
    except FileNotFoundError:
        return entries
    for line in lines:
        try:
            entry = json.loads(line)
        except ValueError:
            break
        if entry.get("number") != len(entries):
            break
        entries.append(entry)
    return entries


def append_journal(path: Path, entries: list[dict]) -> None:
    """Append one round's entries in one write, flushed to disk before the round runs."""
    text = "".join(json.dumps(entry, sort_keys=True) + "\n" for entry in entries)
    with open(path, "a") as handle:
        handle.write(text)
        handle.flush()
        os.fsync(handle.fileno())


def run_spec_of(entry: dict) -> RunSpec:
    return RunSpec(entry["run_id"], entry["number"], entry["overrides"],
                   {"evaluation": entry["number"], **entry["parameters"]})


def objective_of(spec, root: Path, identifier: str) -> float | None:
    """The evaluation's objective, or None when the run did not finish or has no such number."""
    summary = read_summary(root / "runs" / identifier)
    if summary is None or summary.get("status") != "finished":
        return None
    try:
        value = acceptance.lookup(summary, spec.objective)
    except acceptance.MissingFigure:
        return None
    if isinstance(value, bool) or not isinstance(value, (int, float)) or value != value:
        return None
    return float(value)


def drop_torn_tail(path: Path, entries: list[dict]) -> None:
    """Rewrite the journal as ``entries`` when it holds more (a line torn by a kill), so appends stay whole."""
    text = "".join(json.dumps(entry, sort_keys=True) + "\n" for entry in entries)
    if path.is_file() and path.read_text() != text:
        staging = path.parent / f".{path.name}.partial"
        staging.write_text(text)
        os.replace(staging, path)
