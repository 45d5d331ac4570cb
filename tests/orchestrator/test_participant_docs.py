"""docs/participants.md lists exactly the options every built-in participant type accepts.

Each section ``## `<type>` `` holds a table whose first column names option keys in
backticks; together they must equal the ``OPTIONS`` of the class registered for that type
by this project (entry-point group ``rhnc_cosim.participants``).
"""

from __future__ import annotations

import re
from pathlib import Path

from orchestrator import plugins

PAGE = Path(__file__).resolve().parents[2] / "docs" / "participants.md"


def documented_options(text: str) -> dict[str, set[str]]:
    """Section type name -> option keys named in the first column of its table."""
    sections: dict[str, set[str]] = {}
    current = None
    for line in text.splitlines():
        heading = re.fullmatch(r"## `(\w+)`", line.strip())
        if heading:
            current = sections.setdefault(heading.group(1), set())
        elif current is not None and line.startswith("| `"):
            current.update(re.findall(r"`(\w+)`", line.split("|")[1]))
    return sections


def own_types() -> dict[str, type]:
    return {name: registration.load() for name, registration in plugins.registrations("participants").items()
            if registration.distribution == plugins.DISTRIBUTION}


def test_every_type_has_a_section():
    assert set(documented_options(PAGE.read_text())) == set(own_types())


def test_each_section_lists_exactly_the_accepted_options():
    documented = documented_options(PAGE.read_text())
    for name, cls in own_types().items():
        assert documented[name] == set(cls.OPTIONS), name


def test_the_reader_sees_a_missing_option():
    text = PAGE.read_text().replace("| `arrival_radius_nm` |", "| arrival radius |")
    assert "arrival_radius_nm" not in documented_options(text)["goal"]
