"""Scenario loading: a TOML file into frozen dataclasses, every error naming the file and the key.

The format is documented in ``docs/scenario-format.md``.  Reading (with its size and
nesting limits) is :mod:`orchestrator.toml_input`, the checks are the pydantic models of
:mod:`orchestrator.scenario_model`, the result the dataclasses of
:mod:`orchestrator.scenario_spec` (re-exported here).
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from orchestrator.errors import ScenarioError
from orchestrator.scenario_model import EXCHANGE_ORDERS, MAX_STEPS, MAX_TIME_S, build_scenario_parts
from orchestrator.scenario_spec import (Connection, OutputSpec, ParticipantSpec, Scenario, SimulationSpec,
                                        StopCondition, VariableMapping, VectorMapping)
from orchestrator.toml_input import apply_override, check_nesting, read_toml

__all__ = ["Connection", "EXCHANGE_ORDERS", "MAX_STEPS", "MAX_TIME_S", "OutputSpec", "ParticipantSpec", "Scenario",
           "SimulationSpec", "StopCondition", "VariableMapping", "VectorMapping", "apply_override", "load_scenario",
           "read_toml"]

#: Top-level keys that mark the other input files, their kind and the subcommand that reads them.
OTHER_FILE_KINDS = (("batch", "a batch file", "batch"), ("runs", "a comparison file", "compare"),
                    ("planner", "an offline planning file", "plan"), ("cases", "an offline planning file", "plan"))


def load_scenario(path, overrides: Mapping[str, Any] | None = None) -> Scenario:
    """Read and check a scenario file.

    Parameters
    ----------
    path : path-like
        The scenario TOML file; relative paths inside it resolve against its folder.
    overrides : mapping, optional
        Values replacing (or adding) keys of the file before it is checked, by dotted
        path: ``{"participants.nav.options.k2": 0.0, "simulation.dt_s": 60.0}``.  The
        batch runner varies scenarios this way.  The scenario hash covers them.

    Raises
    ------
    ScenarioError
        For a missing file, a TOML syntax error, an unknown key, a wrong type, a value
        beyond a limit or an inconsistent value; the message names the file and the key.
    """
    path = Path(path)
    data, raw = read_toml(path, "scenario")
    where = str(path)
    if overrides:
        for dotted, value in overrides.items():
            apply_override(data, dotted, value, where)
        check_nesting(data, where)
        raw = raw + b"\n# overrides\n" + json.dumps(dict(overrides), sort_keys=True, default=str).encode()
    _refuse_other_file_kinds(data, where)
    simulation, participants, connections, metocean, outputs, acceptance = build_scenario_parts(
        data, where, path.stem, path.parent)
    from orchestrator.acceptance import parse_acceptance  # batch files share the format

    return Scenario(
        path=path.resolve(),
        simulation=simulation,
        participants=participants,
        connections=connections,
        metocean=metocean,
        outputs=outputs,
        sha256=hashlib.sha256(raw).hexdigest(),
        acceptance=parse_acceptance(acceptance, where),
    )


def _refuse_other_file_kinds(data: dict, where: str) -> None:
    """A batch, comparison or planning file given where a scenario is read: name the right command."""
    if "participants" in data or "simulation" in data:
        return
    for key, kind, command in OTHER_FILE_KINDS:
        if key in data:
            raise ScenarioError(f"{where}: {kind} (it has '{key}'), not a scenario: "
                                f"use 'python -m orchestrator {command} {where}'")
