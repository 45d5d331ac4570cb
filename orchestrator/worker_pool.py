"""The batch's local worker processes: each runs one run at a time, dies with the batch.

Unlike a generic process pool, the batch knows which run each worker is doing, so

* a worker that dies is charged with its own run only (the others go on), with how it died:
  killed from outside (SIGKILL, SIGTERM: the out-of-memory killer, an operator) is an
  infrastructure failure that a resume redoes; a crash of its own (SIGSEGV in an FMU, an
  exit code) is the run's failure and is kept;
* a worker whose participant call has passed its time limit by more than the grace
  (native code that holds the interpreter lock, where the run's own watchdog cannot run;
  see :mod:`orchestrator.time_limits`) is ended by the batch and its run recorded as
  ``timed out``;
* every worker dies with the batch process: on Linux the kernel sends it SIGKILL when its
  parent dies (``prctl(PR_SET_PDEATHSIG)``), elsewhere a thread watches the parent's pid.
  A batch killed with SIGKILL therefore leaves no worker behind that could still write
  into the results folder of the next batch.
"""

from __future__ import annotations

import contextlib
import logging
import multiprocessing
import multiprocessing.connection
import os
import signal
import time
from collections import deque
from collections.abc import Callable, Iterator
from typing import Any

from orchestrator.child_processes import die_with_parent

log = logging.getLogger(__name__)

#: Seconds between the parent's checks of its workers' deadlines.
POLL_S = 0.25
#: Extra seconds the parent waits past a worker's published deadline before ending it.
DEADLINE_MARGIN_S = 5.0
#: Signals that mean "killed from outside": the run itself did nothing wrong.
INFRASTRUCTURE_SIGNALS = (signal.SIGKILL, signal.SIGTERM, signal.SIGINT, signal.SIGHUP)


def _worker_main(connection, deadline, reason, parent_pid: int, execute: Callable[[Any], dict]) -> None:
    """A worker's life: receive a task, run it, send its record; ``None`` ends it."""
    die_with_parent(parent_pid)
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # idle: Ctrl-C is the batch's (a running run gets it)
    from orchestrator import time_limits

    def publish(value: float, why: str = "") -> None:
        deadline.value = value
        reason.value = why.encode()[:500]

    time_limits.deadline_hook(publish)
    while True:
        try:
            task = connection.recv()
        except (EOFError, OSError):
            return
        if task is None:
            return
        record = execute(task)
        publish(0.0)
        try:
            connection.send(record)
        except (BrokenPipeError, OSError):
            return


class _Worker:
    def __init__(self, context, execute: Callable[[Any], dict]) -> None:
        self.connection, child = context.Pipe()
        self.deadline = context.Value("d", 0.0, lock=False)
        self.reason = context.Array("c", 512, lock=False)
        self.process = context.Process(target=_worker_main, name="rhnc-batch-worker", daemon=True,
                                       args=(child, self.deadline, self.reason, os.getpid(), execute))
        self.process.start()
        child.close()
        self.task = None

    def kill(self) -> None:
        with contextlib.suppress(OSError):
            self.process.kill()
        self.process.join(5.0)


def describe_death(exitcode: int | None) -> tuple[str, bool]:
    """How a worker died and whether that is an infrastructure failure (a resume redoes it)."""
    if exitcode is not None and exitcode < 0:
        number = -exitcode
        name = signal.Signals(number).name if number in signal.Signals._value2member_map_ else str(number)
        return f"killed by {name}", number in INFRASTRUCTURE_SIGNALS
    return f"exit code {exitcode}", False


class WorkerPool:
    """``workers`` spawned processes running ``execute(task)`` one task at a time.

    Parameters
    ----------
    workers : int
        Number of processes.
    execute : callable
        Module-level function ``execute(task) -> record`` (a dict with at least ``status``).
    """

    def __init__(self, workers: int, execute: Callable[[Any], dict]) -> None:
        self.workers = max(1, int(workers))
        self.execute = execute

    def run(self, tasks: list) -> Iterator[tuple[Any, dict]]:
        """Yield ``(task, record)`` as runs end; closing the generator lets running runs end.

        A worker that died yields ``{"status": "worker_died", "reason": ..., "infrastructure": bool}``;
        one ended at its deadline ``{"status": "timed out", "reason": ...}``.
        """
        from orchestrator import interrupts

        if not tasks:
            return
        context = multiprocessing.get_context("spawn")
        queue = deque(tasks)
        pool = [_Worker(context, self.execute) for _ in range(min(self.workers, len(tasks)))]
        try:
            while queue or any(w.task is not None for w in pool):
                for index, worker in enumerate(pool):
                    if worker.task is None and queue and not interrupts.stop_requested():
                        if not worker.process.is_alive():  # died or ended by the batch: a fresh one
                            worker.connection.close()
                            pool[index] = worker = _Worker(context, self.execute)
                        worker.task = queue.popleft()
                        worker.connection.send(worker.task)
                if interrupts.stop_requested():
                    queue.clear()  # never start another run after Ctrl-C
                busy = [w for w in pool if w.task is not None]
                if not busy:
                    break
                ready = multiprocessing.connection.wait(
                    [w.connection for w in busy] + [w.process.sentinel for w in busy], timeout=POLL_S)
                for worker in busy:
                    record = self._collect(worker, ready)
                    if record is not None:
                        task, worker.task = worker.task, None
                        yield task, record
        finally:
            self._stop(pool)

    def _collect(self, worker: _Worker, ready) -> dict | None:
        """The record of ``worker``'s run if it ended (or died, or passed its deadline)."""
        if worker.connection in ready or worker.connection.poll():
            try:
                return worker.connection.recv()
            except (EOFError, OSError):
                pass  # died while sending: below
        if worker.process.sentinel in ready or not worker.process.is_alive():
            worker.process.join(1.0)
            how, infrastructure = describe_death(worker.process.exitcode)
            from orchestrator.batch_run import WORKER_DIED

            return {"status": "worker_died", "reason": f"{WORKER_DIED}: {how}", "infrastructure": infrastructure}
        deadline = worker.deadline.value
        if deadline and time.monotonic() > deadline + DEADLINE_MARGIN_S:
            why = worker.reason.value.decode(errors="replace") or "a participant call passed its time limit"
            log.warning("ending worker %d: %s", worker.process.pid, why)
            worker.kill()
            return {"status": "timed out", "infrastructure": False,
                    "reason": f"{why}; the call held the interpreter lock, so the batch ended its worker"}
        return None

    @staticmethod
    def _stop(pool: list[_Worker]) -> None:
        """Let running runs end (as interrupted after Ctrl-C: SIGTERM to the batch is passed on), then stop."""
        from orchestrator import interrupts

        if interrupts.stop_requested():
            interrupts.acknowledge()
        if interrupts.stop_requested() == "SIGTERM":  # sent to this process alone: pass it on
            for worker in pool:
                if worker.task is not None:
                    with contextlib.suppress(OSError):
                        os.kill(worker.process.pid, signal.SIGINT)
        for worker in pool:  # each ends after its current run (which publishes its folder)
            with contextlib.suppress(OSError, ValueError):
                worker.connection.send(None)
        for worker in pool:
            worker.process.join(None if worker.task is not None else 10.0)
            if worker.process.is_alive():
                worker.kill()
            worker.connection.close()
