"""Errors a user can act on; the CLI prints them as one line and exits non-zero."""

import errno

#: OS error numbers that mean the disk (or the user's quota) is full.
DISK_FULL_ERRNOS = (errno.ENOSPC, errno.EDQUOT)


class ToolchainError(Exception):
    """Base class of every error the CLI reports as one clear line."""

    exit_code = 1


class ScenarioError(ToolchainError, ValueError):
    """A scenario file (or batch file) is malformed: names the file and the key."""

    exit_code = 2


class FmuError(ToolchainError):
    """An FMU is missing, invalid, or lacks a mapped variable."""

    exit_code = 2


class ModelError(ToolchainError):
    """A participant produced a non-finite value or refused a step during a run."""

    exit_code = 3


class SolverError(ToolchainError):
    """An optimisation problem could not be solved and no fallback applies."""

    exit_code = 3


class ResultsError(ToolchainError):
    """The results cannot be written (read-only folder, disk full): nothing half-written is left."""

    exit_code = 4


def is_disk_full(exc: BaseException) -> bool:
    """True for an ``OSError`` saying that the disk or the quota is full."""
    return isinstance(exc, OSError) and exc.errno in DISK_FULL_ERRNOS
