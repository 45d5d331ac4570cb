"""The reliability campaign's cases beyond fuzzed scenarios: interrupts, bad FMUs, full disks, crashes.

Each case is a command (``run`` or ``validate``) on a small scenario with something done to
it, and a judgement of the answer:

* **interrupt** -- Ctrl-C (SIGINT to the run's process) at each phase of a run: set-up, a
  step, terminate, the summaries, the writing of the time series, a figure.  Exit 130; the
  run folder published (status ``interrupted``, or ``finished`` with every file once the
  steps were all done and the signal came while the results were written); no staging
  folder and no temporary folder left.
* **bad FMU** -- the KCS FMU with a symbolic link entry, an entry whose data fail their CRC,
  an entry whose size lies, an entry outside the folder, a declared zip bomb, a truncated
  archive, a file that is no zip, no ``modelDescription.xml``: ``validate`` and ``run`` both
  exit 2 with one ``error:`` line and write nothing.
* **full disk** -- the results folder on a tmpfs of 4 KiB to 1 MiB (``mount``, as root), or,
  without one, ``ENOSPC`` raised by each writer in turn: exit 4 and nothing kept, or exit 0
  with a complete folder when it fits.
* **crash** -- a participant that ends the process (``os._exit``, SIGKILL, SIGSEGV, abort),
  then a normal run on the same folders: that run removes what the dead one left.

:func:`cases` lists them; each returns (argv, setup, judge) for ``fuzz_scenarios.py``'s runner.
"""

from __future__ import annotations

import errno
import json
import os
import shutil
import signal
import stat
import subprocess
import zipfile
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

REPO = Path(__file__).resolve().parents[1]

#: Participants the cases use, written next to the scenarios (imported by the run as a module).
PARTICIPANTS = '''
import ctypes, os, signal, time
from orchestrator.participant import Participant


def ctrl_c(pid=None):
    os.kill(pid or os.getpid(), signal.SIGINT)
    for _ in range(500):
        time.sleep(0.01)


class Phase(Participant):
    """Ctrl-C in the phase ``phase`` (setup, step, terminate, summary), or the process ended
    in its step by ``crash`` (exit, kill, segv, abort)."""

    @classmethod
    def from_options(cls, name, options, context):
        participant = cls(name)
        participant.phase = options.get("phase", "")
        participant.crash = options.get("crash", "")
        return participant

    input_names = property(lambda self: [])
    output_names = property(lambda self: ["ok"])

    def setup(self, start_time, inputs):
        if self.phase == "setup":
            ctrl_c()
        return {"ok": 1.0}

    def step(self, time, step_size, inputs):
        if time >= 20.0 and self.phase == "step":
            ctrl_c()
        if time >= 20.0 and self.crash == "exit":
            os._exit(7)
        if time >= 20.0 and self.crash == "kill":
            os.kill(os.getpid(), signal.SIGKILL)
        if time >= 20.0 and self.crash == "segv":
            ctypes.string_at(0)
        if time >= 20.0 and self.crash == "abort":
            os.abort()
        return {"ok": 1.0}

    def terminate(self):
        if self.phase == "terminate":
            ctrl_c()

    def summary(self):
        if self.phase == "summary":
            ctrl_c()
        return {"phase": self.phase}


def interrupting_figure(frame, scenario, cosim, out_dir):
    """A figure whose drawing is interrupted by Ctrl-C (to the run's process)."""
    os.kill(os.getppid() if os.getppid() != 1 else os.getpid(), signal.SIGINT)
    time.sleep(0.3)
    (out_dir / "interrupted.txt").write_text("drawn")
    return ["interrupted.txt"]
'''

#: A small run: the KCS turning circle, 60 s in 5 s steps, one figure.
SCENARIO = """
connections = ["helm.tau_u -> ship.tau_u", "helm.tau_r -> ship.tau_r"]
[simulation]
name = "{name}"
stop_s = 60.0
dt_s = 5.0
[participants.helm]
type = "scripted_tau"
[participants.helm.options]
tau_u_N = 7.7377e5
tau_r_steps = [[30.0, 3.3e8]]
[participants.ship]
fmu = "{fmu}"
[participants.ship.parameters]
u0 = 9.26
{extra}
[outputs]
analyses = []
figures = {figures}
"""


@dataclass
class Job:
    """One command of the campaign: what to run, in which folders, and how to judge the answer."""

    kind: str
    name: str
    argv: list[str]
    folder: Path  # this job's own folder: scenario, results, temporary files
    setup: Callable[[], None] | None = None
    judge: Callable[["Job", int | None, str], str] | None = None  # -> "ok" or what is wrong

    @property
    def results(self) -> Path:
        return self.folder / "results"

    @property
    def tmp(self) -> Path:
        return self.folder / "tmp"


def _scenario(job_folder: Path, name: str, extra: str = "", figures: str = "[]", fmu: str = "KCS") -> Path:
    job_folder.mkdir(parents=True, exist_ok=True)
    (job_folder / "tmp").mkdir(exist_ok=True)
    (job_folder / "campaign_participants.py").write_text(PARTICIPANTS)
    path = job_folder / f"{name}.toml"
    path.write_text(SCENARIO.format(name=name, extra=extra, figures=figures, fmu=fmu))
    return path


def _leftovers(job: Job) -> list[str]:
    left = [p.name for p in job.tmp.iterdir()] if job.tmp.is_dir() else []
    if job.results.is_dir():
        left += [str(p.relative_to(job.results)) for p in job.results.rglob(".*.partial")]
    return left


def _published(job: Job) -> list[Path]:
    return [p for p in job.results.glob("*/*") if p.is_dir() and not p.name.startswith(".")] \
        if job.results.is_dir() else []


def _errors(stderr: str) -> list[str]:
    return [line for line in stderr.splitlines() if line.startswith("error:")]


# -- interrupts ------------------------------------------------------------------------------------------
def _judge_interrupt(phase: str):
    def judge(job: Job, code: int | None, stderr: str) -> str:
        if code != 130:
            return f"exit {code}, not 130"
        folders = _published(job)
        if len(folders) != 1:
            return f"{len(folders)} run folders published"
        summary = json.loads((folders[0] / "summary.json").read_text())
        steps = summary["simulation"]["steps_done"]
        whole = phase in ("writing", "figure")
        expected = "finished" if whole else "interrupted"
        if summary["status"] != expected:
            return f"status {summary['status']}, not {expected}"
        if phase in ("terminate", "summary", "writing", "figure") and steps != 12:
            return f"{steps} steps kept of 12"
        if phase == "figure" and "interrupted.txt" not in summary.get("figures", []):
            return "the figure was not completed"
        if _leftovers(job):
            return f"left {_leftovers(job)}"
        return "ok"
    return judge


def _send_ctrl_c_while_writing() -> None:
    from orchestrator import recorder

    write = recorder.Recorder.write_parquet

    def interrupted(self, path, *args, **kwargs):
        os.kill(os.getpid(), signal.SIGINT)
        return write(self, path, *args, **kwargs)

    recorder.Recorder.write_parquet = interrupted


def interrupt_jobs(root: Path) -> list[Job]:
    jobs = []
    for phase in ("setup", "step", "terminate", "summary", "writing", "figure"):
        folder = root / f"interrupt-{phase}"
        participant = "" if phase in ("writing", "figure") else phase
        extra = ('[participants.phase]\ntype = "python"\nclass = "campaign_participants:Phase"\n'
                 f'[participants.phase.options]\nphase = "{participant}"\n')
        figures = '["interrupting"]' if phase == "figure" else "[]"
        path = _scenario(folder, f"interrupt_{phase}", extra, figures)
        setup = _send_ctrl_c_while_writing if phase == "writing" else None
        if phase == "figure":
            setup = _register_figure
        jobs.append(Job("interrupt", phase, ["run", str(path), "--results", str(folder / "results"),
                                              "--no-progress"], folder, setup, _judge_interrupt(phase)))
    return jobs


def _register_figure() -> None:
    """Register the interrupting figure as a package would (entry point), in this process only."""
    from orchestrator import plugins

    plugins.registrations("figures")["interrupting"] = plugins.Registration(
        "interrupting", "campaign_participants:interrupting_figure", "campaign")


# -- bad FMUs ------------------------------------------------------------------------------------------
def _doctor(fmu: Path, how: str) -> None:
    if how == "symlink":
        info = zipfile.ZipInfo("resources/passwd")
        info.create_system = 3
        info.external_attr = (stat.S_IFLNK | 0o777) << 16
        with zipfile.ZipFile(fmu, "a") as archive:
            archive.writestr(info, "/etc/passwd")
    elif how in ("bad-crc", "size-lies"):
        with zipfile.ZipFile(fmu, "a", zipfile.ZIP_STORED if how == "bad-crc" else zipfile.ZIP_DEFLATED) as archive:
            archive.writestr("resources/data.bin", b"model data " * 500)
        data = bytearray(fmu.read_bytes())
        if how == "bad-crc":
            with zipfile.ZipFile(fmu) as archive:
                entry = archive.getinfo("resources/data.bin")
            start = entry.header_offset + 30 + len(entry.filename.encode()) + len(entry.extra)
            data[start + 5] ^= 0xFF
        else:
            record = data.rindex(b"PK\x01\x02", 0, data.rindex(b"resources/data.bin"))
            data[record + 24:record + 28] = (10).to_bytes(4, "little")
        fmu.write_bytes(bytes(data))
    elif how in ("dotdot", "absolute"):
        with zipfile.ZipFile(fmu, "a") as archive:
            archive.writestr("../escape.txt" if how == "dotdot" else "/tmp/escape.txt", "x")
    elif how == "bomb":
        with zipfile.ZipFile(fmu, "a", zipfile.ZIP_DEFLATED) as archive:
            archive.writestr("resources/bomb.bin", b"\0" * (3 * 1024**2))
    elif how == "truncated":
        fmu.write_bytes(fmu.read_bytes()[: fmu.stat().st_size // 2])
    elif how == "not-a-zip":
        fmu.write_text("this is not an archive")
    elif how == "no-model-description":
        with zipfile.ZipFile(fmu) as source, zipfile.ZipFile(fmu.with_suffix(".tmp"), "w") as target:
            for entry in source.infolist():
                if entry.filename != "modelDescription.xml":
                    target.writestr(entry, source.read(entry))
        fmu.with_suffix(".tmp").replace(fmu)


def _judge_bad_input(job: Job, code: int | None, stderr: str) -> str:
    if code != 2:
        return f"exit {code}, not 2"
    lines = stderr.strip().splitlines()
    if len(lines) != 1 or not lines[0].startswith("error:"):
        return f"{len(lines)} lines on stderr"
    if job.results.exists() or _leftovers(job):
        return "something was written"
    return "ok"


def _small_bombs() -> None:
    from orchestrator import fmu_archive

    fmu_archive.MAX_ENTRY_BYTES = 1024**2


def bad_fmu_jobs(root: Path) -> list[Job]:
    from orchestrator import fmu_build

    kcs = Path(fmu_build.ensure_built("KCS"))
    jobs = []
    for how in ("symlink", "bad-crc", "size-lies", "dotdot", "absolute", "bomb", "truncated", "not-a-zip",
                "no-model-description"):
        for command in ("validate", "run"):
            folder = root / f"fmu-{how}-{command}"
            folder.mkdir(parents=True)
            fmu = folder / "doctored.fmu"
            shutil.copyfile(kcs, fmu)
            _doctor(fmu, how)
            path = _scenario(folder, "doctored", fmu=str(fmu))
            argv = [command, str(path)] + (["--results", str(folder / "results"), "--no-progress"]
                                           if command == "run" else [])
            jobs.append(Job("bad FMU", f"{how} ({command})", argv, folder,
                            _small_bombs if how == "bomb" else None, _judge_bad_input))
    return jobs


# -- full disk ----------------------------------------------------------------------------------------
def _judge_full_disk(job: Job, code: int | None, stderr: str) -> str:
    if code == 0:
        folders = _published(job)
        complete = len(folders) == 1 and (folders[0] / "summary.json").is_file() and \
            (folders[0] / "track.png").is_file()
        return "ok" if complete and not _leftovers(job) else "exit 0 without a complete folder"
    if code != 4:
        return f"exit {code}, not 4 or 0"
    if _published(job) or _leftovers(job):
        return f"kept {[str(p) for p in _published(job)] + _leftovers(job)}"
    return "ok" if len(_errors(stderr)) == 1 else "not one error line"


def _enospc_in(target: str) -> Callable[[], None]:
    def setup() -> None:
        import importlib

        module_name, _, attribute = target.rpartition(".")
        module_name, _, class_name = module_name.rpartition(".")
        owner = getattr(importlib.import_module(module_name), class_name)

        def full(*args, **kwargs):
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

        setattr(owner, attribute, full)
    return setup


def tmpfs_available(probe: Path) -> bool:
    probe.mkdir(parents=True, exist_ok=True)
    done = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=16k", "tmpfs", str(probe)], capture_output=True)
    if done.returncode != 0:
        return False
    subprocess.run(["umount", str(probe)], check=False)
    return True


def full_disk_jobs(root: Path) -> list[Job]:
    """Runs into a tmpfs too small for their results, or (without one) with ENOSPC raised by each writer."""
    jobs = []
    if tmpfs_available(root / "probe"):
        for size in ("4k", "8k", "12k", "16k", "20k", "24k", "28k", "32k", "48k", "64k", "1m"):
            folder = root / f"disk-{size}"
            path = _scenario(folder, "full_disk", figures='["track"]')
            (folder / "results").mkdir()
            mount = ["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(folder / "results")]
            jobs.append(Job("full disk", f"tmpfs of {size}", ["run", str(path), "--results",
                            str(folder / "results"), "--no-progress"], folder, None, _judge_full_disk))
            jobs[-1].mount = mount
    else:
        for target in ("orchestrator.results.RunFolder.write_json", "orchestrator.recorder.Recorder.write_parquet",
                       "matplotlib.figure.Figure.savefig", "pandas.DataFrame.to_csv"):
            folder = root / f"disk-{target.rsplit('.', 1)[-1]}"
            path = _scenario(folder, "full_disk", figures='["track"]')
            jobs.append(Job("full disk", f"ENOSPC from {target}", ["run", str(path), "--results",
                            str(folder / "results"), "--no-progress"], folder, _enospc_in(target), _judge_full_disk))
    return jobs


# -- crashes ----------------------------------------------------------------------------------------------
def crash_jobs(root: Path) -> list[Job]:
    """A run that ends its process, then a normal run in the same folders, which must clean up after it."""
    jobs = []
    for crash in ("exit", "kill", "segv", "abort"):
        folder = root / f"crash-{crash}"
        extra = ('[participants.phase]\ntype = "python"\nclass = "campaign_participants:Phase"\n'
                 f'[participants.phase.options]\ncrash = "{crash}"\n')
        dead = _scenario(folder, "crashing", extra)
        later = _scenario(folder, "later")
        args = ["--results", str(folder / "results"), "--no-progress"]
        jobs.append(Job("crash", f"{crash}: the run", ["run", str(dead), *args], folder, None, _judge_crash))
        jobs.append(Job("crash", f"{crash}: the next run", ["run", str(later), *args], folder, None, _judge_next))
    return jobs


def _judge_crash(job: Job, code: int | None, stderr: str) -> str:
    return "ok" if code not in (0, None) and "Traceback" not in stderr else f"exit {code}"


def _judge_next(job: Job, code: int | None, stderr: str) -> str:
    if code != 0:
        return f"exit {code}"
    return f"left {_leftovers(job)}" if _leftovers(job) else "ok"


def cases(root: Path) -> list[Job]:
    """Every non-fuzz job, in the order they run (a crash's next run after the crash)."""
    return interrupt_jobs(root) + bad_fmu_jobs(root) + full_disk_jobs(root) + crash_jobs(root)
