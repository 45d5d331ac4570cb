"""The FMI slave of an exported participant (a PythonFMU template, see orchestrator/export.py).

``export`` copies this file into the FMU as ``<participant>.py`` with the class renamed to
the participant's name. It reads ``resources/participant/export.json``, offers every port
as Real variables (arrays element by element, ``port[i,j]``) with the start values the
port had in the exported scenario's first step, and the participant's FMU parameters
(for the NMPC: its loop delay), builds the participant with its scenario options when
initialisation ends, and calls its ``setup`` and ``step``.

Errors reach the master as FMI statuses with a message through its logger: an input that
is not finite, or a step the participant refuses (a reference of the wrong layout), is
``fmi2Discard`` with an error message naming the variable (and the same line on stderr,
since PythonFMU passes messages on only with logging on); a participant that cannot be
built is ``fmi2Fatal`` with the reason; an input the master never set is a warning, once.
"""

import json
import logging
import math
from pathlib import Path

import numpy as np
from pythonfmu import Fmi2Causality, Fmi2Slave, Fmi2Variability, Real
from pythonfmu.enums import Fmi2Status


def _element_names(port, shape):
    if not shape:
        return [port]
    return [f"{port}[{','.join(map(str, index))}]" for index in np.ndindex(*shape)]


class ExportedParticipant(Fmi2Slave):
    """An rhnc-cosim participant behind FMI 2.0 co-simulation."""

    author = "rhnc-cosim developers"
    license = "MIT"
    description = "rhnc-cosim participant exported by 'python -m orchestrator export'"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self._bundle = Path(self.resources) / "participant"
        self._spec = json.loads((self._bundle / "export.json").read_text())
        self._values = {}
        self._set_by_master = set()
        self._unset_reported = False
        self._participant = None
        self._input_names = [n for entry in self._spec["inputs"] for n in _element_names(entry["port"], entry["shape"])]
        self._parameters = {}
        for entry in self._spec.get("parameters", []):
            name = entry["name"]
            self._parameters[name] = float(entry["start"])
            self.register_variable(Real(
                name, causality=Fmi2Causality.parameter, variability=Fmi2Variability.fixed,
                description=entry.get("description"), start=float(entry["start"]),
                getter=lambda name=name: self._parameters[name],
                setter=lambda value, name=name: self._parameters.__setitem__(name, float(value))))
        for kind, causality in (("inputs", Fmi2Causality.input), ("outputs", Fmi2Causality.output)):
            for entry in self._spec[kind]:
                starts = entry.get("start") or [0.0] * len(_element_names(entry["port"], entry["shape"]))
                for name, start in zip(_element_names(entry["port"], entry["shape"]), starts):
                    self._values[name] = float(start)
                    self.register_variable(Real(
                        name, causality=causality, variability=Fmi2Variability.continuous,
                        description=entry.get("descriptions", {}).get(name),
                        start=float(start) if kind == "inputs" else None,
                        getter=lambda name=name: self._values[name],
                        setter=(lambda value, name=name: self._set_input(name, value))
                        if kind == "inputs" else None))

    def _set_input(self, name, value):
        self._values[name] = float(value)
        self._set_by_master.add(name)

    # -- ports -----------------------------------------------------------------------------
    def _inputs(self):
        inputs = {}
        for entry in self._spec["inputs"]:
            values = [self._values[n] for n in _element_names(entry["port"], entry["shape"])]
            inputs[entry["port"]] = (np.array(values, dtype=float).reshape(entry["shape"])
                                     if entry["shape"] else values[0])
        return inputs

    def _publish(self, outputs):
        for entry in self._spec["outputs"]:
            if entry["port"] not in outputs:
                continue
            value = np.asarray(outputs[entry["port"]], dtype=float)
            if list(value.shape) != list(entry["shape"]):
                raise ValueError(f"{self._spec['participant']}: output '{entry['port']}' has shape "
                                 f"{list(value.shape)}, the FMU was exported with {entry['shape']}")
            for name, element in zip(_element_names(entry["port"], entry["shape"]), value.ravel()):
                self._values[name] = float(element)

    def _refuse(self, message):
        """Report ``message`` through the master's logger as an error; False: PythonFMU returns
        fmi2Discard (an exception would be fmi2Fatal).  PythonFMU passes messages on only
        with logging on, so the message also goes to the process's log (stderr by default)."""
        text = f"{self._spec['participant']}: {message}"
        self.log(text, Fmi2Status.error)
        logging.getLogger("orchestrator.exported_participant").error("%s", text)
        return False

    # -- lifecycle -------------------------------------------------------------------------
    def exit_initialization_mode(self):
        try:
            self._build()
        except Exception as exc:  # a master sees the reason, not only the status
            self._refuse(f"could not be built: {type(exc).__name__}: {exc}")
            raise

    def _build(self):
        from orchestrator import plugins
        from orchestrator.participant import BuildContext
        from orchestrator.participant_build import participant_class

        metocean = None
        if self._spec["metocean"]:  # the [metocean] table's object, saved by the export
            metocean = plugins.load("scenario_tables", "metocean").from_netcdf(self._bundle / self._spec["metocean"])
        name = self._spec["participant"]
        where = f"{self._spec['scenario']} (exported): participants.{name}"
        context = BuildContext(where=where, scenario_dir=self._bundle, step_size=self._spec["step_size_s"],
                               start_time=self._spec["start_s"], stop_time=self._spec["stop_s"],
                               metocean=metocean)
        cls = participant_class(self._spec["target"], f"{where}.class")
        options = {**self._spec["options"], **self._parameters}  # the FMU's parameters are options
        self._participant = cls.from_options(name, options, context)
        self._publish(self._participant.setup(self._spec["start_s"], self._inputs()))

    def do_step(self, current_time, step_size):
        bad = [name for name in self._input_names if not math.isfinite(self._values[name])]
        if bad:
            return self._refuse(f"input{'s' if len(bad) > 1 else ''} not finite at t = {current_time:g} s: "
                                + ", ".join(f"{n} = {self._values[n]!r}" for n in bad[:5])
                                + (f" and {len(bad) - 5} more" if len(bad) > 5 else ""))
        if not self._unset_reported:
            self._unset_reported = True
            unset = [n for n in self._input_names if n not in self._set_by_master]
            if unset:
                self.log(f"{self._spec['participant']}: {len(unset)} input(s) never set by the master, their start "
                         f"values (the exported scenario's first step) are used: {', '.join(unset[:8])}"
                         + (" ..." if len(unset) > 8 else ""), Fmi2Status.warning)
        from orchestrator.errors import ToolchainError

        try:
            self._publish(self._participant.step(current_time, step_size, self._inputs()))
        except (ToolchainError, ValueError) as exc:  # the participant refuses its inputs
            return self._refuse(str(exc))
        return True

    def terminate(self):
        if self._participant is not None:
            self._participant.terminate()
