"""Check a scenario and its FMUs without running it."""

from __future__ import annotations

from orchestrator.errors import ToolchainError


def validate_scenario(path) -> list[str]:
    """Problems found in the scenario and its FMUs (empty when it is ready to run).

    Loads the scenario, builds every participant (so every option, parameter, mapping
    and connection is checked) and runs fmpy's validation on each FMU.
    """
    from fmpy.validation import validate_fmu

    from orchestrator.fmu_participant import FmuParticipant
    from orchestrator.master import CoSimulation
    from orchestrator.scenario import load_scenario

    try:
        scenario = load_scenario(path)
        cosim = CoSimulation(scenario)
    except ToolchainError as exc:
        return [str(exc)]
    problems = []
    try:
        for participant in cosim.participants:
            if isinstance(participant, FmuParticipant):
                for problem in validate_fmu(str(participant.fmu_path)):
                    problems.append(f"{participant.fmu_path.name}: {problem}")
    finally:
        cosim.close()
    return problems
