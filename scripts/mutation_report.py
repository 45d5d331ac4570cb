"""Mutation testing of the core modules with mutmut; writes ``docs/mutation-report.md``.

For each module, a clean copy of the committed tree (``git archive HEAD``) is made in a
temporary folder, mutmut is configured there to mutate that module alone and to run the
module's own tests, and its verdicts are collected.  A surviving mutant is either killed by
a new test (rerun the script) or explained:

* automatically, when the mutated line only feeds the text of a log message (``LOG.info``,
  ``log.warning``, ...): the message's wording is not behaviour;
* by hand, in :data:`EXPLAINED` (mutant name -> why it is equivalent or out of reach).

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

#: Survivors explained by hand: mutant name -> reason (names are those of ``mutmut results``).
_NO_ROWS = "an empty (0, k) array: no row is read, the column count does not matter"
_FLOAT = ("the dtype only changes for integer input, and every use combines it with a float array "
          "(numpy promotes), so the results are the same floats")
_SIGN = "only the sign of the range rate is used, and the divisor is positive either way"
_TRIGGER = "rhnc.trigger.x\u01c1EventTrigger\u01c1update__mutmut_"
_VOYAGE = "rhnc.voyage.x_account_voyage__mutmut_"
_REFERENCE = "rhnc.reference.x_reference_states__mutmut_"
_REST_END = ("an end row at rest means p2 - 4 p1 + 3 p0 = 0 to within the rest threshold (one-sided difference "
             "zero), which makes velocity and acceleration at the neighbouring row parallel to that precision: the "
             "neighbour's yaw rate is 0 (exactly for a ship stopped dead)")
_NAN_TEXT = "float() reads 'NAN' as 'nan': the same NaN"
_TRAPEZOID = "the trapezoid rule over fewer than two samples is 0.0, the value of the other branch"
EXPLAINED: dict[str, str] = {
    f"{_TRIGGER}6": _NO_ROWS, f"{_TRIGGER}18": _NO_ROWS,
    **{f"{_TRIGGER}{n}": _FLOAT for n in (10, 12, 28, 30, 33, 35, 39, 41)},
    f"{_TRIGGER}14": "obstacle rows have 5 columns, so an array of size 1 cannot occur",
    f"{_TRIGGER}21": "extending the state list by zero entries changes nothing",
    f"{_TRIGGER}25": "deleting the states past the last one deletes nothing",
    f"{_TRIGGER}62": _SIGN, f"{_TRIGGER}71": _SIGN,
    f"{_TRIGGER}75": ("differs only when |offset . to_goal| < 1 m^2, i.e. the obstacle abeam to within a "
                      "millimetre per kilometre of range: below the resolution of any position"),
    f"{_TRIGGER}78": "the default cause is never recorded: a transition always sets its own",
    **{f"{_VOYAGE}{n}": _NAN_TEXT for n in (77, 119, 127)},
    **{f"{_VOYAGE}{n}": _FLOAT for n in (7, 9)},
    **{f"{_VOYAGE}{n}": _TRAPEZOID for n in (28, 34, 39, 45)},
    **{f"{_REFERENCE}{n}": _FLOAT for n in (5, 7)},
    **{f"{_REFERENCE}{n}": ("the end accelerations feed only the end yaw rates, which are then replaced by "
                            "their neighbours' (or 0 at rest)") for n in (84, 85, 86, 87, 89, 90, 91)},
    **{f"{_REFERENCE}{n}": _REST_END for n in (143, 145, 151, 155)},
    **{f"rhnc.energy.x_{name}__mutmut_{n}": _FLOAT for name, numbers in (
        ("speed_through_water", (15, 17)), ("frictional_coefficient", (9, 11)), ("wave_speed", (9, 11)),
        ("power_components", (4, 6, 9, 11, 18, 20, 23, 25)), ("fuel_rate_t_h", (5, 7))) for n in numbers},
    **{f"rhnc.energy.x_power_components__mutmut_{n}": ("np.broadcast(along_wind, None) has the shape of "
                                                        "along_wind, which wind_speed shares (both come from the "
                                                        "same wind arrays)") for n in (48, 50)},
    f"{_REFERENCE}112": ("np.all(None) is False: the hold loop then runs for an all-moving path too, and there "
                         "it leaves every heading as it is"),
}

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


def explain(name: str, diff: str, in_log_calls: set[str]) -> str:
    if name in EXPLAINED:
        return EXPLAINED[name]
    removed = [line[1:].strip() for line in diff.splitlines() if line.startswith("-") and not line.startswith("---")]
    if removed and all(line in in_log_calls for line in removed):
        return "only the text or arguments of a log message change (wording, not behaviour)"
    return ""


def run_module(key: str, children: int) -> Verdicts:
    source, tests = MODULES[key]
    started = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix=f"mutmut-{key}-") as tmp:
        work = Path(tmp)
        archive = subprocess.run(["git", "archive", "HEAD"], cwd=REPO, capture_output=True, check=True).stdout
        subprocess.run(["tar", "-x", "-C", str(work)], input=archive, check=True)
        config = (f"\n[tool.mutmut]\nsource_paths = [{json.dumps(source)}]\n"
                  f"pytest_add_cli_args_test_selection = {json.dumps(tests)}\n"
                  "pytest_add_cli_args = [\"-p\", \"no:cacheprovider\", \"-m\", \"not slow\"]\n"
                  "also_copy = [\"orchestrator\", \"rhnc\", \"models\", \"scenarios\", \"batches\"]\n")
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
                survivors.append((name, diff, explain(name, diff, in_log_calls)))
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
