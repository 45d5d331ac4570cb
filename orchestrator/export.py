"""Export a Python participant of a scenario as an FMI 2.0 co-simulation FMU (``export``).

``python -m orchestrator export S.toml NAME`` packs the participant ``NAME`` (navigation,
NMPC, traffic, reference path, goal, or a user's ``type = "python"`` class) with its
options, as the scenario configures it, into ``NAME.fmu``, so that another FMI master
(OSP's libcosim, for instance) can run our autonomy against its own ship.

Route taken: a Python-backed FMU built with PythonFMU (the FMU's binary is PythonFMU's
small C wrapper, which starts the Python interpreter and calls the slave class in
``resources/``). The alternative, a C wrapper of our own embedding Python, would duplicate
that wrapper; a pure C port of the NMPC would duplicate CasADi. What runs the FMU needs: a
shared-library CPython (3.11 or newer) with this package installed (``pip install
rhnc-cosim``: CasADi, NumPy, SciPy, ...), the same as for running a scenario.

Interface of the FMU. Every input and output port of the participant is an FMI Real
variable; an array port of shape (n, m) becomes n * m scalar variables named
``port[i,j]`` (0-based, the time-series columns' convention). The shapes are those the
ports have in the scenario: the export runs the scenario for a few macro steps to see
them (the obstacle list, for example, has one row per obstacle of the scenario's traffic).
The FMU's communication step is the participant's (``every`` times ``dt_s``); it holds its
outputs between steps.

Timing. As in our master, the participant decides at ``t`` from its inputs at ``t``; an FMI
master reads the outputs after ``doStep(t, h)``. Under a master that steps all FMUs
together (Jacobi, as libcosim does) a decision made at ``t`` reaches the ship in the step
from ``t + h``: run the reference scenario with ``[simulation] exchange = "jacobi"`` to
compare like with like.
"""

from __future__ import annotations

import contextlib
import json
import logging
import shutil
import tempfile
from collections.abc import Iterator
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from orchestrator.errors import ScenarioError
from orchestrator.participant import Participant

log = logging.getLogger(__name__)

SLAVE_TEMPLATE = Path(__file__).with_name("exported_participant.py")
#: Folder of the FMU's resources with export.json, the met-ocean field and the option files.
BUNDLE = "participant"
PROBE_STEPS_PER_PARTICIPANT_STEP = 2


class _ShapeProbe(Participant):
    """Forwards to a participant and records the shape of every port value it sees."""

    def __init__(self, inner: Participant) -> None:
        super().__init__(inner.name)
        self.inner = inner
        self.outputs_at_step_end = inner.outputs_at_step_end
        self.shapes: dict[str, dict[str, list[int]]] = {"inputs": {}, "outputs": {}}
        #: each input's value at the participant's first step: the FMU's start values
        self.first_inputs: dict[str, list[float]] = {}

    @property
    def input_names(self):
        return self.inner.input_names

    @property
    def output_names(self):
        return self.inner.output_names

    def _record(self, kind: str, values) -> None:
        for port, value in values.items():
            self.shapes[kind][port] = list(np.shape(value))

    def setup(self, start_time, inputs):
        self._record("inputs", inputs)
        outputs = self.inner.setup(start_time, inputs)
        self._record("outputs", outputs)
        return outputs

    def step(self, time, step_size, inputs):
        self._record("inputs", inputs)
        for port, value in inputs.items():
            self.first_inputs.setdefault(port, [float(v) for v in np.ravel(value)])
        outputs = self.inner.step(time, step_size, inputs)
        self._record("outputs", outputs)
        return outputs

    def terminate(self):
        self.inner.terminate()


@contextlib.contextmanager
def nothing_left_on_failure(out_dir) -> Iterator[None]:
    """Remove what the block wrote into ``out_dir`` (and the folder, if it made it) when it raises.

    An export that is refused half-way (the second of two participants unknown, a port of
    unknown size) leaves the folder as it found it, not one FMU of several.
    """
    out_dir = Path(out_dir)
    existed = out_dir.exists()
    before = {path.name for path in out_dir.iterdir()} if existed and out_dir.is_dir() else set()
    try:
        yield
    except BaseException:
        if not existed:
            shutil.rmtree(out_dir, ignore_errors=True)
        elif out_dir.is_dir():
            for path in out_dir.iterdir():
                if path.name in before:
                    continue
                if path.is_dir():
                    shutil.rmtree(path, ignore_errors=True)
                else:
                    path.unlink(missing_ok=True)
        raise


def check_exportable(scenario, scenario_path, names) -> None:
    """Refuse names that are not Python participants of the scenario, before anything is built."""
    specs = {spec.name: spec for spec in scenario.participants}
    for name in names:
        if name not in specs:
            raise ScenarioError(f"{scenario_path}: no participant '{name}' (participants: {', '.join(specs)})")
        if specs[name].is_fmu:
            raise ScenarioError(f"{scenario_path}: participants.{name} is an FMU already ({specs[name].fmu})")
        _check_json(specs[name].options, f"{scenario_path}: participants.{name}.options")


def export_participant(scenario_path, participant: str, out_dir=".") -> Path:
    """Write ``<out_dir>/<participant>.fmu``; return its path.

    Raises
    ------
    ScenarioError
        The scenario has no such participant, it is an FMU already, or a port stays
        unconnected and unseen in the probe run (its shape is unknown).
    """
    from orchestrator.master import CoSimulation
    from orchestrator.scenario import load_scenario

    scenario_path = Path(scenario_path)
    scenario = load_scenario(scenario_path)
    check_exportable(scenario, scenario_path, [participant])
    spec = next(spec for spec in scenario.participants if spec.name == participant)
    probe_steps = min(scenario.simulation.steps,
                      PROBE_STEPS_PER_PARTICIPANT_STEP * max(s.every for s in scenario.participants))
    # in Jacobi order, as most FMI masters step: the participant's defaults that depend on
    # the exchange order (the NMPC's loop delay) are then those the FMU declares
    probe_scenario = replace(scenario, simulation=replace(
        scenario.simulation, stop_s=scenario.simulation.start_s + probe_steps * scenario.simulation.dt_s,
        stop_when=(), exchange="jacobi"))
    cosim = CoSimulation(probe_scenario)
    try:
        index = [p.name for p in cosim.participants].index(participant)
        probe = _ShapeProbe(cosim.participants[index])
        cosim.participants[index] = probe
        outcome = cosim.run(progress=False)
        if outcome.status != "finished":
            raise ScenarioError(f"{scenario_path}: the probe run for the export failed: {outcome.reason}")
        layout = _layout(probe, scenario_path)
        with tempfile.TemporaryDirectory(prefix=f"export-{participant}-") as folder:
            tmp = Path(folder)
            bundle = tmp / BUNDLE
            bundle.mkdir()
            _resources(spec, scenario, cosim, bundle)
            description = {
                "participant": participant,
                "target": _target(spec),
                "options": spec.options,
                "step_size_s": spec.every * scenario.simulation.dt_s,
                "start_s": scenario.simulation.start_s,
                "stop_s": scenario.simulation.stop_s,
                "metocean": "metocean.nc" if cosim.metocean is not None else None,
                "inputs": layout["inputs"],
                "outputs": layout["outputs"],
                "parameters": [{"name": name, **entry} for name, entry in probe.inner.fmu_parameters().items()],
                "scenario": scenario_path.name,
            }
            (bundle / "export.json").write_text(json.dumps(description, indent=1))
            script = tmp / f"{participant}.py"
            script.write_text(SLAVE_TEMPLATE.read_text().replace("class ExportedParticipant(",
                                                                 f"class {participant}("))
            units = {name: entry.get("units", {}).get(name, entry.get("unit", ""))
                     for kind in ("inputs", "outputs") for entry in description[kind]
                     for name in entry.get("descriptions", {})}
            units.update({entry["name"]: entry.get("unit", "") for entry in description["parameters"]})
            return _build(script, [bundle], Path(out_dir), participant, units)
    finally:
        cosim.close()


def _build(script: Path, files: list[Path], out_dir: Path, participant: str,
           units: dict[str, str] | None = None) -> Path:
    from pythonfmu.builder import FmuBuilder

    out_dir.mkdir(parents=True, exist_ok=True)
    target = out_dir / f"{participant}.fmu"
    partial = out_dir / f".{participant}.fmu.partial"
    built = FmuBuilder.build_FMU(script, dest=partial.with_suffix(".fmu"), project_files=files,
                                 needsExecutionTool="true", canGetAndSetFMUstate="false",
                                 canSerializeFMUstate="false")
    _complete_model_structure(Path(built), target, units)
    Path(built).unlink()
    log.info("exported %s", target)
    return target


def _complete_model_structure(source: Path, target: Path, units: dict[str, str] | None = None) -> None:
    """Copy the FMU, listing every output among the InitialUnknowns (PythonFMU leaves them out,
    which FMI 2.0 requires for outputs computed at initialisation), and giving each variable
    of ``units`` (variable name -> unit) its unit, declared in UnitDefinitions."""
    import xml.etree.ElementTree as ET
    import zipfile

    from orchestrator.model_description import child

    with zipfile.ZipFile(source) as old, zipfile.ZipFile(target, "w", zipfile.ZIP_DEFLATED) as new:
        for item in old.infolist():
            data = old.read(item.filename)
            if item.filename == "modelDescription.xml":
                root = ET.fromstring(data)
                variables = child(root, "ModelVariables").findall("ScalarVariable")
                structure = child(root, "ModelStructure")
                initial = structure.find("InitialUnknowns")
                if initial is None:
                    initial = ET.SubElement(structure, "InitialUnknowns")
                for index, variable in enumerate(variables, start=1):
                    if variable.get("causality") == "output":
                        ET.SubElement(initial, "Unknown", {"index": str(index)})
                    unit = (units or {}).get(variable.get("name", ""))
                    if unit:
                        child(variable, "Real").set("unit", unit)
                used = sorted({unit for unit in (units or {}).values() if unit})
                if used:
                    definitions = ET.Element("UnitDefinitions")
                    for unit in used:
                        ET.SubElement(ET.SubElement(definitions, "Unit", {"name": unit}), "BaseUnit",
                                      {k: str(v) for k, v in BASE_UNITS.get(unit, {}).items()})
                    position = list(root).index(child(root, "CoSimulation")) + 1
                    root.insert(position, definitions)
                ET.indent(root)
                data = b'<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(root)
            new.writestr(item, data)


def _target(spec) -> str:
    from orchestrator.participant_build import participant_target

    return participant_target(spec, f"participants.{spec.name}")


def _layout(probe: _ShapeProbe, scenario_path: Path) -> dict[str, list[dict[str, Any]]]:
    layout: dict[str, list[dict[str, Any]]] = {"inputs": [], "outputs": []}
    for kind, names in (("inputs", probe.input_names), ("outputs", probe.output_names)):
        for port in names:
            shape = probe.shapes[kind].get(port)
            if shape is None:
                if kind == "inputs":
                    continue  # unconnected in the scenario: the FMU does not offer it
                raise ScenarioError(
                    f"{scenario_path}: participants.{probe.name}: output '{port}' was never produced "
                    "in the probe run, so its size is unknown")
            entry = {"port": port, "shape": shape, **_port_meaning(probe.inner, port, shape)}
            if kind == "inputs":
                entry["start"] = probe.first_inputs.get(port)
            layout[kind].append(entry)
    return layout


#: Base-unit exponents of the units ports declare (FMI 2.0 UnitDefinitions).
BASE_UNITS = {"m": {"m": 1}, "s": {"s": 1}, "rad": {"rad": 1}, "m/s": {"m": 1, "s": -1},
              "rad/s": {"rad": 1, "s": -1}, "N": {"kg": 1, "m": 1, "s": -2}, "N.m": {"kg": 1, "m": 2, "s": -2}}


def _port_meaning(participant, port: str, shape: list[int]) -> dict[str, Any]:
    """Unit, description and a description per element (``port[i,j]``) from ``participant.port_info``."""
    info = participant.port_info(port)
    if not info:
        return {}
    text = info.get("description", "")
    meaning: dict[str, Any] = {"unit": info.get("unit", ""), "description": text}
    columns = info.get("columns")
    descriptions, units = {}, {}
    for index in np.ndindex(*shape):
        name = port + (f"[{','.join(map(str, index))}]" if shape else "")
        if not index:
            descriptions[name] = text
            continue
        column = columns[index[-1]] if columns and index[-1] < len(columns) else None
        position = ", ".join(map(str, index))
        where = f"row {index[0]}, {column}" if len(index) == 2 and column else (column or f"element {position}")
        descriptions[name] = f"{where}: {text}"
        unit = column.rpartition("[")[2].rstrip("]") if column and column.endswith("]") else ""
        if unit in BASE_UNITS:  # a column's own unit, "u surge [m/s]"
            units[name] = unit
    meaning["descriptions"] = descriptions
    if units:
        meaning["units"] = units
    return meaning


def _resources(spec, scenario, cosim, folder: Path) -> None:
    """Files the participant reads: the met-ocean field and files its options name by a
    path relative to the scenario (copied to the same relative path)."""
    if cosim.metocean is not None:
        cosim.metocean.to_netcdf(folder / "metocean.nc")
    for value in _strings(spec.options):
        if not value or Path(value).is_absolute() or ".." in Path(value).parts:
            continue
        candidate = scenario.directory / value
        if candidate.is_file():
            copy = folder / value
            copy.parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(candidate, copy)


def _strings(value):
    if isinstance(value, str):
        yield value
    elif isinstance(value, dict):
        for item in value.values():
            yield from _strings(item)
    elif isinstance(value, list):
        for item in value:
            yield from _strings(item)


def _check_json(options, where: str) -> None:
    """Options go into the FMU as JSON: refuse what JSON cannot hold (NaN and infinities included)."""
    try:
        json.dumps(options, allow_nan=False)
    except (TypeError, ValueError) as exc:
        raise ScenarioError(f"{where}: the options cannot be written into the FMU: {exc}") from exc


def exported_layout(fmu) -> dict[str, list[dict[str, Any]]]:
    """The ports (name and shape) of an exported participant FMU, from its ``export.json``."""
    import zipfile

    with zipfile.ZipFile(fmu) as archive:
        description = json.loads(archive.read(f"resources/{BUNDLE}/export.json"))
    return {"inputs": description["inputs"], "outputs": description["outputs"]}
