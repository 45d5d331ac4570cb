"""Check a scenario and its FMUs without running it.

Validation builds every participant, so every option, parameter (against the ranges the
FMU declares), mapping and connection is checked, and runs fmpy's validation on each FMU.
When ``[simulation] stop_when`` names outputs, the participants are also set up (not
stepped) to see that those outputs are numbers, as the run checks before its first step.
It does not run code that came with the scenario: a ``type = "python"`` participant whose
module lies in the scenario's folder or in the current folder (where ``python -m`` finds
it first) is not imported unless ``trust_code`` is given; its ports and the connections to
it are then left unchecked and the report says so.  FMUs are native code whichever way:
validate untrusted scenarios in a sandbox.
"""

from __future__ import annotations

import importlib.util
import os
import sys
from dataclasses import dataclass, field, replace
from pathlib import Path

from orchestrator.errors import ToolchainError


@dataclass
class ValidationReport:
    """What validation found: problems (the scenario cannot run) and notes (what it did not check)."""

    problems: list[str] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        return not self.problems


def validate_scenario(path, trust_code: bool = False) -> list[str]:
    """Problems found in the scenario and its FMUs (empty when it is ready to run).

    See :func:`check_scenario` for the notes on what was not checked.
    """
    return check_scenario(path, trust_code).problems


def check_scenario(path, trust_code: bool = False) -> ValidationReport:
    """Load the scenario, build every participant and validate each FMU.

    Parameters
    ----------
    path : path-like
        The scenario file.
    trust_code : bool
        Import ``type = "python"`` participant classes from the scenario's folder (or the
        current folder) too; by default they are named in the notes and not imported.
    """
    from fmpy.validation import validate_fmu

    from orchestrator.fmu_participant import FmuParticipant
    from orchestrator.master import CoSimulation
    from orchestrator.scenario import load_scenario

    report = ValidationReport()
    try:
        scenario = load_scenario(path)
        if not trust_code:
            scenario = _without_local_code(scenario, report)
        cosim = CoSimulation(scenario)
    except ToolchainError as exc:
        report.problems.append(str(exc))
        return report
    try:
        for participant in cosim.participants:
            if isinstance(participant, FmuParticipant):
                for problem in validate_fmu(str(participant.fmu_path)):
                    report.problems.append(f"{participant.fmu_path.name}: {problem}")
        _check_stop_ports(cosim, report)
    finally:
        cosim.close()
    return report


def _check_stop_ports(cosim, report: ValidationReport) -> None:
    """The ``stop_when`` ports are numbers: seen in the participants' set-up outputs, as the run
    sees them before its first step.  A set-up that fails is the run's to report (exit 3): a note."""
    from orchestrator.master import StopConditionError

    try:
        cosim.check_stop_ports()
    except StopConditionError as exc:
        report.problems.append(str(exc))
    except Exception as exc:  # a participant's set-up: not a property of the scenario file
        report.notes.append(f"{cosim.scenario.path}: simulation.stop_when: not checked, a participant's set-up "
                            f"raised {type(exc).__name__}: {exc}")


def local_module_folder(class_path: str, scenario_dir: Path) -> Path | None:
    """The folder a participant class would be imported from, when it is the scenario's folder
    or the current folder and the module is not imported yet; otherwise None.

    A module that cannot be imported from here at all (say, it lies beside the scenario but
    the command was started from another folder) is not local: building it fails as the run
    would, so that ``validate`` and ``run`` agree.

    Found with :func:`importlib.util.find_spec` on the top-level name, which runs no code.
    """
    module_name = class_path.partition(":")[0]
    top = module_name.partition(".")[0]
    if not top or top in sys.modules:
        return None
    untrusted = {scenario_dir.resolve(), Path.cwd().resolve()}
    # the scenario's folder is not on sys.path, but a user may run from it or add it
    try:
        spec = importlib.util.find_spec(top)
    except (ImportError, ValueError):
        spec = None
    if spec is None:  # not importable from here: the build fails as the run would (importing nothing)
        return None
    if not spec.origin or spec.origin in ("built-in", "frozen"):
        return None
    folder = Path(spec.origin).resolve().parent
    if spec.submodule_search_locations:  # a package: where its folder lies
        folder = folder.parent
    return folder if folder in untrusted else None


def _without_local_code(scenario, report: ValidationReport):
    """The scenario without the Python participants whose code would come from an untrusted folder."""
    skipped = set()
    for spec in scenario.participants:
        if spec.type != "python" or not spec.class_path:
            continue
        folder = local_module_folder(spec.class_path, scenario.directory)
        if folder is not None:
            skipped.add(spec.name)
            report.notes.append(
                f"{scenario.path}: participants.{spec.name}: class '{spec.class_path}' not imported: its module is in "
                f"{_shown_folder(folder)}, and validate runs no code that comes with a scenario; give --trust-code "
                f"to import and check it (only for code you trust)")
    if not skipped:
        return scenario
    simulation = replace(scenario.simulation, stop_when=tuple(
        c for c in scenario.simulation.stop_when if c.participant not in skipped))
    return replace(scenario, participants=tuple(p for p in scenario.participants if p.name not in skipped),
                   connections=tuple(c for c in scenario.connections
                                     if c.source not in skipped and c.target not in skipped),
                   simulation=simulation)


def _shown_folder(folder: Path) -> str:
    try:
        return os.path.relpath(folder) if not os.path.relpath(folder).startswith("..") else str(folder)
    except ValueError:
        return str(folder)
