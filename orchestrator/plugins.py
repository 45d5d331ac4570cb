"""What installed packages add to the co-simulation master, found through Python entry points.

The master knows no domain: every participant type, analysis, figure, extra command,
scenario table and comparison extension is found here, by name, in an entry-point group
that any installed distribution may declare in its ``pyproject.toml``::

    [project.entry-points."rhnc_cosim.participants"]
    my_autopilot = "my_package.autopilot:Autopilot"

The master's own scripted participants are declared the same way, and so is every
built-in ship participant, analysis and command of the ``rhnc`` package.  The groups and
what each entry must be are listed in :data:`GROUPS` (``docs/plugins.md`` explains them
with an example package).

A source checkout that is on ``sys.path`` but not (re)installed, so that the installed
metadata of ``rhnc-cosim`` may be stale or missing, reads the entry points of its own
``pyproject.toml`` in place of that distribution's metadata: running from the tree one is
editing sees the tree's own registrations.
"""

from __future__ import annotations

import functools
import importlib
import logging
import tomllib
from dataclasses import dataclass
from importlib.metadata import EntryPoint, entry_points
from pathlib import Path

from orchestrator.errors import ScenarioError

log = logging.getLogger(__name__)

#: This project's distribution name (its own entry points may come from a source checkout).
DISTRIBUTION = "rhnc-cosim"

#: Kind of registration -> entry-point group.  What an entry must load:
#:
#: ``participants``
#:     a class with ``from_options(name, options, context) -> Participant``
#:     (:mod:`orchestrator.participant`), named by a scenario's ``type = "<name>"``;
#: ``analyses``
#:     ``function(frame, scenario, cosim, out_dir, **options) -> dict``, named in
#:     ``[outputs] analyses``; it may carry ``check_options(options)`` raising ValueError;
#: ``figures``
#:     ``function(frame, scenario, cosim, out_dir) -> list[str]``, named in ``[outputs] figures``;
#: ``commands``
#:     an object with ``add_arguments(parser)``, ``help`` and ``run(args) -> int``: a
#:     subcommand of ``python -m orchestrator``;
#: ``scenario_tables``
#:     a class or module for a scenario's top-level table of that name (``[metocean]``) with
#:     ``from_scenario_table(table, scenario_dir, where)`` and ``from_netcdf(path)``; the
#:     object built has ``write_fmu_files(work_dir) -> {placeholder: path}``,
#:     ``to_netcdf(path)`` and ``source``; participants see it as ``context.<name>``;
#: ``comparisons``
#:     a comparison extension class (``from_table``, ``run_overrides``, ``evaluate``,
#:     ``summarise_sweep``; :mod:`orchestrator.compare`) for a comparison file's table;
#: ``comparison_figures``
#:     ``function(spec, reports, target_folder) -> list[str]`` drawn once per comparison;
#: ``model_libraries``
#:     an object describing a folder of C models that ``build`` compiles into FMUs
#:     (:mod:`orchestrator.fmu_build`);
#: ``batch``
#:     a module giving a batch file's domain tables what they need (``encounters``:
#:     target placement for Monte Carlo encounters; ``situations``: traffic-situation files);
#: ``port_tables``
#:     an :class:`orchestrator.plant_ports.PortTable`: the canonical ports FMU variables are
#:     mapped onto, and the ``[participants.<plant>.initial]`` keys.
GROUPS = {
    "participants": "rhnc_cosim.participants",
    "analyses": "rhnc_cosim.analyses",
    "figures": "rhnc_cosim.figures",
    "commands": "rhnc_cosim.commands",
    "scenario_tables": "rhnc_cosim.scenario_tables",
    "comparisons": "rhnc_cosim.comparisons",
    "comparison_figures": "rhnc_cosim.comparison_figures",
    "model_libraries": "rhnc_cosim.model_libraries",
    "batch": "rhnc_cosim.batch",
    "port_tables": "rhnc_cosim.port_tables",
}


@dataclass(frozen=True)
class Registration:
    """One entry: its name, ``module:attribute`` target and the distribution declaring it."""

    name: str
    target: str
    distribution: str

    def load(self):
        """Import the target (the module itself when no attribute is named)."""
        module_name, _, attribute = self.target.partition(":")
        module = importlib.import_module(module_name.strip())
        if not attribute:
            return module
        value = module
        for part in attribute.strip().split("."):
            value = getattr(value, part)
        return value


def source_checkout() -> Path | None:
    """The root of the source checkout this package is imported from, or None when installed."""
    pyproject = _source_pyproject()
    return pyproject.parent if pyproject is not None else None


@functools.lru_cache(maxsize=None)
def _source_pyproject() -> Path | None:
    """This package's checkout's ``pyproject.toml`` when the package is imported from one
    (read once per process)."""
    candidate = Path(__file__).resolve().parent.parent / "pyproject.toml"
    if not candidate.is_file():
        return None
    try:
        with candidate.open("rb") as handle:
            project = tomllib.load(handle).get("project", {})
    except (OSError, tomllib.TOMLDecodeError):
        return None
    return candidate if project.get("name") == DISTRIBUTION else None


def _source_entries(pyproject: Path, group: str) -> dict[str, str]:
    return dict(_declared_entry_points(pyproject).get(group, {}))


@functools.lru_cache(maxsize=None)
def _declared_entry_points(pyproject: Path) -> dict:
    """The ``[project.entry-points]`` of ``pyproject`` (read once per process, not per group)."""
    with pyproject.open("rb") as handle:
        return tomllib.load(handle)["project"].get("entry-points", {})


@functools.lru_cache(maxsize=None)
def _installed_entry_points():
    """Every installed entry point, of every group: read once (each read looks at the metadata
    of every installed distribution; reading it per group cost a run ten such reads)."""
    return entry_points()


def _clear_caches() -> None:
    """Forget what was read (a test that installs a distribution on the path)."""
    _registrations.cache_clear()
    _installed_entry_points.cache_clear()
    _normalised_name.cache_clear()


def registrations(kind: str) -> dict[str, Registration]:
    """Every entry of the group of ``kind`` (see :data:`GROUPS`), by name (read once per
    process; ``registrations.cache_clear()`` forgets it).

    Two distributions registering one name is refused (naming both), so that which one
    runs never depends on the order of ``sys.path``.
    """
    return _registrations(kind)


# callers (and tests) forget the registrations as they did when this function was the cache
registrations.cache_clear = _clear_caches  # type: ignore[attr-defined]


@functools.lru_cache(maxsize=None)
def _registrations(kind: str) -> dict[str, Registration]:
    group = GROUPS[kind]
    pyproject = _source_pyproject()
    found: dict[str, Registration] = {}

    def add(name: str, target: str, distribution: str) -> None:
        earlier = found.get(name)
        if earlier is not None and earlier.distribution != distribution:
            raise ScenarioError(f"entry point '{name}' of group {group} is registered twice: by "
                                f"{earlier.distribution} ({earlier.target}) and by {distribution} ({target})")
        found[name] = Registration(name, target, distribution)

    for entry in _installed_entry_points().select(group=group):
        distribution = _distribution_name(entry)
        if pyproject is not None and distribution == DISTRIBUTION:
            continue  # the checkout's own declarations stand in for its installed metadata
        add(entry.name, entry.value, distribution)
    if pyproject is not None:
        for name, target in _source_entries(pyproject, group).items():
            add(name, target, DISTRIBUTION)
    return dict(sorted(found.items()))


def _distribution_name(entry: EntryPoint) -> str:
    return _normalised_name(entry.dist) if entry.dist is not None else "unknown"


@functools.lru_cache(maxsize=None)
def _normalised_name(distribution) -> str:
    """A distribution's name, normalised; once per distribution object (its ``name`` parses its
    whole metadata file, and every entry point of a distribution read at once shares one)."""
    name = distribution.name
    return name.replace("_", "-").lower() if name else "unknown"


def names(kind: str) -> list[str]:
    """The registered names of ``kind``, sorted."""
    return list(registrations(kind))


def load(kind: str, name: str):
    """The object registered as ``name`` in the group of ``kind``; KeyError when none is."""
    return registrations(kind)[name].load()


def target(kind: str, name: str) -> str:
    """The ``module:attribute`` of an entry (what an exported FMU records)."""
    return registrations(kind)[name].target


def load_all(kind: str) -> dict:
    """Every object of ``kind``, loaded, by name."""
    return {name: registration.load() for name, registration in registrations(kind).items()}


class LazyModule:
    """A module registered in the ``batch`` group, imported on first attribute access.

    Lets a generic module name a domain helper at import time without importing it (nor
    requiring it to be installed) until a file actually uses that table.
    """

    def __init__(self, kind: str, name: str) -> None:
        self._kind, self._name = kind, name

    def __getattr__(self, attribute: str):
        try:
            module = load(self._kind, self._name)
        except KeyError:
            raise ScenarioError(f"no installed package provides '{self._name}' (entry-point group "
                                f"{GROUPS[self._kind]})") from None
        return getattr(module, attribute)


def toolchain_loggers() -> tuple[str, ...]:
    """Loggers of this toolchain: the master's and every package registering entry points."""
    packages = {registration.target.split(":")[0].split(".")[0].strip()
                for kind in GROUPS for registration in registrations(kind).values()}
    return ("orchestrator", *sorted(packages - {"orchestrator"}))
