"""Mutation testing of the core modules with mutmut; writes ``docs/mutation-report.md``.

For each module, a clean copy of the committed tree (``git archive HEAD``, plus the FMUs
already built under ``fmus/``) is made in a temporary folder, mutmut is configured there to
mutate that module's files alone and to run the module's own tests, and its verdicts are
stored in ``docs/mutation-verdicts.json`` (one entry per module, replaced when the module is
rerun).  The report is rendered from the stored verdicts.  A surviving mutant is either
killed by a new test (commit it, rerun the module) or explained:

* automatically, when the mutated lines only feed a log message (``LOG.info``,
  ``log.warning``, ...): the message's wording is not behaviour;
* by hand, in ``scripts/mutation_equivalents.py``, matched on the mutated line itself (so
  the explanation follows the code, not mutmut's numbering, which moves when a module
  changes).  After editing it, ``--report-only`` re-renders the report without rerunning.

A module's verdicts hold for the code they were made on: the run stores the SHA-256 of each
mutated file as committed (the copy mutmut worked on), and the report marks the module
**stale** when a file's content differs today (runs stored before the hashes were: the
file as of the run's commit, stale when that path did not exist then).  A stale module
needs a new run, not a retest of its survivors (which keeps the run's hashes).

Each mutant gets a time limit of ``(t + timeout_constant) * timeout_multiplier`` seconds,
``t`` being the clean run time of the tests that cover it; a mutant that runs out of it
(an endless loop, a solver that no longer converges) counts as killed, as mutmut does.

Run (slow: about a mutant a second on an idle core for the quick modules, several seconds
each for the NMPC)::

    python scripts/mutation_report.py --only trigger voyage
    python scripts/mutation_report.py --only nmpc --sample 80 --timeout-multiplier 3
    python scripts/mutation_report.py --only nmpc_terminal nmpc_problem --timeout-multiplier 3
    python scripts/mutation_report.py --only master --survivors-only   # after new tests
    python scripts/mutation_report.py --report-only       # re-render with new explanations
    python scripts/mutation_report.py                     # every module (hours)
"""

from __future__ import annotations

import argparse
import ast
import datetime as dt
import hashlib
import json
import random
import re
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from mutation_equivalents import EXPLAINED_RULES  # noqa: E402

from orchestrator.marked_blocks import replace_between  # noqa: E402

REPO = Path(__file__).resolve().parents[1]
REPORT = REPO / "docs" / "mutation-report.md"
VERDICTS = REPO / "docs" / "mutation-verdicts.json"

@dataclass(frozen=True)
class Module:
    """One unit of the report: the files mutated together and the tests run against them.

    ``tests`` is the pytest selection (files or node ids); mutmut runs, for each mutant, only
    those of them that executed the mutated function in a clean run, stopping at the first
    failure.  ``pytest_args`` narrows it further (``-k``/``-m`` expressions).
    """

    sources: tuple[str, ...]
    tests: tuple[str, ...]
    pytest_args: tuple[str, ...] = ()
    #: "python" (mutmut) or "c" (scripts/mutation_c.py: one source mutation, rebuilt and tested)
    language: str = "python"


MODULES = {
    "trigger": Module(("rhnc/navigation/trigger.py",), ("tests/rhnc/test_trigger.py", "tests/rhnc/test_navigation_participant.py")),
    "reference": Module(("rhnc/navigation/reference.py",), ("tests/rhnc/test_reference.py",)),
    "energy": Module(("rhnc/ship/energy.py",), ("tests/rhnc/test_energy.py",)),
    "voyage": Module(("rhnc/voyage/voyage.py",), ("tests/rhnc/test_voyage.py",)),
    "planner": Module(("rhnc/navigation/planner.py",), ("tests/rhnc/test_fields_planner.py", "tests/rhnc/test_planner_guards.py")),
    "fields": Module(("rhnc/navigation/fields.py",), ("tests/rhnc/test_fields_planner.py", "tests/rhnc/test_fields_guards.py")),
    # the NMPC's parts together (slow: some 4000 mutants against solver runs; see --sample) ...
    "nmpc": Module(("rhnc/control/nmpc.py", "rhnc/control/nmpc_bounds.py", "rhnc/control/nmpc_settings.py",
                    "rhnc/control/nmpc_problem.py", "rhnc/control/nmpc_terminal.py", "rhnc/control/nmpc_warm_start.py",
                    "rhnc/control/nmpc_colregs.py", "rhnc/control/nmpc_actions.py", "rhnc/control/nmpc_alteration.py",
                    "rhnc/control/nmpc_manoeuvre.py"),
                   ("tests/rhnc/test_nmpc.py", "tests/rhnc/test_nmpc_colregs.py", "tests/rhnc/test_nmpc_manoeuvre.py",
                    "tests/rhnc/test_return_to_route.py",
                    "tests/rhnc/test_nmpc_limits.py",
                    "tests/rhnc/test_nmpc_cost.py", "tests/rhnc/test_nmpc_warm_start.py",
                    "tests/rhnc/test_nmpc_preparation.py", "tests/rhnc/test_nmpc_domain_parts.py",
                    "tests/rhnc/test_nmpc_failed_steps.py", "tests/rhnc/test_nmpc_step_parts.py")),
    # ... or file by file (each its own run, so that a part finishes and reports on its own)
    "nmpc_warm_start": Module(("rhnc/control/nmpc_warm_start.py",), ("tests/rhnc/test_nmpc.py",
                                                             "tests/rhnc/test_nmpc_warm_start.py",
                                                             "tests/rhnc/test_nmpc_failed_steps.py", "tests/rhnc/test_nmpc_step_parts.py")),
    "nmpc_terminal": Module(("rhnc/control/nmpc_terminal.py",), ("tests/rhnc/test_nmpc.py", "tests/rhnc/test_nmpc_step_parts.py")),
    "nmpc_colregs": Module(("rhnc/control/nmpc_colregs.py", "rhnc/control/nmpc_actions.py",
                            "rhnc/control/nmpc_alteration.py", "rhnc/control/nmpc_manoeuvre.py"),
                           ("tests/rhnc/test_nmpc_colregs.py", "tests/rhnc/test_nmpc_manoeuvre.py", "tests/rhnc/test_nmpc_limits.py",
                            "tests/rhnc/test_return_to_route.py",
                            "tests/rhnc/test_nmpc_domain_parts.py", "tests/rhnc/test_nmpc_step_parts.py")),
    "nmpc_problem": Module(("rhnc/control/nmpc_problem.py",), ("tests/rhnc/test_nmpc.py", "tests/rhnc/test_nmpc_colregs.py",
                                                       "tests/rhnc/test_nmpc_cost.py", "tests/rhnc/test_nmpc_preparation.py",
                                                       "tests/rhnc/test_nmpc_step_parts.py")),
    "nmpc_controller": Module(("rhnc/control/nmpc.py", "rhnc/control/nmpc_settings.py"),
                              ("tests/rhnc/test_nmpc.py", "tests/rhnc/test_nmpc_colregs.py",
                               "tests/rhnc/test_nmpc_limits.py", "tests/rhnc/test_nmpc_preparation.py", "tests/rhnc/test_nmpc_step_parts.py")),
    "nmpc_codegen": Module(("rhnc/control/nmpc_codegen.py",), ("tests/rhnc/test_nmpc_codegen.py",
                                                       "tests/rhnc/test_nmpc_codegen_cache.py")),
    "master": Module(("orchestrator/master.py", "orchestrator/participant_build.py"),
                     ("tests/orchestrator/test_master.py", "tests/orchestrator/test_master_guards.py",
                      "tests/orchestrator/test_fmu_participant.py", "tests/orchestrator/test_failure_paths.py",
                      "tests/orchestrator/test_time_limits.py", "tests/orchestrator/test_plugins.py",
                      "tests/orchestrator/test_recorder_streaming.py", "tests/orchestrator/test_master_stop_ports.py")),
    # the scenario file's reader (TOML reading and limits, pydantic tables, the frozen result): its own
    # tests, the hostile-input ones, and those reading the tables it parses for others
    "scenario": Module(("orchestrator/scenario.py", "orchestrator/scenario_model.py",
                        "orchestrator/scenario_participants.py", "orchestrator/scenario_spec.py",
                        "orchestrator/toml_input.py"),
                       ("tests/orchestrator/test_scenario.py", "tests/orchestrator/test_scenario_acceptance.py",
                        "tests/orchestrator/test_scenario_reader.py", "tests/orchestrator/test_toml_input.py",
                        "tests/orchestrator/test_loader_limits.py", "tests/orchestrator/test_loader_fuzz.py",
                        "tests/orchestrator/test_port_mapping.py", "tests/orchestrator/test_batch_spec.py",
                        "tests/orchestrator/test_master.py", "tests/orchestrator/test_fmu_participant.py"),
                       # (about validate's imports, and fails in mutmut's copy, whose sys.path differs)
                       ("-k", "not test_validate_imports_no_code_beside_the_scenario_unless_trusted")),
    "fmu_participant": Module(("orchestrator/fmu_participant.py",), ("tests/orchestrator/test_fmu_participant.py",
                                                                     "tests/orchestrator/test_fmu_participant_guards.py",
                                                                     "tests/orchestrator/test_fmu_participant_types.py",
                                                                     "tests/orchestrator/test_fmu_participant_values.py",
                                                                     # (the per-port bindings: vectors, scaling, wrapping)
                                                                     "tests/orchestrator/test_port_mapping.py")),
    # core modules first mutated after the wings split (each against the tests that exercise it)
    "weather_routing": Module(("rhnc/routing/weather_routing.py",), ("tests/rhnc/test_weather_routing.py",)),
    "route_search": Module(("rhnc/routing/route_search.py",), ("tests/rhnc/test_route_search.py",
                                                               "tests/rhnc/test_weather_routing.py")),
    "equal_arrival": Module(("rhnc/voyage/equal_arrival.py",), ("tests/rhnc/test_equal_arrival.py",
                                                                "tests/rhnc/test_voyage_comparison.py")),
    # (the closed-loop offset removal, which the slow tests show through the NMPC, is checked part by part
    # on short synthetic records in test_disturbance_observer.py: the estimate, its bounds, the trimmed reference)
    "disturbance_observer": Module(("rhnc/control/disturbance_observer.py",),
                                   ("tests/rhnc/test_disturbance_observer.py", "tests/rhnc/test_nmpc_limits.py")),
    "solver_watchdog": Module(("rhnc/control/solver_watchdog.py", "rhnc/control/solve_pace.py"),
                              ("tests/rhnc/test_solver_watchdog_protocol.py", "tests/rhnc/test_solver_worker_lifetime.py",
                               "tests/rhnc/test_solve_time_bound.py",
                               "tests/rhnc/test_nmpc_solve_attempts.py", "tests/rhnc/test_nmpc_limits.py")),
    "colregs": Module(("rhnc/encounters/colregs.py",), ("tests/rhnc/test_colregs.py", "tests/rhnc/test_colregs_rules.py",
                                                        "tests/rhnc/test_imazu.py", "tests/rhnc/test_nmpc_colregs.py")),
    # (the killed-worker resume and the records of lost runs, which the slow tests check through real
    # workers, are checked run by run without a pool in test_batch_run_resume.py: a mutant costs seconds)
    "batch_run": Module(("orchestrator/batch_run.py",), ("tests/orchestrator/test_batch_run_resume.py",
                                                         "tests/orchestrator/test_batch_lost_runs.py",
                                                         "tests/orchestrator/test_crash_safe_batch.py",
                                                         "tests/orchestrator/test_batch.py")),
    # the shared C layer of the FMUs, against the FMU tests (which rebuild the FMUs from the mutated sources)
    "fmu_common": Module(("models/common/fmu_core.c", "models/common/fmi2_api.c", "models/common/fmi3_api.c",
                          "models/common/rk4.h", "models/common/kcs_dynamics.h"),
                         ("tests/models/test_kcs_fmu.py", "tests/models/test_kcsmmg_fmu.py", "tests/models/test_s175_fmu.py",
                          "tests/models/test_kvlcc2_fmu.py", "tests/models/test_vendor_b_fmu.py",
                          "tests/models/test_metocean_fmu.py", "tests/models/test_fmi3.py", "tests/models/test_fmu_build.py",
                          "tests/orchestrator/test_fmu_participant_guards.py"), language="c"),
}


#: the NMPC file by file: listed in the report only when run
ALTERNATIVE_RUNS = ("nmpc_warm_start", "nmpc_terminal", "nmpc_colregs", "nmpc_problem", "nmpc_controller")


def explained_by_rule(source: str, removed: list[str], added: list[str]) -> str:
    for where, original, mutated, why in EXPLAINED_RULES:
        if where and where != source:
            continue
        if any(re.search(original, r) for r in removed) and any(re.search(mutated, a) for a in added):
            return why
    return ""


LOG_CALLS = {"debug", "info", "warning", "error", "exception", "critical", "log"}

#: mutmut's statuses that count as killed: a time-out is a mutant the tests did not let pass, and so is
#: mutmut's "segfault", a test run ended by a signal (SIGSEGV, or SIGKILL past its processor-time limit)
KILLED = ("killed", "timeout", "segfault")
#: statuses of mutants no test told apart from the original
SURVIVED = ("survived", "no tests")


@dataclass
class Verdicts:
    """mutmut's verdicts on one module, as stored in ``docs/mutation-verdicts.json``."""

    module: str
    sources: list[str]
    counts: dict[str, int]
    survivors: list[dict]  # {"name", "source", "status", "diff"}
    seconds: float
    commit: str = ""
    date: str = ""
    settings: dict = field(default_factory=dict)

    @property
    def total(self) -> int:
        return sum(self.counts.values())

    @property
    def killed(self) -> int:
        return sum(self.counts.get(status, 0) for status in KILLED)

    def explained(self) -> list[tuple[dict, str]]:
        """(survivor, why) for every survivor, ``why`` empty when it is not explained."""
        log_lines = {source: log_message_lines((REPO / source).read_text())
                     if (REPO / source).is_file() and source.endswith(".py") else set() for source in self.sources}
        # an entry carried over from an earlier report has no diff, only its explanation
        return [(s, s["why"] if "why" in s and not s["diff"] else
                 explain(s["source"], s["diff"], log_lines.get(s["source"], set()))) for s in self.survivors
                if s["status"] not in KILLED]  # (a run stored before a crash counted as killed lists it)

    def score(self) -> float:
        return 100.0 * self.killed / max(self.total, 1)


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


def source_of(mutant: str, sources: list[str]) -> str:
    """The file a mutant belongs to, from its name (``rhnc.control.nmpc_problem.x_build_problem__mutmut_3``)."""
    dotted = mutant.split(".x")[0] if ".x" in mutant else mutant.rsplit(".", 1)[0]
    for source in sources:
        if source[:-3].replace("/", ".") == dotted:
            return source
    return sources[0]


def content_hash(data: bytes) -> str:
    """Short SHA-256 of a file's bytes (what the report compares to tell a stale verdict)."""
    return hashlib.sha256(data).hexdigest()[:16]


def committed_hash(source: str, commit: str, root: Path | None = None) -> str | None:
    """:func:`content_hash` of ``source`` as of ``commit``, None where it did not exist (or no git)."""
    root = REPO if root is None else root
    try:
        shown = subprocess.run(["git", "show", f"{commit}:{source}"], cwd=root, capture_output=True)
    except OSError:
        return None
    return content_hash(shown.stdout) if shown.returncode == 0 else None


def run_hashes(v: "Verdicts", root: Path | None = None) -> dict[str, str | None]:
    """Hashes of the files as they were mutated: stored with the run, else from its commit."""
    stored = v.settings.get("source_hashes")
    if stored:
        return dict(stored)
    return {source: committed_hash(source, v.commit, root) if v.commit else None for source in v.sources}


def stale_sources(v: "Verdicts", root: Path | None = None) -> list[str]:
    """The module's files whose content today is not what was mutated (or is not known)."""
    root = REPO if root is None else root
    then = run_hashes(v, root)
    stale = []
    for source in v.sources:
        path = root / source
        now = content_hash(path.read_bytes()) if path.is_file() else None
        if then.get(source) is None or now != then.get(source):
            stale.append(source)
    return stale


#: run in the mutmut copy: the diffs of the mutants named on stdin, as JSON (one process for all,
#: instead of one ``mutmut show`` each)
SHOW_DIFFS = """
import json, sys
from mutmut.mutation.diff_apply import find_mutant, get_diff_for_mutant
print(json.dumps({name: get_diff_for_mutant(name, path=find_mutant(name).path) for name in json.load(sys.stdin)}))
"""


def mutant_names(work: Path) -> list[str]:
    """Every mutant mutmut generated in ``work`` (from its per-file records)."""
    names = []
    for meta in sorted((work / "mutants").rglob("*.meta")):
        names += sorted(json.loads(meta.read_text()).get("exit_code_by_key", {}))
    return names


def run_module(key: str, children: int, timeout_multiplier: float, timeout_constant: float,
               sample: int | None = None, seed: int = 0, previous: Verdicts | None = None) -> Verdicts:
    module = MODULES[key]
    started = time.perf_counter()
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=REPO, capture_output=True,
                            text=True, check=True).stdout.strip()
    with tempfile.TemporaryDirectory(prefix=f"mutmut-{key}-") as tmp:
        work = Path(tmp)
        archive = subprocess.run(["git", "archive", "HEAD"], cwd=REPO, capture_output=True, check=True).stdout
        subprocess.run(["tar", "-x", "-C", str(work)], input=archive, check=True)
        # FMUs already built (rebuilt on demand, by source hash, when stale)
        if (REPO / "fmus").is_dir():
            shutil.copytree(REPO / "fmus", work / "fmus", dirs_exist_ok=True,
                            ignore=shutil.ignore_patterns("build", "__pycache__"))
        # every top-level folder the code may read (packages, models, ships, scenarios, fmus, ...)
        data_folders = sorted(p.name for p in work.iterdir() if p.is_dir() and p.name not in ("tests", ".ci"))
        settings = {"tests": list(module.tests), "pytest_args": ["-m", "not slow", *module.pytest_args],
                    "timeout_multiplier": timeout_multiplier, "timeout_constant": timeout_constant,
                    "children": children,
                    "source_hashes": {source: committed_hash(source, "HEAD") for source in module.sources}}
        config = (f"\n[tool.mutmut]\nsource_paths = {json.dumps(list(module.sources))}\n"
                  f"pytest_add_cli_args_test_selection = {json.dumps(list(module.tests))}\n"
                  # mutmut runs the tests in its own process (-n 0: no xdist workers), where its switch is
                  f"pytest_add_cli_args = {json.dumps(['-n', '0', '-p', 'no:cacheprovider', *settings['pytest_args']])}\n"
                  f"also_copy = {json.dumps(data_folders)}\n"
                  f"timeout_multiplier = {timeout_multiplier}\ntimeout_constant = {timeout_constant}\n")
        with open(work / "pyproject.toml", "a") as handle:
            handle.write(config)
        with open(work / "tests" / "conftest.py", "a") as handle:
            handle.write(FASTEST_FIRST)
        mutmut_run = [sys.executable, "-m", "mutmut", "run", "--max-children", str(children)]
        chosen = None
        if sample or previous:
            # generate the mutants and the test coverage (a filter matching nothing stops mutmut
            # right after), then test a random sample of them
            subprocess.run(mutmut_run + ["no-such-mutant"], cwd=work, capture_output=True, text=True)
            everything = mutant_names(work)
            if previous:  # only the earlier run's survivors that still exist
                chosen = sorted({s["name"] for s in previous.survivors} & set(everything))
                settings.update({key_: value for key_, value in previous.settings.items() if key_ == "sample"})
            else:
                chosen = sorted(random.Random(seed).sample(everything, min(sample, len(everything))))
                settings["sample"] = {"size": len(chosen), "of": len(everything), "seed": seed}
        run = subprocess.run(mutmut_run + (chosen or []), cwd=work, capture_output=True, text=True)
        (REPO / "results").mkdir(exist_ok=True)
        (REPO / "results" / f"mutmut-{key}.log").write_text(run.stdout[-20000:] + "\n" + run.stderr[-20000:])
        listing = subprocess.run([sys.executable, "-m", "mutmut", "results", "--all", "true"], cwd=work,
                                 capture_output=True, text=True).stdout
        counts: dict[str, int] = {}
        statuses = {}
        for line in listing.splitlines():
            match = re.match(r"\s*(\S+__mutmut_\d+): (.+)$", line)
            if match and (chosen is None or match.group(1) in chosen):
                statuses[match.group(1)] = status = match.group(2).strip()
                counts[status] = counts.get(status, 0) + 1
        if sample and not previous:  # a sample cut short is the smaller sample it tested
            statuses = {name: status for name, status in statuses.items() if status != "not checked"}
            counts = {}
            for status in statuses.values():
                counts[status] = counts.get(status, 0) + 1
            settings["sample"]["size"] = len(statuses)
        left = [name for name, status in statuses.items() if status not in KILLED]
        shown = subprocess.run([sys.executable, "-c", SHOW_DIFFS], cwd=work, input=json.dumps(left),
                               capture_output=True, text=True, check=True).stdout
        diffs = json.loads(shown)
        survivors = []
        for name in left:
            diff = "\n".join(line for line in diffs[name].splitlines()
                             if line.startswith(("-", "+")) and not line.startswith(("---", "+++")))
            survivors.append({"name": name, "source": source_of(name, list(module.sources)),
                              "status": statuses[name], "diff": diff})
    if not counts:
        raise RuntimeError(f"mutmut gave no verdicts for {key}; see results/mutmut-{key}.log")
    stamp = dt.datetime.now(dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    seconds = time.perf_counter() - started
    if previous:
        # the earlier verdicts stand for every mutant not retested; the retested take their new verdict
        # a retest cut short leaves some unchecked: they keep their earlier verdict
        before = {s["name"]: s["status"] for s in previous.survivors}
        unchecked = [name for name, status in statuses.items() if status == "not checked"]
        for name in unchecked:
            statuses[name] = before[name]
        for entry in survivors:
            entry["status"] = statuses[entry["name"]]
        counts = dict(previous.counts)
        for status in before.values():
            counts[status] -= 1
        for entry in previous.survivors:  # survivors whose function no longer exists keep their verdict too
            if entry["name"] not in statuses:
                statuses[entry["name"]] = entry["status"]
                survivors.append(entry)
        for status in statuses.values():
            counts[status] = counts.get(status, 0) + 1
        counts = {status: n for status, n in counts.items() if n}
        settings["survivors_retested"] = {"commit": commit, "date": stamp, "count": len(statuses) - len(unchecked),
                                          "minutes": round(seconds / 60, 1)}
        # the verdicts not retested are the full run's: its hashes say what they hold for
        settings.pop("source_hashes")
        return Verdicts(key, list(module.sources), counts, survivors, previous.seconds, previous.commit,
                        previous.date, {**previous.settings, **settings})
    return Verdicts(key, list(module.sources), counts, survivors, seconds, commit, stamp, settings)


#: appended to the copy's tests/conftest.py: each mutant's tests run fastest first (by the clean
#: run's durations), so that with pytest's -x a killed mutant costs its quickest failing test
FASTEST_FIRST = """

def pytest_collection_modifyitems(config, items):  # added by scripts/mutation_report.py
    import json
    import pathlib
    for stats in (pathlib.Path("mutmut-stats.json"), pathlib.Path("mutants/mutmut-stats.json")):
        if stats.is_file():
            seconds = json.loads(stats.read_text()).get("duration_by_test", {})
            items.sort(key=lambda item: seconds.get(item.nodeid, 0.0))
            break
"""


def load_verdicts() -> dict[str, Verdicts]:
    if not VERDICTS.is_file():
        return {}
    return {key: Verdicts(**value) for key, value in json.loads(VERDICTS.read_text()).items()}


def save_verdicts(verdicts: dict[str, Verdicts]) -> None:
    ordered = {key: verdicts[key].__dict__ for key in MODULES if key in verdicts}
    VERDICTS.write_text(json.dumps(ordered, indent=1) + "\n")


def section(v: Verdicts) -> str:
    explained = v.explained()
    equivalent = [(s, why) for s, why in explained if why]
    open_ = [s for s, why in explained if not why]
    others = ", ".join(f"{n} {status}" for status, n in sorted(v.counts.items()) if status != "killed")
    sampled = v.settings.get("sample")
    retested = v.settings.get("survivors_retested")
    carried = (f"Survivors retested on commit {retested['commit']} ({retested['date']}, {retested['count']} "
               f"mutants, {retested['minutes']} min) after new tests; the other verdicts are from the full run. "
               if retested else "")
    if v.settings.get("legacy"):
        carried += ("Carried over from the previous report (mutmut's own diffs not kept then): "
                    + (v.settings["changed"] if "changed" in v.settings else
                       f"the module has not changed since commit {v.commit}") + ". ")
    stale = stale_sources(v)
    if stale:
        carried += ("**Stale**: " + ", ".join(f"`{source}`" for source in stale)
                    + " changed since this run (or its content then is not known); these verdicts need a new "
                      "run before they speak for today's code. ")
    lines = [f"## {v.module} (" + ", ".join(f"`{s}`" for s in v.sources) + ")", "",
             (f"A random sample (seed {sampled['seed']}) of {sampled['size']} of the {sampled['of']} mutants. "
              if sampled else "") + carried + f"{v.total} mutants: {v.counts.get('killed', 0)} killed" + (f", {others}" if others else "")
             + f". **Score {v.score():.0f} %**; {len(equivalent)} survivors explained as equivalent, "
               f"{len(open_)} not. Run on commit {v.commit or '?'}, {v.date or '?'}, {v.seconds / 60:.1f} min "
               f"(tests: " + ", ".join(f"`{t}`" for t in v.settings.get("tests", [])) + ").", ""]
    if open_:
        lines += [f"Survivors not yet killed or explained ({len(open_)}):", ""]
        lines += [f"- `{s['name']}` ({s['status']})\n\n  ```diff\n"
                  + "\n".join(f"  {line}" for line in s["diff"].splitlines()) + "\n  ```" for s in open_]
        lines.append("")
    if equivalent:
        lines += [f"Survivors explained ({len(equivalent)}):", ""]
        for s, why in equivalent:
            changed = [line for line in s["diff"].splitlines() if line.startswith("+")]
            lines.append(f"- `{s['name']}`" + (f" (`{changed[0][1:].strip()[:90]}`)" if changed else "") + f": {why}")
        lines.append("")
    return "\n".join(lines)


def write_report(verdicts: dict[str, Verdicts]) -> None:
    header = ["# Mutation testing report", "",
              "Made by `python scripts/mutation_report.py` (mutmut; each module's files mutated alone and "
              "run against that module's own tests, slow tests excluded; verdicts kept in "
              "`docs/mutation-verdicts.json`). Score = (killed + timeout or crash) / all mutants, a crash being a "
              "test run ended by a signal (mutmut's \"segfault\"). A survivor is listed "
              "with its diff until a test kills it or it is explained as equivalent: a log message's wording "
              "automatically, anything else by hand in `scripts/mutation_equivalents.py`. The last column "
              "counts the explained survivors as equivalent (left out of the total). A module marked stale "
              "was run on files that have changed since (their SHA-256 then and now differ): its "
              "verdicts need a new run.", "",
              "| module | mutants | killed | timeout or crash | survived: equivalent | survived: open | score | "
              "score without equivalents |", "|---|---|---|---|---|---|---|---|"]
    rows, sections = [], []
    for key in MODULES:
        if key not in verdicts and key in ALTERNATIVE_RUNS:
            continue
        if key not in verdicts:
            rows.append(f"| {key} | - | - | - | - | - | not run yet | |")
            continue
        v = verdicts[key]
        explained = v.explained()
        equivalent = sum(1 for _, why in explained if why)
        sampled = v.settings.get("sample")
        rows.append(f"| {key}" + (" **(stale)**" if stale_sources(v) else "")
                    + (" (previous report)" if v.settings.get("legacy") else "")
                    + (" (survivors retested)" if v.settings.get("survivors_retested") else "") + f" | {v.total}"
                    + (f" (sample of {sampled['of']})" if sampled else "")
                    + f" | {v.counts.get('killed', 0)} | {v.counts.get('timeout', 0) + v.counts.get('segfault', 0)} | "
                    f"{equivalent} | {len(explained) - equivalent} | {v.score():.0f} % | "
                    f"{100.0 * v.killed / max(v.total - equivalent, 1):.0f} % |")
        sections.append(section(v))
    stamp = dt.datetime.now(dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    REPORT.write_text("\n".join(header + rows) + f"\n\nRendered {stamp}.\n\n" + "\n".join(sections))


def merged_retest(previous: Verdicts, retest: Verdicts, reached: set[str]) -> Verdicts:
    """The stored run with the verdicts of its survivors in ``reached`` replaced by those of ``retest``
    (a run of just them, after new tests); a survivor not reached (its line has changed since, so its
    name is gone) keeps its verdict, and one that no longer compiles leaves the score."""
    counts = dict(previous.counts)
    counts["survived"] = counts.get("survived", 0) - sum(1 for s in previous.survivors if s["name"] in reached)
    for status, n in retest.counts.items():
        counts[status] = counts.get(status, 0) + n
    still = {s["name"] for s in retest.survivors}
    survivors = [s for s in previous.survivors if s["name"] not in reached or s["name"] in still]
    settings = {**previous.settings, "survivors_retested": {
        "commit": retest.commit, "date": retest.date, "count": len(reached), "minutes": round(retest.seconds / 60, 1)}}
    return Verdicts(previous.module, previous.sources, {k: n for k, n in counts.items() if n}, survivors,
                    previous.seconds, previous.commit, previous.date, settings)


README = REPO / "README.md"
README_BEGIN, README_END = "<!-- mutation-scores:begin -->", "<!-- mutation-scores:end -->"


def readme_summary(verdicts: dict[str, Verdicts]) -> str:
    """The README's lines on the scores, from the stored verdicts (which modules are stale today is the
    report's to say: it depends on the files as they are, not on the runs)."""
    scored, not_run = [], []
    open_total, open_in = 0, []
    for key in MODULES:
        if key not in verdicts:
            if key not in ALTERNATIVE_RUNS:
                not_run.append(key)
            continue
        v = verdicts[key]
        sampled = v.settings.get("sample")
        scored.append(f"{key} {v.score():.0f} %" + (f" (a sample of {sampled['size']} of {sampled['of']})" if sampled
                                                    else f" ({v.total})"))
        opened = sum(1 for _, why in v.explained() if not why)
        if opened:
            open_total += opened
            open_in.append(f"{opened} in {key}")
    lines = ["Scores (killed, timed out or crashed over all mutants; the number of mutants in brackets): "
             + ", ".join(scored) + ".",
             ("Every survivor is killed or explained as equivalent in the report." if not open_total else
              f"Survivors neither killed nor explained: {open_total} ({', '.join(open_in)}); every other one is "
              "explained in the report.")
             + (f" Not run yet: {', '.join(not_run)}." if not_run else "")
             + " The report marks a module **stale** when a file it mutated has changed since its run: its score "
               "is then not today's."]
    return "\n".join(lines)


def write_readme(verdicts: dict[str, Verdicts], readme: Path | None = None) -> None:
    """Replace the README's block between the mutation-score markers (nothing when it has none)."""
    readme = README if readme is None else readme
    text = replace_between(readme.read_text(), README_BEGIN, README_END, readme_summary(verdicts))
    if text is not None:
        readme.write_text(text)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", nargs="+", choices=list(MODULES))
    parser.add_argument("--children", type=int, default=1, help="mutants tested in parallel")
    parser.add_argument("--timeout-multiplier", type=float, default=10.0,
                        help="a mutant's time limit is (clean test time + constant) * this")
    parser.add_argument("--timeout-constant", type=float, default=2.0, help="[s], see --timeout-multiplier")
    parser.add_argument("--sample", type=int, help="test a random sample of this many mutants per module "
                        "(an estimate of the score, for modules too slow to run whole)")
    parser.add_argument("--seed", type=int, default=0, help="of the random sample")
    parser.add_argument("--max-minutes", type=float, help="C modules: start no mutant after this long (the "
                        "mutants tested by then are the sample)")
    parser.add_argument("--survivors-only", action="store_true",
                        help="retest only the survivors of the stored run (after new tests); the others keep "
                             "their verdicts")
    parser.add_argument("--report-only", action="store_true",
                        help="re-render the report from docs/mutation-verdicts.json without running mutmut")
    args = parser.parse_args(argv)
    if not args.report_only:
        for key in args.only or list(MODULES):
            previous = load_verdicts().get(key) if args.survivors_only else None
            if args.survivors_only and previous is None:
                raise SystemExit(f"no stored run of {key} to retest the survivors of")
            if MODULES[key].language == "c":
                from mutation_c import run_c_module

                module = MODULES[key]
                v = Verdicts(**run_c_module(key, module.sources, module.tests, REPO, args.sample, args.seed,
                                            args.timeout_multiplier, args.timeout_constant,
                                            {source: committed_hash(source, "HEAD") for source in module.sources},
                                            args.max_minutes,
                                            {s["name"] for s in previous.survivors} if previous else None))
                if previous:
                    from mutation_c import all_mutants

                    names = {m.name for m in all_mutants(REPO, module.sources)}
                    v = merged_retest(previous, v, {s["name"] for s in previous.survivors} & names)
            else:
                v = run_module(key, args.children, args.timeout_multiplier, args.timeout_constant, args.sample,
                               args.seed, previous)
            verdicts = load_verdicts()  # reread: another run may have stored its module meanwhile
            verdicts[key] = v
            save_verdicts(verdicts)
            write_report(verdicts)
            write_readme(verdicts)
            print(f"{key}: {v.total} mutants, {v.killed} killed, {len(v.survivors)} survived "
                  f"({v.score():.0f} %), {v.seconds:.0f} s", flush=True)
    write_report(load_verdicts())
    write_readme(load_verdicts())
    return 0


if __name__ == "__main__":
    sys.exit(main())
