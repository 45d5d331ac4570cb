"""FMU archives are unpacked within limits: a zip bomb or an entry outside the folder is one line."""

import shutil
import stat
import zipfile
from pathlib import Path

import pytest

from orchestrator import fmu_archive, fmu_build
from orchestrator.cli import main
from orchestrator.errors import FmuError

REPO = Path(__file__).resolve().parents[2]


@pytest.fixture
def kcs_copy(tmp_path):
    target = tmp_path / "KCS_copy.fmu"
    shutil.copyfile(fmu_build.ensure_built("KCS"), target)
    return target


def scenario_with(tmp_path, fmu: Path) -> Path:
    text = (REPO / "scenarios" / "turning_circle.toml").read_text()
    text = text.replace('fmu = "KCS"', f'fmu = "{fmu}"').replace('parameter_set = "default"\n', "")
    path = tmp_path / "turning.toml"
    path.write_text(text)
    return path


def add_entries(fmu: Path, entries: dict[str, int]) -> None:
    with zipfile.ZipFile(fmu, "a", zipfile.ZIP_DEFLATED) as archive:
        for name, size in entries.items():
            archive.writestr(name, b"\0" * size)  # zeros: megabytes that compress to kilobytes


def test_an_entry_larger_than_the_limit_is_refused_before_the_run(tmp_path, kcs_copy, monkeypatch, capsys):
    monkeypatch.setattr(fmu_archive, "MAX_ENTRY_BYTES", 1024**2)
    add_entries(kcs_copy, {"resources/bomb.bin": 2 * 1024**2})
    assert kcs_copy.stat().st_size < 200_000  # small on disk
    path = scenario_with(tmp_path, kcs_copy)
    assert main(["run", str(path), "--results", str(tmp_path / "results"), "--no-progress"]) == 2
    assert capsys.readouterr().err.strip().splitlines() == [
        f"error: {path}: participants.ship.fmu: KCS_copy.fmu: entry 'resources/bomb.bin' unpacks to 2 MiB, "
        "more than the limit of 1 MiB per file (a zip bomb?)"]
    assert not (tmp_path / "results").exists()


def test_entries_larger_than_the_total_limit_are_refused(tmp_path, kcs_copy, monkeypatch):
    monkeypatch.setattr(fmu_archive, "MAX_TOTAL_BYTES", 3 * 1024**2)
    add_entries(kcs_copy, {f"resources/part{i}.bin": 1024**2 for i in range(4)})
    with pytest.raises(FmuError, match=r"KCS_copy.fmu unpacks to more than 3 MiB in all \(a zip bomb\?\)"):
        fmu_archive.check_archive(kcs_copy, "s.toml: participants.ship.fmu")


@pytest.mark.parametrize("name", ["../escape.txt", "/etc/escape.txt", "resources/../../escape.txt"])
def test_an_entry_outside_the_folder_is_refused(tmp_path, kcs_copy, name):
    add_entries(kcs_copy, {name: 10})
    with pytest.raises(FmuError, match=f"entry '{name}' points outside the FMU's folder"):
        fmu_archive.extract_fmu(kcs_copy, tmp_path / "unpacked", "s.toml: participants.ship.fmu")
    assert not (tmp_path / "escape.txt").exists()


def test_an_fmu_within_the_limits_unpacks_whole(tmp_path, kcs_copy):
    target = fmu_archive.extract_fmu(kcs_copy, tmp_path / "unpacked", "here")
    with zipfile.ZipFile(kcs_copy) as archive:
        names = [e.filename for e in archive.infolist() if not e.is_dir()]
        sizes = {e.filename: e.file_size for e in archive.infolist()}
    assert all((target / name).stat().st_size == sizes[name] for name in names)


def add_symlink(fmu: Path, name: str, target: str) -> None:
    info = zipfile.ZipInfo(name)
    info.create_system = 3  # Unix: the mode in the upper bits of external_attr
    info.external_attr = (stat.S_IFLNK | 0o777) << 16
    with zipfile.ZipFile(fmu, "a") as archive:
        archive.writestr(info, target)


def damage_entry(fmu: Path, name: str) -> None:
    """Flip one byte of a stored entry's data: its CRC no longer matches."""
    with zipfile.ZipFile(fmu, "a", zipfile.ZIP_STORED) as archive:
        archive.writestr(name, b"model data " * 100)
    with zipfile.ZipFile(fmu) as archive:
        entry = archive.getinfo(name)
    data = bytearray(fmu.read_bytes())
    start = entry.header_offset + 30 + len(entry.filename.encode()) + len(entry.extra)
    data[start + 5] ^= 0xFF
    fmu.write_bytes(bytes(data))


def understate_size(fmu: Path, name: str) -> None:
    """Declare an entry smaller than its data in the central directory (its size lies)."""
    with zipfile.ZipFile(fmu, "a", zipfile.ZIP_DEFLATED) as archive:
        archive.writestr(name, b"x" * 5000)
    data = bytearray(fmu.read_bytes())
    record = data.rindex(b"PK\x01\x02", 0, data.rindex(name.encode()))
    data[record + 24:record + 28] = (10).to_bytes(4, "little")  # uncompressed size
    fmu.write_bytes(bytes(data))


@pytest.mark.parametrize("command", ["validate", "run"])
@pytest.mark.parametrize("damage, message", [
    (lambda fmu: add_symlink(fmu, "resources/passwd", "/etc/passwd"),
     "entry 'resources/passwd' is a symbolic link; an FMU may hold only files and folders (rebuild the FMU "
     "without it)"),
    (lambda fmu: damage_entry(fmu, "resources/data.bin"),
     "entry 'resources/data.bin' is damaged (Bad CRC-32 for file 'resources/data.bin'); rebuild the FMU or "
     "copy it again"),
    (lambda fmu: understate_size(fmu, "resources/liar.bin"),
     "entry 'resources/liar.bin' is damaged (Bad CRC-32 for file 'resources/liar.bin'); rebuild the FMU or "
     "copy it again"),
], ids=["symlink", "bad-crc", "size-lies"])
def test_a_damaged_or_doctored_archive_is_bad_input_for_validate_and_run(tmp_path, kcs_copy, capsys, command,
                                                                          damage, message):
    damage(kcs_copy)
    path = scenario_with(tmp_path, kcs_copy)
    extra = ["--results", str(tmp_path / "results"), "--no-progress"] if command == "run" else []
    assert main([command, str(path), *extra]) == 2
    assert capsys.readouterr().err.strip().splitlines() == [
        f"error: {path}: participants.ship.fmu: KCS_copy.fmu: {message}"]
    assert not (tmp_path / "results").exists()
