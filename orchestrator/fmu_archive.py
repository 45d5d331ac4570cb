"""Opening an FMU archive safely: bounded unpacked sizes, no entry outside the extraction folder.

An FMU is a zip file, and a zip entry can declare gigabytes that compress to a few
kilobytes (a "zip bomb"); an entry named ``../x`` or ``/x`` would be written outside the
folder.  Before anything is read, every entry's declared unpacked size, their total and
their number are checked against the limits below, and every name must stay inside the
archive's folder.  Python's :mod:`zipfile` never returns more than an entry declares (a
longer stream fails its CRC check), so checking the declared sizes bounds what is
written; the copy counts the bytes all the same.

Then, still before a run (``validate`` and ``run`` alike), every entry is read through once
within those limits: an entry whose data does not match its declared size or CRC (a
damaged or doctored archive) is refused, and so is a symbolic link or another special
file, which an FMU has no use for.  What the run unpacks later is thus what was checked.
"""

from __future__ import annotations

import stat
import zipfile
import zlib
from pathlib import Path, PurePosixPath

from orchestrator.errors import FmuError

#: Largest unpacked size of one entry [bytes].
MAX_ENTRY_BYTES = 512 * 1024**2
#: Largest unpacked size of all entries together [bytes].
MAX_TOTAL_BYTES = 1024**3
#: Most entries an FMU may hold.
MAX_ENTRIES = 10_000
_COPY_CHUNK = 1024**2


def _size(count: int) -> str:
    return f"{count / 1024**3:.1f} GiB" if count >= 1024**3 else f"{count / 1024**2:.0f} MiB"


def check_archive(path: Path, where: str, read: bool = True) -> list[zipfile.ZipInfo]:
    """The entries of the FMU ``path``; :class:`FmuError` naming ``where`` if it is unsafe to unpack.

    With ``read``, every entry is also read through once to check its data (see the module
    docstring); :func:`extract_fmu` checks them while it copies instead.
    """
    try:
        with zipfile.ZipFile(path) as archive:
            entries = archive.infolist()
    except (OSError, zipfile.BadZipFile) as exc:
        raise FmuError(f"{where}: {path} is not a valid FMU: {exc}") from exc
    if len(entries) > MAX_ENTRIES:
        raise FmuError(f"{where}: {path.name} holds {len(entries)} entries, more than the limit of {MAX_ENTRIES}")
    total = 0
    for entry in entries:
        name = PurePosixPath(entry.filename.replace("\\", "/"))
        if name.is_absolute() or ".." in name.parts or (name.parts and ":" in name.parts[0]):
            raise FmuError(f"{where}: {path.name}: entry '{entry.filename}' points outside the FMU's folder")
        if entry.file_size > MAX_ENTRY_BYTES:
            raise FmuError(f"{where}: {path.name}: entry '{entry.filename}' unpacks to {_size(entry.file_size)}, "
                           f"more than the limit of {_size(MAX_ENTRY_BYTES)} per file (a zip bomb?)")
        total += entry.file_size
        if total > MAX_TOTAL_BYTES:
            raise FmuError(f"{where}: {path.name} unpacks to more than {_size(MAX_TOTAL_BYTES)} in all "
                           "(a zip bomb?)")
        kind = stat.S_IFMT(entry.external_attr >> 16)  # 0 when the archiver recorded no file type
        if kind not in (0, stat.S_IFREG, stat.S_IFDIR):
            what = "a symbolic link" if kind == stat.S_IFLNK else "a special file"
            raise FmuError(f"{where}: {path.name}: entry '{entry.filename}' is {what}; an FMU may hold only "
                           "files and folders (rebuild the FMU without it)")
    if read:
        _read_through(path, entries, where)
    return entries


#: What :mod:`zipfile` raises for an entry whose data do not match its header.
_DAMAGED = (zipfile.BadZipFile, zlib.error, EOFError, NotImplementedError, RuntimeError, ValueError)


def _read_through(path: Path, entries: list[zipfile.ZipInfo], where: str) -> None:
    """Read every entry once (CRC and size checked by :mod:`zipfile`), at most what it declares."""
    entry = None
    try:
        with zipfile.ZipFile(path) as archive:
            for entry in entries:
                if entry.is_dir():
                    continue
                read = 0
                with archive.open(entry) as source:
                    while chunk := source.read(_COPY_CHUNK):
                        read += len(chunk)
                if read != entry.file_size:
                    raise zipfile.BadZipFile(f"{read} bytes where the archive declares {entry.file_size}")
    except _DAMAGED as exc:
        named = f"entry '{entry.filename}'" if entry is not None else "the archive"
        raise FmuError(f"{where}: {path.name}: {named} is damaged ({exc}); rebuild the FMU or copy it "
                       "again") from None
    except OSError as exc:
        raise FmuError(f"{where}: {path} cannot be read: {exc.strerror or exc}") from None


def extract_fmu(path: Path, target: Path, where: str) -> Path:
    """Unpack the FMU ``path`` into the folder ``target`` within the limits; returns ``target``."""
    entries = check_archive(Path(path), where, read=False)
    target = Path(target)
    written = 0
    try:
        with zipfile.ZipFile(path) as archive:
            for entry in entries:
                written = _extract_entry(archive, entry, target, written, path, where)
    except _DAMAGED as exc:  # an entry longer than it declares fails its CRC check
        raise FmuError(f"{where}: {Path(path).name} is not a valid FMU: {exc}") from exc
    return target


def _extract_entry(archive: zipfile.ZipFile, entry: zipfile.ZipInfo, target: Path, written: int, path: Path,
                   where: str) -> int:
    """Unpack one entry; returns the bytes written so far, this entry included."""
    destination = target / entry.filename.replace("\\", "/")
    if entry.is_dir():
        destination.mkdir(parents=True, exist_ok=True)
        return written
    destination.parent.mkdir(parents=True, exist_ok=True)
    with archive.open(entry) as source, open(destination, "wb") as sink:
        while chunk := source.read(_COPY_CHUNK):
            written += len(chunk)
            if written > MAX_TOTAL_BYTES:
                raise FmuError(f"{where}: {Path(path).name} unpacks to more than {_size(MAX_TOTAL_BYTES)} in all "
                               "(a zip bomb?)")
            sink.write(chunk)
    if entry.external_attr >> 16 & 0o111:
        destination.chmod(0o755)
    return written
