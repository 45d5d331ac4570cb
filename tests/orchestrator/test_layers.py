"""Layers with one-way arrows: the master never imports ``rhnc``, and no modules import in a loop.

Every Python file of ``orchestrator/`` (and, for loops, of ``rhnc/``) is parsed and each
``import``/``from ... import`` (at any depth, lazy ones inside functions included) and each
``importlib.import_module`` or ``__import__`` call with a literal name is checked.  What the
master needs of a domain it finds through entry points (:mod:`orchestrator.plugins`).
Modules that import each other in a loop, even through lazy imports, cannot be read, tested
or moved one without the other: the lower one must not know the higher.
"""

from __future__ import annotations

import ast
from pathlib import Path

import orchestrator

ENGINE = Path(orchestrator.__file__).resolve().parent
DOMAIN = "rhnc"
#: The packages whose modules must not import each other in a loop.
LAYERED = (ENGINE, ENGINE.parent / DOMAIN)


def _imported_modules(tree: ast.AST):
    """``(line, module, names)`` per import; ``names`` those of a ``from module import ...``."""
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield node.lineno, alias.name, ()
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            yield node.lineno, node.module, tuple(alias.name for alias in node.names)
        elif isinstance(node, ast.Call) and node.args and isinstance(node.args[0], ast.Constant):
            function = node.func
            name = function.attr if isinstance(function, ast.Attribute) else getattr(function, "id", "")
            if name in ("import_module", "__import__") and isinstance(node.args[0].value, str):
                yield node.lineno, node.args[0].value, ()


def domain_imports(folder: Path) -> list[str]:
    """``file:line module`` for every import of the domain package under ``folder``."""
    found = []
    for path in sorted(folder.rglob("*.py")):
        tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
        for line, module, _ in _imported_modules(tree):
            if module == DOMAIN or module.startswith(DOMAIN + "."):
                found.append(f"{path.relative_to(folder.parent)}:{line} {module}")
    return found


def import_graph(packages) -> dict[str, set[str]]:
    """Module -> the modules of ``packages`` it imports (``from package import module`` included)."""
    paths = {}
    for package in packages:
        for path in sorted(Path(package).rglob("*.py")):
            parts = path.relative_to(Path(package).parent).with_suffix("").parts
            paths[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = path
    graph = {}
    for module, path in paths.items():
        tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
        imported = set()
        for _, name, names in _imported_modules(tree):
            submodules = [f"{name}.{item}" for item in names if f"{name}.{item}" in paths]
            if submodules:
                imported.update(submodules)
            elif name in paths:
                imported.add(name)
        graph[module] = imported - {module}
    return graph


def import_cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The groups of modules that import each other in a loop (strongly connected, sorted)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    cycles = []

    def visit(module: str) -> None:
        index[module] = low[module] = len(index)
        stack.append(module)
        for other in sorted(graph[module]):
            if other not in index:
                visit(other)
                low[module] = min(low[module], low[other])
            elif other in stack:
                low[module] = min(low[module], index[other])
        if low[module] == index[module]:
            group = []
            while not group or group[-1] != module:
                group.append(stack.pop())
            if len(group) > 1:
                cycles.append(sorted(group))

    for module in sorted(graph):
        if module not in index:
            visit(module)
    return sorted(cycles)


def test_orchestrator_imports_nothing_of_rhnc():
    assert domain_imports(ENGINE) == []


def test_the_check_sees_lazy_and_dynamic_imports(tmp_path):
    package = tmp_path / "engine"
    package.mkdir()
    (package / "a.py").write_text("def f():\n    from rhnc.ship.ships import load_ship\n")
    (package / "b.py").write_text("import importlib\nimportlib.import_module('rhnc.weather.metocean')\n")
    (package / "c.py").write_text("import rhnc_cosim_extra\nfrom orchestrator import plugins\n")
    assert domain_imports(package) == ["engine/a.py:2 rhnc.ship.ships", "engine/b.py:2 rhnc.weather.metocean"]


def test_no_modules_import_each_other_in_a_loop():
    cycles = import_cycles(import_graph(LAYERED))
    assert cycles == [], f"modules that import each other in a loop: {cycles}; move what the lower one needs below both"


def test_the_loop_check_sees_lazy_imports_and_submodules(tmp_path):
    package = tmp_path / "pkg"
    (package / "inner").mkdir(parents=True)
    (package / "__init__.py").write_text("")
    (package / "inner" / "__init__.py").write_text("")
    (package / "field.py").write_text("def to_file():\n    from pkg.inner import writer\n")
    (package / "inner" / "writer.py").write_text("import pkg.field\n")
    (package / "top.py").write_text("from pkg import field\nimport pkg.inner.writer\n")
    graph = import_graph([package])
    assert graph["pkg.top"] == {"pkg.field", "pkg.inner.writer"}
    assert import_cycles(graph) == [["pkg.field", "pkg.inner.writer"]]


#: The wings of the domain, lowest first: a wing imports only the wings before it (and
#: itself); ``cosim`` registers them all with the engine and may import any of them.
WINGS = ("ship", "chart", "weather", "routing", "voyage", "navigation", "encounters", "control", "cosim")


def wing_violations(graph: dict[str, set[str]], domain: str = DOMAIN, wings=WINGS) -> list[str]:
    """``importer -> imported`` for every import from a lower wing into a higher one."""
    rank = {wing: position for position, wing in enumerate(wings)}

    def wing_of(module: str) -> str | None:
        parts = module.split(".")
        return parts[1] if len(parts) > 1 and parts[0] == domain else None

    found = []
    for module, imported in sorted(graph.items()):
        if wing_of(module) is None:
            continue
        for other in sorted(imported):
            if wing_of(other) is not None and rank[wing_of(other)] > rank[wing_of(module)]:
                found.append(f"{module} -> {other}")
    return found


def test_every_domain_module_lives_in_a_wing():
    loose = [module for module in import_graph([ENGINE.parent / DOMAIN])
             if module != DOMAIN and module.split(".")[1] not in WINGS]
    assert loose == [], f"modules outside the wings {WINGS}: {loose}"


def test_wings_import_one_way():
    violations = wing_violations(import_graph([ENGINE.parent / DOMAIN]))
    assert violations == [], f"a lower wing imports a higher one: {violations}"


def test_the_wing_check_sees_an_import_upwards():
    graph = {"rhnc.ship.ship_model": {"rhnc.control.nmpc"}, "rhnc.control.nmpc": {"rhnc.ship.ship_model"}}
    assert wing_violations(graph) == ["rhnc.ship.ship_model -> rhnc.control.nmpc"]


def _wings_diagram():
    import importlib.util
    import sys

    script = ENGINE.parent / "scripts" / "wings_diagram.py"
    spec = importlib.util.spec_from_file_location("wings_diagram_under_test", script)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    try:
        spec.loader.exec_module(module)
    finally:
        del sys.modules[spec.name]
    return module


def test_the_drawing_of_the_wings_is_todays_and_its_arrows_point_down():
    drawing = _wings_diagram()
    assert drawing.WINGS == WINGS
    edges = drawing.wing_edges(ENGINE.parent)
    rank = {wing: position for position, wing in enumerate(("orchestrator",) + WINGS)}
    assert edges and all(rank[imported] < rank[importer] for importer, imported in edges)
    committed = (ENGINE.parent / "docs" / "wings.md").read_text(encoding="utf-8")
    assert committed == drawing.page(edges), "docs/wings.md is not today's drawing: run python scripts/wings_diagram.py"


def test_the_drawing_counts_the_modules_importing_another_wing(tmp_path):
    drawing = _wings_diagram()
    for wing, text in (("ship", "import orchestrator.geometry\n"),
                       ("control", "from rhnc.ship import ship_model\nfrom rhnc.encounters.colregs import x\n"),
                       ("control", "def f():\n    import rhnc.ship.energy\n")):
        folder = tmp_path / "rhnc" / wing
        folder.mkdir(parents=True, exist_ok=True)
        (folder / f"m{len(list(folder.iterdir()))}.py").write_text(text)
    assert drawing.wing_edges(tmp_path) == {("ship", "orchestrator"): 1, ("control", "ship"): 2,
                                            ("control", "encounters"): 1}
