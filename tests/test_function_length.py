"""No function of ``orchestrator/`` or ``rhnc/`` runs over 60 lines without saying why.

A function's length is counted from its ``def`` line to its last line, its docstring left
out (nested functions count in the function that holds them, and on their own).  A longer
function either is split by step, or its docstring holds a paragraph starting ``Length:``
that says why one piece reads better (a declarative table, one pass a reader follows top to
bottom, ...): at least :data:`REASON_WORDS` words after the label.

The tree checked is the one this file lies in (not whichever copy of the packages Python
imports), and the check is shown to fail on a constructed tree with a long function that
gives no reason.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
PACKAGES = ("orchestrator", "rhnc")
MAX_LINES = 60
REASON = "Length:"
#: Words a reason needs after ``Length:`` (a label alone is no reason).
REASON_WORDS = 3
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


def package_files(root: Path = ROOT) -> list[Path]:
    """The Python files of :data:`PACKAGES` below ``root``."""
    return [path for package in PACKAGES for path in sorted((root / package).rglob("*.py"))]


def long_functions(root: Path = ROOT) -> dict[str, tuple[int, str]]:
    """``file::name -> (lines, docstring)`` of every function over :data:`MAX_LINES`."""
    result = {}
    for path in package_files(root):
        for name, lines, doc in function_lengths(path.read_text(encoding="utf-8")):
            if lines > MAX_LINES:
                result[f"{path.relative_to(root).as_posix()}::{name}"] = (lines, doc)
    return result


def gives_reason(doc: str) -> bool:
    """True when a paragraph of ``doc`` starts ``Length:`` and says something after it."""
    for paragraph in doc.split("\n\n"):
        text = " ".join(paragraph.split())
        if text.startswith(REASON) and len(text[len(REASON):].split()) >= REASON_WORDS:
            return True
    return False


def unexplained(root: Path = ROOT, not_yet_split: set[str] = NOT_YET_SPLIT) -> list[str]:
    """``file::name (n lines)`` of every long function that gives no reason."""
    return [f"{where} ({lines} lines)" for where, (lines, doc) in sorted(long_functions(root).items())
            if where not in not_yet_split and not gives_reason(doc)]


def test_every_long_function_gives_its_reason():
    assert len(package_files()) > 100, f"too few files of {PACKAGES} below {ROOT}: the wrong tree?"
    found = unexplained()
    assert not found, ("functions over 60 lines without a 'Length:' paragraph in their docstring "
                       "(split them by step, or say why not):\n" + "\n".join(found))


def test_the_list_of_functions_not_yet_split_holds_only_long_ones():
    assert not NOT_YET_SPLIT - set(long_functions()), "no longer long: remove from NOT_YET_SPLIT: " + ", ".join(sorted(NOT_YET_SPLIT - set(long_functions())))


def _tree_with(tmp_path: Path, docstring: str, body_lines: int) -> Path:
    """A tree with one function in ``rhnc/`` of ``body_lines`` lines after its docstring."""
    (tmp_path / "orchestrator").mkdir()
    (tmp_path / "rhnc" / "deep").mkdir(parents=True)
    (tmp_path / "orchestrator" / "short.py").write_text("def short():\n    return 1\n")
    (tmp_path / "rhnc" / "deep" / "long.py").write_text(
        f"class Plan:\n    def make(self):\n        \"\"\"{docstring}\"\"\"\n" + "        x = 1\n" * body_lines)
    return tmp_path


@pytest.mark.parametrize("docstring, body_lines, reported", [
    ("Make the plan.", 59, False),                                  # 60 lines with its def: allowed
    ("Make the plan.", 60, True),                                   # 61: over
    ("Make the plan.\n\n        Length: one declarative table, row by row.", 60, False),
    ("Make the plan.\n\n        Length:", 60, True),                # a label is no reason
    ("Make the plan.\n\n        Length: short.", 60, True),
    ("Make the plan, Length: in passing, not a paragraph of its own.", 60, True),
])
def test_a_long_function_without_a_reason_is_reported(tmp_path, docstring, body_lines, reported):
    root = _tree_with(tmp_path, docstring, body_lines)
    expected = [f"rhnc/deep/long.py::Plan.make ({body_lines + 1} lines)"] if reported else []
    assert unexplained(root, set()) == expected
    assert unexplained(root, {"rhnc/deep/long.py::Plan.make"}) == []     # the list of exceptions holds


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
