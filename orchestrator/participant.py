"""The one lifecycle every co-simulation participant follows, FMU or Python.

A participant has named input and output ports.  The master

1. calls ``setup(start_time, inputs)`` once, in the scenario's participant order,
   with whatever connected inputs are already known (outputs of participants set
   up before it), and records the returned initial outputs;
2. at every communication point ``t`` at which the participant is due (every
   ``every`` macro steps), gathers its inputs from the connections and calls
   ``step(t, step_size, inputs)``, which returns the outputs;
3. calls ``terminate()`` once at the end, also after a failure.

Timing of outputs: a *sampled* participant (``outputs_at_step_end = False``, the
default for Python participants: navigation, control, traffic, scripts) returns
outputs that are decided at ``t`` and held over ``[t, t + step_size)``.  A
*dynamic* participant (``outputs_at_step_end = True``: FMUs) returns its outputs at
``t + step_size``.  The recorder labels each output with that time.

Port values are floats or numpy arrays (vectors or matrices of floats); FMU ports
are floats only.  Participants never call each other: everything they exchange
goes through the master's connections.
"""

from __future__ import annotations

import abc
from collections.abc import Mapping, Sequence
from typing import Any, Union

import numpy as np

from orchestrator.errors import ModelError
from orchestrator.toml_input import checked, is_finite_number  # noqa: F401 (part of the participant interface)

Value = Union[float, np.ndarray]


class Participant(abc.ABC):
    """Base class of every co-simulation participant.

    Parameters
    ----------
    name : str
        The participant's name in the scenario (``ship``, ``nav``, ...).
    """

    #: True for participants whose outputs describe the end of the step (FMUs).
    outputs_at_step_end: bool = False

    def __init__(self, name: str) -> None:
        self.name = name

    @property
    @abc.abstractmethod
    def input_names(self) -> Sequence[str]:
        """Names of the input ports."""

    @property
    @abc.abstractmethod
    def output_names(self) -> Sequence[str]:
        """Names of the output ports."""

    @abc.abstractmethod
    def setup(self, start_time: float, inputs: Mapping[str, Value]) -> dict[str, Value]:
        """Prepare for a run starting at ``start_time`` [s]; return the initial outputs.

        ``inputs`` holds only the connected inputs already known at set-up.
        """

    @abc.abstractmethod
    def step(self, time: float, step_size: float, inputs: Mapping[str, Value]) -> dict[str, Value]:
        """Advance from ``time`` to ``time + step_size`` [s] with ``inputs``; return outputs."""

    def terminate(self) -> None:
        """Release resources; called once, also after a failed run."""

    def require_inputs(self, inputs: Mapping[str, Value], names: Sequence[str] | None = None) -> None:
        """Raise :class:`~orchestrator.errors.ModelError` naming every one of ``names`` (default: all
        input ports) that ``inputs`` lacks: a port the participant cannot step without."""
        missing = [port for port in (self.input_names if names is None else names) if port not in inputs]
        if missing:
            ports = ", ".join(f"'{port}'" for port in missing)
            raise ModelError(f"participant '{self.name}': input{'s' if len(missing) > 1 else ''} {ports} "
                             f"must be connected")

    def connected(self, sources: Mapping[str, "Participant"]) -> None:
        """Told once, after every connection is checked, which participant drives each input.

        ``sources`` maps this participant's connected input ports to the participants
        whose outputs feed them.  Only for checks (e.g. whether a controller's model was made
        for the plant it steers); participants still exchange values only through ports.
        """

    def summary(self) -> dict[str, Any]:
        """Key figures for ``summary.json`` (JSON-serialisable), gathered after the run."""
        return {}

    def tables(self) -> dict[str, list[dict[str, Any]]]:
        """Event logs for the results folder: each written as ``<participant>_<name>.csv``."""
        return {}

    def summary_from_outputs(self, outputs: Mapping[str, np.ndarray]) -> dict[str, Any]:
        """The figures of :meth:`summary` that its recorded outputs determine, from them alone.

        ``outputs`` maps output ports to their samples at this participant's steps (arrays
        flattened to ``port[i,j]`` keys).  Used to judge a run made by another FMI master
        (``python -m orchestrator check``), where only the recorded outputs are known.
        """
        return {}

    def fmu_parameters(self) -> dict[str, dict[str, Any]]:
        """Options an exported FMU offers as FMI parameters: name -> ``start`` (its value here),
        ``unit``, ``description``.  The FMU passes their values as options when it builds
        the participant.  None by default."""
        return {}

    def port_info(self, port: str) -> dict[str, Any]:
        """What a port means, for an exported FMU's description: ``unit`` (SI, "" for none),
        ``description``, and for array ports ``columns`` (the meaning of each column, or of
        each element of a vector).  Empty when the participant says nothing."""
        return {}


def reject_unknown_options(options: Mapping[str, Any], allowed: Sequence[str], where: str) -> None:
    """Raise ``ScenarioError`` naming the first option key not in ``allowed``.

    ``where`` names the place in the scenario, e.g. ``"scenario.toml: participants.nav"``.
    """
    from orchestrator.errors import ScenarioError

    for key in options:
        if key not in allowed:
            raise ScenarioError(
                f"{where}: unknown option '{key}' (valid: {', '.join(sorted(allowed))})"
            )


def check_options(model, options: Mapping[str, Any], where: str):
    """``options`` validated by ``model``, a pydantic model (usually derived from
    :class:`orchestrator.toml_input.TomlTable`: unknown keys forbidden, strict types).

    The way a participant type (built-in or a user's own) declares its options: one model
    in place of hand-written checks, and every problem one :class:`ScenarioError` line
    ``<scenario file>: 'participants.<name>.options.<key>' ...``.

    Parameters
    ----------
    model : type
        The options model.
    options : mapping
        ``[participants.<name>.options]``.
    where : str
        ``BuildContext.where`` (``"<scenario file>: participants.<name>"``).
    """
    file, _, table = where.rpartition(": ")
    prefix = tuple(table.split(".")) + ("options",) if file else ("options",)
    return checked(model, dict(options), file or where, prefix)


class BuildContext:
    """What a participant factory may know about the scenario it is built for.

    Attributes
    ----------
    where : str
        Prefix for error messages: ``"<scenario file>: participants.<name>"``.
    scenario_dir : pathlib.Path
        Folder of the scenario file; relative paths in options resolve against it.
    step_size : float
        This participant's communication step [s] (``every`` times the macro step).
    start_time, stop_time : float
        Simulation interval [s].
    metocean : object or None
        What the package registered for the scenario's ``[metocean]`` table built from it
        (``rhnc_cosim.scenario_tables``): the one met-ocean source, the same data the
        environment FMU reads.
    output_delay_s : float
        How long after its step from ``t`` this participant's outputs reach the others [s]:
        0 in the master's Gauss-Seidel order, its own step in Jacobi order (as in an FMI
        master that steps every FMU at once).  A controller compensates its loop by it.
    input_ages_s : dict
        Per connected input port, how old its value is when this participant steps at ``t``
        [s]: in Jacobi order the step of a sampled source (its outputs describe the start
        of its step and arrive at its end), 0 from an FMU (its outputs describe the end of
        its step); 0 in Gauss-Seidel order.
    """

    def __init__(self, where, scenario_dir, step_size, start_time, stop_time, metocean=None, output_delay_s=0.0,
                 input_ages_s=None):
        self.where = where
        self.output_delay_s = output_delay_s
        self.input_ages_s = dict(input_ages_s or {})
        self.scenario_dir = scenario_dir
        self.step_size = step_size
        self.start_time = start_time
        self.stop_time = stop_time
        self.metocean = metocean
