"""FMI 2.0 co-simulation FMUs as participants, through FMPy's own classes.

Ports are the FMU's input and output variables, or, where the scenario maps them,
canonical names (``x``, ``tau_u``, ...) bound to vendor variables with a unit scale
(``canonical = scale * fmu_value``).  The plant's canonical names have a fixed
causality, so a mapping that binds ``tau_u`` to an FMU output is refused.
"""

from __future__ import annotations

import logging
import math
import shutil
import tempfile
import tomllib
from collections.abc import Mapping
from pathlib import Path

from fmpy.fmi1 import FMICallException

from orchestrator.errors import FmuError, ModelError, ScenarioError
from orchestrator.fmi_slave import REAL_TYPES, SUPPORTED_VERSIONS, FmiSlave
from orchestrator.participant import Participant, Value
from orchestrator.scenario import ParticipantSpec, VariableMapping

log = logging.getLogger(__name__)

#: Canonical plant ports (spec section 1) and the causality each must have.
CANONICAL_PLANT_PORTS = {
    **{name: "output" for name in ("x", "y", "psi", "u", "v", "r", "sog", "cog")},
    **{name: "input" for name in ("tau_u", "tau_r", "current_north", "current_east",
                                  "wind_speed", "wind_direction", "hs")},
}


def resolve_fmu(reference: str, scenario_dir: Path, where: str, fmi_version: str = "2.0") -> Path:
    """Path of the FMU a scenario names: a built-in model (built on demand for ``fmi_version``) or a file."""
    from orchestrator import fmu_build

    if not reference.endswith(".fmu") and "/" not in reference and "\\" not in reference:
        if reference not in fmu_build.model_names():
            raise FmuError(
                f"{where}.fmu: no built-in model '{reference}' (valid: {', '.join(fmu_build.model_names())},"
                " or a path to an .fmu file)"
            )
        return fmu_build.ensure_built(reference, fmi_version=fmi_version)
    path = Path(reference)
    path = path if path.is_absolute() else scenario_dir / path
    if not path.is_file():
        raise FmuError(f"{where}.fmu: FMU file not found: {path}")
    return path


def read_parameter_set(fmu_reference: str, set_name: str, where: str) -> dict:
    """Values of a named parameter set of a built-in model (``models/<Name>/parameter_sets.toml``)."""
    from orchestrator import fmu_build

    file = fmu_build.MODELS_DIR / fmu_reference / "parameter_sets.toml"
    if not file.is_file():
        raise ScenarioError(f"{where}.parameter_set: model '{fmu_reference}' has no parameter sets ({file} missing)")
    with file.open("rb") as handle:
        sets = tomllib.load(handle)
    if set_name not in sets:
        raise ScenarioError(
            f"{where}.parameter_set: no set '{set_name}' in {file.name} (valid: {', '.join(sets)})"
        )
    return {key: value for key, value in sets[set_name].items() if key != "description"}


class FmuParticipant(Participant):
    """A co-simulation FMU (FMI 2.0 or 3.0) stepped through :class:`orchestrator.fmi_slave.FmiSlave`.

    Parameters
    ----------
    spec : ParticipantSpec
        The scenario's table for this participant.
    fmu_path : Path
        The FMU file.
    where : str
        Error prefix naming the scenario file and table.
    string_substitutions : mapping
        Values for ``${...}`` placeholders in string parameters (``${metocean.grid}``).
    """

    outputs_at_step_end = True
    #: outputs are checked here, where the FMU variable can be named
    checks_outputs_finite = True

    def __init__(self, spec: ParticipantSpec, fmu_path: Path, where: str,
                 string_substitutions: Mapping[str, str] | None = None) -> None:
        super().__init__(spec.name)
        from fmpy import read_model_description

        self.fmu_path = Path(fmu_path)
        self.where = where
        try:
            self.model_description = read_model_description(str(self.fmu_path))
        except Exception as exc:  # fmpy raises plain exceptions for broken archives/XML
            raise FmuError(f"{where}.fmu: {self.fmu_path} is not a valid FMU: {exc}") from exc
        if self.model_description.fmiVersion not in SUPPORTED_VERSIONS or self.model_description.coSimulation is None:
            raise FmuError(f"{where}.fmu: {self.fmu_path} is not an FMI 2.0 or 3.0 co-simulation FMU")
        self.variables = {v.name: v for v in self.model_description.modelVariables}
        self.parameters = self._parameter_values(spec, string_substitutions or {})
        self._inputs: dict[str, VariableMapping] = {}
        self._outputs: dict[str, VariableMapping] = {}
        self._bind_ports(spec.mapping)
        self._input_refs = {port: self.variables[b.variable].valueReference for port, b in self._inputs.items()}
        self._output_ports = list(self._outputs)
        self._output_refs = [self.variables[self._outputs[p].variable].valueReference for p in self._output_ports]
        self._output_scales = [self._outputs[p].scale for p in self._output_ports]
        self._slave = None
        self._unzip_dir = None
        self._messages: list[str] = []

    # -- ports -------------------------------------------------------------------------
    @property
    def input_names(self):
        return list(self._inputs)

    @property
    def output_names(self):
        return list(self._outputs)

    def _bind_ports(self, mapping: Mapping[str, VariableMapping]) -> None:
        mapped_variables = set()
        for port, target in mapping.items():
            variable = self.variables.get(target.variable)
            if variable is None:
                raise FmuError(
                    f"{self.where}.mapping.{port}: FMU {self.fmu_path.name} has no variable '{target.variable}'"
                )
            if variable.causality not in ("input", "output"):
                raise FmuError(
                    f"{self.where}.mapping.{port}: variable '{target.variable}' has causality "
                    f"'{variable.causality}'; only inputs and outputs can be mapped"
                )
            expected = CANONICAL_PLANT_PORTS.get(port)
            if expected is not None and variable.causality != expected:
                raise FmuError(
                    f"{self.where}.mapping.{port}: '{port}' is a plant {expected} but FMU variable "
                    f"'{target.variable}' is an {variable.causality}"
                )
            if variable.type not in REAL_TYPES:
                raise FmuError(f"{self.where}.mapping.{port}: variable '{target.variable}' is not Real")
            (self._inputs if variable.causality == "input" else self._outputs)[port] = target
            mapped_variables.add(target.variable)
        for variable in self.model_description.modelVariables:
            if variable.name in mapped_variables or variable.type not in REAL_TYPES:
                continue
            if variable.causality == "input":
                self._inputs.setdefault(variable.name, VariableMapping(variable.name))
            elif variable.causality == "output":
                self._outputs.setdefault(variable.name, VariableMapping(variable.name))

    def _parameter_values(self, spec: ParticipantSpec, substitutions: Mapping[str, str]) -> dict:
        values = {}
        if spec.parameter_set is not None:
            values.update(read_parameter_set(spec.fmu, spec.parameter_set, self.where))
        values.update(spec.parameters)
        for name, value in values.items():
            variable = self.variables.get(name)
            if variable is None:
                raise FmuError(f"{self.where}.parameters.{name}: FMU {self.fmu_path.name} has no variable '{name}'")
            if variable.causality != "parameter" or variable.variability == "constant":
                raise FmuError(
                    f"{self.where}.parameters.{name}: variable '{name}' is a {variable.causality}, not a parameter"
                )
            if isinstance(value, str):
                for key, replacement in substitutions.items():
                    value = value.replace("${" + key + "}", replacement)
                if "${" in value:
                    raise ScenarioError(f"{self.where}.parameters.{name}: unknown placeholder in {value!r}")
                if variable.type != "String":
                    raise ScenarioError(f"{self.where}.parameters.{name}: '{name}' is {variable.type}, got a string")
            elif variable.type == "String":
                raise ScenarioError(f"{self.where}.parameters.{name}: '{name}' is a String parameter")
            values[name] = value
        return values

    # -- lifecycle -----------------------------------------------------------------------
    def setup(self, start_time: float, inputs: Mapping[str, Value]) -> dict[str, Value]:
        from fmpy import extract

        self._unzip_dir = tempfile.mkdtemp(prefix=f"fmu-{self.name}-")
        extract(str(self.fmu_path), self._unzip_dir)
        self._slave = FmiSlave(self.model_description, self._unzip_dir, self.name, self._on_message)
        self._slave.instantiate()
        self._call("EnterInitializationMode", self._slave.enter_initialization, start_time)
        for name, value in self.parameters.items():
            self._set_variable(name, value)
        self._set_inputs(inputs)
        self._call("ExitInitializationMode", self._slave.exit_initialization)
        return self._read_outputs(start_time)

    def step(self, time: float, step_size: float, inputs: Mapping[str, Value]) -> dict[str, Value]:
        self._set_inputs(inputs)
        self._call("DoStep", self._slave.do_step, time, step_size)
        return self._read_outputs(time + step_size)

    def terminate(self) -> None:
        if self._slave is not None:
            try:
                self._slave.terminate()
            except Exception:  # a failed FMU may refuse terminate; freeing it is what matters
                log.debug("%s: %s failed", self.name, self._slave.name("Terminate"), exc_info=True)
            try:
                self._slave.free()
            except Exception:
                log.debug("%s: %s failed", self.name, self._slave.name("FreeInstance"), exc_info=True)
            self._slave = None
        if self._unzip_dir is not None:
            shutil.rmtree(self._unzip_dir, ignore_errors=True)
            self._unzip_dir = None

    # -- helpers ---------------------------------------------------------------------------
    def _on_message(self, status: int, category: str, text: str) -> None:
        # errors are raised with this text (ModelError); warnings are only logged
        level = logging.WARNING if status in (1, 2) else logging.DEBUG
        log.log(level, "%s [%s]: %s", self.name, category, text)
        if status >= 1:
            self._messages.append(text)

    def _call(self, function: str, call, *args, **kwargs):
        """Call the FMU; ``function`` is the name without its ``fmi2``/``fmi3`` prefix."""
        if self._messages:
            self._messages.clear()
        try:
            return call(*args, **kwargs)
        except FMICallException as exc:
            detail = self._messages[-1] if self._messages else str(exc)
            raise ModelError(
                f"{self.name} ({self.fmu_path.name}): {self._slave.name(function)} failed: {detail}") from exc

    def _set_variable(self, name: str, value) -> None:
        variable = self.variables[name]
        refs = [variable.valueReference]
        if variable.type in REAL_TYPES:
            self._call("SetReal", self._slave.set_reals, refs, [float(value)])
        elif variable.type in ("Integer", "Enumeration", "Int32"):
            self._call("SetInteger", self._slave.set_integers, refs, [int(value)])
        elif variable.type == "Boolean":
            self._call("SetBoolean", self._slave.set_booleans, refs, [bool(value)])
        else:
            self._call("SetString", self._slave.set_strings, refs, [str(value)])

    def _set_inputs(self, inputs: Mapping[str, Value]) -> None:
        if not inputs:
            return
        refs, values = [], []
        for port, value in inputs.items():
            number = float(value)
            if not math.isfinite(number):
                raise ModelError(f"{self.name}: input '{port}' received a non-finite value ({number})")
            refs.append(self._input_refs[port])
            values.append(number / self._inputs[port].scale)
        self._call("SetReal", self._slave.set_reals, refs, values)

    def _read_outputs(self, time: float) -> dict[str, Value]:
        if not self._output_refs:
            return {}
        values = self._call("GetReal", self._slave.get_reals, self._output_refs)
        outputs = {}
        for port, value, scale in zip(self._output_ports, values, self._output_scales):
            if not math.isfinite(value):
                raise ModelError(
                    f"{self.name} ({self.fmu_path.name}): output '{self._outputs[port].variable}' "
                    f"is {value} at t = {time:g} s"
                )
            outputs[port] = value * scale
        return outputs
