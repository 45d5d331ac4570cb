"""Wall-time limits on each participant call, so that no participant can block a run for ever.

Every ``setup`` and ``step`` of a participant runs under a wall-time limit
(``[simulation] step_timeout_s``, or ``step_timeout_s`` in the participant's own table;
default :data:`DEFAULT_STEP_TIMEOUT_S`).  One watchdog thread per run watches the call in
progress:

* at the limit it marks the call as timed out and interrupts it: on the main thread with
  a SIGALRM sent to that thread, whose handler raises :class:`StepTimeout` (this wakes a
  ``time.sleep`` and reaches Python code, and CasADi's solvers, which check for signals at
  every iteration); on another thread (a Dask worker) by raising :class:`StepTimeout`
  asynchronously in it, which reaches Python code at its next bytecode.  The master then
  ends the run with status ``timed out``, a reason naming the participant, and writes the
  results as for any run.  :class:`StepTimeout` derives from ``BaseException`` so that a
  participant's ``except Exception`` does not swallow it, and the master checks the flag
  after every call too, for a participant that swallows it all the same;
* native code never sees a Python exception: an FMU's ``fmi2DoStep`` that loops for ever
  runs with the interpreter lock released (ctypes releases it), so the watchdog can still
  run.  When the call has not returned ``grace_s`` after the limit, the watchdog calls the
  registered emergency writers (the run's ``summary.json`` with status ``timed out`` and the
  time series so far) and ends the process with exit code :data:`EXIT_TIMED_OUT`.  In a
  batch, the worker process ends this way and the batch keeps the run's published folder.

A native call that holds the interpreter lock and never returns stops the watchdog too;
in a batch the parent process ends such a worker when its call deadline (published by
:func:`deadline_hook`) has passed by more than the grace (see :mod:`orchestrator.worker_pool`).
"""

from __future__ import annotations

import contextlib
import ctypes
import logging
import os
import signal
import sys
import threading
import time
from collections.abc import Callable, Iterator

log = logging.getLogger(__name__)

#: Default wall-time limit of one participant call (set-up or step) [s].
DEFAULT_STEP_TIMEOUT_S = 300.0
#: Exit code of a process ended because a call never returned (a failed run, as for ``run``).
EXIT_TIMED_OUT = 3
#: Status of a run stopped at a time limit.
TIMED_OUT = "timed out"
#: How often the watchdog looks at the call in progress [s]: a call is interrupted at most
#: this long after its limit.
POLL_S = 0.05


class StepTimeout(BaseException):
    """A participant call exceeded its wall-time limit (not an ``Exception``: not swallowed by one)."""


def describe(participant: str, phase: str, time_s: float, limit_s: float) -> str:
    """The one-line reason of a timed-out run."""
    return (f"participant '{participant}' did not return from {phase} at t = {time_s:g} s "
            f"within its wall-time limit of {limit_s:g} s (step_timeout_s)")


class CallWatch:
    """The watchdog of one run: at most one participant call is watched at a time.

    Parameters
    ----------
    grace_s : float
        Time after the limit that a call has to return (after the interrupt) before the
        watchdog ends the process [s].
    emergency : callable, optional
        ``emergency(reason)`` writes what it can of the run before the process ends.
    """

    def __init__(self, grace_s: float = 2.0, emergency: Callable[[str], None] | None = None) -> None:
        self.grace_s = grace_s
        self.emergency = emergency
        self.expired: str | None = None  # the reason, once a call timed out
        self._lock = threading.Condition()
        # (generation, deadline, (participant, phase, time_s, limit_s)) of the call in progress
        self._call: tuple[int, float, tuple[str, str, float, float]] | None = None
        self._generation = 0
        self._closed = False
        self._thread_id = threading.get_ident()
        self._main = threading.current_thread() is threading.main_thread()
        self._previous_handler = None
        if self._main:
            self._previous_handler = signal.signal(signal.SIGALRM, _on_alarm)
        global _active
        _active = self
        self._watchdog = threading.Thread(target=self._watch, name="rhnc-step-watchdog", daemon=True)
        self._watchdog.start()

    # -- the master's side ----------------------------------------------------------------------
    @contextlib.contextmanager
    def call(self, participant: str, phase: str, time_s: float, limit_s: float | None) -> Iterator[None]:
        """Watch one call; raises :class:`StepTimeout` after it if it timed out (even if swallowed)."""
        self.begin(participant, phase, time_s, limit_s)
        try:
            yield
        finally:
            self.end()
        self.check()

    def begin(self, participant: str, phase: str, time_s: float, limit_s: float | None) -> None:
        """Start watching a call (no limit: nothing to watch).  What :meth:`call` does in three
        calls, for the master's loop: ``begin``; ``try: <call> finally: end()``; ``check()``."""
        if limit_s is None:
            return
        deadline = time.monotonic() + limit_s
        # No lock and no wake-up of the watchdog per call: it polls (every POLL_S at most)
        # and reads this tuple, which the master alone writes.  Waking the watchdog thread
        # at every call made it compete for the interpreter lock with every FMU call, which
        # releases it: that tripled the master's overhead per step.
        self._generation += 1
        self._call = (self._generation, deadline, (participant, phase, time_s, limit_s))
        if _deadline_sink is not None:
            _publish_deadline(deadline + self.grace_s, describe(participant, phase, time_s, limit_s))

    def end(self) -> None:
        """The watched call returned (or raised)."""
        self._call = None
        if _deadline_sink is not None:
            _publish_deadline(0.0, "")

    def check(self) -> None:
        """Raise :class:`StepTimeout` if the last call timed out (even if it swallowed the interrupt)."""
        if self.expired is not None:
            raise StepTimeout(self.expired)

    def close(self) -> None:
        """Stop the watchdog and restore the SIGALRM handler.

        After a time-out the module's handler stays installed (it does nothing once no run is
        watched): a SIGALRM sent just before the close may still be pending, and the default
        action of SIGALRM would end the process.
        """
        global _active
        with self._lock:
            self._closed = True
            self._call = None
            self._lock.notify_all()
        if _active is self:
            _active = None
        if self._main and self._previous_handler is not None and self.expired is None:
            signal.signal(signal.SIGALRM, self._previous_handler)
        self._previous_handler = None

    # -- the watchdog's side --------------------------------------------------------------------

    def _watch(self) -> None:
        with self._lock:
            while not self._closed:
                call = self._call
                if call is None:
                    self._lock.wait(POLL_S)
                    continue
                generation, deadline, what = call
                remaining = deadline - time.monotonic()
                if remaining > 0:
                    self._lock.wait(min(remaining, POLL_S))
                    continue
                # the call is over its limit: interrupt it, then give it grace_s to return
                reason = describe(*what)
                self.expired = reason
                log.warning("%s: interrupting it", reason)
                self._interrupt()
                end = time.monotonic() + self.grace_s
                while self._is_watching(generation) and time.monotonic() < end:
                    self._lock.wait(min(end - time.monotonic(), POLL_S))
                if self._is_watching(generation) and not self._closed:
                    self._end_process(reason)
                return

    def _is_watching(self, generation: int) -> bool:
        call = self._call
        return call is not None and call[0] == generation

    def _interrupt(self) -> None:
        from orchestrator import interrupts

        if self._main:
            if not interrupts.stop_requested():  # after Ctrl-C SIGALRM is the interrupt's last resort
                signal.pthread_kill(self._thread_id, signal.SIGALRM)
        else:
            ctypes.pythonapi.PyThreadState_SetAsyncExc(ctypes.c_ulong(self._thread_id), ctypes.py_object(StepTimeout))

    def _end_process(self, reason: str) -> None:
        why = f"{reason}; the call did not return {self.grace_s:g} s after it was interrupted " \
              "(native code), so the process was ended"
        if self.emergency is not None:
            try:
                self.emergency(why)
            except Exception as exc:  # best effort: the process ends either way
                print(f"could not write the timed-out run's status: {exc}", file=sys.stderr, flush=True)
        print(f"error: {why}", file=sys.stderr, flush=True)
        sys.stdout.flush()
        os._exit(EXIT_TIMED_OUT)


_active: CallWatch | None = None


def _on_alarm(_number, _frame) -> None:
    watch = _active
    if watch is not None and watch.expired is not None and watch._call is not None:
        raise StepTimeout(watch.expired)


# -- where a batch worker publishes its call deadline ------------------------------------------------
_deadline_sink: Callable[[float, str], None] | None = None


def deadline_hook(sink: Callable[[float, str], None] | None) -> None:
    """Register ``sink(deadline, reason)``: called with the ``time.monotonic()`` by which the call
    in progress must have returned (limit plus grace) and the reason to give if it does not, and
    with ``(0.0, "")`` when no call is in progress."""
    global _deadline_sink
    _deadline_sink = sink


def _publish_deadline(deadline: float, reason: str) -> None:
    if _deadline_sink is not None:
        _deadline_sink(deadline, reason)
