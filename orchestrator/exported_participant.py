"""The FMI slave of an exported participant (a PythonFMU template, see orchestrator/export.py).

``export`` copies this file into the FMU as ``<participant>.py`` with the class renamed to
the participant's name. It reads ``resources/participant/export.json``, offers every port
as Real variables (arrays element by element, ``port[i,j]``), builds the participant with
its scenario options when initialisation ends, and calls its ``setup`` and ``step``.
"""

import json
from pathlib import Path

import numpy as np
from pythonfmu import Fmi2Causality, Fmi2Slave, Fmi2Variability, Real


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
        self._participant = None
        for kind, causality in (("inputs", Fmi2Causality.input), ("outputs", Fmi2Causality.output)):
            for entry in self._spec[kind]:
                for name in _element_names(entry["port"], entry["shape"]):
                    self._values[name] = 0.0
                    self.register_variable(Real(
                        name, causality=causality, variability=Fmi2Variability.continuous,
                        getter=lambda name=name: self._values[name],
                        setter=(lambda value, name=name: self._values.__setitem__(name, float(value)))
                        if kind == "inputs" else None))

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

    # -- lifecycle -------------------------------------------------------------------------
    def exit_initialization_mode(self):
        from orchestrator import plugins
        from orchestrator.participant_build import participant_class
        from orchestrator.participant import BuildContext

        metocean = None
        if self._spec["metocean"]:  # the [metocean] table's object, saved by the export
            metocean = plugins.load("scenario_tables", "metocean").from_netcdf(self._bundle / self._spec["metocean"])
        name = self._spec["participant"]
        where = f"{self._spec['scenario']} (exported): participants.{name}"
        context = BuildContext(where=where, scenario_dir=self._bundle, step_size=self._spec["step_size_s"],
                               start_time=self._spec["start_s"], stop_time=self._spec["stop_s"],
                               metocean=metocean)
        cls = participant_class(self._spec["target"], f"{where}.class")
        self._participant = cls.from_options(name, self._spec["options"], context)
        self._publish(self._participant.setup(self._spec["start_s"], self._inputs()))

    def do_step(self, current_time, step_size):
        self._publish(self._participant.step(current_time, step_size, self._inputs()))
        return True

    def terminate(self):
        if self._participant is not None:
            self._participant.terminate()
