"""Mutation testing of the C FMU layer (``models/common``): one source mutation at a time, rebuilt and tested.

mutmut mutates Python only, so this module does for the shared C layer what it does for the
packages: it lists every mutation of a few kinds on the layer's code lines (comparison and
logical operators swapped, ``+``/``-`` and ``*``/``/`` exchanged, a ``return`` status
changed, a condition negated), draws a seeded random sample of them and, for each, copies the
committed tree (``git archive HEAD``) to a temporary folder, applies the mutation there and
runs the FMU tests in that copy.  Those tests build the models' FMUs on demand, by source
hash, so each mutant is compiled into every FMU it reaches.  A mutant is

* **killed** when a test fails, or **timeout** when the tests run past their time limit;
* **survived** when every test passes;
* **not compiled** when the compiler refuses it (left out of the score, as mutmut never
  generates invalid code).

Verdicts go into ``docs/mutation-verdicts.json`` as the module ``fmu_common``, in the form of
:mod:`mutation_report`'s, so the report lists this layer beside the Python modules, with its
survivors (explained by hand in ``scripts/mutation_equivalents.py`` or killed by a new test)
and marked stale when a mutated file changes.  Run from the checkout::

    python scripts/mutation_report.py --only fmu_common --sample 20 --seed 1
"""

from __future__ import annotations

import datetime as dt
import hashlib
import math
import random
import re
import resource
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

#: one mutation kind: a pattern matched on a code line and its replacement
OPERATORS: tuple[tuple[str, str, str], ...] = (
    ("==", r"==", "!="),
    ("!=", r"!=", "=="),
    ("<=", r"<=", "<"),
    (">=", r">=", ">"),
    ("<", r"(?<![<-])<(?![<=])", "<="),
    (">", r"(?<![>-])>(?![>=])", ">="),
    ("&&", r"&&", "||"),
    ("||", r"\|\|", "&&"),
    ("+", r"(?<=[\w)\]] )\+(?= [\w(])", "-"),
    ("-", r"(?<=[\w)\]] )-(?= [\w(])", "+"),
    ("*", r"(?<=[\w)\]] )\*(?= [\w(])", "/"),
    ("/", r"(?<=[\w)\]] )/(?= [\w(])", "*"),
    ("return OK", r"return (fmi[23])OK;", r"return \1Error;"),
    ("return Error", r"return (fmi[23])Error;", r"return \1OK;"),
)


@dataclass(frozen=True)
class CMutant:
    """One mutation: ``source`` line ``line`` (1-based) becomes ``mutated``."""

    source: str
    line: int
    original: str
    mutated: str

    @property
    def name(self) -> str:
        stem = self.source.rsplit("/", 1)[-1].replace(".", "_")
        return f"{stem}:{self.line}:{hashlib.sha256(self.mutated.encode()).hexdigest()[:6]}"

    @property
    def diff(self) -> str:
        return f"-{self.original}\n+{self.mutated}"


def _code_lines(text: str):
    """``(number, line)`` of the lines holding code: comments, preprocessor lines and logging calls left out."""
    in_comment = False
    for number, line in enumerate(text.splitlines(), start=1):
        stripped = line.strip()
        if in_comment:
            in_comment = "*/" not in stripped
            continue
        if stripped.startswith("/*"):
            in_comment = "*/" not in stripped
            continue
        if not stripped or stripped.startswith(("#", "//", "*")) or re.match(r"log_(error|warning|debug)\(", stripped):
            continue
        yield number, line


def _without_strings(line: str) -> str:
    """The line with its string literals and trailing comment blanked (same length), so no mutation lands there."""
    blanked = re.sub(r'"(\\.|[^"\\])*"', lambda m: " " * len(m.group(0)), line)
    for marker in ("/*", "//"):
        at = blanked.find(marker)
        if at >= 0:
            blanked = blanked[:at] + " " * (len(blanked) - at)
    return blanked


def mutants_of(source: str, text: str) -> list[CMutant]:
    """Every mutation of :data:`OPERATORS` on the code lines of ``text`` (the file ``source``), one change each."""
    found = []
    for number, line in _code_lines(text):
        searchable = _without_strings(line)
        for _, pattern, replacement in OPERATORS:
            for match in re.finditer(pattern, searchable):
                mutated = line[:match.start()] + match.expand(replacement) + line[match.end():]
                if mutated != line:
                    found.append(CMutant(source, number, line, mutated))
        negated = _negated_condition(line, searchable)
        if negated:
            found.append(CMutant(source, number, line, negated))
    return found


def _negated_condition(line: str, searchable: str) -> str | None:
    """The line with its ``if (...)`` condition negated (``if (!(...))``), None without one on the line."""
    match = re.search(r"\bif \(", searchable)
    if not match:
        return None
    depth, start = 0, match.end() - 1
    for at in range(start, len(searchable)):
        depth += {"(": 1, ")": -1}.get(searchable[at], 0)
        if depth == 0:
            return line[:start + 1] + "!(" + line[start + 1:at] + ")" + line[at:]
    return None  # the condition continues on the next line


def all_mutants(root: Path, sources: tuple[str, ...]) -> list[CMutant]:
    return [m for source in sources for m in mutants_of(source, (root / source).read_text(encoding="utf-8"))]


def _copy_tree(work: Path, repo: Path) -> None:
    """The committed tree, and the FMUs already built (rebuilt by the tests where their sources differ)."""
    archive = subprocess.run(["git", "archive", "HEAD"], cwd=repo, capture_output=True, check=True).stdout
    subprocess.run(["tar", "-x", "-C", str(work)], input=archive, check=True)
    if (repo / "fmus").is_dir():
        shutil.copytree(repo / "fmus", work / "fmus", dirs_exist_ok=True,
                        ignore=shutil.ignore_patterns("build", "__pycache__", ".*.partial"))


#: a mutant's wall-time cap, as a multiple of its processor-time limit: a backstop for a test run that
#: waits without computing, far above what sharing the machine's cores with other jobs stretches it to
WALL_CAP_PER_CPU_S = 30.0


def _children_cpu_s() -> float:
    """Processor time [s] of this process's ended and waited-for children (and theirs), so far."""
    used = resource.getrusage(resource.RUSAGE_CHILDREN)
    return used.ru_utime + used.ru_stime


def _pytest(work: Path, tests: tuple[str, ...], cpu_limit_s: float | None) -> tuple[int | None, str]:
    """Exit status of the tests in ``work`` (None: past the wall cap) and the end of their output.

    ``cpu_limit_s`` limits the processor time of each process of the run (the kernel ends one past
    it with SIGXCPU), so that the verdict does not depend on how busy the machine is; the wall
    cap (:data:`WALL_CAP_PER_CPU_S` times it) only catches a run that waits without computing.
    """
    # in one process (-n 0: no xdist workers), whose processor time the limit below bounds
    command = [sys.executable, "-m", "pytest", "-q", "-x", "-n", "0", "-p", "no:cacheprovider", "-m", "not slow", *tests]

    def limit_cpu() -> None:  # in the test run's process, before it starts
        if cpu_limit_s is not None:
            seconds = max(1, math.ceil(cpu_limit_s))
            resource.setrlimit(resource.RLIMIT_CPU, (seconds, seconds + 1))

    try:
        done = subprocess.run(command, cwd=work, capture_output=True, text=True, preexec_fn=limit_cpu,
                              timeout=None if cpu_limit_s is None else WALL_CAP_PER_CPU_S * cpu_limit_s)
    except subprocess.TimeoutExpired:
        return None, ""
    return done.returncode, (done.stdout + done.stderr)[-3000:]


def verdict_of(returncode: int | None, output: str) -> str:
    """mutmut's words for one mutant's test run (``not compiled`` where the build refused the source)."""
    if returncode is None or returncode in (-signal.SIGXCPU, -signal.SIGKILL):
        return "timeout"
    if returncode == 0:
        return "survived"
    if re.search(r"building model \w+ failed", output):
        return "not compiled"
    return "killed"


def run_c_module(key: str, sources: tuple[str, ...], tests: tuple[str, ...], repo: Path, sample: int | None,
                 seed: int, timeout_multiplier: float, timeout_constant: float, hashes: dict[str, str | None],
                 max_minutes: float | None = None, only: set[str] | None = None):
    """Run a sample of the C mutants of ``sources``; returns the arguments of a ``Verdicts``.

    ``max_minutes``: no mutant is started after that long; the mutants tested by then are the
    sample (drawn in random order, so a sample cut short is still a random one).  ``only``: test
    just the mutants of these names (an earlier run's survivors, after new tests).
    """
    started = time.perf_counter()
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=repo, capture_output=True, text=True,
                            check=True).stdout.strip()
    everything = all_mutants(repo, sources)
    if only is not None:
        chosen = [m for m in everything if m.name in only]
    else:
        chosen = everything if not sample else random.Random(seed).sample(everything, min(sample, len(everything)))
    with tempfile.TemporaryDirectory(prefix=f"mutation-{key}-") as tmp:
        clean = Path(tmp) / "clean"
        clean.mkdir()
        _copy_tree(clean, repo)
        status, output = _pytest(clean, tests, None)  # builds every FMU once, from the clean sources
        if status != 0:
            raise RuntimeError(f"the FMU tests fail on the clean copy:\n{output}")
        cpu_before = _children_cpu_s()  # a clean run with the FMUs built: what a mutant's run costs at most
        status, output = _pytest(clean, tests, None)
        if status != 0:
            raise RuntimeError(f"the FMU tests fail on the clean copy:\n{output}")
        # the processor time of the whole run (its compilers included) as each process's limit: generous
        limit = (_children_cpu_s() - cpu_before + timeout_constant) * timeout_multiplier
        counts: dict[str, int] = {}
        survivors = []
        tested = 0
        for number, mutant in enumerate(chosen, start=1):
            if max_minutes is not None and time.perf_counter() - started > 60.0 * max_minutes:
                break
            tested += 1
            path = clean / mutant.source
            original_text = path.read_text(encoding="utf-8")
            lines = original_text.splitlines(keepends=True)
            ending = lines[mutant.line - 1][len(mutant.original):]
            lines[mutant.line - 1] = mutant.mutated + ending
            path.write_text("".join(lines), encoding="utf-8")
            try:
                status, output = _pytest(clean, tests, limit)
            finally:
                path.write_text(original_text, encoding="utf-8")
            verdict = verdict_of(status, output)
            counts[verdict] = counts.get(verdict, 0) + 1
            print(f"[{number}/{len(chosen)}] {mutant.name}: {verdict}", flush=True)
            if verdict == "survived":
                survivors.append({"name": mutant.name, "source": mutant.source, "status": verdict,
                                  "diff": mutant.diff})
    settings = {"tests": list(tests), "pytest_args": ["-m", "not slow"], "timeout_multiplier": timeout_multiplier,
                "cpu_limit_s": round(limit, 1),
                "timeout_constant": timeout_constant, "children": 1, "source_hashes": hashes,
                "sample": {"size": tested, "of": len(everything), "seed": seed},
                "not_compiled_excluded": counts.pop("not compiled", 0)}
    stamp = dt.datetime.now(dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    return dict(module=key, sources=list(sources), counts=counts, survivors=survivors,
                seconds=time.perf_counter() - started, commit=commit, date=stamp, settings=settings)
