"""The modelDescription.xml of a built FMU: FMI 2.0 as written in ``models/``, or FMI 3.0 derived.

Each model keeps one hand-written FMI 2.0 description. At build time it gets

* its source file list from what was compiled (so it never names a file the FMU lacks),
* the product's metadata: author, version, licence and generation date,

and, for an FMI 3.0 build (whose sources are listed in ``sources/buildDescription.xml``
instead), is translated element by element: ``ScalarVariable``/``Real``
becomes ``Float64`` (``String`` keeps its name, its start value becomes a ``Start``
child), ``SimpleType``/``Real`` becomes ``Float64Type``, the ``guid`` becomes the
``instantiationToken``, the model structure lists outputs and initial unknowns by value
reference, and the independent variable ``time`` is added (value reference
:data:`FMI3_TIME_VR`, served by ``models/common/fmi3_api.c``). Units and display units
carry over unchanged: FMI 3.0 kept FMI 2.0's unit definitions.
"""

from __future__ import annotations

import datetime as _dt
import xml.etree.ElementTree as ET
from collections.abc import Sequence

from orchestrator.errors import FmuError

#: Value reference of the FMI 3.0 independent variable ``time`` (outside every model's table).
FMI3_TIME_VR = 1000000

AUTHOR = "rhnc-cosim developers"
LICENSE = "MIT"

_SCALAR_ATTRIBUTES = ("name", "valueReference", "description", "causality", "variability", "initial",
                      "canHandleMultipleSetPerTimeInstant")
_REAL_ATTRIBUTES = ("declaredType", "quantity", "unit", "displayUnit", "relativeQuantity", "min", "max",
                    "nominal", "unbounded", "start")
_COSIMULATION_FMI3 = {
    "canHandleVariableCommunicationStepSize": "true",
    "canGetAndSetFMUState": None,      # taken from the FMI 2.0 flag of the same meaning
    "canSerializeFMUState": None,
    "providesIntermediateUpdate": "false",
    "canReturnEarlyAfterIntermediateUpdate": "false",
    "hasEventMode": "false",
}


def child(element: ET.Element, tag: str) -> ET.Element:
    """The first ``tag`` element under ``element``; :class:`FmuError` naming it when there is none."""
    found = element.find(tag)
    if found is None:
        raise FmuError(f"modelDescription.xml: <{element.tag}> has no <{tag}>")
    return found


def attribute(element: ET.Element, name: str) -> str:
    """The ``name`` attribute of ``element``; :class:`FmuError` naming both when it is missing."""
    value = element.get(name)
    if value is None:
        raise FmuError(f"modelDescription.xml: <{element.tag}> has no {name} attribute")
    return value


def _generation_date() -> str:
    return _dt.datetime.now(_dt.timezone.utc).replace(microsecond=0).isoformat().replace("+00:00", "Z")


def finish_fmi2(text: str, source_files: Sequence[str], version: str) -> str:
    """The FMI 2.0 description with the compiled source list and the product's metadata."""
    root = ET.fromstring(text)
    _set_metadata(root, version)
    _replace_source_files(child(root, "CoSimulation"), source_files)
    return _serialise(root)


def to_fmi3(text: str, source_files: Sequence[str], version: str) -> str:
    """Translate a finished FMI 2.0 co-simulation description into FMI 3.0."""
    old = ET.fromstring(text)
    if old.get("fmiVersion") != "2.0" or old.find("CoSimulation") is None:
        raise ValueError("expected an FMI 2.0 co-simulation modelDescription")
    root = ET.Element("fmiModelDescription", {
        "fmiVersion": "3.0",
        "modelName": old.get("modelName", ""),
        "instantiationToken": old.get("guid", ""),
    })
    for key in ("description", "generationTool", "variableNamingConvention"):
        value = old.get(key)
        if value is not None:
            root.set(key, value)
    _set_metadata(root, version)
    old_cosim = child(old, "CoSimulation")
    cosim = ET.SubElement(root, "CoSimulation", {"modelIdentifier": old_cosim.get("modelIdentifier", "")})
    for key, value in _COSIMULATION_FMI3.items():
        fmi2_key = key.replace("FMUState", "FMUstate")
        cosim.set(key, value if value is not None else old_cosim.get(fmi2_key, "false"))
    units = old.find("UnitDefinitions")
    if units is not None:
        root.append(units)
    _types_fmi3(old, root)
    for name in ("LogCategories", "DefaultExperiment"):
        element = old.find(name)
        if element is not None:
            root.append(element)
    ordered = _variables_fmi3(old, root)
    _structure_fmi3(old, root, ordered)
    return _serialise(root)


def _types_fmi3(old: ET.Element, root: ET.Element) -> None:
    """The FMI 2.0 Real types as FMI 3.0 Float64Type definitions."""
    types = old.find("TypeDefinitions")
    if types is not None:
        new_types = ET.SubElement(root, "TypeDefinitions")
        for simple in types.findall("SimpleType"):
            real = simple.find("Real")
            if real is None:
                raise ValueError(f"type {simple.get('name')}: only Real types translate to FMI 3.0")
            attributes = {"name": attribute(simple, "name")}
            attributes.update({k: v for k, v in real.attrib.items() if k in _REAL_ATTRIBUTES})
            ET.SubElement(new_types, "Float64Type", attributes)


def _variables_fmi3(old: ET.Element, root: ET.Element) -> list:
    """The variables in FMI 3.0 form (time first); returns the value references in FMI 2.0 index order."""
    variables = ET.SubElement(root, "ModelVariables")
    ET.SubElement(variables, "Float64", {"name": "time", "valueReference": str(FMI3_TIME_VR),
                                         "causality": "independent", "variability": "continuous",
                                         "description": "simulation time"})
    ordered = []  # value references in FMI 2.0 index order (1-based indices)
    for scalar in child(old, "ModelVariables").findall("ScalarVariable"):
        attributes = {k: v for k, v in scalar.attrib.items() if k in _SCALAR_ATTRIBUTES}
        ordered.append(scalar.get("valueReference"))
        real = scalar.find("Real")
        string = scalar.find("String")
        if real is not None:
            attributes.update({k: v for k, v in real.attrib.items() if k in _REAL_ATTRIBUTES})
            ET.SubElement(variables, "Float64", attributes)
        elif string is not None:
            element = ET.SubElement(variables, "String", attributes)
            start = string.get("start")
            if start is not None:
                ET.SubElement(element, "Start", {"value": start})
        else:
            raise ValueError(f"variable {scalar.get('name')}: only Real and String translate to FMI 3.0")
    return ordered


def _structure_fmi3(old: ET.Element, root: ET.Element, ordered: list) -> None:
    """Outputs and initial unknowns, FMI 2.0 indices turned into value references."""
    structure = ET.SubElement(root, "ModelStructure")
    old_structure = old.find("ModelStructure")
    for section, tag in (("Outputs", "Output"), ("InitialUnknowns", "InitialUnknown")):
        block = old_structure.find(section) if old_structure is not None else None
        for unknown in [] if block is None else block.findall("Unknown"):
            attributes = {"valueReference": ordered[int(attribute(unknown, "index")) - 1]}
            dependencies = unknown.get("dependencies")
            if dependencies is not None:
                attributes["dependencies"] = " ".join(ordered[int(i) - 1] for i in dependencies.split())
            ET.SubElement(structure, tag, attributes)


def build_description_fmi3(model_identifier: str, source_files: Sequence[str]) -> str:
    """``sources/buildDescription.xml`` of an FMI 3.0 FMU: the C files to compile."""
    root = ET.Element("fmiBuildDescription", {"fmiVersion": "3.0"})
    configuration = ET.SubElement(root, "BuildConfiguration", {"modelIdentifier": model_identifier})
    file_set = ET.SubElement(configuration, "SourceFileSet", {"language": "C99"})
    for name in source_files:
        ET.SubElement(file_set, "SourceFile", {"name": name})
    return _serialise(root)


def bounds_header(text: str) -> str:
    """``model_bounds.h``: the declared min/max of every Real variable, for the FMU to enforce.

    The shared layer refuses a value outside the range when it is set (e.g. a negative wave
    height), so the description is the single source of the ranges.
    """
    root = ET.fromstring(text)
    rows = []
    for scalar in child(root, "ModelVariables").findall("ScalarVariable"):
        real = scalar.find("Real")
        if real is None:
            continue
        low_text, high_text = real.get("min"), real.get("max")
        if low_text is None and high_text is None:
            continue
        low = repr(float(low_text)) if low_text is not None else "-HUGE_VAL"
        high = repr(float(high_text)) if high_text is not None else "HUGE_VAL"
        rows.append(f"    {{{int(attribute(scalar, 'valueReference'))}u, {low}, {high}}}, /* {scalar.get('name')} */")
    rows.append("    {(fmi2ValueReference)-1, -HUGE_VAL, HUGE_VAL} /* end marker: no variable */")
    return "\n".join([
        "/* Generated by orchestrator/fmu_build.py from modelDescription.xml. Do not edit. */",
        "#ifndef MODEL_BOUNDS_H", "#define MODEL_BOUNDS_H", "#include <math.h>",
        '#include "fmu_model.h"',
        "static const VariableBounds model_bounds[] = {", *rows, "};", "#endif", "",
    ])


def _set_metadata(root: ET.Element, version: str) -> None:
    root.set("author", AUTHOR)
    root.set("version", version)
    root.set("license", LICENSE)
    root.set("copyright", f"{AUTHOR}, {LICENSE} licence")
    root.set("generationDateAndTime", _generation_date())


def _replace_source_files(cosim: ET.Element, source_files: Sequence[str]) -> None:
    old = cosim.find("SourceFiles")
    if old is not None:
        cosim.remove(old)
    files = ET.SubElement(cosim, "SourceFiles")
    for name in source_files:
        ET.SubElement(files, "File", {"name": name})


def _serialise(root: ET.Element) -> str:
    ET.indent(root, space="  ")
    return '<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(root, encoding="unicode") + "\n"
