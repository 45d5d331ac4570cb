"""FMI 2.0 co-simulation FMUs as participants, through FMPy's own classes.

Ports are the FMU's input and output variables, or, where the scenario maps them,
canonical names (``x``, ``tau_u``, ...) bound to vendor variables and converted to SI
(:mod:`orchestrator.port_mapping`: scale and offset, declared units, geodetic positions,
polar vectors).  The plant's canonical names have a fixed causality, so a mapping that
binds ``tau_u`` to an FMU output is refused.
"""

from __future__ import annotations

import logging
import math
import shutil
import tomllib
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

from fmpy.fmi1 import FMICallException

from orchestrator.errors import FmuError, ModelError, ScenarioError
from orchestrator.fmu_archive import check_archive, extract_fmu
from orchestrator.leftovers import owned_temp_folder
from orchestrator.fmi_slave import REAL_TYPES, SUPPORTED_VERSIONS, FmiSlave
from orchestrator.participant import Participant, Value, is_finite_number
from orchestrator.plant_ports import PLANT_PORTS
from orchestrator.geometry import wrap_float
from orchestrator.port_mapping import ScalarBinding, bind_ports, initial_start_values
from orchestrator.scenario import ParticipantSpec

log = logging.getLogger(__name__)

#: Keys of a parameter set that describe it rather than set an FMU parameter.
SET_METADATA_KEYS = ("description", "plant_fmu", "plant_guid")

#: Canonical plant ports and the causality each must have.
CANONICAL_PLANT_PORTS = {name: port.causality for name, port in PLANT_PORTS.items()}


def _unbound(*_args: object) -> list[float]:
    """Stands for a per-step FMU call before set-up binds it (or for outputs there are none of)."""
    raise RuntimeError("an FMU participant was stepped before its set-up")


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
    return {key: value for key, value in sets[set_name].items() if key not in SET_METADATA_KEYS}


#: Range of an FMI integer (a C int, 32 bits) that a scenario may set.
INT32_RANGE = (-(2 ** 31), 2 ** 31 - 1)


def declared_range(variable) -> tuple[float, float]:
    """``[min, max]`` a variable of a modelDescription declares, on itself or on its declared type
    (-inf / +inf where nothing is declared)."""
    bounds = []
    for attribute, default in (("min", -math.inf), ("max", math.inf)):
        text = getattr(variable, attribute, None)
        if text is None and getattr(variable, "declaredType", None) is not None:
            text = getattr(variable.declaredType, attribute, None)
        try:
            bounds.append(float(text) if text is not None else default)
        except (TypeError, ValueError):
            bounds.append(default)
    return bounds[0], bounds[1]


def check_parameter_value(variable, value, where: str, fmu_name: str) -> None:
    """Refuse a parameter value of the wrong kind, not finite, or outside the range the FMU declares.

    Raises
    ------
    ScenarioError
        ``<where>: ...`` naming the FMU variable, its type and its declared range.
    """
    kind = variable.type
    if kind == "Boolean":
        if not isinstance(value, bool):
            raise ScenarioError(f"{where}: '{variable.name}' is a Boolean parameter of {fmu_name}, got {value!r}")
        return
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ScenarioError(f"{where}: '{variable.name}' is a {kind} parameter of {fmu_name}, got {value!r}")
    if not is_finite_number(value):
        raise ScenarioError(f"{where}: '{variable.name}' must be a finite number, got {value!r}")
    low, high = declared_range(variable)
    if kind in ("Integer", "Enumeration") or kind.startswith(("Int", "UInt")):
        if not isinstance(value, int):
            raise ScenarioError(f"{where}: '{variable.name}' is an {kind} parameter of {fmu_name}, got {value!r}")
        low, high = max(low, INT32_RANGE[0]), min(high, INT32_RANGE[1])
    if not low <= value <= high:
        raise ScenarioError(f"{where}: {value!r} is outside the range [{low:g}, {high:g}] that {fmu_name} declares "
                            f"for '{variable.name}'")


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
        check_archive(self.fmu_path, f"{where}.fmu")  # before any entry is read: no zip bomb, no '../'
        try:
            self.model_description = read_model_description(str(self.fmu_path))
        except Exception as exc:  # fmpy raises plain exceptions for broken archives/XML
            raise FmuError(f"{where}.fmu: {self.fmu_path} is not a valid FMU: {exc}") from exc
        if self.model_description.fmiVersion not in SUPPORTED_VERSIONS or self.model_description.coSimulation is None:
            raise FmuError(f"{where}.fmu: {self.fmu_path} is not an FMI 2.0 or 3.0 co-simulation FMU")
        self.variables = {v.name: v for v in self.model_description.modelVariables}
        self._input_bindings, self._output_bindings = bind_ports(
            spec, self.variables, self.model_description, where, self.fmu_path.name)
        self.parameters = self._parameter_values(spec, string_substitutions or {})
        self.parameters.update(initial_start_values(spec, self._output_bindings, self.variables,
                                                    self.model_description, where))
        self._input_binding = {port: b for b in self._input_bindings for port in b.ports}
        self._input_refs = {v: self.variables[v].valueReference for b in self._input_bindings for v in b.variables}
        self._canonical_inputs: dict[str, float] = {}
        self._output_variables = [v for b in self._output_bindings for v in b.variables]
        self._output_refs = [self.variables[v].valueReference for v in self._output_variables]
        # where every port is one variable (``scale * fmu + offset``), a step converts them in
        # one loop: (value reference, scale, offset) per input port, (port, scale, offset, wrap)
        # per output in the order of the value references
        self._scalar_inputs = ({port: (self._input_refs[b.variables[0]], b.scale, b.offset)
                                for b in self._input_bindings for port in b.ports}
                               if all(type(b) is ScalarBinding for b in self._input_bindings) else None)
        self._scalar_outputs = ([(b.ports[0], b.scale, b.offset, b.wrap) for b in self._output_bindings]
                                if all(type(b) is ScalarBinding for b in self._output_bindings) else None)
        #: every output a step returns is a finite Python float (each port one variable): the
        #: master publishes them without looking at their types
        self.outputs_are_floats = self._scalar_outputs is not None
        # where every output is one variable: the ports in the order of the values read, and
        # which of them are scaled (index, scale, offset) and wrapped (index)
        if self._scalar_outputs is not None:
            self._output_ports = tuple(port for port, *_ in self._scalar_outputs)
            self._scaled_outputs = tuple((index, scale, offset) for index, (_, scale, offset, _) in
                                         enumerate(self._scalar_outputs) if (scale, offset) != (1.0, 0.0))
            self._wrapped_outputs = tuple(index for index, (*_, wrap) in enumerate(self._scalar_outputs) if wrap)
        # FMPy's calls on arrays made once, bound at set-up; a writer per set of input ports given
        #: bound at set-up (:meth:`_bind_calls`): a step's doStep and the outputs' getReal
        self._do_step: Callable[[float, float], object] = _unbound
        self._read_reals: Callable[[], list[float]] = _unbound
        # (the call, whether every port is the variable unscaled)
        self._input_writers: dict[tuple[str, ...], tuple[Callable[[list[float]], None], bool]] = {}
        self._slave = None
        self._unzip_dir: str | None = None
        self._unzip_lock = None
        self._messages: list[str] = []

    # -- ports -------------------------------------------------------------------------
    @property
    def input_names(self):
        return list(self._input_binding)

    @property
    def output_names(self):
        return [port for b in self._output_bindings for port in b.ports]

    @property
    def identity(self) -> dict[str, str]:
        """The FMU's model name and GUID (what a prediction model may be declared for)."""
        return {"model_name": self.model_description.modelName, "guid": self.model_description.guid}

    def _parameter_values(self, spec: ParticipantSpec, substitutions: Mapping[str, str]) -> dict:
        values = {}
        if spec.parameter_set is not None and spec.fmu is not None:   # an FMU participant names its FMU
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
            else:
                check_parameter_value(variable, value, f"{self.where}.parameters.{name}", self.fmu_path.name)
            values[name] = value
        return values

    # -- lifecycle -----------------------------------------------------------------------
    def setup(self, start_time: float, inputs: Mapping[str, Value]) -> dict[str, Value]:
        unzip_dir, self._unzip_lock = owned_temp_folder("rhnc-fmu-")
        self._unzip_dir = str(unzip_dir)
        extract_fmu(self.fmu_path, unzip_dir, f"{self.where}.fmu")
        self._slave = FmiSlave(self.model_description, self._unzip_dir, self.name, self._on_message)
        self._slave.instantiate()
        self._bind_calls()
        self._call("EnterInitializationMode", self._slave.enter_initialization, start_time)
        for name, value in self.parameters.items():
            self._set_variable(name, value)
        self._set_inputs(inputs)
        self._call("ExitInitializationMode", self._slave.exit_initialization)
        return self._read_outputs(start_time)

    def step(self, time: float, step_size: float, inputs: Mapping[str, Value]) -> dict[str, Value]:
        if inputs:
            if self._scalar_inputs is not None:
                self._set_scalar_inputs(inputs, self._scalar_inputs)
            else:
                self._set_inputs(inputs)
        if self._messages:  # what _call does, without a call more per step
            self._messages.clear()
        try:
            self._do_step(time, step_size)
        except FMICallException as exc:
            raise self._refused("DoStep", exc) from exc
        return self._read_outputs(time + step_size)

    def _bind_calls(self) -> None:
        """The per-step FMU calls on value-reference and value arrays made once for this instance."""
        slave = self._slave
        self._do_step = slave.stepper()
        self._read_reals = slave.real_reader(self._output_refs) if self._output_refs else _unbound
        self._input_writers = {}

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
            self._unzip_lock.release(remove_file=False)
            self._unzip_dir = None

    def remove_files(self) -> None:
        """Remove the unpacked FMU without calling it (the process is ending with a call still in it)."""
        if self._unzip_dir is not None:
            shutil.rmtree(self._unzip_dir, ignore_errors=True)

    # -- helpers ---------------------------------------------------------------------------
    def _on_message(self, status: int, category: str, text: str) -> None:
        # errors are raised with this text (ModelError); warnings are only logged
        level = logging.WARNING if status in (1, 2) else logging.DEBUG
        log.log(level, "%s [%s]: %s", self.name, category, text)
        if status >= 1:
            self._messages.append(text)

    def _call(self, function: str, call, *args):
        """Call the FMU; ``function`` is the name without its ``fmi2``/``fmi3`` prefix."""
        if self._messages:
            self._messages.clear()
        try:
            return call(*args)
        except FMICallException as exc:
            raise self._refused(function, exc) from exc

    def _refused(self, function: str, exc: FMICallException) -> ModelError:
        """The error of a refused call, with the FMU's last message about it."""
        detail = self._messages[-1] if self._messages else str(exc)
        return ModelError(f"{self.name} ({self.fmu_path.name}): {self._slave.name(function)} failed: {detail}")

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
        if self._scalar_inputs is not None:
            self._set_scalar_inputs(inputs, self._scalar_inputs)
            return
        touched = []
        for port, value in inputs.items():
            self._canonical_inputs[port] = self._finite_input(port, value)
            binding = self._input_binding[port]
            if binding not in touched:
                touched.append(binding)
        refs, values = [], []
        for binding in touched:
            for variable, value in binding.to_fmu(self._canonical_inputs).items():
                refs.append(self._input_refs[variable])
                values.append(value)
        self._call("SetReal", self._slave.set_reals, refs, values)

    def _set_scalar_inputs(self, inputs: Mapping[str, Value],
                           scalar_inputs: dict[str, tuple[Any, float, float]]) -> None:
        """:meth:`_set_inputs` where every input port is one variable (``scalar_inputs``: port ->
        (value reference, scale, offset)): the same values, one loop, one call on the arrays made
        for these ports (once per set of ports given)."""
        ports = tuple(inputs)
        writer = self._input_writers.get(ports)
        if writer is None:
            writer = self._input_writers[ports] = (
                self._slave.real_writer([scalar_inputs[port][0] for port in ports]),
                all(scalar_inputs[port][1:] == (1.0, 0.0) for port in ports))
        write, plain = writer
        if plain:  # (number - 0.0) / 1.0 is the number
            values = [float(value) for value in inputs.values()]
            if math.isfinite(sum(values)):  # (a NaN or inf sums to one)
                if self._messages:  # what _call does, without a call more per step
                    self._messages.clear()
                try:
                    write(values)
                except FMICallException as exc:
                    raise self._refused("SetReal", exc) from exc
                return
        values = []
        for port, value in inputs.items():
            number = self._finite_input(port, value)
            _, scale, offset = scalar_inputs[port]
            values.append((number - offset) / scale)
        self._call("SetReal", write, values)

    def _finite_input(self, port: str, value: Value) -> float:
        """``value`` given to input ``port`` as a float, refused (naming both) when not finite."""
        number = float(value)
        if not math.isfinite(number):
            raise ModelError(f"{self.name}: input '{port}' received a non-finite value ({number})")
        return number

    def _read_outputs(self, time: float) -> dict[str, Value]:
        if not self._output_refs:
            return {}
        if self._messages:
            self._messages.clear()
        try:
            values = self._read_reals()
        except FMICallException as exc:
            raise self._refused("GetReal", exc) from exc
        if self._scalar_outputs is not None and math.isfinite(sum(values)):  # (a NaN or inf sums to one)
            # scale * value + offset, wrapped where the port is an angle: 1.0 * value + 0.0 is
            # value + 0.0 (-0.0 becomes 0.0)
            scaled = [value + 0.0 for value in values]
            for index, scale, offset in self._scaled_outputs:
                scaled[index] = scale * values[index] + offset
            for index in self._wrapped_outputs:
                scaled[index] = wrap_float(scaled[index])
            return dict(zip(self._output_ports, scaled))
        by_variable = {}
        for variable, value in zip(self._output_variables, values):
            if not math.isfinite(value):
                raise ModelError(
                    f"{self.name} ({self.fmu_path.name}): output '{variable}' is {value} at t = {time:g} s"
                )
            by_variable[variable] = value
        outputs: dict[str, Value] = {}
        for binding in self._output_bindings:
            outputs.update(binding.to_canonical(by_variable))
        return outputs
