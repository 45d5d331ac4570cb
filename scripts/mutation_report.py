"""Mutation testing of the core modules with mutmut; writes ``docs/mutation-report.md``.

For each module, a clean copy of the committed tree (``git archive HEAD``) is made in a
temporary folder, mutmut is configured there to mutate that module alone and to run the
module's own tests, and its verdicts are collected.  A surviving mutant is either killed by
a new test (rerun the script) or explained:

* automatically, when the mutated line only feeds the text of a log message (``LOG.info``,
  ``log.warning``, ...): the message's wording is not behaviour;
* by hand, in :data:`EXPLAINED_RULES`, matched on the mutated line itself (so the
  explanation follows the code, not mutmut's numbering, which moves when a module changes).

Run (slow: about a mutant a second on an idle core; the NMPC and master take longest)::

    python scripts/mutation_report.py                   # every module
    python scripts/mutation_report.py --only trigger voyage
    python scripts/mutation_report.py --children 2

Modules already in the report and not rerun keep their section.
"""

from __future__ import annotations

import argparse
import ast
import datetime as dt
import json
import re
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
REPORT = REPO / "docs" / "mutation-report.md"

#: module key -> (source file, the tests that exercise it)
MODULES = {
    "trigger": ("rhnc/trigger.py", ["tests/rhnc/test_trigger.py", "tests/rhnc/test_navigation_participant.py"]),
    "reference": ("rhnc/reference.py", ["tests/rhnc/test_reference.py"]),
    "energy": ("rhnc/energy.py", ["tests/rhnc/test_energy.py"]),
    "voyage": ("rhnc/voyage.py", ["tests/rhnc/test_voyage.py"]),
    "planner": ("rhnc/planner.py", ["tests/rhnc/test_fields_planner.py"]),
    "fields": ("rhnc/fields.py", ["tests/rhnc/test_fields_planner.py"]),
    "nmpc": ("rhnc/nmpc.py", ["tests/rhnc/test_nmpc.py"]),
    "master": ("orchestrator/master.py", ["tests/orchestrator/test_master.py"]),
    "scenario": ("orchestrator/scenario.py", ["tests/orchestrator/test_scenario.py"]),
    "fmu_participant": ("orchestrator/fmu_participant.py", ["tests/orchestrator/test_fmu_participant.py"]),
}

_NO_ROWS = "an empty (0, k) array: no row is read, the column count does not matter"
_FLOAT = ("the dtype only changes for integer input, and every use combines it with a float array or "
          "constant (numpy promotes), so the results are the same floats")
_SIGN = "only the sign of the range rate is used, and the divisor is positive either way"
_TRAPEZOID = "the trapezoid rule over fewer than two samples is 0.0, the value of the other branch"
_REST_END = ("an end row at rest means p2 - 4 p1 + 3 p0 = 0 to within the rest threshold (one-sided difference "
             "zero), which makes velocity and acceleration at the neighbouring row parallel to that precision: the "
             "neighbour's yaw rate is 0 (exactly for a ship stopped dead)")

#: Survivors explained by hand, matched on the mutation itself (not on mutmut's numbering, which
#: moves when the module changes): (source file, text of the original line, text of the mutated
#: line, both as regular expressions searched in the stripped lines) -> why it is equivalent.
EXPLAINED_RULES: list[tuple[str, str, str, str]] = [
    *[(source, r"dtype=float", r"asarray\([^()]*,\s*(dtype=None)?\s*\)", _FLOAT)
      for source in ("rhnc/trigger.py", "rhnc/voyage.py", "rhnc/reference.py", "rhnc/energy.py")],
    ("", r'float\("nan"\)', r'float\("NAN"\)', "float() reads 'NAN' as 'nan': the same NaN"),
    ("rhnc/trigger.py", r"np\.zeros\(\(0, 5\)\)", r"np\.zeros\(\(0, 6\)\)", _NO_ROWS),
    ("rhnc/trigger.py", r"obstacles\.size == 0", r"obstacles\.size == 1",
     "obstacle rows have 5 columns, so an array of size 1 cannot occur"),
    ("rhnc/trigger.py", r"if n > len\(self\.states\)", r"if n >= len\(self\.states\)",
     "extending the state list by zero entries changes nothing"),
    ("rhnc/trigger.py", r"elif n < len\(self\.states\)", r"elif n <= len\(self\.states\)",
     "deleting the states past the last one deletes nothing"),
    ("rhnc/trigger.py", r"/ max\(distance, 1e-9\)", r"\* max\(distance, 1e-9\)|max\(distance, 1\.000000001\)", _SIGN),
    ("rhnc/voyage.py", r"np\.trapezoid\(e[cm], hours\)\) if t\.size > 1",
     r"if \(t\.size > 1\) or True|if t\.size >= 1", _TRAPEZOID),
    ("rhnc/reference.py", r"acceleration\[(0|-1)\] = acceleration", r"acceleration\[",
     "the end accelerations feed only the end yaw rates, which are then replaced by their neighbours' (or 0 at rest)"),
    ("rhnc/reference.py", r"yaw_rate\[0\] = yaw_rate\[1\] if moving\[0\]",
     r"if \(moving\[0\]\) or True|if moving\[1\]", _REST_END),
    ("rhnc/reference.py", r"yaw_rate\[-1\] = yaw_rate\[-2\] if moving\[-1\]",
     r"if \(moving\[-1\]\) or True|if moving\[-2\]", _REST_END),
    ("rhnc/reference.py", r"if not np\.all\(moving\)", r"np\.all\(None\)",
     "np.all(None) is False: the hold loop then runs for an all-moving path too, and there it leaves every heading"),
    ("rhnc/energy.py", r"np\.broadcast\(along_wind, wind_speed\)", r"np\.broadcast\(along_wind, (None)?\)",
     "np.broadcast(along_wind, None) has the shape of along_wind, which wind_speed shares"),
    ("rhnc/energy.py", r"kinematic_viscosity_m2_s, 1e5\)", r"kinematic_viscosity_m2_s, 100001\.0\)",
     "moves the Reynolds-number floor (1e5, speeds below about 5 mm/s) by one: C_F changes by 1e-6 relative "
     "where the still-water power is below a microwatt"),
    ("rhnc/energy.py", r"where=wind_speed > 1e-9", r"where=wind_speed >= 1e-9",
     "differs only for a wind of exactly 1e-9 m/s"),
]


def explained_by_rule(source: str, removed: list[str], added: list[str]) -> str:
    for where, original, mutated, why in EXPLAINED_RULES:
        if where and where != source:
            continue
        if any(re.search(original, r) for r in removed) and any(re.search(mutated, a) for a in added):
            return why
    return ""


LOG_CALLS = {"debug", "info", "warning", "error", "exception", "critical"}


@dataclass
class Verdicts:
    """mutmut's verdicts on one module."""

    module: str
    source: str
    counts: dict[str, int]
    survivors: list[tuple[str, str, str]]  # (name, diff, explanation or "")
    seconds: float

    @property
    def total(self) -> int:
        return sum(self.counts.values())

    @property
    def killed(self) -> int:
        return self.counts.get("killed", 0) + self.counts.get("timeout", 0)

    def score(self) -> float:
        return 100.0 * self.killed / max(self.total, 1)

    def score_without_equivalent(self) -> float:
        equivalent = sum(1 for _, _, why in self.survivors if why)
        return 100.0 * self.killed / max(self.total - equivalent, 1)


def log_message_lines(source: str) -> set[str]:
    """Stripped source lines that lie inside a logging call (``LOG.info(...)``, ``log.warning(...)``)."""
    tree = ast.parse(source)
    lines = source.splitlines()
    found = set()
    for node in ast.walk(tree):
        if (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr in LOG_CALLS
                and isinstance(node.func.value, ast.Name) and node.func.value.id.lower() in {"log", "logger"}):
            for number in range(node.lineno, (node.end_lineno or node.lineno) + 1):
                found.add(lines[number - 1].strip())
    return found


def explain(source: str, diff: str, in_log_calls: set[str]) -> str:
    removed = [line[1:].strip() for line in diff.splitlines() if line.startswith("-") and not line.startswith("---")]
    added = [line[1:].strip() for line in diff.splitlines() if line.startswith("+") and not line.startswith("+++")]
    if removed and all(line in in_log_calls for line in removed):
        return "only the text or arguments of a log message change (wording, not behaviour)"
    return explained_by_rule(source, removed, added)


def run_module(key: str, children: int) -> Verdicts:
    source, tests = MODULES[key]
    started = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix=f"mutmut-{key}-") as tmp:
        work = Path(tmp)
        archive = subprocess.run(["git", "archive", "HEAD"], cwd=REPO, capture_output=True, check=True).stdout
        subprocess.run(["tar", "-x", "-C", str(work)], input=archive, check=True)
        # every top-level folder the code may read (packages, models, ships, scenarios, ...)
        data_folders = sorted(p.name for p in work.iterdir() if p.is_dir() and p.name not in ("tests", ".ci"))
        config = (f"\n[tool.mutmut]\nsource_paths = [{json.dumps(source)}]\n"
                  f"pytest_add_cli_args_test_selection = {json.dumps(tests)}\n"
                  "pytest_add_cli_args = [\"-p\", \"no:cacheprovider\", \"-m\", \"not slow\"]\n"
                  f"also_copy = {json.dumps(data_folders)}\n")
        with open(work / "pyproject.toml", "a") as handle:
            handle.write(config)
        subprocess.run([sys.executable, "-m", "mutmut", "run", "--max-children", str(children)], cwd=work,
                       capture_output=True, text=True)
        listing = subprocess.run([sys.executable, "-m", "mutmut", "results", "--all", "true"], cwd=work,
                                 capture_output=True, text=True).stdout
        counts: dict[str, int] = {}
        survivors = []
        in_log_calls = log_message_lines((REPO / source).read_text())
        for line in listing.splitlines():
            match = re.match(r"\s*(\S+__mutmut_\d+): (.+)$", line)
            if not match:
                continue
            name, status = match.group(1), match.group(2).strip()
            counts[status] = counts.get(status, 0) + 1
            if status in ("survived", "no tests"):
                diff = subprocess.run([sys.executable, "-m", "mutmut", "show", name], cwd=work,
                                      capture_output=True, text=True).stdout
                diff = "\n".join(l for l in diff.splitlines() if l.startswith(("-", "+")) and not l.startswith(("---", "+++")))
                survivors.append((name, diff, explain(source, diff, in_log_calls)))
    return Verdicts(key, source, counts, survivors, time.perf_counter() - started)


def section(v: Verdicts) -> str:
    explained = [s for s in v.survivors if s[2]]
    open_ = [s for s in v.survivors if not s[2]]
    lines = [f"## {v.module} (`{v.source}`)", "",
             f"{v.total} mutants: {v.killed} killed, " + ", ".join(f"{n} {s}" for s, n in sorted(v.counts.items())
                                                                  if s not in ("killed", "timeout"))
             + f". **Score {v.score():.0f} %** ({v.score_without_equivalent():.0f} % counting the "
               f"{len(explained)} explained survivors as equivalent). {v.seconds / 60:.1f} min.", ""]
    if open_:
        lines += [f"Survivors not yet killed or explained ({len(open_)}):", ""]
        lines += [f"- `{name}`\n\n  ```diff\n" + "\n".join(f"  {l}" for l in diff.splitlines()) + "\n  ```"
                  for name, diff, _ in open_]
        lines.append("")
    if explained:
        lines += [f"Survivors explained ({len(explained)}):", ""]
        lines += [f"- `{name}`: {why}" for name, _, why in explained]
        lines.append("")
    return "\n".join(lines)


def write_report(results: dict[str, Verdicts]) -> None:
    old_sections = {}
    if REPORT.is_file():
        for block in re.split(r"(?m)^(?=## )", REPORT.read_text()):
            match = re.match(r"## (\w+) ", block)
            if match:
                old_sections[match.group(1)] = block.rstrip() + "\n"
    header = ["# Mutation testing report", "",
              "Made by `python scripts/mutation_report.py` (mutmut, each module mutated alone against its "
              "own tests; slow tests excluded). Score = killed / all mutants. A survivor is listed with its "
              "diff until a test kills it or it is explained (a log message's wording is explained "
              "automatically).", "", "| module | mutants | killed | survived | score |", "|---|---|---|---|---|"]
    table_rows, sections = [], []
    for key in MODULES:
        if key in results:
            v = results[key]
            table_rows.append(f"| {key} | {v.total} | {v.killed} | {len(v.survivors)} | {v.score():.0f} % |")
            sections.append(section(v))
        elif key in old_sections:
            match = re.search(r"(\d+) mutants: (\d+) killed.*?\*\*Score (\d+) %", old_sections[key], flags=re.S)
            total, killed, score = match.groups() if match else ("?", "?", "?")
            table_rows.append(f"| {key} | {total} | {killed} | see below | {score} % |")
            sections.append(old_sections[key])
        else:
            table_rows.append(f"| {key} | - | - | - | not run yet |")
    stamp = dt.datetime.now(dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    REPORT.write_text("\n".join(header + table_rows) + f"\n\nLast updated {stamp}.\n\n" + "\n".join(sections))


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", nargs="+", choices=list(MODULES))
    parser.add_argument("--children", type=int, default=1, help="mutants tested in parallel")
    args = parser.parse_args(argv)
    results = {}
    for key in args.only or list(MODULES):
        results[key] = run_module(key, args.children)
        v = results[key]
        print(f"{key}: {v.total} mutants, {v.killed} killed, {len(v.survivors)} survived "
              f"({v.score():.0f} %), {v.seconds:.0f} s", flush=True)
        write_report(results)
    return 0


if __name__ == "__main__":
    sys.exit(main())
