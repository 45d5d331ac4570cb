"""Building a scenario's participants: which class, built from which options, with what context.

A Python participant's class is its ``class`` (``type = "python"``) or the entry registered
under its ``type`` in ``rhnc_cosim.participants`` (:mod:`orchestrator.plugins`); it builds
itself from its options with ``from_options``.  An FMU participant is an
:class:`~orchestrator.fmu_participant.FmuParticipant`.  A scenario's top-level domain table
(``[metocean]``) is built by the object registered under its name in
``rhnc_cosim.scenario_tables``.  Used by :class:`orchestrator.master.CoSimulation` and by
whatever else builds a participant the way a run does (an exported FMU).
"""

from __future__ import annotations

import importlib
import logging
from pathlib import Path

from orchestrator import plugins
from orchestrator.errors import ScenarioError, ToolchainError
from orchestrator.participant import BuildContext, Participant

log = logging.getLogger(__name__)


def input_ages(scenario, name: str) -> dict[str, float]:
    """How old each connected input of participant ``name`` is when it steps [s] (see
    :class:`~orchestrator.participant.BuildContext`): in Jacobi order a sampled (Python)
    source's step, 0 from an FMU; 0 in Gauss-Seidel order."""
    if scenario.simulation.exchange != "jacobi":
        return {}
    specs = {spec.name: spec for spec in scenario.participants}
    return {c.target_port: 0.0 if specs[c.source].is_fmu else specs[c.source].every * scenario.simulation.dt_s
            for c in scenario.connections if c.target == name}


def build_participant(spec, scenario, metocean, substitutions: dict[str, str]) -> Participant:
    """The participant ``spec`` of ``scenario`` describes, built as a run needs it.

    An FMU participant gets the file placeholders replaced by ``substitutions``; a Python
    participant's class (see :func:`participant_target`) builds itself with
    ``from_options``, seeing ``metocean`` (the scenario's domain table object, or None).
    Whatever goes wrong is one :class:`~orchestrator.errors.ScenarioError` naming the
    scenario file and the participant.
    """
    where = f"{scenario.path}: participants.{spec.name}"
    if spec.is_fmu:
        from orchestrator.fmu_participant import FmuParticipant, resolve_fmu

        path = resolve_fmu(spec.fmu, scenario.directory, where, spec.fmi_version)
        return FmuParticipant(spec, path, where, substitutions)
    target = participant_target(spec, where)
    cls = participant_class(target, f"{where}.class", scenario.directory)
    context = BuildContext(
        where=where,
        scenario_dir=scenario.directory,
        step_size=spec.every * scenario.simulation.dt_s,
        start_time=scenario.simulation.start_s,
        stop_time=scenario.simulation.stop_s,
        metocean=metocean,
        output_delay_s=spec.every * scenario.simulation.dt_s if scenario.simulation.exchange == "jacobi" else 0.0,
        input_ages_s=input_ages(scenario, spec.name),
    )
    try:
        participant = cls.from_options(spec.name, spec.options, context)
    except ToolchainError:
        raise
    except Exception as exc:  # the class's own check of its options, or its bug: one line
        log.debug("from_options raised", exc_info=True)
        raise ScenarioError(f"{where}: {target} could not be built from its options: "
                            f"{type(exc).__name__}: {exc}") from exc
    except SystemExit as exc:
        raise ScenarioError(f"{where}: {target} called sys.exit({exc.code!r}) while being built") from exc
    if not isinstance(participant, Participant):
        raise ScenarioError(f"{where}: {target} does not build an orchestrator.participant.Participant")
    return participant


def participant_target(spec, where: str) -> str:
    """``module:Class`` of a Python participant: its ``class`` for ``type = "python"``, else the
    entry registered under its type in ``rhnc_cosim.participants``."""
    if spec.type == "python":
        return spec.class_path
    types = plugins.names("participants")
    if spec.type not in types:
        raise ScenarioError(
            f"{where}.type: unknown participant type '{spec.type}' "
            f"(valid: {', '.join(sorted(types))}, python)"
        )
    return plugins.target("participants", spec.type)


def build_scenario_table(name: str, table: dict, scenario_dir: Path, where: str):
    """The object a registered package builds from a scenario's top-level table ``name``."""
    try:
        handler = plugins.load("scenario_tables", name)
    except KeyError:
        raise ScenarioError(f"{where}: no installed package handles a [{name}] table (entry-point group "
                            f"{plugins.GROUPS['scenario_tables']})") from None
    return handler.from_scenario_table(table, scenario_dir, where)


def participant_class(target: str, where: str, scenario_dir: Path | None = None):
    """The participant class ``target`` (``package.module:Class``) names, imported; errors name ``where``.

    When the module is not found but lies in ``scenario_dir``, the error says so: the scenario's
    folder is not on the import path unless the command is started from it.
    """
    module_name, _, class_name = target.partition(":")
    if not module_name or not class_name:
        raise ScenarioError(f"{where}: '{target}' must read 'package.module:Class'")
    try:
        module = importlib.import_module(module_name)
    except ImportError as exc:
        hint = ""
        top = module_name.partition(".")[0]
        if (isinstance(exc, ModuleNotFoundError) and scenario_dir is not None
                and any((Path(scenario_dir) / name).is_file() for name in (f"{top}.py", f"{top}/__init__.py"))):
            hint = (f" (it lies in the scenario's folder {scenario_dir}, which is not on the import path: start "
                    "the command from that folder, or install the module)")
        raise ScenarioError(f"{where}: cannot import module '{module_name}': {exc}{hint}") from exc
    cls = getattr(module, class_name, None)
    if cls is None or not hasattr(cls, "from_options"):
        raise ScenarioError(f"{where}: '{target}' is not a participant class with from_options()")
    return cls
