"""Folders a run leaves behind when its process dies, and their removal by a later run.

A run writes into folders that it removes or publishes when it ends: its staging folder
(``.<run-id>.<pid>-<token>.partial``, :mod:`orchestrator.results`), its work folder
(``rhnc-run-<pid>-*``) and the unpacked FMUs (``rhnc-fmu-<pid>-*``) in the temporary
folder.  A process that is killed (SIGKILL, a crash in native code, ``os._exit``) removes
nothing.  So each such folder holds a lock file, ``.owner.lock``, locked (``flock``) by the
process that made it for as long as it lives; the operating system frees the lock when the
process dies, however it dies.  A later run removes the folders whose lock it can take, and
never a folder whose lock is held: that of a run still going, in this process or another,
under any process id namespace that shares the file.

A folder without a lock file (made before this scheme, or caught in the instant between
its creation and its lock) is removed only when the process its name names is gone and
nothing in it changed for :data:`UNLOCKED_GRACE_S`.
"""

from __future__ import annotations

import logging
import os
import secrets
import shutil
import tempfile
import time
from collections.abc import Iterable
from pathlib import Path
from typing import Any

log = logging.getLogger(__name__)

#: The lock file in each folder a run owns.
LOCK_NAME = ".owner.lock"
#: Name prefixes of a run's folders in the temporary folder (followed by ``<pid>-``).
TEMP_PREFIXES = ("rhnc-run-", "rhnc-fmu-")
#: Age [s] below which a folder without a lock file is never removed.
UNLOCKED_GRACE_S = 60.0

fcntl: Any
try:
    import fcntl
except ImportError:  # not POSIX: no lock files, folders are judged by their process id only
    fcntl = None


class OwnerLock:
    """The lock on ``<folder>/.owner.lock`` this process holds while the folder is in use."""

    def __init__(self, folder: Path) -> None:
        self.folder = Path(folder)
        self._handle = None
        if fcntl is None:
            return
        # lock a file under a name of its own, then rename it into place: a lock file that
        # exists is always locked by its owner, never caught unlocked by another run
        pending = self.folder / f".owner-{secrets.token_hex(4)}.lock"
        try:
            handle = open(pending, "w")
        except OSError:
            return  # the folder's own creation will fail or has failed: nothing to hold
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
            handle.write(f"{os.getpid()}\n")
            handle.flush()
            os.replace(pending, self.folder / LOCK_NAME)
        except OSError:  # a file system without locks: the folder is judged by its process id
            handle.close()
            pending.unlink(missing_ok=True)
            return
        self._handle = handle

    def release(self, remove_file: bool = True) -> None:
        """Let the folder go (before it is published, with ``remove_file``, or after it was removed)."""
        if self._handle is None:
            return
        if remove_file:
            (self.folder / LOCK_NAME).unlink(missing_ok=True)
        self._handle.close()
        self._handle = None


def owned_temp_folder(prefix: str) -> tuple[Path, OwnerLock]:
    """A new folder ``<prefix><pid>-*`` in the temporary folder, locked by this process."""
    folder = Path(tempfile.mkdtemp(prefix=f"{prefix}{os.getpid()}-"))
    return folder, OwnerLock(folder)


def abandoned(folder: Path, pid: int | None) -> bool:
    """The process that owned ``folder`` has ended (``pid``: the one its name holds, if any)."""
    lock_path = Path(folder) / LOCK_NAME
    if fcntl is not None:
        try:
            handle = open(lock_path, "r+")
        except FileNotFoundError:
            handle = None
        except OSError:
            return False  # cannot tell: keep it
        if handle is not None:
            with handle:
                try:
                    fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
                except OSError:
                    return False  # held: its run is going on
                fcntl.flock(handle, fcntl.LOCK_UN)
                return True
    if pid is None or process_alive(pid):
        return False
    try:
        age = time.time() - Path(folder).stat().st_mtime
    except OSError:
        return False
    return age > UNLOCKED_GRACE_S


def process_alive(pid: int) -> bool:
    """The process ``pid`` exists and has not ended (a zombie has: nobody reaped it yet)."""
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True  # another user's process
    return not _is_zombie(pid)


def _is_zombie(pid: int) -> bool:
    """The process has ended but nobody has reaped it (a container whose first process does
    not reap orphans keeps a killed worker so): it will never write again."""
    import psutil

    try:
        return psutil.Process(pid).status() == psutil.STATUS_ZOMBIE
    except psutil.ZombieProcess:
        return True
    except psutil.Error:
        return False  # gone meanwhile, or not to be read: the signal check above is all there is


def _pid_after(name: str, prefix: str) -> int | None:
    text = name[len(prefix):].split("-", 1)[0]
    return int(text) if text.isdigit() else None


def _staging_pid(name: str) -> int | None:
    """The process id in ``.<run-id>.<pid>-<token>.partial``."""
    middle = name[:-len(".partial")].rsplit(".", 1)[-1]
    text = middle.split("-", 1)[0]
    return int(text) if text.isdigit() else None


def _remove(candidates: Iterable[tuple[Path, int | None]]) -> list[Path]:
    removed = []
    for folder, pid in candidates:
        if folder.is_dir() and not folder.is_symlink() and abandoned(folder, pid):
            shutil.rmtree(folder, ignore_errors=True)
            removed.append(folder)
    if removed:
        log.info("removed %d folders left by runs whose process ended: %s", len(removed),
                 ", ".join(str(p) for p in removed))
    return removed


def remove_abandoned_temp_folders(folder: Path | None = None) -> list[Path]:
    """Remove the work folders and unpacked FMUs of dead runs from the temporary folder."""
    folder = Path(folder or tempfile.gettempdir())
    try:
        entries = [entry for entry in folder.iterdir() if entry.name.startswith(TEMP_PREFIXES)]
    except OSError:
        return []
    return _remove((entry, _pid_after(entry.name, next(p for p in TEMP_PREFIXES if entry.name.startswith(p))))
                   for entry in entries)


def remove_abandoned_staging(results_root: Path) -> list[Path]:
    """Remove the staging folders of dead runs under ``results_root`` (its groups and batches' runs)."""
    root = Path(results_root)
    try:
        found = [*root.glob("*/.*.partial"), *root.glob("*/runs/.*.partial")] if root.is_dir() else []
    except OSError:  # an unreadable results folder: writing into it will say so
        return []
    return _remove((path, _staging_pid(path.name)) for path in found)
