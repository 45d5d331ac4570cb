"""Run several scenarios and tabulate one analysis side by side, next to published figures.

A comparison file (TOML), e.g. ``scenarios/exp2_table3.toml`` for the paper's Table 3::

    name = "exp2_table3"
    analysis = "voyage"                          # which analysis of each run to tabulate
    metrics = ["cost_usd", "co2_t", "cost_per_nm_usd", "co2_per_nm_kg"]
    baseline = "Offline-SPNC"                    # relative changes are taken against it

    [set]                                        # dotted-key overrides applied to every run
    "metocean" = { generator = "storm_off_route" }           # replaces the whole table

    [sweep]                                      # optional: the whole comparison once per value
    key = "metocean.member"
    range = [0, 29]                              # or values = [...]

    [[runs]]
    label = "RHNC"
    scenario = "exp2_rhnc.toml"                  # relative to this file
    set = { "participants.nav.options.k3" = 8.0 }   # this run's own overrides, optional
    paper = { cost_usd = 10473, co2_t = 31.264 } # published values, optional
    figures = { "navigation_fields.png" = "figure10_fields.png" }   # copied, renamed

``python -m orchestrator compare FILE`` runs every scenario into
``results/<name>/<run-id>/runs/<label>/``, then writes ``table.csv`` and ``table.md`` (ours
and the paper's value of each metric per run, and each run's change against the
baseline), the figures of every registered comparison figure (entry-point group
``rhnc_cosim.comparison_figures``: the ship domain draws ``tracks.png``, all tracks over the
met-ocean field) and the copied figures.
With ``[sweep]`` each value gets such a folder under ``members/`` and the top folder holds
the sweep's table.

A table named in the entry-point group ``rhnc_cosim.comparisons`` (``[voyage]``) hands
the runs to a domain extension, which may set further overrides on every run, run more
scenarios through the same machinery and add its own tables (``docs/compare-format.md``).
The engine here knows nothing of what the extension measures.
"""

from __future__ import annotations

import copy
import hashlib
import json
import logging
import math
import re
import shutil
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pandas as pd

from orchestrator.errors import ScenarioError
from orchestrator import plugins

log = logging.getLogger(__name__)



@dataclass
class Section:
    """What an extension adds to a comparison's output.

    ``markdown`` is appended to ``table.md``; each table in ``tables`` is written as
    ``<name>.csv``; ``summary`` goes into ``summary.json`` under the extension's name;
    ``flags`` are warnings printed under the tables and kept in ``summary.json``;
    ``failed_runs`` names every run the extension made that failed (its label and trial)
    with the reason: they join the comparison's own failed runs in the table, the summary
    and on stderr, and the command exits 3.
    """

    markdown: str = ""
    tables: dict[str, pd.DataFrame] = field(default_factory=dict)
    summary: dict[str, Any] = field(default_factory=dict)
    flags: list[str] = field(default_factory=list)
    failed_runs: dict[str, str] = field(default_factory=dict)


class ScenarioRunner:
    """Runs a scenario of the comparison into ``<folder>/runs/<label>/<run-id>/``.

    Extensions call it for the runs they add, so every run of a comparison goes through
    :func:`orchestrator.run.run_scenario` with the same results layout.
    """

    def __init__(self, runs_dir: Path, progress: bool) -> None:
        self.runs_dir = Path(runs_dir)
        self.progress = progress

    def __call__(self, scenario: Path, overrides: dict[str, Any], label: str):
        from orchestrator.run import run_scenario

        return run_scenario(scenario, self.runs_dir, progress=self.progress, overrides=copy.deepcopy(overrides),
                            group=slug(label))


def load_comparison(path: Path) -> dict[str, Any]:
    """Read and check a comparison file (:mod:`orchestrator.compare_spec`); errors name the file and the key."""
    from orchestrator.compare_spec import load_comparison as load

    return load(path, tuple(plugins.names("comparisons")))


def load_extensions(spec: dict[str, Any], path: Path) -> dict[str, Any]:
    """Build the extensions the comparison names; each checks its table and every run."""
    extensions = {}
    for name, registration in plugins.registrations("comparisons").items():
        if name not in spec:
            continue
        table = spec[name]
        if not isinstance(table, dict):
            raise ScenarioError(f"{path}: '{name}' must be a table ([{name}])")
        extension_class = registration.load()
        extensions[name] = extension_class.from_table(table, Path(path), spec)
    return extensions


def run_comparison(path, results_root="results", progress: bool = True) -> Path:
    """Run the comparison in ``path``; return the folder with the table and figures.

    Every input error (the comparison file, an extension's table, a run's scenario with
    the overrides applied) is raised before the first run starts.
    """
    from orchestrator.results import RunFolder, new_run_id

    path = Path(path)
    spec = load_comparison(path)
    extensions = load_extensions(spec, path)
    members = [None] if "sweep" not in spec else spec["sweep"]["values"]
    member_overrides = [_member_overrides(spec, value) for value in members]
    for overrides in member_overrides:
        _check_runs(spec, extensions, path, overrides)
    folder = RunFolder(Path(results_root), spec["name"], new_run_id(_digest(path)))
    try:
        if "sweep" not in spec:
            sections, summary = _compare_once(spec, extensions, path, member_overrides[0], folder.staging, progress)
            summary["comparison"] = str(path.resolve())
            folder.write_json("summary.json", summary)
        else:
            key = spec["sweep"]["key"]
            per_member: dict[str, list[tuple[Any, Any]]] = {name: [] for name in extensions}
            statuses, failed_runs = {}, {}
            for value, overrides in zip(members, member_overrides):
                log.info("comparison %s: %s = %s", spec["name"], key, value)
                target = folder.path("members") / slug(f"{key}={value}")
                target.mkdir(parents=True)
                sections, summary = _compare_once(spec, extensions, path, overrides, target, progress)
                (target / "summary.json").write_text(json.dumps(summary, indent=2, default=str) + "\n")
                statuses[str(value)] = summary["status"]
                failed_runs.update({f"{key}={value}: {label}": reason
                                    for label, reason in summary["failed_runs"].items()})
                for name in extensions:
                    per_member[name].append((value, sections[name]))
            markdown = [f"# {spec['name']}: sweep over {key} ({len(members)} values)", ""]
            sweep_summary: dict[str, Any] = {"comparison": str(path.resolve()), "sweep_key": key,
                                             "members": statuses,
                                             "status": "finished" if all(
                                                 s == "finished" for s in statuses.values()) else "failed",
                                             "failed_runs": failed_runs}
            for name, extension in extensions.items():
                section = extension.summarise_sweep(key, per_member[name], folder.staging)
                _write_section(section, folder.staging)
                markdown.append(section.markdown)
                sweep_summary[name] = section.summary
            markdown += failed_runs_markdown(failed_runs)
            folder.path("table.md").write_text("\n".join(markdown) + "\n")
            folder.write_json("summary.json", sweep_summary)
    except BaseException:
        folder.discard()
        raise
    return folder.publish()


def _compare_once(spec, extensions, path: Path, overrides: dict, out_dir: Path, progress: bool):
    """One pass over the runs (and the extensions' runs) into ``out_dir``."""
    runner = ScenarioRunner(out_dir / "runs", progress)
    reports = {}
    for i, run in enumerate(spec["runs"]):
        scenario = path.parent / run["scenario"]
        report = runner(scenario, _run_overrides(run, extensions, scenario, overrides, f"{path}: runs[{i}]"),
                        run["label"])
        reports[run["label"]] = report
        for source, target in run.get("figures", {}).items():
            if (report.folder / source).is_file():
                shutil.copyfile(report.folder / source, out_dir / target)
    table = comparison_table(spec, {label: r.summary for label, r in reports.items()})
    table.to_csv(out_dir / "table.csv", index=False)
    markdown = [f"# {spec['name']}", "", markdown_table(table), ""]
    sections, flags = {}, []
    failed = {label: f"{r.status}: {r.reason}" for label, r in reports.items() if not r.ok}
    for name, extension in extensions.items():
        section = extension.evaluate(reports, runner, overrides, out_dir)
        _write_section(section, out_dir)
        sections[name] = section
        flags += section.flags
        failed.update(section.failed_runs)
        markdown.append(section.markdown)
    markdown += failed_runs_markdown(failed)
    (out_dir / "table.md").write_text("\n".join(markdown) + "\n")
    for draw in plugins.load_all("comparison_figures").values():
        draw(spec, reports, out_dir)
    for label, reason in failed.items():
        log.error("comparison %s: run '%s' %s", spec["name"], label, reason)
    summary = {
        "runs": {label: str(r.folder.relative_to(out_dir)) for label, r in reports.items()},
        "overrides": overrides,
        "status": "failed" if failed else "finished",
        "failed_runs": failed,
        "flags": flags,
        "table": table.to_dict(orient="records"),
    }
    summary.update({name: section.summary for name, section in sections.items()})
    return sections, summary


def failed_runs_markdown(failed: dict[str, str]) -> list[str]:
    """The ``table.md`` lines naming every failed run (none when every run finished)."""
    if not failed:
        return []
    rows = pd.DataFrame([{"run": label, "outcome": reason} for label, reason in failed.items()])
    return [f"## Failed runs ({len(failed)})", "", markdown_table(rows), ""]


def failed_runs_of(folder: Path) -> dict[str, str]:
    """The failed runs a published comparison folder's ``summary.json`` names."""
    summary = json.loads((Path(folder) / "summary.json").read_text())
    return dict(summary.get("failed_runs") or {})


def _check_runs(spec, extensions, path: Path, overrides: dict) -> None:
    """Load every run's scenario with its overrides, so bad input stops before any run."""
    from orchestrator.scenario import load_scenario

    for i, run in enumerate(spec["runs"]):
        scenario = path.parent / run["scenario"]
        load_scenario(scenario, _run_overrides(run, extensions, scenario, overrides, f"{path}: runs[{i}]"))


def _run_overrides(run, extensions, scenario: Path, overrides: dict, where: str) -> dict[str, Any]:
    """The comparison's overrides, then the run's own ``set``, then the extensions'."""
    merged = copy.deepcopy({**overrides, **run["set"]})
    for extension in extensions.values():
        merged.update(extension.run_overrides(scenario, merged, where))
    return merged


def _member_overrides(spec, value) -> dict[str, Any]:
    overrides = copy.deepcopy(spec["set"])
    if value is not None:
        overrides[spec["sweep"]["key"]] = value
    return overrides


def _write_section(section: Section, out_dir: Path) -> None:
    for name, frame in section.tables.items():
        frame.to_csv(out_dir / f"{name}.csv", index=False)


def comparison_table(spec: dict, summaries: dict[str, dict]) -> pd.DataFrame:
    """One row per metric: ours and the paper's value per run, and changes to the baseline."""
    analysis = spec["analysis"]
    rows = []
    baseline = spec.get("baseline")
    for metric in spec["metrics"]:
        row: dict[str, Any] = {"metric": metric}
        for run in spec["runs"]:
            label = run["label"]
            row[f"{label} (ours)"] = summaries[label].get("analyses", {}).get(analysis, {}).get(metric)
            if "paper" in run:
                row[f"{label} (paper)"] = run["paper"].get(metric)
        if baseline:
            for run in spec["runs"]:
                label = run["label"]
                if label == baseline:
                    continue
                for source in ("ours", "paper"):
                    value, reference = row.get(f"{label} ({source})"), row.get(f"{baseline} ({source})")
                    row[f"{label} vs {baseline} (% {source})"] = _change(value, reference)
        rows.append(row)
    return pd.DataFrame(rows)


def markdown_table(table: pd.DataFrame) -> str:
    header = "| " + " | ".join(str(c) for c in table.columns) + " |"
    rule = "|" + "|".join("---" for _ in table.columns) + "|"
    lines = [header, rule]
    for _, row in table.iterrows():
        lines.append("| " + " | ".join(_format(v) for v in row) + " |")
    return "\n".join(lines)


def slug(text: str) -> str:
    """A folder name for a label: letters, digits, ``-``, ``_``, ``=`` and ``.``."""
    return re.sub(r"[^A-Za-z0-9_.=-]+", "_", str(text)).strip("_") or "run"


def _change(value, reference):
    if not isinstance(value, (int, float)) or not isinstance(reference, (int, float)) or not reference:
        return None
    return 100.0 * (value - reference) / reference


def _format(value) -> str:
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "-"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, float):
        return f"{value:,.2f}" if abs(value) < 1e5 else f"{value:,.0f}"
    return str(value)


def _digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()
