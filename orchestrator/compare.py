"""Run several scenarios and tabulate one analysis side by side, next to published figures.

A comparison file (TOML), e.g. ``scenarios/exp2_table3.toml`` for the paper's Table 3::

    name = "exp2_table3"
    analysis = "voyage"                          # which analysis of each run to tabulate
    metrics = ["cost_usd", "co2_t", "cost_per_nm_usd", "co2_per_nm_kg"]
    baseline = "Offline-SPNC"                    # relative changes are taken against it

    [[runs]]
    label = "RHNC"
    scenario = "exp2_rhnc.toml"                  # relative to this file
    paper = { cost_usd = 10473, co2_t = 31.264 } # published values, optional
    figures = { "navigation_fields.png" = "figure10_fields.png" }   # copied, renamed

``python -m orchestrator compare FILE`` runs every scenario into
``results/<name>/<run-id>/runs/``, then writes ``table.csv`` and ``table.md`` (ours and the
paper's value of each metric per run, and each run's change against the baseline),
``tracks.png`` (all tracks over the met-ocean field) and the copied figures.
"""

from __future__ import annotations

import logging
import math
import shutil
from pathlib import Path
from typing import Any

import pandas as pd

from orchestrator.errors import ScenarioError
from orchestrator.scenario import read_toml

log = logging.getLogger(__name__)

KEYS = ("name", "analysis", "metrics", "baseline", "runs")
RUN_KEYS = ("label", "scenario", "paper", "figures")


def load_comparison(path: Path) -> dict[str, Any]:
    """Read and check a comparison file; errors name the file and the key."""
    data, _ = read_toml(path, "comparison")
    for key in data:
        if key not in KEYS:
            raise ScenarioError(f"{path}: unknown key '{key}' (valid: {', '.join(KEYS)})")
    for key in ("name", "analysis"):
        if not isinstance(data.get(key), str):
            raise ScenarioError(f"{path}: '{key}' must be a string")
    metrics = data.get("metrics")
    if not isinstance(metrics, list) or not metrics or not all(isinstance(m, str) for m in metrics):
        raise ScenarioError(f"{path}: 'metrics' must be a non-empty list of names")
    runs = data.get("runs")
    if not isinstance(runs, list) or not runs:
        raise ScenarioError(f"{path}: at least one [[runs]] table is needed")
    labels = []
    for i, run in enumerate(runs):
        where = f"{path}: runs[{i}]"
        for key in run:
            if key not in RUN_KEYS:
                raise ScenarioError(f"{where}: unknown key '{key}' (valid: {', '.join(RUN_KEYS)})")
        if not isinstance(run.get("label"), str) or not isinstance(run.get("scenario"), str):
            raise ScenarioError(f"{where}: 'label' and 'scenario' must be strings")
        scenario = path.parent / run["scenario"]
        if not scenario.is_file():
            raise ScenarioError(f"{where}.scenario: scenario file not found: {scenario}")
        for key in run.get("paper", {}):
            if key not in metrics:
                raise ScenarioError(f"{where}.paper: '{key}' is not one of the metrics")
        labels.append(run["label"])
    if "baseline" in data and data["baseline"] not in labels:
        raise ScenarioError(f"{path}: baseline '{data['baseline']}' is not a run label ({', '.join(labels)})")
    return data


def run_comparison(path, results_root="results", progress: bool = True) -> Path:
    """Run the comparison in ``path``; return the folder with the table and figures."""
    from orchestrator.results import RunFolder, new_run_id
    from orchestrator.run import run_scenario

    path = Path(path)
    spec = load_comparison(path)
    folder = RunFolder(Path(results_root), spec["name"], new_run_id(_digest(path)))
    try:
        reports = {}
        for run in spec["runs"]:
            report = run_scenario(path.parent / run["scenario"], folder.staging / "runs", progress=progress)
            reports[run["label"]] = report
            for source, target in run.get("figures", {}).items():
                if (report.folder / source).is_file():
                    shutil.copyfile(report.folder / source, folder.path(target))
        table = comparison_table(spec, {label: r.summary for label, r in reports.items()})
        table.to_csv(folder.path("table.csv"), index=False)
        folder.path("table.md").write_text(markdown_table(table) + "\n")
        _tracks_figure(spec, reports, folder.path("tracks.png"))
        failed = {label: r.reason for label, r in reports.items() if not r.ok}
        folder.write_json("summary.json", {
            "comparison": str(path.resolve()),
            "runs": {label: str(r.folder.relative_to(folder.staging)) for label, r in reports.items()},
            "status": "failed" if failed else "finished",
            "failed_runs": failed,
            "table": table.to_dict(orient="records"),
        })
    except BaseException:
        folder.discard()
        raise
    return folder.publish()


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
    header = "| " + " | ".join(table.columns) + " |"
    rule = "|" + "|".join("---" for _ in table.columns) + "|"
    lines = [header, rule]
    for _, row in table.iterrows():
        lines.append("| " + " | ".join(_format(v) for v in row) + " |")
    return "\n".join(lines)


def _change(value, reference):
    if not isinstance(value, (int, float)) or not isinstance(reference, (int, float)) or not reference:
        return None
    return 100.0 * (value - reference) / reference


def _format(value) -> str:
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "-"
    if isinstance(value, float):
        return f"{value:,.2f}" if abs(value) < 1e5 else f"{value:,.0f}"
    return str(value)


def _digest(path: Path) -> str:
    import hashlib

    return hashlib.sha256(path.read_bytes()).hexdigest()


def _tracks_figure(spec, reports, target: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from rhnc.metocean import NM, MetOceanField

    fig, ax = plt.subplots(figsize=(7, 6))
    first = next(iter(reports.values())).folder / "metocean.nc"
    if first.is_file():
        field = MetOceanField.from_netcdf(first).snapshot(0.0)  # at departure when it varies in time
        mesh = ax.pcolormesh(field.y / NM, field.x / NM, field.wind_speed, shading="auto", cmap="viridis")
        fig.colorbar(mesh, ax=ax, label="wind speed [m/s]")
    for (label, report), colour in zip(reports.items(), ("tab:red", "white", "tab:orange", "tab:cyan")):
        frame = pd.read_parquet(report.folder / "timeseries.parquet") if (
            report.folder / "timeseries.parquet").is_file() else pd.read_csv(report.folder / "timeseries.csv")
        plant = next(c[:-2] for c in frame.columns if c.endswith(".x") and f"{c[:-2]}.psi" in frame.columns)
        ax.plot(frame[f"{plant}.y"] / NM, frame[f"{plant}.x"] / NM, color=colour, lw=2, label=label)
    ax.set_xlabel("east [nm]")
    ax.set_ylabel("north [nm]")
    ax.set_aspect("equal")
    ax.legend(loc="lower right")
    ax.set_title(f"{spec['name']}: tracks")
    fig.tight_layout()
    fig.savefig(target, dpi=120)
    plt.close(fig)
