"""Time limits for CasADi NLP solves: the solver runs in a forked worker that can be killed.

fatrop has an iteration limit but no clock, and CasADi's iteration callback is not called
by its interface; on a state outside the model's range (NaN in the dynamics) it was seen
to loop inside one iteration for more than 11 minutes, where no iteration limit can stop
it.  A thread cannot be stopped from outside either.  So the solver runs in a child
process, forked from the controller after the problem is built (the child inherits the
compiled solvers, nothing is rebuilt or pickled): each solve sends the numeric arguments
through a pipe and waits for the answer under two limits,

* ``cpu_time_s``: the processor time the worker spends on this solve (read with
  psutil), so that the verdict does not depend on how many other
  processes share the machine: on a loaded machine a solve of a few hundred ms of CPU
  can take seconds of wall time, and a wall-clock limit would then cut normal solves;
* ``wall_time_s``: a hard cap on the wall time, for a worker that gets no CPU at all
  and for a process whose times cannot be read.

When a limit is hit, the child is killed, the call reports ``wall_time_exceeded`` and
the next call forks a fresh worker.  The processor-time limit is also kept to the
millisecond: the worker arms a profiling timer (``ITIMER_PROF``, the process's own processor
time) when it starts the solver call, ``TIMER_MARGIN_S`` short of the limit (the kernel counts it
by its clock tick: a 100 ms timer was seen to end a process after 85-103 ms), and the
timer's signal ends it wherever the solve is, native code included; the parent's check
every ``POLL_S`` (the worker's user time since the call started, read from the parent) is
then only the backstop, ``POLL_GRACE_S`` past the limit.  The processor
time of a call the timer ended is the worker's user time at its end less its user time when it
started the call (written to memory shared with the parent); its system time is left out, as
it counts the unmapping of the worker's memory at its end (10-90 ms, measured), not the solve.

Iteration caps: a call may ask for an iteration cap (``solve(..., iteration_cap=n)``); the
worker then serves it with a solver object built by ``factories[name](n)`` (kept, and
renewed, with that cap while the calls ask for it); an object built for a new cap is built
before the timer is armed, and its processor time is reported apart (``build_cpu_s``), not
as the solve's.  The controller derives the cap from
the processor time per iteration it has measured (:mod:`rhnc.control.solve_pace`), so
that a long solve stops at its cap, at a point it can still use, before the timer ends it
with nothing.  The pipe adds some 0.1-0.3 ms per solve.  Where
``os.fork`` does not exist (Windows), or with both limits None, solves run in this
process under the iteration limit only.

Fresh solvers (``renew``): after a call whose outcome ``renew(outcome)`` marks, the next
call of that name gets a new solver object from its factory.  fatrop's solver object keeps
part of its last solve's state (the iterate's data are not reset between calls): started
from the next, shifted guess, it then needed more iterations and sometimes failed where a
new object of the same problem solved (the measurements are in
``docs/nmpc-performance.md``).  The worker builds the replacement right after it has sent
its answer, while the controller applies the plan and the plant moves on, so that the
solve itself does not wait for it; its processor time is reported apart
(``SolveOutcome.preparation_cpu_s``).
"""

from __future__ import annotations

import dataclasses
import logging
import math
import multiprocessing
import os
import signal
import time
import weakref
from collections.abc import Callable, Mapping

import casadi as ca
import numpy as np
import psutil

from orchestrator.child_processes import die_with_parent

LOG = logging.getLogger(__name__)

#: status reported when a solve was stopped at its time limit
WALL_TIME_STATUS = "wall_time_exceeded"
#: how often the parent checks the worker's processor time [s]
POLL_S = 0.02
#: the worker's timer is armed this much short of the processor-time limit [s]: the kernel
#: counts processor-time timers by its clock tick (seen ending a call 12 ms past the time armed)
TIMER_MARGIN_S = 0.02
#: the parent's own check stops a worker only this much past the limit [s], so that the
#: worker's timer acts first: the parent reads the worker's time through /proc in 10 ms ticks,
#: from before the worker has taken the request (it may still be building a renewed solver)
POLL_GRACE_S = 0.05


@dataclasses.dataclass
class SolveOutcome:
    """What one bounded solve returned.

    Attributes
    ----------
    x, g : numpy.ndarray
        Primal solution and constraint values (NaN when stopped).
    f : float
        Objective.
    success : bool
        The solver reported success.
    iterations : int
        Solver iterations (-1 when unknown).
    status : str
        Solver's return status, or ``WALL_TIME_STATUS``.
    wall_time_s : float
        Wall time of the call [s], pipe included.
    timed_out : bool
        Stopped at a time limit.
    stopped_by : str
        Which limit stopped it: ``"cpu"``, ``"wall"`` or ``""``.
    cpu_time_s : float
        Processor time of the solver call [s] (in the process that ran it; in the worker,
        with the unpacking of the request and the building of the answer).
    lam_x, lam_g : numpy.ndarray
        Multipliers of the bounds and of the constraints at ``x`` (NaN when stopped): the
        next solve's dual warm start.
    preparation_cpu_s : float
        Processor time [s] spent outside the solve on building a fresh solver object
        (``renew``): in the worker the one this call used, built after the previous answer;
        in this process the one built after this call for the next.
    acceptable : bool
        The solver stopped at a point that meets its relaxed ("acceptable") tolerances
        rather than its tolerance (fatrop's return flag, IPOPT's status); ``success`` is
        then False, and the caller judges the point.
    iteration_cap : int or None
        The iteration cap the call asked for and its solver object had (None: the solver's
        own iteration limit).
    build_cpu_s : float
        Processor time [s] of a solver object built for this call, while the caller waited (a
        new iteration cap): outside the call's processor-time limit and ``cpu_time_s``.
    """

    x: np.ndarray
    g: np.ndarray
    f: float
    success: bool
    iterations: int
    status: str
    wall_time_s: float
    timed_out: bool = False
    stopped_by: str = ""
    cpu_time_s: float = float("nan")
    lam_x: np.ndarray | None = None
    lam_g: np.ndarray | None = None
    preparation_cpu_s: float = 0.0
    acceptable: bool = False
    iteration_cap: int | None = None
    build_cpu_s: float = 0.0


#: fatrop's return flag (``stats()["fatrop"]["return_flag"]``) for a stop at an acceptable point
FATROP_ACCEPTABLE_FLAG = 2


def _outcome(solver: ca.Function, result: Mapping, elapsed: float, cpu: float) -> SolveOutcome:
    stats = solver.stats()
    success = bool(stats.get("success", False))
    acceptable = not success and (
        stats.get("return_status") == "Solved_To_Acceptable_Level"
        or stats.get("fatrop", {}).get("return_flag") == FATROP_ACCEPTABLE_FLAG)
    return SolveOutcome(
        x=np.array(result["x"]).ravel(), g=np.array(result["g"]).ravel(), f=float(result["f"]),
        success=success, iterations=int(stats.get("iter_count", -1)), acceptable=acceptable,
        status=str(stats.get("return_status", "unknown")), wall_time_s=elapsed, cpu_time_s=cpu,
        lam_x=np.array(result["lam_x"]).ravel() if "lam_x" in result else None,
        lam_g=np.array(result["lam_g"]).ravel() if "lam_g" in result else None,
    )


class BufferedCall:
    """Calls of one nlpsol solver through CasADi's argument buffers: numpy arrays in and out.

    A call with keyword arguments converts each of the eight inputs to a CasADi matrix and
    each of the six outputs back (0.7-0.8 ms of a 2-3 ms solve of the NMPC's NLP, measured
    on a loaded machine); here the inputs are copied into arrays the solver reads in
    place and it writes its outputs into arrays, the same numbers to the bit.  An input not
    given takes the solver's default, as in a keyword call.  ``stats()`` are those of the
    last buffered call.
    """

    def __init__(self, solver: ca.Function) -> None:
        self._inputs = [(solver.name_in(i), solver.default_in(i), np.zeros(solver.numel_in(i)))
                        for i in range(solver.n_in())]
        self._outputs = {solver.name_out(i): np.zeros(solver.numel_out(i)) for i in range(solver.n_out())}
        self._buffer, self._evaluate = solver.buffer()
        for i, (_, _, array) in enumerate(self._inputs):
            self._buffer.set_arg(i, array.data)  # type: ignore[call-arg]
        for i, array in enumerate(self._outputs.values()):
            self._buffer.set_res(i, array.data)  # type: ignore[call-arg]

    @classmethod
    def of(cls, solver: ca.Function) -> "BufferedCall":
        """The buffered calls of ``solver`` (made at its first call, kept with it)."""
        call = getattr(solver, "_rhnc_buffered_call", None)
        if call is None:
            call = cls(solver)
            solver._rhnc_buffered_call = call
        return call

    def __call__(self, arguments: Mapping[str, np.ndarray]) -> dict[str, np.ndarray | float]:
        """Solve; the outputs are the buffers themselves (valid until the next call), ``f`` a float."""
        for name, default, array in self._inputs:
            value = arguments.get(name)
            array[:] = default if value is None else value
        self._evaluate()
        result: dict[str, np.ndarray | float] = dict(self._outputs)
        result["f"] = float(self._outputs["f"][0])
        return result

    def stats(self) -> dict:
        return self._buffer.stats()


def _timed_call(solver, arguments) -> SolveOutcome:
    start, cpu_start = time.perf_counter(), time.process_time()
    if isinstance(solver, ca.Function):
        solver = BufferedCall.of(solver)
        result = solver(arguments)
    else:  # any callable of nlpsol's keywords (the tests' stand-ins)
        result = solver(**arguments)
    return _outcome(solver, result, time.perf_counter() - start, time.process_time() - cpu_start)


def _serve(connection, solvers: dict[str, ca.Function], factories: Mapping[str, Callable[..., ca.Function]],
           renew: Callable[[SolveOutcome], bool] | None, cpu_time_s: float | None = None,
           started=None) -> None:
    """Child's loop: receive (solver name, arguments, iteration cap, processor-time limit),
    solve, send the outcome; replace the solver just used, once the answer is sent, when
    ``renew`` says so.

    ``cpu_time_s``: the profiling timer ends this process when a call has used that much
    processor time, or the request's own limit when it has one (module docstring);
    ``started``: a shared ``multiprocessing`` value that gets this process's user processor
    time as each solver call starts."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the parent's to handle
    signal.signal(signal.SIGPROF, signal.SIG_DFL)  # the timer's signal ends the process
    preparation = dict.fromkeys(solvers, 0.0)
    caps: dict[str, int | None] = dict.fromkeys(solvers)  # the iteration cap of each object
    while True:
        cpu_start = time.process_time()  # waiting for a request costs no processor time
        try:
            name, arguments, cap, limit = connection.recv()
        except (EOFError, OSError):
            return
        limit = cpu_time_s if limit is None else limit
        try:
            # a new cap's object is built before the timer is armed: its building (about 3 ms
            # compiled, 0.5-1 s interpreted) is not the solve's, and ended by the timer it
            # failed the step (a calm solve after an ended one, interpreted, on a loaded machine)
            built_s = _object_for_cap(solvers, caps, factories, name, cap)
            if started is not None:
                started.value = os.times().user
            if limit is not None:
                signal.setitimer(signal.ITIMER_PROF, max(limit - TIMER_MARGIN_S, limit / 2))
            outcome = _timed_call(solvers[name], arguments)
        except Exception as error:  # noqa: BLE001 - a solver refusing its call: raised by the controller
            signal.setitimer(signal.ITIMER_PROF, 0.0)
            if not _send(connection, SolverError(f"{type(error).__name__}: {' '.join(str(error).split())}")):
                return
            continue
        signal.setitimer(signal.ITIMER_PROF, 0.0)
        # the worker's share of the call: unpacking the request, solving, building the answer
        outcome.cpu_time_s = time.process_time() - cpu_start - built_s
        outcome.preparation_cpu_s = preparation.get(name, 0.0)
        outcome.iteration_cap, outcome.build_cpu_s = cap, built_s
        if not _send(connection, outcome):
            return
        preparation[name] = 0.0
        if renew is not None and renew(outcome):  # the controller is not waiting now
            start = time.process_time()
            solvers[name] = _build(factories[name], cap)
            preparation[name] = time.process_time() - start


def _build(factory: Callable[..., ca.Function], cap: int | None) -> ca.Function:
    """A new solver object from its factory, with the iteration cap when there is one."""
    return factory() if cap is None else factory(cap)


def _object_for_cap(solvers: dict, caps: dict, factories: Mapping[str, Callable[..., ca.Function]], name: str,
                    cap: int | None) -> float:
    """Make ``solvers[name]`` an object built with iteration cap ``cap`` (the one there is kept
    while the calls ask for its cap); returns the processor time [s] the building took (0: kept)."""
    if name in solvers and caps.get(name) == cap:
        return 0.0
    start = time.process_time()
    solvers[name], caps[name] = _build(factories[name], cap), cap
    return time.process_time() - start


def _send(connection, message) -> bool:
    try:
        connection.send(message)
    except (BrokenPipeError, OSError):
        return False
    return True


class SolverError(RuntimeError):
    """A solver call that raised in the worker (an option the installed CasADi does not
    know, a function that cannot be evaluated): raised again in the controller's process,
    with its message, as the call would raise without a worker."""


def _kill(pid: int) -> None:
    try:
        os.kill(pid, signal.SIGKILL)
        os.waitpid(pid, 0)
    except (ProcessLookupError, ChildProcessError):
        pass


class BoundedSolver:
    """Named CasADi solvers called with a wall-time limit.

    Parameters
    ----------
    solvers : mapping of str to casadi.Function
        Solvers built already (a forked worker inherits them).
    factories : mapping of str to callable
        Builds the other solvers by name on first use (in the worker when there is one).
    wall_time_s : float or None
        Hard wall-time limit per call [s]; None with ``cpu_time_s`` None: no limits, solve
        in this process.
    cpu_time_s : float or None
        Limit of the worker's processor time per call [s] (Linux; ignored elsewhere).
    renew : callable, optional
        ``renew(outcome) -> bool``: after a call with this outcome, that solver name gets a
        new object from its factory (module docstring); ``factories`` must then build every
        name.  None: each object serves every call of its name.
    """

    def __init__(self, solvers: Mapping[str, ca.Function], factories: Mapping[str, Callable[[], ca.Function]],
                 wall_time_s: float | None, cpu_time_s: float | None = None,
                 renew: Callable[[SolveOutcome], bool] | None = None) -> None:
        missing = sorted(set(solvers) - set(factories)) if renew is not None else []
        if missing:
            raise ValueError(f"renewed solvers need a factory for every solver; none for {', '.join(missing)}")
        self.factories = dict(factories)
        self.wall_time_s = wall_time_s
        self.cpu_time_s = cpu_time_s
        self.renew = renew
        self._solvers: dict[str, ca.Function] = dict(solvers)
        self._caps: dict[str, int | None] = dict.fromkeys(solvers)  # the iteration cap of each object
        self._pid: int | None = None
        self._process: psutil.Process | int | None = None  # the worker, whose processor time is read
        self._connection = None
        self._finalizer = None
        self._request_cpu = None  # shared with the worker (_ensure_worker)
        self.timeouts = 0
        if (wall_time_s is not None or cpu_time_s is not None) and not hasattr(os, "fork"):
            LOG.warning("no os.fork on this platform: NMPC solves are limited by iterations only")
            self.wall_time_s = self.cpu_time_s = None

    def start(self) -> None:
        """Fork the worker now (when solves run in one), so that the first solve does not pay for it."""
        if self.in_worker:
            self._ensure_worker()

    @property
    def in_worker(self) -> bool:
        """Solves run in the forked worker (False: in this process)."""
        return self.wall_time_s is not None or self.cpu_time_s is not None

    def solve(self, name: str, *, iteration_cap: int | None = None, cpu_time_s: float | None = None,
              **arguments) -> SolveOutcome:
        """Call solver ``name`` with nlpsol arguments (x0, p, lbx, ubx, lbg, ubg, optionally lam_x0, lam_g0);
        ``iteration_cap``: served by an object built with that cap (module docstring);
        ``cpu_time_s``: this call's processor-time limit, below the solver's own (None: that one)."""
        if not self.in_worker:
            built_s = _object_for_cap(self._solvers, self._caps, self.factories, name, iteration_cap)
            outcome = _timed_call(self._solvers[name], arguments)
            outcome.iteration_cap, outcome.build_cpu_s = iteration_cap, built_s
            if self.renew is not None and self.renew(outcome):  # here the replacement is part of the step
                start = time.process_time()
                self._solvers[name] = _build(self.factories[name], iteration_cap)
                outcome.preparation_cpu_s = time.process_time() - start
            return outcome
        arguments = {key: np.asarray(value, dtype=float) for key, value in arguments.items()}
        start = time.perf_counter()
        self._ensure_worker()
        limit = self.cpu_time_s if cpu_time_s is None or self.cpu_time_s is None else min(cpu_time_s, self.cpu_time_s)
        if self._request_cpu is not None:  # the worker writes its time here as the solver call starts
            self._request_cpu.value = math.nan
        self._connection.send((name, arguments, iteration_cap, limit))
        wall_limit = math.inf if self.wall_time_s is None else self.wall_time_s
        while not self._connection.poll(min(POLL_S, wall_limit)):
            elapsed = time.perf_counter() - start
            cpu = self._call_cpu_s() if limit is not None else None
            over_cpu = cpu is not None and cpu > limit + POLL_GRACE_S
            if elapsed > wall_limit or over_cpu:
                LOG.warning("NMPC solve stopped at its time limit (%.3g s wall, %s s CPU)", elapsed,
                            "?" if cpu is None else f"{cpu:.3g}")
                self.close()
                return self._stopped_at_limit(arguments, elapsed, "cpu" if over_cpu else "wall",
                                              cpu if cpu is not None else float("nan"), iteration_cap)
        try:
            outcome = self._connection.recv()
        except EOFError:  # the worker's timer ended it, or it died (out of memory, a crash in the solver)
            signalled, cpu = self._reap()
            elapsed = time.perf_counter() - start
            request_cpu = self._request_cpu.value if self._request_cpu is not None else None
            self.close()
            if signalled == signal.SIGPROF:
                LOG.warning("NMPC solve stopped at its processor-time limit (%.3g s)", limit)
                return self._stopped_at_limit(arguments, elapsed, "cpu",
                                              cpu - request_cpu if cpu is not None and request_cpu is not None
                                              else float(limit or "nan"), iteration_cap)
            LOG.warning("NMPC solver worker died; starting a new one")
            return self._stopped(arguments, elapsed, "solver_worker_died")
        if isinstance(outcome, SolverError):
            raise outcome
        outcome.wall_time_s = time.perf_counter() - start
        return outcome

    def _call_cpu_s(self) -> float | None:
        """Processor time [s] the worker's solver call has used so far: its user time since the
        call started (None before it has started: the worker is unpacking the request or building
        a solver object for a new cap; or when it cannot be read)."""
        started = self._request_cpu.value if self._request_cpu is not None else math.nan
        if not math.isfinite(started):
            return None
        try:
            process = self._process if isinstance(self._process, psutil.Process) else psutil.Process(self._process)
            return process.cpu_times().user - started
        except (psutil.Error, TypeError, ValueError):
            return None

    @staticmethod
    def _stopped(arguments, elapsed: float, status: str) -> SolveOutcome:
        n = len(np.atleast_1d(arguments.get("x0", [])))
        ng = len(np.atleast_1d(arguments.get("lbg", [])))
        return SolveOutcome(np.full(n, np.nan), np.full(ng, np.nan), float("nan"), False, -1, status, elapsed,
                            timed_out=status == WALL_TIME_STATUS, lam_x=np.full(n, np.nan), lam_g=np.full(ng, np.nan))

    def _stopped_at_limit(self, arguments, elapsed: float, stopped_by: str, cpu_time_s: float,
                          iteration_cap: int | None) -> SolveOutcome:
        """A call a time limit stopped (``stopped_by``: ``"cpu"`` or ``"wall"``), counted."""
        self.timeouts += 1
        stopped = self._stopped(arguments, elapsed, WALL_TIME_STATUS)
        stopped.stopped_by, stopped.cpu_time_s, stopped.iteration_cap = stopped_by, cpu_time_s, iteration_cap
        return stopped

    def _reap(self) -> tuple[int | None, float | None]:
        """Wait for the ended worker: the signal that ended it (None: it exited) and its whole
        user processor time [s] (None when it cannot be read): its system time also counts the
        unmapping of its memory as it ends (10-90 ms, measured), which is not the solve's."""
        if self._pid is None:
            return None, None
        try:
            _, status, usage = os.wait4(self._pid, 0)
        except (ChildProcessError, OSError):
            return None, None
        if self._finalizer is not None:  # reaped: its number may be another process's from now on
            self._finalizer.detach()
            self._finalizer = None
        signalled = os.WTERMSIG(status) if os.WIFSIGNALED(status) else None
        return signalled, usage.ru_utime

    def _ensure_worker(self) -> None:
        if self._pid is not None:
            return
        parent_end, child_end = multiprocessing.Pipe()
        # the worker's user processor time when its latest solver call started (for a call its timer ends)
        self._request_cpu = multiprocessing.RawValue("d", math.nan)
        parent = os.getpid()
        pid = os.fork()
        if pid == 0:  # child
            parent_end.close()
            # ends with the controller's process (even by SIGKILL): a solve looping in native
            # code must not outlive it
            die_with_parent(parent)
            try:
                _serve(child_end, dict(self._solvers), self.factories, self.renew, self.cpu_time_s,
                       self._request_cpu)
            finally:
                os._exit(0)
        child_end.close()
        self._pid, self._connection = pid, parent_end
        try:
            self._process = psutil.Process(pid)
        except psutil.Error:  # read by its number at every solve then (None when it cannot be)
            self._process = pid
        self._finalizer = weakref.finalize(self, _kill, pid)

    def close(self) -> None:
        """Stop the worker (a new one starts on the next solve)."""
        if self._finalizer is not None:
            self._finalizer()
            self._finalizer = None
        if self._connection is not None:
            self._connection.close()
        self._pid, self._process, self._connection = None, None, None
