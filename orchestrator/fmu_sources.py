"""The built-in models' sources: which models there are, what determines each FMU, where it goes.

The models come from the model library registered in the entry-point group
``rhnc_cosim.model_libraries`` (:mod:`orchestrator.plugins`; ``models/`` of the ship
domain): ``models_dir`` holds one folder per model and the shared FMI layer in
``common/``; ``shared_parameter_set`` names the model whose ``parameter_sets.toml`` every
model is built with; ``extra_inputs(name)`` lists further files whose content determines an
FMU.  The SHA-256 over all of them (:func:`source_hash`) is stored in each FMU and keys the
per-user cache an installed toolchain builds into (:func:`default_fmu_dir`).
:mod:`orchestrator.fmu_build` compiles.
"""

from __future__ import annotations

import hashlib
from pathlib import Path

from orchestrator.errors import FmuError


def _checkout_fmus() -> Path | None:
    from orchestrator.plugins import source_checkout

    root = source_checkout()
    return root / "fmus" if root is not None else None


#: Where built-in FMUs go in a source checkout: its ``fmus/`` folder.  An installed toolchain
#: (None here) builds them into the per-user cache instead (:func:`default_fmu_dir`).
FMUS_DIR = _checkout_fmus()
#: Name of the per-user cache folder (``platformdirs.user_cache_dir``).
CACHE_NAME = "rhnc-cosim"

COMMON = "common"
RESOURCES = "resources"
# Bump when the build recipe itself changes, so existing FMUs are rebuilt.
RECIPE_VERSION = "2"
SOURCE_SUFFIXES = (".c", ".h")
FMI_VERSIONS = ("2.0", "3.0")
#: The FMI API file of the shared layer per version; the other version's is left out.
API_SOURCES = {"2.0": "fmi2_api.c", "3.0": "fmi3_api.c"}


def model_library():
    """The registered model library (the first by name), or None when no package registers one."""
    from orchestrator import plugins

    libraries = plugins.names("model_libraries")
    return plugins.load("model_libraries", libraries[0]) if libraries else None


def __getattr__(name: str):
    if name == "MODELS_DIR":  # the registered library's folder, looked up when asked for
        library = model_library()
        return Path(library.models_dir) if library is not None else None
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def _models_dir(models_dir: Path | None) -> Path:
    if models_dir is not None:
        return Path(models_dir)
    library = model_library()
    if library is None:
        raise FmuError("no built-in models: no installed package registers a model library "
                       "(entry-point group rhnc_cosim.model_libraries)")
    return Path(library.models_dir)


def model_names(models_dir: Path | None = None) -> list[str]:
    """Names of the buildable models: folders of ``models_dir`` with a ``model.c``."""
    if models_dir is None and model_library() is None:
        return []
    models_dir = _models_dir(models_dir)
    return sorted(
        p.name for p in Path(models_dir).iterdir()
        if p.is_dir() and p.name != COMMON and (p / "model.c").is_file()
    )


def _check_name(name: str, models_dir: Path) -> Path:
    names = model_names(models_dir)
    if name not in names:
        raise FmuError(f"unknown model {name!r}; valid models: {', '.join(names)}")
    return Path(models_dir) / name


def _check_version(fmi_version: str) -> str:
    if fmi_version not in FMI_VERSIONS:
        raise FmuError(f"unknown FMI version {fmi_version!r} (valid: {', '.join(FMI_VERSIONS)})")
    return fmi_version


def _sources(name: str, models_dir: Path, fmi_version: str = "2.0") -> list[Path]:
    """C sources and headers of one model for one FMI version: its folder's and the shared layer's."""
    other_apis = {api for version, api in API_SOURCES.items() if version != fmi_version}
    files = []
    for folder in (Path(models_dir) / COMMON, Path(models_dir) / name):
        files += sorted(p for p in folder.iterdir() if p.suffix in SOURCE_SUFFIXES and p.name not in other_apis)
    return files


def _shared_set() -> str:
    """The model whose ``parameter_sets.toml`` every model of the library is built with (its
    ``[default]`` set becomes ``<name>_parameter_defaults.h``): the library's
    ``shared_parameter_set`` (``KCS`` for the ship models)."""
    shared = getattr(model_library(), "shared_parameter_set", None)
    if not shared:
        raise FmuError("the registered model library names no shared_parameter_set")
    return shared


def _shared_parameter_file(models_dir: Path) -> Path:
    return Path(models_dir) / _shared_set() / "parameter_sets.toml"


def _own_parameter_sets(name: str, models_dir: Path) -> Path | None:
    """The model's own parameter set file, when it has one besides the shared set."""
    path = Path(models_dir) / name / "parameter_sets.toml"
    return path if name != _shared_set() and path.is_file() else None


def _resources(name: str, models_dir: Path) -> list[Path]:
    """Files shipped in the FMU's ``resources/``: the model folder's ``resources/`` (e.g. a default grid)."""
    folder = Path(models_dir) / name / RESOURCES
    return sorted(p for p in folder.rglob("*") if p.is_file()) if folder.is_dir() else []


def _inputs(name: str, models_dir: Path, fmi_version: str = "2.0") -> list[Path]:
    """Every file whose content determines the FMU."""
    models_dir = Path(models_dir)
    own = _own_parameter_sets(name, models_dir)
    library = model_library()  # its inputs and checks hold for a copy of its folder too
    return _sources(name, models_dir, fmi_version) + _resources(name, models_dir) + [
        models_dir / name / "modelDescription.xml",
        _shared_parameter_file(models_dir),
        *([own] if own else []),
        *(library.extra_inputs(name) if library is not None else []),
    ]


def default_fmu_dir(name: str, models_dir: Path | None = None, fmi_version: str = "2.0") -> Path:
    """Where a built-in model's FMU goes unless told: the checkout's ``fmus/``, or else
    ``<user cache>/rhnc-cosim/fmus/<source hash>/`` so that FMUs of other sources (another
    installed version) never overwrite each other and an unchanged source is built once."""
    if FMUS_DIR is not None:
        return Path(FMUS_DIR)
    from platformdirs import user_cache_dir

    return Path(user_cache_dir(CACHE_NAME)) / "fmus" / source_hash(name, models_dir, fmi_version)[:16]


def fmu_path(name: str, out_dir: Path | None = None, fmi_version: str = "2.0") -> Path:
    """Where the FMU of a model is built: ``<out_dir>/<name>.fmu`` or ``<out_dir>/fmi3/<name>.fmu``."""
    if out_dir is None:
        out_dir = default_fmu_dir(name, None, fmi_version)
    return Path(out_dir) / (f"{name}.fmu" if _check_version(fmi_version) == "2.0" else f"fmi3/{name}.fmu")


def source_hash(name: str, models_dir: Path | None = None, fmi_version: str = "2.0") -> str:
    """SHA-256 over the recipe and FMI versions and the relative path and content of every input."""
    models_dir = _models_dir(models_dir)
    digest = hashlib.sha256(f"{RECIPE_VERSION} {_check_version(fmi_version)}".encode())
    for path in _inputs(name, models_dir, fmi_version):
        relative = path.relative_to(models_dir) if path.is_relative_to(models_dir) else Path(path.parent.name, path.name)
        digest.update(str(relative).encode() + b"\0")
        digest.update(path.read_bytes() + b"\0")
    return digest.hexdigest()
