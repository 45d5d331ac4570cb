"""Draw the domain's wings and the imports between them into ``docs/wings.md`` (a Mermaid graph).

The wings of ``rhnc/`` are listed lowest first; an arrow ``a --> b`` says that modules of
wing ``a`` import modules of wing ``b`` (at any depth, lazy imports included), labelled with
how many of ``a``'s modules do so; every wing imports the engine (``orchestrator``), drawn
once below them.  The arrows are read from the code, so the drawing shows the arrows as they
are: ``tests/orchestrator/test_layers.py`` checks that they all point down and that the
committed drawing is the one this script draws today.  Run after moving code between wings::

    python scripts/wings_diagram.py
"""

from __future__ import annotations

import ast
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DOMAIN = "rhnc"
ENGINE = "orchestrator"
#: the wings, lowest first (as tests/orchestrator/test_layers.py orders them)
WINGS = ("ship", "chart", "weather", "routing", "voyage", "navigation", "encounters", "control", "cosim")
OUTPUT = ROOT / "docs" / "wings.md"
BEGIN, END = "```mermaid", "```"


def _imports(path: Path):
    """Every module name imported by the file (``import a.b``, ``from a.b import c`` as ``a.b.c`` and ``a.b``)."""
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield alias.name
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            yield node.module
            for alias in node.names:
                yield f"{node.module}.{alias.name}"


def wing_of(module: str) -> str | None:
    parts = module.split(".")
    if parts[0] == ENGINE:
        return ENGINE
    return parts[1] if parts[0] == DOMAIN and len(parts) > 1 and parts[1] in WINGS else None


def wing_edges(root: Path = ROOT) -> dict[tuple[str, str], int]:
    """``(importing wing, imported wing) -> number of the importing wing's modules that import it``."""
    edges: dict[tuple[str, str], int] = {}
    for wing in WINGS:
        for path in sorted((root / DOMAIN / wing).rglob("*.py")):
            reached = {wing_of(name) for name in _imports(path)} - {None, wing}
            for other in reached:
                edges[(wing, str(other))] = edges.get((wing, str(other)), 0) + 1
    return edges


def diagram(edges: dict[tuple[str, str], int]) -> str:
    """The Mermaid graph: the wings top (highest) to bottom (lowest), the engine under them."""
    lines = [BEGIN, "flowchart TB"]
    for wing in reversed(WINGS):
        lines.append(f"    {wing}[{wing}/]")
    lines.append(f"    {ENGINE}[({ENGINE}: the engine)]")
    for wing in reversed(WINGS):
        for other in [*reversed(WINGS), ENGINE]:
            count = edges.get((wing, other))
            if count:
                lines.append(f"    {wing} -->|{count}| {other}")
    lines.append(END)
    return "\n".join(lines)


def page(edges: dict[tuple[str, str], int]) -> str:
    return ("# The domain's wings\n\n"
            "`rhnc/` is cut into wings by role, lowest first: "
            + ", ".join(f"`{wing}/`" for wing in WINGS)
            + ". A wing imports only the wings below it, and the engine (`orchestrator/`) imports none of them. "
              "An arrow reads *imports*; its label is the number of the importing wing's modules that import "
              "the other wing. Drawn from the code by `python scripts/wings_diagram.py`; "
              "`tests/orchestrator/test_layers.py` checks that every arrow points down and that this drawing "
              "is today's.\n\n" + diagram(edges) + "\n")


def main() -> int:
    OUTPUT.write_text(page(wing_edges()), encoding="utf-8")
    print(f"wrote {OUTPUT.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
