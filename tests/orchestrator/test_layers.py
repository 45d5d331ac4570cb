"""The co-simulation master is a layer below the ship domain: it never imports ``rhnc``.

Every Python file of ``orchestrator/`` is parsed and each ``import``/``from ... import``
(at any depth, lazy ones inside functions included) and each ``importlib.import_module``
or ``__import__`` call with a literal name is checked.  What the master needs of a domain it
finds through entry points (:mod:`orchestrator.plugins`).
"""

from __future__ import annotations

import ast
from pathlib import Path

import orchestrator

ENGINE = Path(orchestrator.__file__).resolve().parent
DOMAIN = "rhnc"


def _imported_modules(tree: ast.AST):
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield node.lineno, alias.name
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            yield node.lineno, node.module
        elif isinstance(node, ast.Call) and node.args and isinstance(node.args[0], ast.Constant):
            function = node.func
            name = function.attr if isinstance(function, ast.Attribute) else getattr(function, "id", "")
            if name in ("import_module", "__import__") and isinstance(node.args[0].value, str):
                yield node.lineno, node.args[0].value


def domain_imports(folder: Path) -> list[str]:
    """``file:line module`` for every import of the domain package under ``folder``."""
    found = []
    for path in sorted(folder.rglob("*.py")):
        tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
        for line, module in _imported_modules(tree):
            if module == DOMAIN or module.startswith(DOMAIN + "."):
                found.append(f"{path.relative_to(folder.parent)}:{line} {module}")
    return found


def test_orchestrator_imports_nothing_of_rhnc():
    assert domain_imports(ENGINE) == []


def test_the_check_sees_lazy_and_dynamic_imports(tmp_path):
    package = tmp_path / "engine"
    package.mkdir()
    (package / "a.py").write_text("def f():\n    from rhnc.ships import load_ship\n")
    (package / "b.py").write_text("import importlib\nimportlib.import_module('rhnc.metocean')\n")
    (package / "c.py").write_text("import rhnc_cosim_extra\nfrom orchestrator import plugins\n")
    assert domain_imports(package) == ["engine/a.py:2 rhnc.ships", "engine/b.py:2 rhnc.metocean"]
