"""A run's results folder: written in a hidden staging folder and renamed when complete.

``results/<scenario>/<run-id>/`` holds

* ``timeseries.parquet`` (or ``.csv``): every participant output on the macro-step grid,
* ``summary.json``: scenario, hash, versions, status and reason, key figures,
* ``metocean.nc``: the met-ocean field the run used (when it has one),
* figures (``track.png`` and those of the scenario's analyses).

Nothing is half-written: a crash while writing leaves only the staging folder
``.<run-id>.<process>-<token>.partial``, never a run folder that looks complete.  Each
attempt stages in a folder of its own, so two processes writing the same run id never
write into each other's files; the first to publish keeps the id, a later one gets
``<run-id>-2`` (``-3``, ...).  The staging folder holds a lock of its process
(:mod:`orchestrator.leftovers`), so that a later run removes it if the process dies.
"""

from __future__ import annotations

import datetime as dt
import json
import logging
import os
import platform
import secrets
import shutil
from pathlib import Path
from typing import Any

from orchestrator.errors import ResultsError
from orchestrator.leftovers import OwnerLock, process_alive

log = logging.getLogger(__name__)


def new_run_id(scenario_hash: str) -> str:
    """``<UTC timestamp>-<scenario hash prefix>``, unique enough and sortable."""
    stamp = dt.datetime.now(dt.timezone.utc).strftime("%Y%m%dT%H%M%S%fZ")
    return f"{stamp}-{scenario_hash[:8]}"


def versions() -> dict[str, str]:
    """Versions of the toolchain and the libraries a result depends on."""
    import importlib.metadata as md

    found = {"python": platform.python_version()}
    for package in ("rhnc-cosim", "fmpy", "numpy", "scipy", "casadi", "pandas"):
        try:
            found[package] = md.version(package)
        except md.PackageNotFoundError:
            found[package] = "not installed"
    return found


class RunFolder:
    """Stages a run's files and publishes them atomically.

    Parameters
    ----------
    results_root : Path
        The ``results`` folder.
    scenario_name : str
        Sub-folder name.
    run_id : str
        The run's id.
    """

    def __init__(self, results_root: Path, scenario_name: str, run_id: str) -> None:
        self.final = Path(results_root) / scenario_name / run_id
        self.staging = self.final.parent / f".{run_id}.{os.getpid()}-{secrets.token_hex(4)}.partial"
        # the folders this run makes above its staging folder: removed again if it keeps nothing
        self._made = [folder for folder in (self.final.parent, self.final.parent.parent) if not folder.exists()]
        try:
            self.staging.mkdir(parents=True, exist_ok=False)
        except OSError as exc:
            raise ResultsError(f"{self.final.parent}: cannot write results here: "
                               f"{exc.strerror or exc}") from exc
        # held while this process lives: a later run removes the folder only once it is gone
        self._owner = OwnerLock(self.staging)

    def path(self, name: str) -> Path:
        """Where to write ``name`` while staging."""
        return self.staging / name

    def write_json(self, name: str, data: dict[str, Any]) -> Path:
        target = self.path(name)
        target.write_text(json.dumps(data, indent=2, sort_keys=False, default=json_default) + "\n")
        return target

    def publish(self) -> Path:
        """Rename the staging folder to the run folder; returns the final path.

        When another process published the same run id first, this one is published as
        ``<run-id>-2`` (``-3``, ...) and ``final`` is updated.
        """
        wanted = self.final
        for attempt in range(1, 1000):
            target = wanted if attempt == 1 else wanted.with_name(f"{wanted.name}-{attempt}")
            if target.exists():
                continue
            try:
                self.staging.rename(target)  # atomic; fails if another process took the name
            except OSError:
                if target.exists():
                    continue
                raise
            if attempt > 1:
                log.warning("run folder %s was published by another process: this run is in %s", wanted, target)
            self.final = target
            self._owner.folder = target  # renamed with its lock held: never a staging folder without one
            self._owner.release()
            return target
        raise OSError(f"no free run folder name next to {wanted}")

    def discard(self) -> None:
        """Remove the staging folder, and the folders made for it that nothing else has used since."""
        shutil.rmtree(self.staging, ignore_errors=True)
        self._owner.release(remove_file=False)
        for folder in self._made:
            try:
                folder.rmdir()  # only when empty: another run may be writing there by now
            except OSError:
                break


def stale_staging(parent: Path, run_id: str) -> list[Path]:
    """Staging folders of ``run_id`` under ``parent`` left by an attempt whose process has ended.

    A staging folder belongs to the attempt that made it (its name holds the process id): one
    whose process is still alive is never returned, so clearing stale folders never deletes
    the files of another attempt that is still writing.
    """
    parent = Path(parent)
    found = sorted({*parent.glob(f".{run_id}.*.partial"), *parent.glob(f".{run_id}.partial")})
    return [path for path in found if not _owner_alive(path, run_id)]


def _owner_alive(staging: Path, run_id: str) -> bool:
    """The process named in ``.<run-id>.<pid>-<token>.partial`` is still running (not this one's orphan)."""
    middle = staging.name[len(run_id) + 2:-len(".partial")]
    pid_text = middle.split("-", 1)[0]
    if not pid_text.isdigit():
        return False
    pid = int(pid_text)
    if pid == os.getpid():
        return False  # an attempt of this process that ended without publishing
    return process_alive(pid)


def json_default(value):
    """JSON for numpy numbers and arrays and paths; anything else is refused (TypeError)."""
    import numpy as np

    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, Path):
        return str(value)
    raise TypeError(f"cannot write {type(value).__name__} to JSON")
