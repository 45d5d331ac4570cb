"""Fuzz the scenario loader: mutate the shipped scenarios and check every answer is clean.

Each generated scenario is a shipped scenario (``scenarios/**/*.toml`` with a
``[simulation]`` table) with one or two mutations: a value replaced by a hostile one
(NaN, infinities, 1e308, the smallest subnormal, empty, NUL, 300-character and ``..``
strings, arrays nested 500 deep, wrong types), a key deleted or added, one of the inputs
known to have broken the loader before, or the text itself damaged.  ``validate`` runs on
every one (and ``run``, with the scenario cut to a few steps, on every tenth) in a child
process with a time limit, and each answer is put in one class:

``exit 2, one line``    refused with one ``error:`` line (what bad input must get)
``exit 0``              accepted (the mutation left a valid scenario)
``exit 3``              ``run`` only: a run that failed, with its results written
``traceback``           a Python traceback on stderr (a bug)
``several lines``       exit 2 but more than one ``error:`` line or other stderr text
``hang``                no answer within the time limit (a bug)
``crash``               killed by a signal or another exit code (a bug)

Usage::

    python scripts/fuzz_scenarios.py --count 1200 --jobs 2          # the campaign
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
import threading
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
                    mutations.append(_known_bad(data, rng))
            text = to_toml(data)
        cases.append(Case(index, base, tuple(mutations), text, run))
    return cases


# -- running ----------------------------------------------------------------------------------
@dataclass
class Outcome:
    case: Case
    command: str
    verdict: str
    returncode: int | None
    seconds: float
    max_rss_mb: float
    stderr_tail: str


def classify(returncode: int | None, stderr: str, command: str) -> str:
    """The class of an answer (see the module docstring)."""
    if returncode is None:
        return "hang"
    if "Traceback (most recent call last)" in stderr:
        return "traceback"
    if returncode < 0 or returncode not in (0, 2, 3, 130):
        return "crash"
    if returncode == 0:
        return "exit 0"
    if returncode == 3 and command == "run":
        return "exit 3"
    errors = [line for line in stderr.splitlines() if line.startswith("error:")]
    return "exit 2, one line" if returncode == 2 and len(errors) == 1 else "several lines"


def run_case(case: Case, folder: Path, command: str, timeout_s: float) -> Outcome:
    """Write the case beside its base (so relative paths resolve) and run the CLI on it."""
    relative = case.base.relative_to(REPO / "scenarios")
    path = folder / "scenarios" / relative.parent / f"fuzz_{case.index:05d}.toml"
    path.write_text(case.text, encoding="utf-8")
    args = [sys.executable, "-m", "orchestrator", command, str(path)]
    if command == "run":
        args += ["--results", str(folder / "results" / f"{case.index:05d}"), "--no-progress"]
    env = {**os.environ, "PYTHONPATH": str(REPO), "MPLBACKEND": "Agg"}
    with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err:
        start = time.perf_counter()
        child = subprocess.Popen(args, stdout=out, stderr=err, cwd=folder, env=env, start_new_session=True)
        timed_out = threading.Event()

        def stop():
            timed_out.set()
            try:
                os.killpg(child.pid, signal.SIGKILL)
            except ProcessLookupError:
                pass

        timer = threading.Timer(timeout_s, stop)
        timer.start()
        _, status, usage = os.wait4(child.pid, 0)
        timer.cancel()
        child.returncode = os.waitstatus_to_exitcode(status)
        seconds = time.perf_counter() - start
        err.seek(0)
        stderr = err.read().decode("utf-8", "replace")
    returncode = None if timed_out.is_set() else child.returncode
    path.unlink(missing_ok=True)
    shutil.rmtree(folder / "results" / f"{case.index:05d}", ignore_errors=True)
    return Outcome(case, command, classify(returncode, stderr, command), returncode, seconds,
                   usage.ru_maxrss / 1024.0, stderr[-600:])


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--count", type=int, default=1200, help="generated scenarios (default 1200)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--jobs", type=int, default=2, help="child processes at once (default 2)")
    parser.add_argument("--timeout", type=float, default=60.0, help="time limit per command [s] (default 60)")
    parser.add_argument("--run-every", type=int, default=10, help="also 'run' every n-th case (0: never)")
    parser.add_argument("--keep", default=None, help="work in this folder and keep the failing cases there")
    parser.add_argument("--report", default=None, help="write every outcome as JSON lines here")
    args = parser.parse_args(argv)

    folder = Path(args.keep or tempfile.mkdtemp(prefix="rhnc-fuzz-")).resolve()
    if (folder / "scenarios").exists():
        shutil.rmtree(folder / "scenarios")
    shutil.copytree(REPO / "scenarios", folder / "scenarios")
    cases = generate(args.count, args.seed, run_every=args.run_every)
    jobs = [(case, "validate") for case in cases] + [(case, "run") for case in cases if case.run]
    counts = {"validate": collections.Counter(), "run": collections.Counter()}
    bad, largest = [], {"validate": 0.0, "run": 0.0}
    report = open(args.report, "w") if args.report else None
    lock = threading.Lock()
    pending = iter(jobs)
    started = time.perf_counter()

    def worker():
        while True:
            with lock:
                job = next(pending, None)
            if job is None:
                return
            outcome = run_case(job[0], folder, job[1], args.timeout)
            with lock:
                counts[outcome.command][outcome.verdict] += 1
                largest[outcome.command] = max(largest[outcome.command], outcome.max_rss_mb)
                if outcome.verdict not in ("exit 2, one line", "exit 0", "exit 3"):
                    bad.append(outcome)
                    if args.keep:
                        keep = folder / "failing" / f"{outcome.command}_{outcome.case.index:05d}.toml"
                        keep.parent.mkdir(exist_ok=True)
                        keep.write_text(outcome.case.text, encoding="utf-8")
                if report:
                    report.write(json.dumps({"index": outcome.case.index, "base": str(outcome.case.base.name),
                                             "mutations": outcome.case.mutations, "command": outcome.command,
                                             "verdict": outcome.verdict, "returncode": outcome.returncode,
                                             "seconds": round(outcome.seconds, 2),
                                             "max_rss_mb": round(outcome.max_rss_mb, 1),
                                             "stderr_tail": outcome.stderr_tail}) + "\n")
                    report.flush()
                done = sum(sum(c.values()) for c in counts.values())
                if done % 50 == 0:
                    print(f"{done}/{len(jobs)} done, {len(bad)} bad, {time.perf_counter() - started:.0f} s",
                          file=sys.stderr, flush=True)

    threads = [threading.Thread(target=worker) for _ in range(max(1, args.jobs))]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    if report:
        report.close()
    print(f"{len(cases)} generated scenarios (seed {args.seed}), {len(jobs)} commands, "
          f"time limit {args.timeout:g} s, {time.perf_counter() - started:.0f} s wall time")
    for command in ("validate", "run"):
        shown = ", ".join(f"{verdict}: {n}" for verdict, n in sorted(counts[command].items()))
        print(f"  {command}: {sum(counts[command].values())} ({shown}); largest peak memory "
              f"{largest[command]:.0f} MB")
    for outcome in bad[:30]:
        tail = outcome.stderr_tail.strip().splitlines()[-1:] or [""]
        print(f"  BAD {outcome.verdict} {outcome.command} #{outcome.case.index} {outcome.case.base.name} "
              f"{list(outcome.case.mutations)}: {tail[0][:200]}")
    if not args.keep:
        shutil.rmtree(folder, ignore_errors=True)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
