"""A whole scenario as an OSP system: every participant an FMU, and ``OspSystemStructure.xml``.

``python -m orchestrator export S.toml --osp DIR`` writes into ``DIR`` the FMUs of every
participant (Python participants exported with :mod:`orchestrator.export`, built-in models
copied) and an ``OspSystemStructure.xml`` that OSP's libcosim (``cosim`` command line, or
``libcosimpy``'s ``CosimExecution.from_osp_config_file``) runs as it is: the scenario's
macro step as base step, each participant's step (``every`` times ``dt_s``), its start
values, and the connections element by element (an array port ``reference`` of shape
(16, 7) becomes 112 variable connections ``reference[i,j]``).

When the scenario has ``[[acceptance]]`` criteria it is copied beside the system as
``scenario.toml``: ``python -m orchestrator check <libcosim's CSV files> --scenario
DIR/scenario.toml`` judges libcosim's run by them (:mod:`orchestrator.foreign_results`).

libcosim steps every simulator of a communication point at once (Jacobi), so the system
reproduces the scenario run with ``[simulation] exchange = "jacobi"``; with our default
order (Gauss-Seidel) a decision reaches the ship one step earlier.
"""

from __future__ import annotations

import logging
import shutil
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from orchestrator.errors import ScenarioError

log = logging.getLogger(__name__)

NAMESPACE = "http://opensimulationplatform.com/MSMI/OSPSystemStructure"
CONFIG_NAME = "OspSystemStructure.xml"
#: The scenario, with its acceptance criteria, beside the system (``check --scenario``).
SCENARIO_COPY = "scenario.toml"
#: Name of the scenario's met-ocean grid inside the environment FMU's resources.
GRID_RESOURCE = "scenario.grid"


def export_osp_system(scenario_path, out_dir) -> Path:
    """Write the scenario's FMUs and ``OspSystemStructure.xml`` into ``out_dir``; return the XML's path."""
    from orchestrator.export import export_participant, exported_layout
    from orchestrator.fmu_participant import FmuParticipant
    from orchestrator.master import CoSimulation
    from orchestrator.scenario import load_scenario

    scenario_path = Path(scenario_path)
    out_dir = Path(out_dir)
    scenario = load_scenario(scenario_path)
    for spec in scenario.participants:
        if spec.is_fmu and (spec.mapping or spec.initial):
            # OSP connects FMU variables as they are: no unit conversion, projection or renaming
            raise ScenarioError(f"{scenario_path}: participants.{spec.name}.mapping: an OSP system connects FMU "
                                "variables directly; an FMU behind a mapping (names, units, geodetic, vectors, "
                                "initial state) cannot be exported")
    out_dir.mkdir(parents=True, exist_ok=True)
    if scenario.simulation.stop_when:
        log.warning("%s: libcosim has no stop condition; the OSP system runs to the scenario's stop time",
                    scenario_path)
    shapes: dict[tuple[str, str], list[int]] = {}
    cosim = CoSimulation(scenario)
    try:
        fmus = {}
        grid = cosim.work_dir / "metocean.grid"
        for participant in cosim.participants:
            if isinstance(participant, FmuParticipant):
                target = out_dir / f"{participant.name}.fmu"
                extra = {GRID_RESOURCE: grid} if str(grid) in map(str, participant.parameters.values()) else {}
                _copy_with_resources(participant.fmu_path, target, extra)
                fmus[participant.name] = (target, participant)
                for port in (*participant.input_names, *participant.output_names):
                    shapes[(participant.name, port)] = []
        for spec in scenario.participants:
            if spec.is_fmu:
                continue
            fmu = export_participant(scenario_path, spec.name, out_dir)
            for entries in exported_layout(fmu).values():
                for entry in entries:
                    shapes[(spec.name, entry["port"])] = entry["shape"]
        root = _system_structure(scenario, scenario_path, fmus, shapes, grid, out_dir)
        ET.indent(root)
        if scenario.acceptance:  # the criteria travel with the system: python -m orchestrator check ... --scenario
            shutil.copyfile(scenario_path, out_dir / SCENARIO_COPY)
        config = out_dir / CONFIG_NAME
        config.write_text('<?xml version="1.0" encoding="utf-8"?>\n' + ET.tostring(root, encoding="unicode") + "\n")
        return config
    finally:
        cosim.close()


def _system_structure(scenario, scenario_path: Path, fmus: dict, shapes: dict[tuple[str, str], list[int]], grid: Path,
                      out_dir: Path) -> ET.Element:
    """``OspSystemStructure``: the time grid, one simulator per participant, a connection per element."""
    root = ET.Element("OspSystemStructure", {"xmlns": NAMESPACE, "version": "0.1"})
    ET.SubElement(root, "StartTime").text = repr(scenario.simulation.start_s)
    ET.SubElement(root, "BaseStepSize").text = repr(scenario.simulation.dt_s)
    ET.SubElement(root, "Algorithm").text = "fixedStep"
    simulators = ET.SubElement(root, "Simulators")
    for spec in scenario.participants:
        element = ET.SubElement(simulators, "Simulator", {
            "name": spec.name, "source": f"{spec.name}.fmu",
            "stepSize": repr(spec.every * scenario.simulation.dt_s)})
        if spec.name in fmus:
            _initial_values(element, fmus[spec.name][1], grid, out_dir)
    connections = ET.SubElement(root, "Connections")
    for connection in scenario.connections:
        source = (connection.source, connection.source_port)
        target = (connection.target, connection.target_port)
        shape = shapes.get(source, shapes.get(target))
        if shape is None or (target in shapes and shapes[target] != shape):
            raise ScenarioError(f"{scenario_path}: connection '{connection}' joins ports of unknown "
                                "or different sizes")
        for suffix in _element_suffixes(shape):
            pair = ET.SubElement(connections, "VariableConnection")
            ET.SubElement(pair, "Variable", {"simulator": source[0], "name": source[1] + suffix})
            ET.SubElement(pair, "Variable", {"simulator": target[0], "name": target[1] + suffix})
    return root


def _copy_with_resources(source: Path, target: Path, extra: dict[str, Path]) -> None:
    """Copy an FMU, adding files to its ``resources/`` (the scenario's met-ocean grid)."""
    if not extra:
        shutil.copyfile(source, target)
        return
    import zipfile

    with zipfile.ZipFile(source) as old, zipfile.ZipFile(target, "w", zipfile.ZIP_DEFLATED) as new:
        for item in old.infolist():
            if item.filename not in {f"resources/{name}" for name in extra}:
                new.writestr(item, old.read(item.filename))
        for name, path in extra.items():
            new.write(path, f"resources/{name}")


def _initial_values(element: ET.Element, participant, grid: Path, out_dir: Path) -> None:
    values = ET.SubElement(element, "InitialValues")
    for name, value in participant.parameters.items():
        initial = ET.SubElement(values, "InitialValue", {"variable": name})
        if isinstance(value, str):
            if Path(value) == grid:  # the scenario's met-ocean grid, shipped in the FMU's resources
                value = GRID_RESOURCE
            ET.SubElement(initial, "String", {"value": value})
        elif isinstance(value, bool):
            ET.SubElement(initial, "Boolean", {"value": "true" if value else "false"})
        else:
            ET.SubElement(initial, "Real", {"value": repr(float(value))})


def _element_suffixes(shape) -> list[str]:
    if not shape:
        return [""]
    return [f"[{','.join(map(str, index))}]" for index in np.ndindex(*shape)]
