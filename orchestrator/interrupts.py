"""Stopping a run on Ctrl-C (SIGINT) or SIGTERM within a second, wherever it is.

Python runs a signal handler only between bytecodes of the main thread, and a library
that calls back into Python while it computes (CasADi checks for signals at every solver
iteration) may catch the ``KeyboardInterrupt`` itself: the solve then reports a failure,
the NMPC applies its fallback and the run would go on.  So the command line installs
:func:`handle_signals` for the duration of a command:

* the first SIGINT or SIGTERM records a stop request (:func:`stop_requested`) and raises
  ``KeyboardInterrupt`` where the main thread is, which aborts a native solve at its next
  iteration;
* the master checks :func:`stop_requested` between participant steps, so the run stops
  even when a library swallowed the exception, and reports status ``interrupted``;
* a watchdog thread waits ``grace_s`` for the master to acknowledge the request
  (:func:`acknowledge`); when a call does not return in time it runs the registered
  emergency writers (the run's ``summary.json`` with status ``interrupted``) and ends the
  process with exit code 130;
* while results are being written (:func:`deferred`), a signal is only recorded: the
  files are completed first, then the command exits 130;
* a second signal ends the process at once (exit 130), after the emergency writers;
* last resort: a native call that holds the interpreter lock (a library building or
  solving without checking for signals) keeps both the master and the watchdog thread
  from running, so the first signal also arms a real-time timer whose SIGALRM, left at its
  default action, ends the process after ``2 * grace_s`` unless the stop was acknowledged
  (exit by SIGALRM, no status written: nothing in Python can run at that point).
"""

from __future__ import annotations

import contextlib
import logging
import os
import signal
import sys
import threading
from collections.abc import Callable, Iterator

log = logging.getLogger(__name__)

#: Exit code of an interrupted command (128 + SIGINT, what shells report for Ctrl-C).
EXIT_INTERRUPTED = 130
#: Seconds the master has to notice a stop request before the watchdog ends the process.
GRACE_S = 1.0

_SIGNALS = (signal.SIGINT, signal.SIGTERM)


class _State:
    """The process's stop request (one per process: signals are process-wide)."""

    def __init__(self) -> None:
        self.reset()

    def reset(self) -> None:
        self.signal_name: str | None = None
        self.acknowledged = threading.Event()
        self.deferring = 0
        self.installed = False
        self.grace_s = GRACE_S
        self.emergency: list[Callable[[str, str], None]] = []
        self.where: Callable[[], str] | None = None
        self.alarm_armed = False


_state = _State()


def stop_requested() -> str | None:
    """The name of the signal that asked to stop (``"SIGINT"``, ``"SIGTERM"``), or None."""
    return _state.signal_name


def reason() -> str:
    """The run's reason for an interrupted status."""
    if _state.signal_name in (None, "SIGINT"):
        return "interrupted by the user (Ctrl-C)"
    return f"interrupted by {_state.signal_name}"


def acknowledge() -> None:
    """The master has stopped: the watchdog and the last-resort timer stand down."""
    _state.acknowledged.set()
    _disarm_alarm()


def _disarm_alarm() -> None:
    if _state.alarm_armed:
        signal.setitimer(signal.ITIMER_REAL, 0.0)
        _state.alarm_armed = False


@contextlib.contextmanager
def deferred() -> Iterator[None]:
    """Within this block a signal is recorded but does not raise (results being written)."""
    _state.deferring += 1
    try:
        yield
    finally:
        _state.deferring -= 1


@contextlib.contextmanager
def emergency_writer(write: Callable[[str, str], None]) -> Iterator[None]:
    """Register ``write(reason, status)``, called by a watchdog before it ends the process.

    ``status`` is ``"interrupted"`` here, ``"timed out"`` from :mod:`orchestrator.time_limits`.
    """
    _state.emergency.append(write)
    try:
        yield
    finally:
        _state.emergency.remove(write)


@contextlib.contextmanager
def reporting_position(where: Callable[[], str]) -> Iterator[None]:
    """Register ``where()`` (e.g. "stepping participant 'ctrl' at t = 40 s") for the log line."""
    previous, _state.where = _state.where, where
    try:
        yield
    finally:
        _state.where = previous


@contextlib.contextmanager
def handle_signals(grace_s: float = GRACE_S) -> Iterator[None]:
    """Install the stop handlers for SIGINT and SIGTERM (main thread only) for this block."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    _state.reset()
    _state.installed = True
    _state.grace_s = grace_s
    previous = {number: signal.signal(number, _on_signal) for number in _SIGNALS}
    try:
        yield
    finally:
        for number, handler in previous.items():
            signal.signal(number, handler)
        _state.acknowledged.set()  # the watchdog of a handled request stands down
        _disarm_alarm()
        _state.reset()  # the request belonged to this block: later runs in this process start clean


@contextlib.contextmanager
def handled(grace_s: float = GRACE_S) -> Iterator[None]:
    """:func:`handle_signals` for a library call (a batch, a search) that its caller may already
    run under them: the command line's handlers stay as they are, a plain Python caller gets them
    for the call (without them a SIGTERM would end the process at once, and a SIGINT ignored
    by a shell's background job would be ignored)."""
    if _state.installed:
        yield
        return
    with handle_signals(grace_s):
        yield


def _on_signal(number: int, _frame) -> None:
    name = signal.Signals(number).name
    if _state.signal_name is not None:  # a second signal: stop now
        log.warning("%s again: stopping at once", name)
        _emergency_exit(f"{reason()}; stopped at once by a second {name}")
    _state.signal_name = name
    position = ""
    if _state.where is not None:
        try:
            position = f" while {_state.where()}"
        except Exception:  # the position is only for the message
            position = ""
    print(f"{name} received{position}: stopping the run", file=sys.stderr, flush=True)
    if _state.deferring:
        return  # results are being written: let them complete
    watchdog = threading.Thread(target=_watch, name="rhnc-stop-watchdog", daemon=True)
    watchdog.start()
    if hasattr(signal, "setitimer"):
        signal.signal(signal.SIGALRM, signal.SIG_DFL)
        signal.setitimer(signal.ITIMER_REAL, 2.0 * _state.grace_s)
        _state.alarm_armed = True
    raise KeyboardInterrupt


def _watch() -> None:
    if _state.acknowledged.wait(_state.grace_s):
        return
    _emergency_exit(f"{reason()}; a call did not return within {_state.grace_s:g} s of the signal, "
                    "the process was ended by the watchdog")


def write_emergency(why: str, status: str = "interrupted") -> None:
    """Call the registered emergency writers (best effort: each failure is printed)."""
    for write in list(_state.emergency):
        try:
            write(why, status)
        except Exception as exc:  # best effort: the process ends either way
            print(f"could not write the {status} run's status: {exc}", file=sys.stderr, flush=True)


def _emergency_exit(why: str) -> None:
    write_emergency(why)
    print(f"error: {why}", file=sys.stderr, flush=True)
    sys.stdout.flush()
    os._exit(EXIT_INTERRUPTED)
