"""The co-simulation master: builds the participants of a scenario and steps them.

Exchange order (documented in ``docs/scenario-format.md``): at every communication
point the participants due there step in declaration order (Gauss-Seidel); each sees
the latest outputs of all others. With ``[simulation] exchange = "jacobi"`` the master
hands on data as one that steps all FMUs at once (OSP's libcosim): set-ups see no other
outputs, and the outputs of a step from ``t`` reach the others at ``t + step_size``.  A participant declared with ``every = m`` steps
every m macro steps with a step of ``m * dt_s`` and holds its outputs in between.

Stop conditions (``[simulation] stop_when``) are checked as soon as the participant whose
output they read has stepped: once one holds, the participants after it in that round are
not stepped (a ship is never stepped past its arrival), and the row of that time is the
last.  With Jacobi exchange an output reaches the bus one round later, so a condition met
there ends the run before the next round.
"""

from __future__ import annotations

import contextlib
import json
import logging
import math
import operator
import time as wallclock
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from orchestrator import interrupts, leftovers, plugins, time_limits
from orchestrator.errors import ModelError, ResultsError, ScenarioError, ToolchainError
from orchestrator.participant import Participant, Value
from orchestrator.participant_build import build_participant, build_scenario_table
from orchestrator.recorder import FLOAT, Recorder
from orchestrator.results import json_default
from orchestrator.scenario import Scenario

log = logging.getLogger(__name__)


class StopConditionError(ScenarioError):
    """A ``stop_when`` condition names an output that is not one number."""


@dataclass
class RunOutcome:
    """What a run produced, finished or not."""

    status: str  # "finished", "failed" or "interrupted"
    reason: str
    steps_done: int
    wall_time_s: float
    recorder: Recorder
    participant_summaries: dict[str, dict[str, Any]] = field(default_factory=dict)
    participant_tables: dict[str, list[dict[str, Any]]] = field(default_factory=dict)


class CoSimulation:
    """The participants and connections of one scenario, ready to run.

    Parameters
    ----------
    scenario : Scenario
        A loaded scenario.
    work_dir : Path, optional
        Where derived inputs (the FMU's met-ocean grid) are written; a temporary
        folder by default.

    A scenario's domain table (``[metocean]``) is built by what is registered under its
    name in the entry-point group ``rhnc_cosim.scenario_tables``; the object is handed to
    every Python participant (``context.metocean``) and the files it writes replace their
    placeholders in FMU parameters.
    """

    def __init__(self, scenario: Scenario, work_dir: Path | None = None) -> None:
        from orchestrator.analyses import check_outputs

        check_outputs(scenario)
        self.scenario = scenario
        self._own_work_dir = work_dir is None
        self._work_lock = None
        if work_dir is None:
            leftovers.remove_abandoned_temp_folders()  # of runs whose process died
            self.work_dir, self._work_lock = leftovers.owned_temp_folder("rhnc-run-")
        else:
            self.work_dir = Path(work_dir)
        try:
            self._build_all(scenario)
        except BaseException:  # a participant that fails to build leaves no temporary folder
            self.close()
            raise

    def _build_all(self, scenario: Scenario) -> None:
        self.metocean = None
        substitutions = {}
        if scenario.metocean is not None:
            self.metocean = build_scenario_table("metocean", scenario.metocean, scenario.directory,
                                                 f"{scenario.path}: metocean")
            substitutions.update(self.metocean.write_fmu_files(self.work_dir))
        self.participants: list[Participant] = []
        self.every: dict[str, int] = {}
        self.step_timeout_s: dict[str, float] = {}
        for spec in scenario.participants:
            with _build_notes_shown():
                started = wallclock.perf_counter()
                self.participants.append(build_participant(spec, self.scenario, self.metocean, substitutions))
                took = wallclock.perf_counter() - started
                if took > SLOW_BUILD_S:
                    log.info("participant '%s' was built in %.1f s", spec.name, took)
            self.every[spec.name] = spec.every
            self.step_timeout_s[spec.name] = (scenario.simulation.step_timeout_s if spec.step_timeout_s is None
                                              else spec.step_timeout_s)
        self._check_connections()
        self._check_stop_conditions()
        by_name = {p.name: p for p in self.participants}
        for participant in self.participants:
            participant.connected({c.target_port: by_name[c.source] for c in scenario.connections
                                   if c.target == participant.name})
        # ports are fixed once a participant is built
        self._declared = {p.name: frozenset(p.output_names) for p in self.participants}

    # -- checks of the built participants ---------------------------------------------------
    def _check_connections(self) -> None:
        by_name = {p.name: p for p in self.participants}
        where = self.scenario.path
        for connection in self.scenario.connections:
            source = by_name[connection.source]
            target = by_name[connection.target]
            if connection.source_port not in source.output_names:
                raise ScenarioError(
                    f"{where}: connection '{connection}': {connection.source} has no output "
                    f"'{connection.source_port}' (outputs: {', '.join(source.output_names)})"
                )
            if connection.target_port not in target.input_names:
                raise ScenarioError(
                    f"{where}: connection '{connection}': {connection.target} has no input "
                    f"'{connection.target_port}' (inputs: {', '.join(target.input_names)})"
                )

    def _check_stop_conditions(self) -> None:
        by_name = {p.name: p for p in self.participants}
        for condition in self.scenario.simulation.stop_when:
            participant = by_name.get(condition.participant)
            if participant is None or condition.port not in participant.output_names:
                raise ScenarioError(
                    f"{self.scenario.path}: simulation.stop_when '{condition}': no output "
                    f"'{condition.port}' of a participant '{condition.participant}'")

    def _stop_conditions_met(self, bus: dict, participant: str | None = None) -> list:
        """The stop conditions (of ``participant``'s outputs, or any) that hold on the bus; an
        array where a condition needs one number is refused (:class:`StopConditionError`).

        With ``participant`` only its conditions are looked at: the master asks right after it
        published, and the other conditions' values were checked when theirs were.
        """
        conditions = self.scenario.simulation.stop_when
        if participant is not None:
            conditions = [c for c in conditions if c.participant == participant]
        self._check_stop_values(bus, conditions)
        return _met(conditions, bus)

    def _check_stop_values(self, bus: dict, conditions=None) -> None:
        """Every ``stop_when`` port (of ``conditions``, or all) seen so far holds one number (not an array)."""
        for condition in self.scenario.simulation.stop_when if conditions is None else conditions:
            value = bus.get((condition.participant, condition.port))
            if value is not None and np.ndim(value) != 0:
                raise StopConditionError(
                    f"{self.scenario.path}: simulation.stop_when '{condition}': output '{condition.port}' of "
                    f"'{condition.participant}' is an array of shape {tuple(np.shape(value))}; a stop condition "
                    "needs an output that is one number")

    def check_stop_ports(self) -> None:
        """Set the participants up as a run does, without stepping, and check the ``stop_when``
        ports of their initial outputs (what ``validate`` does); every one set up is terminated.

        Only the participants up to the last one a condition names are set up (a set-up sees
        only the outputs of those before it).  Raises :class:`StopConditionError`.
        """
        sim = self.scenario.simulation
        named = {c.participant for c in sim.stop_when}
        if not named:
            return
        last = max(i for i, p in enumerate(self.participants) if p.name in named)
        bus: dict[tuple[str, str], Value] = {}
        started = []
        try:
            for participant in self.participants[:last + 1]:
                inputs = {} if sim.exchange == "jacobi" else {
                    c.target_port: bus[(c.source, c.source_port)] for c in self.scenario.connections
                    if c.target == participant.name and (c.source, c.source_port) in bus}
                started.append(participant)
                outputs = participant.setup(sim.start_s, inputs)
                bus.update({(participant.name, port): value for port, value in outputs.items()})
            self._check_stop_values(bus)
        finally:
            for participant in started:
                try:
                    participant.terminate()
                except Exception:  # the probe's own clean-up: what it checks is already decided
                    log.debug("terminate after the set-up probe raised", exc_info=True)

    def participant(self, name: str) -> Participant:
        for participant in self.participants:
            if participant.name == name:
                return participant
        raise KeyError(name)

    # -- running -------------------------------------------------------------------------
    def run(self, progress: bool = True, on_step: Callable[[int], None] | None = None,
            spool: Path | None = None) -> RunOutcome:
        """Set up, step and terminate every participant; never raises for a model failure.

        A failure inside the run (a model error, an FMU refusing a step, a participant
        raising) ends the run with status ``failed`` and a reason naming the participant;
        Ctrl-C or SIGTERM (see :mod:`orchestrator.interrupts`) end it with status
        ``interrupted``, checked between participant steps.  What was computed until then
        stays in the recorder, which writes its rows into ``spool`` as the run goes (see
        :class:`~orchestrator.recorder.Recorder`; in memory without one).  A time series that
        cannot be written (disk full) raises :class:`~orchestrator.errors.ResultsError` after
        the participants are terminated.
        """
        sim = self.scenario.simulation
        recorder = Recorder(sim.start_s, sim.dt_s, sim.steps, spool=spool)
        results_error = refused = None
        self.recorder, self.steps_done = recorder, 0
        status, reason = "finished", ""
        started = wallclock.perf_counter()
        bar = _progress_bar(sim.steps, self.scenario.simulation.name, progress)
        watch = time_limits.CallWatch(emergency=lambda why: interrupts.write_emergency(why, time_limits.TIMED_OUT))
        loop = _Loop(self, recorder, watch)
        try:
            with interrupts.reporting_position(loop.position):
                loop.set_up()
                reason = loop.step_all(bar, on_step)
        except KeyboardInterrupt:
            status, reason = "interrupted", interrupts.reason()
        except StopConditionError as exc:
            if self.steps_done == 0:  # found at set-up: bad input, refused as before a run (nothing written)
                refused = exc
            status, reason = "failed", str(exc)
        except ResultsError as exc:  # the disk, not a participant: no run status can be written
            status, reason, results_error = "failed", str(exc), exc
        except time_limits.StepTimeout:
            status, reason = time_limits.TIMED_OUT, watch.expired or "a participant call timed out"
        except ToolchainError as exc:
            status, reason = "failed", _naming(str(exc), loop.participant)
        except SystemExit as exc:  # sys.exit() in a participant ends the run, not the process
            status, reason = "failed", _naming(f"called sys.exit({exc.code!r})", loop.participant)
        except Exception as exc:  # a participant's own bug must still leave the results
            log.debug("participant raised", exc_info=True)
            status, reason = "failed", _naming(f"{type(exc).__name__}: {exc}", loop.participant)
        finally:
            watch.close()
            interrupts.acknowledge()
            if bar is not None:
                bar.close()
        if status == "failed" and interrupts.stop_requested():
            # a library turned the interrupt into an error of its own
            status, reason = "interrupted", interrupts.reason()
        problems, stopped_in = self._terminate_all()
        if results_error is not None:
            raise results_error
        if refused is not None:
            raise refused
        summaries, tables, stopped_while = self._collect_summaries(problems)
        stopped_in = stopped_in or stopped_while
        if stopped_in and status == "finished":  # every step is done and kept: only the summaries may lack
            status, reason = "interrupted", f"{interrupts.reason()} after the last step, while {stopped_in}"
        if problems:
            log.warning("after the run: %s", "; ".join(problems))
            if status == "finished":
                status, reason = "failed", "; ".join(problems)
        return RunOutcome(status, reason, self.steps_done, wallclock.perf_counter() - started, recorder, summaries,
                          tables)

    def _terminate_all(self) -> tuple[list[str], str]:
        """Terminate every participant (also after a failure).

        Returns what went wrong, and what was being done when Ctrl-C or SIGTERM arrived ("" if
        none did): an interrupted ``terminate()`` does not keep the others from theirs.
        """
        problems, stopped_in = [], ""
        for participant in self.participants:
            try:
                participant.terminate()
            except KeyboardInterrupt:
                interrupts.acknowledge()  # handled here: the last-resort timer must not end the writing
                stopped_in = stopped_in or f"participant '{participant.name}' was terminated"
            except (Exception, SystemExit) as exc:  # the other participants are terminated all the same
                log.debug("terminate raised", exc_info=True)
                problems.append(f"{participant.name}: terminate() raised {type(exc).__name__}: {exc}")
        return problems, stopped_in

    def _collect_summaries(self, problems: list[str]) -> tuple[dict, dict, str]:
        """Every participant's summary and tables; a failing one is an ``{"error": ...}`` entry
        (appended to ``problems``).  A Ctrl-C in one of them is that one's entry and the others
        are still collected; the third value says where it arrived ("" if it did not)."""
        summaries, tables, stopped_in = {}, {}, ""
        for participant in self.participants:
            try:
                summary = participant.summary()
                json.dumps(summary, default=json_default)  # what summary.json will hold
                summaries[participant.name] = summary
                for table, rows in participant.tables().items():
                    tables[f"{participant.name}_{table}"] = rows
            except KeyboardInterrupt:
                interrupts.acknowledge()  # handled here: the last-resort timer must not end the writing
                summaries[participant.name] = {"error": f"not collected: {interrupts.reason()}"}
                stopped_in = stopped_in or f"the summary of participant '{participant.name}' was collected"
            except (Exception, SystemExit) as exc:  # a summary must not hide the run's own outcome
                text = (f"its summary cannot be written to JSON ({exc})" if isinstance(exc, TypeError)
                        else f"summary raised {type(exc).__name__}: {exc}")
                summaries[participant.name] = {"error": text}
                problems.append(f"{participant.name}: {text}")
        return summaries, tables, stopped_in

    @staticmethod
    def _check_stop() -> None:
        """End the run here when a stop was requested (even if a library swallowed the signal)."""
        if interrupts.stop_requested():
            raise KeyboardInterrupt

    def _publish(self, participant: Participant, stamp: float, outputs, bus, recorder) -> None:
        declared = self._declared[participant.name]
        checked = getattr(participant, "checks_outputs_finite", False)
        name = participant.name
        if outputs.keys() <= declared and (checked or all(map(_finite, outputs.values()))):
            if bus is not None:
                for port, value in outputs.items():
                    bus[(name, port)] = value
            recorder.add(name, stamp, outputs)
            return
        for port, value in outputs.items():  # the first output refused, in the order given
            if port not in declared:
                raise ModelError(f"{name}: returned an undeclared output '{port}'")
            if not checked and not _finite(value):
                raise ModelError(f"{name}: output '{port}' is not finite at t = {stamp:g} s")
            if bus is not None:
                bus[(name, port)] = value
        recorder.add(name, stamp, outputs)

    def remove_files(self) -> None:
        """The process is ending with a participant call that never returned: remove the temporary
        folders (the work folder, unpacked FMUs) without calling any participant."""
        for participant in getattr(self, "participants", ()):
            remove = getattr(participant, "remove_files", None)
            if remove is not None:
                remove()
        self.close()

    def close(self) -> None:
        """Remove the temporary work folder (if the master made it)."""
        if self._own_work_dir:
            import shutil

            shutil.rmtree(self.work_dir, ignore_errors=True)
            if self._work_lock is not None:
                self._work_lock.release(remove_file=False)


class _Loop:
    """One run's exchange: sets the participants up and steps them, publishing to the bus.

    What it does per call is fixed before the first step (who is due, the bus keys that drive
    each input port, the time limit, whether there are stop conditions at all), so that a
    step of the master costs a few dictionary look-ups beyond the participants' own calls.
    """

    def __init__(self, cosim: CoSimulation, recorder: Recorder, watch: time_limits.CallWatch) -> None:
        self.cosim, self.recorder, self.watch = cosim, recorder, watch
        self.sim = cosim.scenario.simulation
        self.jacobi = self.sim.exchange == "jacobi"
        self.bus: dict[tuple[str, str], Value] = {}
        # Jacobi: outputs of a step from t reach the bus at t + step_size, as an FMI master
        # that steps all FMUs at once hands them on: (release step, participant, outputs)
        self.pending: list[tuple[int, str, dict]] = []
        connections = cosim.scenario.connections
        self.steps, self.dt_s = self.sim.steps, self.sim.dt_s  # (``steps`` is computed at every call)
        # per participant: itself, its name, every, time limit, (its input port, the bus key that
        # drives it), whether its outputs describe the end of its step, whether it checks their
        # finiteness itself, whether they are always finite floats (FMUs whose ports are one
        # variable each: no type to look at), and its publications (below)
        self.plans: list[tuple[Any, ...]] = [(p, p.name, cosim.every[p.name], cosim.step_timeout_s[p.name],
                       tuple((c.target_port, (c.source, c.source_port)) for c in connections if c.target == p.name),
                       p.outputs_at_step_end, getattr(p, "checks_outputs_finite", False),
                       getattr(p, "outputs_are_floats", False) is True, {})
                      for p in cosim.participants]
        # ... the reader of its inputs from the bus (its ports, and one C call giving their values
        # in that order; None for fewer than two), and whether a stop condition names it
        stopping = {c.participant for c in self.sim.stop_when}
        self.plans = [(*plan, _input_reader(plan[4]), plan[1] in stopping) for plan in self.plans]
        # per participant: its declared outputs, whether it checks their finiteness itself
        self.publishing = {p.name: (cosim._declared[p.name], getattr(p, "checks_outputs_finite", False))
                           for p in cosim.participants}
        # the bus keys that anything reads while stepping (a connection, a stop condition): a
        # step puts only those on the bus
        self.read_keys = ({(c.source, c.source_port) for c in connections}
                          | {(c.participant, c.port) for c in self.sim.stop_when})
        self.stop_conditions = bool(self.sim.stop_when)
        self.phase, self.participant, self.time_s = "setting up", None, self.sim.start_s  # for messages

    def position(self) -> str:
        return (f"{self.phase} participant '{self.participant}' at t = {self.time_s:g} s" if self.participant
                else self.phase)

    def set_up(self) -> None:
        """Set every participant up completely: the record starts at t0."""
        start, bus, watch = self.sim.start_s, self.bus, self.watch
        for participant, name, _, limit, inbound, *_ in self.plans:
            self.participant = name
            seen = {} if self.jacobi else bus
            inputs = {port: seen[key] for port, key in inbound if key in seen}
            watch.begin(name, "set-up", start, limit)
            try:
                outputs = participant.setup(start, inputs)
            finally:
                watch.end()
            watch.check()
            self.cosim._publish(participant, start, outputs, bus, self.recorder)
        self.participant = None
        self.cosim._check_stop_values(bus)  # an array port refused before the first step (bad input)
        self.phase = "stepping"

    def step_all(self, bar, on_step: Callable[[int], None] | None) -> str:
        """Step every participant due at each communication point; the reason of an early stop, or ""."""
        sim, cosim = self.sim, self.cosim
        start_s, dt_s, step_round, advance = sim.start_s, sim.dt_s, self._round, self.recorder.advance
        reason, met = "", []
        for k in range(self.steps):
            t = start_s + k * dt_s
            self.time_s = t
            if self.pending:
                met = self._release(k)
                if met:  # Jacobi: what the last round handed on ends the run before this one
                    reason = f"stopped at t = {t:g} s: {met[0]}"
                    break
            met, skipped = step_round(k, t)
            cosim.steps_done = k + 1
            advance(t)  # every participant due at t has stepped: the row of t is final
            if bar is not None:
                bar.update(1)
            if on_step is not None:
                on_step(k)
            if self.stop_conditions:
                met = met or cosim._stop_conditions_met(self.bus)
            if met:
                reason = (f"stopped at t = {t:g} s before the step of {', '.join(skipped)}: {met[0]}"
                          if skipped else f"stopped at t = {t + sim.dt_s:g} s: {met[0]}")
                break
        self.participant = None
        cosim._check_stop()
        return reason

    def _release(self, k: int) -> list:
        """Jacobi: hand on the outputs due at step ``k``; the stop conditions they meet."""
        for _, name, outputs in [item for item in self.pending if item[0] <= k]:
            self.bus.update({(name, port): value for port, value in outputs.items()})
        self.pending = [item for item in self.pending if item[0] > k]
        return self.cosim._stop_conditions_met(self.bus)

    def _round(self, k: int, t: float) -> tuple[list, list[str]]:
        """Step the participants due at step ``k`` (time ``t``) in declaration order.

        Returns the stop conditions met (Gauss-Seidel: once one holds, the participants after
        it are not stepped) and the names of those skipped for it.
        """
        cosim, bus, recorder, watch = self.cosim, self.bus, self.recorder, self.watch
        steps, dt_s, begin, end, jacobi = self.steps, self.dt_s, watch.begin, watch.end, self.jacobi
        stop_requested = interrupts.stop_requested
        met: list = []
        skipped: list[str] = []
        for (participant, name, every, limit, inbound, at_step_end, checked, floats, publications,
             (input_ports, read_inputs), stops) in self.plans:
            if k % every:
                continue
            if met:  # Gauss-Seidel: met earlier in this round, nobody steps past it
                skipped.append(name)
                continue
            self.participant = name
            if stop_requested():  # even if a library swallowed the signal
                raise KeyboardInterrupt
            step_size = (every if k + every <= steps else steps - k) * dt_s
            if read_inputs is None:
                inputs = {port: bus[key] for port, key in inbound if key in bus} if inbound else {}
            else:
                try:  # every driving output on the bus (as from the first step on): one C call
                    inputs = dict(zip(input_ports, read_inputs(bus)))
                except KeyError:  # not yet: the ports whose outputs are there
                    inputs = {port: bus[key] for port, key in inbound if key in bus}
            begin(name, "its step", t, limit)
            try:
                outputs = participant.step(t, step_size, inputs)
            finally:
                end()
            if watch.expired is not None:  # (what watch.check() looks at)
                watch.check()
            stamp = t + step_size if at_step_end else t
            if jacobi:
                cosim._publish(participant, stamp, outputs, None, recorder)
                self.pending.append((k + every, name, outputs))
                continue
            # outputs all floats, all declared, all finite: onto the bus and into the record
            # through keys and columns resolved at their first step (what _publish does)
            ports, values = tuple(outputs), tuple(outputs.values())
            publication = publications.get(ports)
            if publication is None:
                publication = publications[ports] = self._publication(name, ports)
            if publication and (floats or set(map(type, values)) <= FLOAT) and (checked or math.isfinite(sum(values))):
                keys, read, columns = publication
                if read is None:  # every output is read
                    bus.update(zip(keys, values))
                elif read:
                    bus.update(zip(keys, [values[index] for index in read]))
                recorder.add_floats(stamp, columns, values)
            else:  # (a NaN or inf sums to one) refuses the first bad output, records any other kind
                cosim._publish(participant, stamp, outputs, bus, recorder)
            if stops:
                met = cosim._stop_conditions_met(bus, name)
        return met, skipped

    def _publication(self, name: str, ports: tuple[str, ...]) -> tuple:
        """How ``name``'s outputs ``ports`` are published: the bus keys of those read while stepping,
        their places among the outputs (None: all of them, in order), the record's columns; empty
        if one is not declared."""
        if not set(ports) <= self.publishing[name][0]:
            return ()
        read = [index for index, port in enumerate(ports) if (name, port) in self.read_keys]
        keys = tuple((name, ports[index]) for index in read)
        return (keys, None if len(read) == len(ports) else tuple(read),
                self.recorder.float_columns(name, ports))


#: A participant built more slowly than this [s] is named with its build time on stderr.
SLOW_BUILD_S = 10.0


@contextlib.contextmanager
def _build_notes_shown() -> Iterator[None]:
    """Let the toolchain's INFO lines reach the console while a participant is built.

    Building is where a participant does its once-per-machine work (the NMPC compiles its
    NLP to C on first use, a minute or more; an FMU is built from its sources on demand), and
    the packages say so at INFO, which the command line otherwise hides.  Loggers already
    showing more (``-v``) are left as they are.
    """
    raised = []
    for name in plugins.toolchain_loggers():
        logger = logging.getLogger(name)
        if logger.getEffectiveLevel() > logging.INFO:
            raised.append((logger, logger.level))
            logger.setLevel(logging.INFO)
    try:
        yield
    finally:
        for logger, level in raised:
            logger.setLevel(level)


def _met(conditions, bus, participant: str | None = None) -> list:
    """The stop conditions (of ``participant``'s outputs, or any) that hold on the bus."""
    return [c for c in conditions if (participant is None or c.participant == participant)
            and (c.participant, c.port) in bus and c.holds(float(bus[(c.participant, c.port)]))]


def _input_reader(inbound: tuple) -> tuple:
    """A participant's input ports and a call giving the values of their bus keys in that order
    (raising KeyError when one is not on the bus); ``(ports, None)`` for fewer than two ports,
    where the comprehension costs no more."""
    ports = tuple(port for port, _ in inbound)
    if len(inbound) < 2:
        return ports, None
    return ports, operator.itemgetter(*(key for _, key in inbound))


def _naming(message: str, participant: str | None) -> str:
    """``message`` prefixed with the participant that raised, unless it names it already."""
    if participant is None or message.startswith((f"{participant}:", f"{participant} (")):
        return message
    return f"{participant}: {message}"


def _finite(value) -> bool:
    if type(value) is float:
        return math.isfinite(value)
    if isinstance(value, np.ndarray):
        return bool(np.all(np.isfinite(value)))
    return math.isfinite(float(value))


def _progress_bar(total: int, name: str, enabled: bool):
    if not enabled:
        return None
    from tqdm import tqdm

    # delay: only runs longer than a couple of seconds show a bar
    return tqdm(total=total, desc=name, unit="step", delay=2.0, leave=False)
