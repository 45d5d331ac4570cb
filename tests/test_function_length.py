"""No function of ``orchestrator/`` or ``rhnc/`` runs over 60 lines without saying why.

A function's length is counted from its ``def`` line to its last line, its docstring left
out (nested functions count in the function that holds them, and on their own).  A longer
function either is split by step, or its docstring holds a paragraph starting ``Length:``
that says why one piece reads better (a declarative table, one pass a reader follows top to
bottom, ...).
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

import orchestrator

ROOT = Path(orchestrator.__file__).resolve().parent.parent
PACKAGES = ("orchestrator", "rhnc")
MAX_LINES = 60
REASON = "Length:"
#: Over 60 lines and not yet split by step (each waits for work going on in its module):
#: ``file::qualified name``.  An entry that is no longer long fails the test, so the list
#: only shrinks.
NOT_YET_SPLIT: set[str] = set()


def _docstring_lines(node: ast.AST) -> int:
    body = getattr(node, "body", [])
    if body and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant) \
            and isinstance(body[0].value.value, str):
        return body[0].end_lineno - body[0].lineno + 1
    return 0


def function_lengths(source: str):
    """``(qualified name, lines without the docstring, docstring)`` of every function in ``source``."""
    found = []

    def visit(node: ast.AST, prefix: str) -> None:
        for child in ast.iter_child_nodes(node):
            if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef)):
                name = f"{prefix}{child.name}"
                lines = child.end_lineno - child.lineno + 1 - _docstring_lines(child)
                found.append((name, lines, ast.get_docstring(child) or ""))
                visit(child, f"{name}.")
            elif isinstance(child, ast.ClassDef):
                visit(child, f"{prefix}{child.name}.")
            else:
                visit(child, prefix)

    visit(ast.parse(source), "")
    return found


def long_functions() -> dict[str, tuple[int, str]]:
    """``file::name -> (lines, docstring)`` of every function over :data:`MAX_LINES`."""
    result = {}
    for package in PACKAGES:
        for path in sorted((ROOT / package).rglob("*.py")):
            for name, lines, doc in function_lengths(path.read_text(encoding="utf-8")):
                if lines > MAX_LINES:
                    result[f"{path.relative_to(ROOT).as_posix()}::{name}"] = (lines, doc)
    return result


def test_every_long_function_gives_its_reason():
    unexplained = [f"{where} ({lines} lines)" for where, (lines, doc) in sorted(long_functions().items())
                   if where not in NOT_YET_SPLIT and not any(line.strip().startswith(REASON)
                                                           for line in doc.splitlines())]
    assert not unexplained, ("functions over 60 lines without a 'Length:' paragraph in their docstring "
                             "(split them by step, or say why not):\n" + "\n".join(unexplained))


def test_the_list_of_functions_not_yet_split_holds_only_long_ones():
    assert not NOT_YET_SPLIT - set(long_functions()), "no longer long: remove from NOT_YET_SPLIT: " + ", ".join(sorted(NOT_YET_SPLIT - set(long_functions())))


@pytest.mark.parametrize("body, expected", [
    ("    x = 1\n" * 59, 60),
    ('    """A docstring\n\n    over three lines."""\n' + "    x = 1\n" * 59, 60),
    ("    x = 1\n" * 60, 61),
])
def test_a_function_is_measured_without_its_docstring(body, expected):
    (name, lines, _), = function_lengths("def f():\n" + body)
    assert (name, lines) == ("f", expected)


def test_methods_and_nested_functions_are_measured_by_their_qualified_names():
    source = "class A:\n    def m(self):\n        def inner():\n            pass\n        return inner\n"
    assert [(name, lines) for name, lines, _ in function_lengths(source)] == [("A.m", 4), ("A.m.inner", 2)]
