"""Build the C models under ``models/`` into FMI 2.0 and 3.0 co-simulation FMUs under ``fmus/``.

From the same C sources: ``fmus/<Name>.fmu`` (FMI 2.0, the default) and
``fmus/fmi3/<Name>.fmu`` (FMI 3.0). The shared layer's core (``fmu_core.c``) is compiled
with ``fmi2_api.c`` or ``fmi3_api.c``; the FMI 3.0 description is derived from the
model's FMI 2.0 one (:mod:`orchestrator.model_description`).

Each model folder ``models/<Name>/`` holds ``config.h``, ``model.c`` and a
``modelDescription.xml`` whose parameter start values are ``@name@`` placeholders; the
shared FMI layer lives in ``models/common/``. At build time the ``[default]`` set of the
library's shared parameter sets (``models/KCS/parameter_sets.toml``, the single source of
the 3-DOF plant's parameters) is written as the C header ``kcs_parameter_defaults.h``; a model with a parameter set file of
its own (``models/<Name>/parameter_sets.toml``, e.g. ``KCSMMG``) also gets
``model_parameter_defaults.h`` from it.  The model's own set (else the KCS set) fills the
placeholders, so the C start values and the XML can never disagree with the TOML.  The FMU
carries its ``sources/`` and the SHA-256 of every input file in the zip comment, which
``ensure_built`` compares.

In a source checkout the FMUs go into its ``fmus/``; an installed toolchain (the models are
package data) builds them into the per-user cache, ``<user cache>/rhnc-cosim/fmus/<source
hash>/`` (``platformdirs``; ``XDG_CACHE_HOME`` on Linux moves it), built once per source.

The models folder is a *model library* registered in the entry-point group
``rhnc_cosim.model_libraries`` (:mod:`orchestrator.plugins`): an object with ``models_dir``
(the folder), ``extra_inputs(name)`` (further files whose content determines the FMU) and
``check_parameter_set(values, where)`` (refusing a ``[default]`` set with a ``ScenarioError``) and
``shared_parameter_set`` (the model whose parameter sets every model is built with).
The ship domain's library checks the particulars in those sets (length, beam, windage
areas, ...) against the ship's ``ships/KCS.toml``, so a set that disagrees is never built.
"""

from __future__ import annotations

import hashlib
import logging
import os
import re
import shutil
import subprocess
import tempfile
import tomllib
import zipfile
from pathlib import Path

from orchestrator.errors import FmuError

log = logging.getLogger(__name__)


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
MODEL_DEFAULTS_HEADER = "model_parameter_defaults.h"
BOUNDS_HEADER = "model_bounds.h"
RESOURCES = "resources"
HASH_PREFIX = "rhnc-source-sha256="
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


def _default_parameters(models_dir: Path, path: Path | None = None) -> dict[str, float]:
    """The ``[default]`` set of ``path`` (the shared set by default), checked by the model
    library (the ship's particulars)."""
    from orchestrator.errors import ScenarioError

    path = Path(path) if path is not None else _shared_parameter_file(models_dir)
    try:
        with path.open("rb") as f:
            default = tomllib.load(f)["default"]
    except (OSError, tomllib.TOMLDecodeError, KeyError) as exc:
        raise FmuError(f"cannot read the [default] parameter set of {path}: {exc}") from exc
    values = {k: v for k, v in default.items() if k not in ("description", "plant_fmu", "plant_guid")}
    for key, value in values.items():
        if not isinstance(value, (int, float)) or isinstance(value, bool):
            raise FmuError(f"{path}: [default] {key} = {value!r} is not a number")
    library = model_library()
    try:
        if library is not None:
            library.check_parameter_set(values, f"{path}: [default]")
    except ScenarioError as exc:
        raise FmuError(str(exc)) from None
    return {k: float(v) for k, v in values.items()}


def _defaults_header(parameters: dict[str, float], prefix: str, source: str) -> str:
    guard = f"{prefix}_PARAMETER_DEFAULTS_H"
    lines = [
        f"/* Generated by orchestrator/fmu_build.py from {source}",
        " * ([default] set). Do not edit, do not commit. */",
        f"#ifndef {guard}",
        f"#define {guard}",
    ]
    lines += [f"#define {prefix}_DEFAULT_{k} ({v!r})" for k, v in parameters.items()]
    lines += ["#endif", ""]
    return "\n".join(lines)


def _model_description(name: str, models_dir: Path, parameters: dict[str, float],
                       parameter_file: Path | None = None) -> str:
    path = Path(models_dir) / name / "modelDescription.xml"
    parameter_file = parameter_file or _shared_parameter_file(models_dir)
    text = path.read_text(encoding="utf-8")

    def substitute(match: re.Match) -> str:
        key = match.group(1)
        if key not in parameters:
            raise FmuError(
                f"{path}: start value @{key}@ has no entry in the [default] set of {parameter_file}"
            )
        return repr(parameters[key])

    return re.sub(r"@(\w+)@", substitute, text)


def _compiler() -> str:
    for candidate in (os.environ.get("CC"), "cc", "gcc"):
        if candidate and shutil.which(candidate):
            return candidate
    raise FmuError("no C compiler found (set CC, or install cc/gcc)")


def _fmi_headers() -> Path:
    import fmpy

    return Path(fmpy.__file__).resolve().parent / "c-code"


def _first_error(output: str) -> str:
    lines = [line.strip() for line in output.splitlines() if line.strip()]
    for line in lines:
        if "error" in line.lower():
            return line
    return lines[0] if lines else "no compiler output"


def build_fmu(name: str, out_dir: Path | None = None, models_dir: Path | None = None,
              fmi_version: str = "2.0") -> Path:
    """Compile one model into ``out_dir/<name>.fmu`` (FMI 2.0) or ``out_dir/fmi3/<name>.fmu``.

    Parameters
    ----------
    name : str
        Model folder name under ``models_dir`` (see ``model_names``).
    out_dir : Path, optional
        Folder receiving the FMU (created if missing); default :func:`default_fmu_dir`.
    models_dir : Path, optional
        The ``models/`` tree to build from (default: the registered model library's).
    fmi_version : {"2.0", "3.0"}
        The FMI standard of the FMU.

    Returns
    -------
    Path
        The FMU written.

    Raises
    ------
    FmuError
        Unknown model name, unreadable parameter set, or a compilation error (the message
        names the model and the compiler's first error line).
    """
    from fmpy import platform, platform_tuple, sharedLibraryExtension

    from orchestrator import model_description

    models_dir = _models_dir(models_dir)
    model_dir = _check_name(name, models_dir)
    out_dir = default_fmu_dir(name, models_dir, fmi_version) if out_dir is None else out_dir
    fmu = fmu_path(name, out_dir, fmi_version)
    fmu.parent.mkdir(parents=True, exist_ok=True)
    parameters = _default_parameters(models_dir)
    own = _own_parameter_sets(name, models_dir)
    own_parameters = _default_parameters(models_dir, own) if own else None
    sources = _sources(name, models_dir, fmi_version)
    c_files = [p.name for p in sources if p.suffix == ".c"]
    description = model_description.finish_fmi2(
        _model_description(name, models_dir, own_parameters or parameters, own), c_files, _product_version())
    bounds_text = model_description.bounds_header(description)
    extra_sources = {}
    if fmi_version == "3.0":
        description = model_description.to_fmi3(description, c_files, _product_version())
        extra_sources["buildDescription.xml"] = model_description.build_description_fmi3(name, c_files)
    digest = source_hash(name, models_dir, fmi_version)

    with tempfile.TemporaryDirectory(prefix=f"fmu_build_{name}_") as tmp:
        tmp = Path(tmp)
        shared = _shared_set()
        header = tmp / f"{shared.lower()}_parameter_defaults.h"
        header.write_text(_defaults_header(parameters, shared.upper(), f"models/{shared}/parameter_sets.toml"),
                          encoding="utf-8")
        headers = [header]
        if own_parameters is not None:
            model_header = tmp / MODEL_DEFAULTS_HEADER
            model_header.write_text(_defaults_header(own_parameters, "MODEL", f"models/{name}/parameter_sets.toml"),
                                    encoding="utf-8")
            headers.append(model_header)
        bounds = tmp / BOUNDS_HEADER
        bounds.write_text(bounds_text, encoding="utf-8")
        library = tmp / f"{name}{sharedLibraryExtension}"
        command = [
            _compiler(), "-O2", "-shared", "-fPIC", "-fvisibility=hidden", "-Wall",
            f"-I{tmp}", f"-I{model_dir}", f"-I{models_dir / COMMON}", f"-I{_fmi_headers()}",
            *[str(p) for p in sources if p.suffix == ".c"],
            "-o", str(library), "-lm",
        ]
        log.info("building %s: %s", name, " ".join(command))
        result = subprocess.run(command, capture_output=True, text=True)
        if result.returncode != 0:
            raise FmuError(f"building model {name} failed: {_first_error(result.stderr)}")
        if result.stderr.strip():
            log.warning("compiler warnings for %s:\n%s", name, result.stderr.strip())

        # a staging file per process: two runs building the same FMU at once never mix files
        partial = fmu.parent / f".{name}.fmu.{os.getpid()}.partial"
        with zipfile.ZipFile(partial, "w", zipfile.ZIP_DEFLATED) as z:
            z.writestr("modelDescription.xml", description)
            binary_folder = platform if fmi_version == "2.0" else platform_tuple
            z.write(library, f"binaries/{binary_folder}/{library.name}")
            names = set()
            for path in [*sources, *headers, bounds]:
                if path.name in names:
                    raise FmuError(f"building model {name} failed: two sources named {path.name}")
                names.add(path.name)
                z.write(path, f"sources/{path.name}")
            for file_name, text in extra_sources.items():
                z.writestr(f"sources/{file_name}", text)
            for path in _resources(name, models_dir):
                z.write(path, f"resources/{path.relative_to(model_dir / RESOURCES).as_posix()}")
            z.comment = (HASH_PREFIX + digest).encode()
        partial.replace(fmu)
    log.info("built %s", fmu)
    return fmu


def _stored_hash(fmu: Path) -> str | None:
    try:
        with zipfile.ZipFile(fmu) as z:
            comment = z.comment.decode(errors="replace")
    except (OSError, zipfile.BadZipFile):
        return None
    return comment[len(HASH_PREFIX):] if comment.startswith(HASH_PREFIX) else None


def ensure_built(name: str, out_dir: Path | None = None, models_dir: Path | None = None,
                 fmi_version: str = "2.0") -> Path:
    """Return the model's FMU, rebuilding it when missing or built from other sources.

    The comparison is by content: the SHA-256 of the model's sources, the shared layer,
    its modelDescription.xml, the parameter sets and the ship's particulars, stored in the
    FMU's zip comment.
    """
    models_dir = _models_dir(models_dir)
    _check_name(name, models_dir)
    out_dir = default_fmu_dir(name, models_dir, fmi_version) if out_dir is None else out_dir
    fmu = fmu_path(name, out_dir, fmi_version)
    if fmu.is_file() and _stored_hash(fmu) == source_hash(name, models_dir, fmi_version):
        log.debug("%s is up to date", fmu)
        return fmu
    return build_fmu(name, out_dir, models_dir, fmi_version)


def build_all(out_dir: Path | None = None, models_dir: Path | None = None,
              fmi_versions: tuple[str, ...] = ("2.0",)) -> list[Path]:
    """Build every model of ``models_dir`` into ``out_dir`` for each FMI version; the FMUs written."""
    models_dir = _models_dir(models_dir)
    return [build_fmu(name, out_dir, models_dir, version)
            for version in fmi_versions for name in model_names(models_dir)]


def _product_version() -> str:
    """This package's version, written into every modelDescription."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("rhnc-cosim")
    except PackageNotFoundError:  # running from a source tree that is not installed
        return "0+unknown"
