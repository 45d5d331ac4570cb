"""A run's figures, each drawn in a process of its own while the other results are written.

Drawing is the slowest part of writing a run's results (matplotlib lays out and renders
every text of every axes) and the other results do not need it.  So once the time series
is written, :func:`start` forks one process per figure named in ``[outputs] figures``: each
inherits the finished co-simulation (participants, weather, the figure code imported
here before the fork) and draws its figure, while this process writes the weather, the
tables and the analyses.  :meth:`FigureDrawing.collect` then gathers each figure's files,
or why it was not drawn.

Nothing of a figure is half-written:

* a figure that meets a full disk fails the writing of the whole run (the run's writer
  discards its staging folder and reports that nothing was kept), as the time series would;

* a figure draws into a folder of its own, ``.figures-spool/<number>-<name>/`` in the
  staging folder; its files join the run's when it has returned, and the spool is removed;
* a figure that raises, or whose process dies (a crash in native code, killed), is one
  entry of ``figure_errors``; what it had written is dropped and every other result is
  written all the same;
* a figure process ignores SIGINT and SIGTERM, which the run defers while it writes its
  results (:mod:`orchestrator.interrupts`): the run decides.  When a second signal ends the
  run at once, the kernel ends the figure processes with it (``PR_SET_PDEATHSIG``) and the
  emergency writer removes the spool before it publishes the folder.

Off Linux, or when the run is not on the process's main thread (a Dask worker's thread: a
fork takes no other thread along, and their locks could be held), the figures are drawn
here, one after the other, through the same spool.
"""

from __future__ import annotations

import errno
import logging
import os
import pickle
import shutil
import signal
import sys
import threading
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from orchestrator import analyses
from orchestrator.child_processes import die_with_parent
from orchestrator.errors import is_disk_full
from orchestrator.recorder import ColumnFrame

log = logging.getLogger(__name__)

#: Folder in the staging folder where figures are drawn before they join the results.
FIGURE_SPOOL = ".figures-spool"
#: Draw in forked processes on Linux (tests switch it off to compare).  Elsewhere a fork
#: is either missing (Windows) or unsafe once system libraries have started threads (macOS).
FORK = sys.platform.startswith("linux") and hasattr(os, "fork")
_STOP_SIGNALS = {signal.SIGINT, signal.SIGTERM}


@dataclass
class _Figure:
    """One figure being drawn: in process ``pid`` (reporting on ``reader``) or already here."""

    name: str
    folder: Path
    pid: int | None = None
    reader: int | None = None
    outcome: tuple[str, Any] | None = None  # ("drawn", [files]) or ("error", text)

    def result(self) -> tuple[str, Any]:
        """The outcome, once the figure is drawn (every figure has one after the wait)."""
        if self.outcome is None:
            raise RuntimeError(f"figure '{self.name}' has not been drawn yet")
        return self.outcome


class FigureDrawing:
    """The figures of one run, being drawn; :meth:`collect` once, :meth:`cancel` on the way out."""

    def __init__(self, out_dir: Path, figures: list[_Figure]) -> None:
        self.out_dir = Path(out_dir)
        self._figures = figures

    def collect(self) -> tuple[list[str], dict[str, str]]:
        """Wait for every figure; move the drawn ones into the results.

        Returns the file names (in the order of the scenario's figures) and, by figure name,
        why a figure was not drawn.
        """
        files: list[str] = []
        errors: dict[str, str] = {}
        for figure in self._figures:
            if figure.pid is not None:
                figure.outcome = _wait(figure)
        full = [(figure.name, figure.result()[1]) for figure in self._figures if figure.result()[0] == "disk full"]
        if full:  # a run folder without its figures must not look complete: the run's writer discards it
            shutil.rmtree(self.out_dir / FIGURE_SPOOL, ignore_errors=True)
            raise OSError(errno.ENOSPC, f"{full[0][1]} (figure '{full[0][0]}')")
        for figure in self._figures:
            kind, value = figure.result()
            if kind == "drawn":
                _move_contents(figure.folder, self.out_dir)
                files += value
            else:
                log.warning("figure '%s' not drawn: %s", figure.name, value)
                errors[figure.name] = value
        shutil.rmtree(self.out_dir / FIGURE_SPOOL, ignore_errors=True)
        return files, errors

    def cancel(self) -> None:
        """End the figure processes still drawing (the results are not being completed)."""
        for figure in self._figures:
            if figure.pid is not None:
                try:
                    os.kill(figure.pid, signal.SIGKILL)
                except ProcessLookupError:
                    pass
                figure.outcome = _wait(figure)
        shutil.rmtree(self.out_dir / FIGURE_SPOOL, ignore_errors=True)


def start(names, frame, scenario, cosim, out_dir) -> FigureDrawing:
    """Start drawing the figures ``names`` of a finished run into ``out_dir`` (the staging folder).

    Each figure function is imported here first (an import error is that figure's error),
    so that the processes forked next share the import of the drawing library.  A run calls
    this with what it built frozen for the garbage collector (:mod:`orchestrator.run`), so
    that the children's collections leave the inherited objects, and their memory pages,
    alone.
    """
    out_dir = Path(out_dir)
    fork = FORK and threading.current_thread() is threading.main_thread()
    figures: list[_Figure] = []
    try:
        for number, name in enumerate(names):  # a scenario may name a figure twice
            figure = _Figure(name, out_dir / FIGURE_SPOOL / f"{number}-{name}")
            figures.append(figure)
            figure.folder.mkdir(parents=True)
            try:
                function = analyses.figure_function(name)
            except Exception as exc:  # a figure that cannot be imported must not lose the results
                figure.outcome = ("error", f"{type(exc).__name__}: {exc}")
                continue
            drawing = (function, frame, scenario, cosim, figure.folder)
            if fork:
                figure.pid, figure.reader = _fork(drawing)
            else:
                figure.outcome = _draw(*drawing)
    except BaseException:
        FigureDrawing(out_dir, figures).cancel()
        raise
    return FigureDrawing(out_dir, figures)


def _draw(function, frame, scenario, cosim, folder: Path) -> tuple[str, Any]:
    """Draw one figure into ``folder``: ("drawn", file names), ("error", what went wrong) or
    ("disk full", the error's text)."""
    try:
        return "drawn", list(function(frame, scenario, cosim, folder))
    except Exception as exc:  # a figure that cannot be drawn must not lose the results
        if isinstance(exc, OSError) and is_disk_full(exc):  # not the figure's fault: the results as a whole cannot be written
            return "disk full", exc.strerror or str(exc)
        log.debug("figure raised", exc_info=True)
        return "error", f"{type(exc).__name__}: {exc}"


def _fork(drawing: tuple) -> tuple[int, int]:
    """:func:`_draw` ``(*drawing)`` in a forked process; returns its pid and the pipe its outcome comes on."""
    reader, writer = os.pipe()
    parent = os.getpid()
    for stream in (sys.stdout, sys.stderr):  # the child must not write this process's buffered text again
        stream.flush()
    signal.pthread_sigmask(signal.SIG_BLOCK, _STOP_SIGNALS)  # no handler of this process may run in the child
    try:
        pid = os.fork()
    except BaseException:
        os.close(reader)
        os.close(writer)
        raise
    finally:
        if os.getpid() == parent:
            signal.pthread_sigmask(signal.SIG_UNBLOCK, _STOP_SIGNALS)
    if pid == 0:  # the figure's process: never returns
        try:
            os.close(reader)
            for number in _STOP_SIGNALS:
                signal.signal(number, signal.SIG_IGN)
            signal.pthread_sigmask(signal.SIG_UNBLOCK, _STOP_SIGNALS)
            die_with_parent(parent)
            function, frame, *rest = drawing
            if isinstance(frame, ColumnFrame):  # a file handle of its own
                frame = ColumnFrame(frame.path)
            outcome = _draw(function, frame, *rest)
            with os.fdopen(writer, "wb") as pipe:
                pipe.write(pickle.dumps(outcome))
            sys.stdout.flush()
            sys.stderr.flush()
        finally:
            os._exit(0)
    os.close(writer)
    return pid, reader


def _wait(figure: _Figure) -> tuple[str, Any]:
    """The outcome a figure's process sent, once it has ended (its way of ending if none)."""
    if figure.pid is None or figure.reader is None:
        raise RuntimeError(f"figure '{figure.name}' is not being drawn in a process")
    chunks = []
    with os.fdopen(figure.reader, "rb") as pipe:
        while chunk := pipe.read(65536):
            chunks.append(chunk)
    _, status = os.waitpid(figure.pid, 0)
    figure.pid = figure.reader = None
    if chunks:
        try:
            return pickle.loads(b"".join(chunks))
        except Exception as exc:  # a process killed while it wrote its outcome
            return "error", f"the process drawing it sent an unreadable outcome ({type(exc).__name__})"
    if os.WIFSIGNALED(status):
        return "error", f"the process drawing it was ended by {signal.Signals(os.WTERMSIG(status)).name}"
    return "error", f"the process drawing it ended with exit code {os.waitstatus_to_exitcode(status)} and no figure"


def _move_contents(source: Path, target: Path) -> None:
    """Move every file and folder of ``source`` into ``target`` (same file system: renames)."""
    for entry in source.iterdir():
        os.replace(entry, target / entry.name)
