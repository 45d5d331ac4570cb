"""A script of the repository (``scripts/``, ``bench/``, a model folder's) loaded as a module for its tests."""

import importlib.util
import sys
from pathlib import Path
from types import ModuleType


def module_of_file(path: Path, name: str) -> ModuleType:
    """The module of the file ``path``, registered in ``sys.modules`` as ``name`` (its dataclasses
    look their module up by it)."""
    spec = importlib.util.spec_from_file_location(name, path)
    if spec is None or spec.loader is None:
        raise ImportError(f"{path}: not a Python file")
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module
