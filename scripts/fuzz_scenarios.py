"""Fuzz the scenario loader: mutate the shipped scenarios and check every answer is clean.

Each generated scenario is a shipped scenario (``scenarios/**/*.toml`` with a
``[simulation]`` table) with one or two mutations: a value replaced by a hostile one
(NaN, infinities, 1e308, the smallest subnormal, empty, NUL, 300-character and ``..``
strings, arrays nested 500 deep, wrong types), a key deleted or added, one of the inputs
known to have broken the loader before, or the text itself damaged.  ``validate`` runs on
every one (and ``run``, with the scenario cut to a few steps, on every tenth) with a time
limit, and each answer is put in one class:

``exit 2, one line``    refused with one ``error:`` line (what bad input must get)
``exit 0``              accepted (the mutation left a valid scenario)
``exit 3``              ``run`` only: a run that failed, with its results written
``exit 4``              ``run`` only: the results could not be written, nothing kept
``traceback``           a Python traceback on stderr (a bug)
``several lines``       exit 2 but more than one ``error:`` line or other stderr text
``hang``                no answer within the time limit (a bug)
``crash``               killed by a signal or another exit code (a bug)

Each command is forked from this process once it has imported the toolchain, and runs as
``python -m orchestrator`` would (its own folder first on the import path, its own
temporary folder); a fresh interpreter per command would spend some 2 s on imports alone.
Then the cases of ``reliability_cases.py`` run (Ctrl-C at every phase of a run, doctored
FMUs, a full disk, participants that end the process), each judged on what it must do.

Usage::

    nice python scripts/fuzz_scenarios.py --count 2000 --jobs 2 --report campaign.jsonl
    python scripts/fuzz_scenarios.py --count 50 --keep /tmp/fuzz    # keep the files

The generator (:func:`generate`) is deterministic for a seed; ``tests/orchestrator/
test_loader_fuzz.py`` feeds a fixed-seed sample of it to the loader in process.
"""

from __future__ import annotations

import argparse
import collections
import json
import math
import os
import random
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import tomllib
from dataclasses import dataclass
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]

#: Values put in place of a scenario value.
HOSTILE_VALUES = [
    math.nan, math.inf, -math.inf, 1e308, -1e308, 5e-324, 1e300, -1e300, 0, -1, 0.0, 2 ** 63 - 1, -(2 ** 63),
    "", "\0", "x" * 300, "..", "../..", "/etc/passwd", "a\nb", True, False, 5, "5", [], {}, [0, math.inf],
    [math.nan, 1.0], [1.0], [1.0, 2.0, 3.0], [[1.0, 2.0], [3.0]], {"x": 1}, [[]], ["a", 1], 1e-4, 1e-300,
]
#: Depth of the nested array of the "deep" mutation.
DEEP = 500
DEEP_VALUE = "<deep>"  # written as DEEP nested arrays by to_toml
#: Inputs that ended in a traceback, a crash or unbounded memory before, as (dotted key, value);
#: a leading "*" stands for every participant (or FMU participant, "*fmu", Python one, "*py").
KNOWN_BAD = [
    ("simulation.start_s", -1e308), ("simulation.stop_s", 1e308), ("simulation.dt_s", 5e-324),
    ("simulation.dt_s", 1e-300), ("simulation.name", "\0"), ("simulation.name", "n" * 300),
    ("simulation.name", ".."), ("simulation.name", "../x"), ("*py.type", []), ("*fmu.mapping", 5),
    ("metocean.file", 5), ("metocean.origin_deg", 5), ("metocean.x_range_nm", [0, math.inf]),
    ("metocean.resolution_nm", 1e-4), ("metocean.resolution_nm", 0.02), ("*fmu.geodetic.origin_deg", 5),
    ("*fmu.parameters.u0", math.nan), ("*fmu.parameters.u0", -math.inf), ("*fmu.parameters.u0", 1e300),
    ("*py.options.goal_nm", [math.inf, 1.0]), ("*py.options.goal_nm", math.inf), ("simulation.steps", 10 ** 300),
    ("*py.options.resolution_nm", 1e-4), ("*py.options.horizon_steps", 10 ** 9), ("connections", 5),
    ("*fmu.parameters", DEEP_VALUE), ("simulation.stop_when", DEEP_VALUE), ("metocean.duration_h", 1e9),
    ("metocean.time_step_h", 1e-6),
]


@dataclass(frozen=True)
class Case:
    """One generated scenario: its base, what was changed, and its text."""

    index: int
    base: Path
    mutations: tuple[str, ...]
    text: str
    run: bool  # also ``run`` it (cut to a few steps)


# -- TOML writing -------------------------------------------------------------------------
def _value(value) -> str:
    if value is DEEP_VALUE or value == DEEP_VALUE:
        return "[" * DEEP + "1" + "]" * DEEP
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value)
    if isinstance(value, str):
        return json.dumps(value, ensure_ascii=False)
    if isinstance(value, list):
        return "[" + ", ".join(_value(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{json.dumps(str(k))} = {_value(v)}" for k, v in value.items()) + "}"
    raise TypeError(type(value))


def to_toml(data: dict) -> str:
    """``data`` as TOML text: every top-level key as one line with inline tables."""
    return "".join(f"{json.dumps(str(key))} = {_value(value)}\n" for key, value in data.items())


# -- mutations ------------------------------------------------------------------------------
def _paths(node, prefix=()):
    """Every (path, value) below ``node``: table entries and list items."""
    if isinstance(node, dict):
        for key, value in node.items():
            yield prefix + (key,), value
            yield from _paths(value, prefix + (key,))
    elif isinstance(node, list):
        for k, value in enumerate(node):
            yield prefix + (k,), value
            yield from _paths(value, prefix + (k,))


def _set(data, path, value) -> None:
    node = data
    for key in path[:-1]:
        if isinstance(node, dict):
            node = node.setdefault(key, {})
        else:
            node = node[key]
        if not isinstance(node, (dict, list)):
            raise KeyError(path)
    node[path[-1]] = value


def _participants(data: dict, kind: str) -> list[str]:
    table = data.get("participants") if isinstance(data.get("participants"), dict) else {}
    return [name for name, body in table.items() if isinstance(body, dict)
            and (kind == "" or (kind == "fmu") == ("fmu" in body))]


def _known_bad(data: dict, rng: random.Random) -> str:
    dotted, value = rng.choice(KNOWN_BAD)
    head, _, rest = dotted.partition(".")
    if head.startswith("*"):
        names = _participants(data, head[1:])
        if not names:
            return _replace_value(data, rng)
        path = ("participants", rng.choice(names)) + tuple(rest.split("."))
    else:
        path = tuple(dotted.split("."))
    _set(data, path, value)
    return f"{'.'.join(map(str, path))} = {_value(value)[:40]}"


def _replace_value(data: dict, rng: random.Random) -> str:
    path, _ = rng.choice(list(_paths(data)))
    value = DEEP_VALUE if rng.random() < 0.03 else rng.choice(HOSTILE_VALUES)
    _set(data, path, value)
    return f"{'.'.join(map(str, path))} = {_value(value)[:40]}"


def _delete_key(data: dict, rng: random.Random) -> str:
    path, _ = rng.choice([(p, v) for p, v in _paths(data) if isinstance(p[-1], str)])
    node = data
    for key in path[:-1]:
        node = node[key]
    del node[path[-1]]
    return f"del {'.'.join(map(str, path))}"


def _add_key(data: dict, rng: random.Random) -> str:
    tables = [p for p, v in _paths(data) if isinstance(v, dict)] + [()]
    path = rng.choice(tables)
    key = rng.choice(["colour", "", "..", "\0", "k" * 300, "every", "type", "fmu", "options"])
    value = rng.choice(HOSTILE_VALUES)
    _set(data, path + (key,), value)
    return f"add {'.'.join(map(str, path + (key,)))!r} = {_value(value)[:40]}"


MUTATIONS = [(_replace_value, 5), (_known_bad, 3), (_delete_key, 1), (_add_key, 1)]


def _damage_text(text: str, rng: random.Random) -> tuple[str, str]:
    """Text-level damage: cut the file, or insert a character or a deep array."""
    choice = rng.randrange(3)
    at = rng.randrange(len(text) + 1)
    if choice == 0:
        return text[:at], f"cut at byte {at}"
    if choice == 1:
        char = rng.choice(["[", "]", "{", "=", '"', "\0", "\n", "\\", "#"])
        return text[:at] + char + text[at:], f"insert {char!r} at {at}"
    return text + "\ndeep = " + "[" * DEEP + "1" + "]" * DEEP + "\n", "deep array at the end"


def base_scenarios(root: Path = REPO / "scenarios") -> list[Path]:
    """The shipped scenario files (those with a [simulation] table), sorted."""
    found = []
    for path in sorted(root.rglob("*.toml")):
        try:
            if "simulation" in tomllib.loads(path.read_text()):
                found.append(path)
        except (tomllib.TOMLDecodeError, UnicodeDecodeError):
            continue
    return found


def _cap_steps(data: dict, steps: int) -> None:
    simulation = data.get("simulation")
    if isinstance(simulation, dict):
        simulation.pop("stop_s", None)
        simulation["steps"] = steps


def generate(count: int, seed: int = 0, bases: list[Path] | None = None, run_every: int = 10,
             run_steps: int = 3) -> list[Case]:
    """``count`` mutated scenarios, the same for the same seed."""
    bases = bases or base_scenarios()
    parsed = {path: tomllib.loads(path.read_text()) for path in bases}
    cases = []
    for index in range(count):
        rng = random.Random(seed * 1_000_003 + index)
        base = bases[index % len(bases)]
        data = json.loads(json.dumps(parsed[base]))  # deep copy (TOML dates do not occur in scenarios)
        run = run_every > 0 and index % run_every == 0
        if run:
            _cap_steps(data, run_steps)
        mutations = []
        if rng.random() < 0.1:
            text, what = _damage_text(to_toml(data), rng)
            mutations.append(what)
        else:
            for _ in range(1 if rng.random() < 0.7 else 2):
                functions, weights = zip(*MUTATIONS)
                mutation = rng.choices(functions, weights)[0]
                try:
                    mutations.append(mutation(data, rng))
                except (KeyError, IndexError, TypeError):
                    try:
                        mutations.append(_known_bad(data, rng))
                    except (KeyError, IndexError, TypeError):  # the first mutation replaced the table
                        mutations.append("(second mutation did not apply)")
            text = to_toml(data)
        cases.append(Case(index, base, tuple(mutations), text, run))
    return cases


# -- running ----------------------------------------------------------------------------------
@dataclass
class Command:
    """One command line for ``python -m orchestrator``, run in the folder ``cwd`` with ``tmp``
    as its temporary folder; ``setup`` runs in its process first (a test hook)."""

    argv: list
    cwd: Path
    tmp: Path
    setup: object = None
    tag: object = None
    mount: list | None = None  # a tmpfs to mount before it runs (and unmount after)


def classify(returncode: int | None, stderr: str, command: str) -> str:
    """The class of an answer (see the module docstring)."""
    if returncode is None:
        return "hang"
    if "Traceback (most recent call last)" in stderr:
        return "traceback"
    if returncode < 0 or returncode not in (0, 2, 3, 4, 130):
        return "crash"
    if returncode == 0:
        return "exit 0"
    if returncode in (3, 4) and command == "run":
        return f"exit {returncode}"
    errors = [line for line in stderr.splitlines() if line.startswith("error:")]
    return "exit 2, one line" if returncode == 2 and len(errors) == 1 else "several lines"


def warm_up(codegen: bool = False) -> None:
    """Import what the commands use, once, in the process every command is forked from.

    Without ``codegen`` the NMPC's NLP is not compiled to C (``RHNC_NMPC_CODEGEN=0``): a
    mutated weight or horizon is a new problem, whose compile (a minute or more, once per
    problem and machine) would otherwise dominate the campaign and count as over the limit.
    """
    os.environ.setdefault("MPLBACKEND", "Agg")
    if not codegen:
        os.environ["RHNC_NMPC_CODEGEN"] = "0"
    sys.path.insert(0, str(REPO))
    from orchestrator import cli, plugins, run, validate  # noqa: F401

    for kind in ("participants", "analyses", "figures", "scenario_tables", "commands", "port_tables"):
        try:
            plugins.load_all(kind)
        except Exception as exc:  # a group that cannot load is the commands' to report
            print(f"warm-up: {kind}: {type(exc).__name__}: {exc}", file=sys.stderr)
    import matplotlib.pyplot  # noqa: F401
    import pyarrow.parquet  # noqa: F401


def _child(command: Command, out, err) -> None:
    """The forked process: the command as ``python -m orchestrator`` would run it; never returns."""
    code = 1
    try:
        os.setsid()  # a process group of its own: ended whole on a time-out
        os.dup2(out.fileno(), 1)
        os.dup2(err.fileno(), 2)
        os.chdir(command.cwd)
        sys.path.insert(0, str(command.cwd))  # as ``python -m`` puts the current folder first
        command.tmp.mkdir(parents=True, exist_ok=True)
        tempfile.tempdir = str(command.tmp)
        os.environ["TMPDIR"] = str(command.tmp)
        signal.signal(signal.SIGINT, signal.default_int_handler)
        if command.setup is not None:
            command.setup()
        from orchestrator.cli import main as cli_main

        code = cli_main(command.argv)
    except SystemExit as exc:
        code = exc.code if isinstance(exc.code, int) else 1
    except BaseException:
        import traceback

        traceback.print_exc()
    finally:
        try:
            sys.stdout.flush()
            sys.stderr.flush()
        finally:
            os._exit(code if isinstance(code, int) else 1)


def run_commands(commands: list, jobs: int, timeout_s: float, on_done) -> None:
    """Run ``commands``, ``jobs`` at a time, each forked from this (warmed-up) process.

    ``on_done(command, returncode or None on a time-out, stderr, seconds, peak RSS [MB])``
    is called as each ends.  A command past ``timeout_s`` is killed with its process group.
    """
    pending = list(reversed(commands))
    running = {}
    while pending or running:
        while pending and len(running) < jobs:
            command = pending.pop()
            if command.mount:
                subprocess.run(command.mount, check=True)
            out, err = tempfile.TemporaryFile(), tempfile.TemporaryFile()
            sys.stdout.flush()
            sys.stderr.flush()
            pid = os.fork()
            if pid == 0:
                _child(command, out, err)
            running[pid] = [command, out, err, time.monotonic(), False]
        pid, status, usage = os.wait4(-1, os.WNOHANG)
        if pid == 0:
            now = time.monotonic()
            for child, entry in running.items():
                if not entry[4] and now - entry[3] > timeout_s:
                    entry[4] = True
                    _kill_group(child)
            time.sleep(0.02)
            continue
        if pid not in running:
            continue
        command, out, err, started, timed_out = running.pop(pid)
        _kill_group(pid)  # whatever it left running (it should have left nothing)
        seconds = time.monotonic() - started
        err.seek(0)
        stderr = err.read().decode("utf-8", "replace")
        out.close()
        err.close()
        on_done(command, None if timed_out else os.waitstatus_to_exitcode(status), stderr, seconds,
                usage.ru_maxrss / 1024.0)
        if command.mount:  # after the judgement, which reads what is on it
            subprocess.run(["umount", "-l", command.mount[-1]], check=False)


def _kill_group(pid: int) -> None:
    try:
        os.killpg(pid, signal.SIGKILL)
    except (ProcessLookupError, PermissionError):
        pass


def _case_path(case: Case, folder: Path) -> Path:
    relative = case.base.relative_to(REPO / "scenarios")
    return folder / "scenarios" / relative.parent / f"fuzz_{case.index:05d}.toml"


def fuzz_commands(cases: list, folder: Path) -> list:
    """The ``validate`` of every case and the ``run`` of every case marked for it, files written."""
    commands = []
    for case in cases:
        path = _case_path(case, folder)
        path.write_text(case.text, encoding="utf-8")
        commands.append(Command(["validate", str(path)], folder, folder / "tmp" / f"{case.index:05d}",
                                tag=(case, "validate")))
    for case in cases:
        if case.run:
            results = folder / "results" / f"{case.index:05d}"
            commands.append(Command(["run", str(_case_path(case, folder)), "--results", str(results),
                                     "--no-progress"], folder, folder / "tmp" / f"{case.index:05d}r",
                                    tag=(case, "run")))
    return commands


class Tally:
    """Counts of answers by group and class, the bad ones, and the slowest."""

    def __init__(self) -> None:
        self.counts: dict[str, collections.Counter] = collections.defaultdict(collections.Counter)
        self.bad: list[str] = []
        self.longest: dict[str, float] = collections.defaultdict(float)
        self.memory: dict[str, float] = collections.defaultdict(float)

    def add(self, group: str, verdict: str, seconds: float, rss_mb: float, what: str, bad: bool) -> None:
        self.counts[group][verdict] += 1
        self.longest[group] = max(self.longest[group], seconds)
        self.memory[group] = max(self.memory[group], rss_mb)
        if bad:
            self.bad.append(f"{group}: {verdict}: {what}")

    def lines(self) -> list[str]:
        rows = []
        for group, counts in self.counts.items():
            shown = ", ".join(f"{verdict}: {n}" for verdict, n in sorted(counts.items()))
            rows.append(f"  {group}: {sum(counts.values())} ({shown}); tracebacks {counts['traceback']}, over the "
                        f"time limit {counts['hang']}, longest {self.longest[group]:.1f} s, largest peak memory "
                        f"{self.memory[group]:.0f} MB")
        return rows


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--count", type=int, default=2000, help="generated scenarios (default 2000)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--jobs", type=int, default=2, help="commands at once (default 2)")
    parser.add_argument("--timeout", type=float, default=60.0, help="time limit per command [s] (default 60)")
    parser.add_argument("--run-every", type=int, default=10, help="also 'run' every n-th case (0: never)")
    parser.add_argument("--no-cases", action="store_true", help="only the fuzzed scenarios (no interrupts, "
                        "bad FMUs, full disks, crashes)")
    parser.add_argument("--codegen", action="store_true", help="let the NMPC compile its NLP to C (a minute or "
                        "more for each new problem; off by default)")
    parser.add_argument("--keep", default=None, help="work in this folder and keep the failing cases there")
    parser.add_argument("--report", default=None, help="write every outcome as JSON lines here")
    args = parser.parse_args(argv)

    folder = Path(args.keep or tempfile.mkdtemp(prefix="rhnc-fuzz-")).resolve()
    if (folder / "scenarios").exists():
        shutil.rmtree(folder / "scenarios")
    shutil.copytree(REPO / "scenarios", folder / "scenarios")
    warm_up(args.codegen)
    started = time.perf_counter()
    cases = generate(args.count, args.seed, run_every=args.run_every)
    commands = fuzz_commands(cases, folder)
    tally = Tally()
    report = open(args.report, "w") if args.report else None
    done = [0]

    def on_fuzz(command, returncode, stderr, seconds, rss_mb):
        case, kind = command.tag
        verdict = classify(returncode, stderr, kind)
        bad = verdict not in ("exit 2, one line", "exit 0", "exit 3", "exit 4")
        tail = (stderr.strip().splitlines() or [""])[-1][:200]
        tally.add(kind, verdict, seconds, rss_mb, f"#{case.index} {case.base.name} {list(case.mutations)}: {tail}", bad)
        if bad and args.keep:
            keep = folder / "failing" / f"{kind}_{case.index:05d}.toml"
            keep.parent.mkdir(exist_ok=True)
            keep.write_text(case.text, encoding="utf-8")
        if kind == "validate" and not case.run or kind == "run":
            _case_path(case, folder).unlink(missing_ok=True)
        shutil.rmtree(folder / "results" / f"{case.index:05d}", ignore_errors=True)
        shutil.rmtree(command.tmp, ignore_errors=True)
        _write_report(report, {"index": case.index, "base": case.base.name, "mutations": case.mutations,
                               "command": kind, "verdict": verdict, "returncode": returncode,
                               "seconds": round(seconds, 2), "max_rss_mb": round(rss_mb, 1),
                               "stderr_tail": stderr[-600:]})
        _progress(done, len(commands), tally, started)

    run_commands(commands, args.jobs, args.timeout, on_fuzz)
    if not args.no_cases:
        sys.path.insert(0, str(Path(__file__).resolve().parent))
        import reliability_cases

        jobs = reliability_cases.cases(folder / "cases")

        def on_case(command, returncode, stderr, seconds, rss_mb):
            job = command.tag
            verdict = "hang" if returncode is None else "traceback" if "Traceback (most recent" in stderr else \
                job.judge(job, returncode, stderr)
            tally.add(job.kind, verdict if verdict in ("ok", "hang", "traceback") else "wrong", seconds, rss_mb,
                      f"{job.name}: {verdict}: {(stderr.strip().splitlines() or [''])[-1][:200]}", verdict != "ok")
            _write_report(report, {"case": job.kind, "name": job.name, "argv": job.argv, "verdict": verdict,
                                   "returncode": returncode, "seconds": round(seconds, 2),
                                   "stderr_tail": stderr[-600:]})

        run_commands([Command(job.argv, job.folder, job.tmp, job.setup, job, getattr(job, "mount", None))
                      for job in jobs], 1, args.timeout, on_case)  # one at a time: a crash's next run follows it
    if report:
        report.close()
    total = sum(sum(c.values()) for c in tally.counts.values())
    print(f"{len(cases)} generated scenarios (seed {args.seed}), {total} commands in all, time limit "
          f"{args.timeout:g} s, {time.perf_counter() - started:.0f} s wall time, "
          f"{os.times().children_user + os.times().children_system:.0f} s CPU of the commands")
    for line in tally.lines():
        print(line)
    for line in tally.bad[:40]:
        print(f"  BAD {line}")
    if not args.keep:
        shutil.rmtree(folder, ignore_errors=True)
    return 1 if tally.bad else 0


def _write_report(report, record: dict) -> None:
    if report:
        report.write(json.dumps(record, default=str) + "\n")
        report.flush()


def _progress(done: list, total: int, tally: Tally, started: float) -> None:
    done[0] += 1
    if done[0] % 100 == 0:
        print(f"{done[0]}/{total} fuzz commands done, {len(tally.bad)} bad, {time.perf_counter() - started:.0f} s",
              file=sys.stderr, flush=True)


if __name__ == "__main__":
    sys.exit(main())
