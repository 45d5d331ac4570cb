"""One interface to an FMI 2.0 or FMI 3.0 co-simulation FMU, over FMPy's ``FMU2Slave``/``FMU3Slave``.

The FMU participant steps either standard through the same calls; what differs (the
set-up sequence, the name of the real type and of each C function in messages, the logger
callback) stays here.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Sequence
from ctypes import byref
from typing import Any

log = logging.getLogger(__name__)

#: FMPy's type name of a 64-bit real variable, per FMI version.
REAL_TYPES = ("Real", "Float64")
#: FMI versions this module can step.
SUPPORTED_VERSIONS = ("2.0", "3.0")

#: The highest status of a call that succeeded (fmi2Warning, fmi3Warning): FMPy raises above it.
_WARNING = 1

#: Message callback: (status, category, message), status 0 OK .. 4 Fatal.
MessageSink = Callable[[int, str, str], None]


class FmiSlave:
    """A co-simulation FMU instance of either FMI version.

    Parameters
    ----------
    model_description : fmpy.model_description.ModelDescription
        The FMU's description (its ``fmiVersion`` selects the standard).
    unzip_dir : str
        The extracted FMU.
    instance_name : str
        Name of the instance in the FMU's messages.
    sink : callable
        Receives every message the FMU logs.
    """

    def __init__(self, model_description, unzip_dir: str, instance_name: str, sink: MessageSink) -> None:
        self.version = model_description.fmiVersion
        if self.version not in SUPPORTED_VERSIONS:
            raise ValueError(f"FMI version {self.version} is not supported (valid: {', '.join(SUPPORTED_VERSIONS)})")
        self.prefix = "fmi2" if self.version == "2.0" else "fmi3"
        self._sink = sink
        self._keep_alive: Any = None  # the ctypes callbacks the FMU holds, kept from the collector
        identifier = model_description.coSimulation.modelIdentifier
        if self.version == "2.0":
            from fmpy.fmi2 import FMU2Slave

            self._fmu = FMU2Slave(guid=model_description.guid, unzipDirectory=unzip_dir,
                                  modelIdentifier=identifier, instanceName=instance_name)
        else:
            from fmpy.fmi3 import FMU3Slave

            self._fmu = FMU3Slave(guid=model_description.instantiationToken,
                                  unzipDirectory=unzip_dir, modelIdentifier=identifier,
                                  instanceName=instance_name)

    def name(self, function: str) -> str:
        """The C name of a function for messages: ``name("SetReal")`` is fmi2SetReal or fmi3SetFloat64."""
        if self.version == "3.0":
            function = {"SetReal": "SetFloat64", "GetReal": "GetFloat64", "SetInteger": "SetInt32"}.get(
                function, function)
        return self.prefix + function

    # -- lifecycle ---------------------------------------------------------------------
    def instantiate(self) -> None:
        if self.version == "2.0":
            self._fmu.instantiate(callbacks=self._fmi2_callbacks(), loggingOn=False)
        else:
            def log_message(_environment, status, category, message):
                self._sink(int(status), (category or b"").decode(), (message or b"").decode("utf-8", "replace"))

            self._keep_alive = log_message  # FMPy wraps it and keeps the ctypes callback
            self._fmu.instantiate(loggingOn=False, logMessage=log_message)

    def enter_initialization(self, start_time: float) -> None:
        """FMI 2.0: ``fmi2SetupExperiment`` then ``fmi2EnterInitializationMode``; FMI 3.0: one call."""
        if self.version == "2.0":
            self._fmu.setupExperiment(startTime=start_time)
            self._fmu.enterInitializationMode()
        else:
            self._fmu.enterInitializationMode(startTime=start_time)

    def exit_initialization(self) -> None:
        self._fmu.exitInitializationMode()

    def do_step(self, time: float, step_size: float) -> None:
        self._fmu.doStep(time, step_size)

    def terminate(self) -> None:
        self._fmu.terminate()

    def free(self) -> None:
        self._fmu.freeInstance()

    # -- values ------------------------------------------------------------------------
    def set_reals(self, refs: Sequence[int], values: Sequence[float]) -> None:
        if self.version == "2.0":
            self._fmu.setReal(list(refs), list(values))
        else:
            self._fmu.setFloat64(list(refs), list(values))

    def get_reals(self, refs: Sequence[int]) -> list[float]:
        if self.version == "2.0":
            return self._fmu.getReal(list(refs))
        return self._fmu.getFloat64(list(refs))

    def _native(self, function: str):
        """FMPy's C function ``function`` (``"fmi2GetReal"``) as FMPy loaded it (its argument
        and result types declared), called without FMPy's per-call Python layer (``_call``),
        which looks it up by name, offers it to the call logger and checks its status: the
        caller checks the status as ``_call`` does (:func:`_refuse`).  None when a call
        logger is set: then every call goes through FMPy's layer, to be logged."""
        if self._fmu.fmiCallLogger is not None:
            return None
        return getattr(self._fmu.dll, function)

    def real_reader(self, refs: Sequence[int]) -> Callable[[], list[float]]:
        """A call that reads the real variables ``refs`` (after :meth:`instantiate`): what
        :meth:`get_reals` does, through FMPy's ``fmi2GetReal``/``fmi3GetFloat64`` on arrays
        made once here instead of at every call."""
        count = len(refs)
        fmu, component = self._fmu, self._fmu.component
        if self.version == "2.0":
            from fmpy.fmi2 import fmi2Real, fmi2ValueReference

            references, values = (fmi2ValueReference * count)(*refs), (fmi2Real * count)()
            native = self._native("fmi2GetReal")
            if native is None:
                get_real = fmu.fmi2GetReal

                def read() -> list[float]:
                    get_real(component, references, count, values)
                    return values[:]
            else:
                import numpy as np

                # the same memory seen by numpy: tolist() gives the floats faster than slicing ctypes
                seen = np.frombuffer(values, dtype=np.float64)

                def read() -> list[float]:
                    status = native(component, references, count, values)
                    if status > _WARNING:
                        _refuse("fmi2GetReal", status)
                    return seen.tolist()
        else:
            from fmpy.fmi3 import fmi3Float64, fmi3ValueReference

            references, values = (fmi3ValueReference * count)(*refs), (fmi3Float64 * count)()
            get_float64 = fmu.fmi3GetFloat64

            def read() -> list[float]:
                get_float64(component, references, count, values, count)
                return values[:]
        return read

    def real_writer(self, refs: Sequence[int]) -> Callable[[Sequence[float]], None]:
        """A call that sets the real variables ``refs`` to as many values, in that order (after
        :meth:`instantiate`): :meth:`set_reals` on arrays made once."""
        count = len(refs)
        fmu, component = self._fmu, self._fmu.component
        if self.version == "2.0":
            from fmpy.fmi2 import fmi2Real, fmi2ValueReference

            references, values = (fmi2ValueReference * count)(*refs), (fmi2Real * count)()
            native = self._native("fmi2SetReal")
            if native is None:
                set_real = fmu.fmi2SetReal

                def write(numbers: Sequence[float]) -> None:
                    values[:] = numbers
                    set_real(component, references, count, values)
            else:
                def write(numbers: Sequence[float]) -> None:
                    values[:] = numbers
                    status = native(component, references, count, values)
                    if status > _WARNING:
                        _refuse("fmi2SetReal", status)
        else:
            from fmpy.fmi3 import fmi3Float64, fmi3ValueReference

            references, values = (fmi3ValueReference * count)(*refs), (fmi3Float64 * count)()
            set_float64 = fmu.fmi3SetFloat64

            def write(numbers: Sequence[float]) -> None:
                values[:] = numbers
                set_float64(component, references, count, values, count)
        return write

    def stepper(self) -> Callable[[float, float], None]:
        """:meth:`do_step` bound once (after :meth:`instantiate`)."""
        fmu, component = self._fmu, self._fmu.component
        if self.version == "2.0":
            native = self._native("fmi2DoStep")
            if native is None:
                do_step = fmu.fmi2DoStep
                return lambda time, step_size: do_step(component, time, step_size, 1)

            def step(time: float, step_size: float) -> None:
                status = native(component, time, step_size, 1)
                if status > _WARNING:
                    _refuse("fmi2DoStep", status)
            return step
        return self.do_step

    def set_integers(self, refs: Sequence[int], values: Sequence[int]) -> None:
        if self.version == "2.0":
            self._fmu.setInteger(list(refs), list(values))
        else:
            self._fmu.setInt32(list(refs), list(values))

    def set_booleans(self, refs: Sequence[int], values: Sequence[bool]) -> None:
        self._fmu.setBoolean(list(refs), list(values))

    def set_strings(self, refs: Sequence[int], values: Sequence[str]) -> None:
        self._fmu.setString(list(refs), list(values))

    # -- FMI 2.0 callbacks -------------------------------------------------------------------
    def _fmi2_callbacks(self):
        from fmpy import calloc, free
        from fmpy.fmi2 import (fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE,
                               fmi2CallbackFunctions, fmi2CallbackLoggerTYPE)

        def logger(_component, _instance, status, category, message):
            self._sink(int(status), (category or b"").decode(), message.decode("utf-8", "replace") if message else "")

        callbacks = fmi2CallbackFunctions()
        callbacks.logger = fmi2CallbackLoggerTYPE(logger)
        callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
        callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
        try:
            from fmpy.logging import addLoggerProxy

            addLoggerProxy(byref(callbacks))  # formats the FMU's printf-style messages
        except Exception:
            log.debug("fmpy logger proxy unavailable; FMU messages stay unformatted", exc_info=True)
        self._keep_alive = callbacks  # keep the ctypes objects alive
        return callbacks


def _refuse(function: str, status: int):
    """Raise what FMPy's ``_call`` raises for a call that returned ``status`` (above a warning)."""
    from fmpy.fmi1 import FMICallException

    raise FMICallException(function=function, status=status)
