"""What a search writes besides its runs: the table, the progress, the boundary per parameter, the worst cases.

* ``summary.parquet``/``.csv``: the batch table's columns (:func:`orchestrator.batch.batch_table`)
  with ``evaluation`` (counted from 1), ``objective`` and ``failure``, in the order evaluated;
* ``progress.png``: the objective per evaluation, the lowest so far, the failure threshold;
* ``boundary.csv`` and ``boundary.png``: for each parameter, its range cut into bins (a
  choice: its values), with the runs, the lowest and the median objective and the fraction
  of failures in each bin: where along that parameter the failures lie;
* ``worst/NN-<run-id>.toml``: the worst evaluations (lowest objective), each a one-run batch
  file of the same base scenario and overrides, so ``python -m orchestrator batch`` on it
  reruns exactly that run (the same run id) without the search.
"""

from __future__ import annotations

import json
import math
import os
import shutil
from pathlib import Path

from orchestrator.batch import batch_table, write_table
from orchestrator.search_spec import SearchSpec

#: Bins of a number's range in the boundary summary.
BOUNDARY_BINS = 8


def search_table(spec: SearchSpec, root: Path, journal: list[dict]):
    """One row per journaled evaluation, with its objective and whether it is a failure."""
    import pandas as pd

    from orchestrator.search_journal import objective_of, run_spec_of

    runs = [run_spec_of(entry) for entry in journal]
    if not runs:
        return pd.DataFrame(columns=["run_id", "evaluation", "status", "objective", "failure", "passed"])
    table = batch_table(spec.batch, root, runs).rename(columns={"index": "evaluation"})
    table = table.drop(columns=["param:evaluation"], errors="ignore")
    table["evaluation"] = table["evaluation"] + 1  # counted from 1, as a person counts them
    table["objective"] = [objective_of(spec, root, run.run_id) for run in runs]
    table["objective"] = table["objective"].astype(float)
    table["failure"] = [spec.is_failure(None if math.isnan(v) else v, bool(p))
                        for v, p in zip(table["objective"], table["passed"])]
    return table


def findings(spec: SearchSpec, table) -> dict:
    """``first_failure`` (evaluations up to and including the first failure), ``failures``, ``best``."""
    failed = table[table["failure"].astype(bool)] if len(table) else table
    values = table["objective"].dropna() if len(table) else []
    return {"first_failure": int(failed["evaluation"].min()) if len(failed) else None,
            "failures": int(len(failed)), "best": float(min(values)) if len(values) else None,
            "objective": spec.objective}


def write_outputs(spec: SearchSpec, root: Path, journal: list[dict]):
    """Table, progress figure, boundary summary and worst cases of the search in ``root``; returns the table."""
    table = search_table(spec, root, journal)
    write_table(table, root)
    write_progress(spec, table, root / "progress.png")
    boundary = boundary_summary(spec, table)
    staging = root / ".boundary.csv.partial"
    boundary.to_csv(staging, index=False)
    os.replace(staging, root / "boundary.csv")
    write_boundary_figure(spec, table, boundary, root / "boundary.png")
    write_worst(spec, table, root)
    return table


def write_progress(spec: SearchSpec, table, target: Path) -> Path:
    """Objective per evaluation (failures in red), the lowest so far, and the failure threshold."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(9, 4.5), layout="constrained")
    ax = fig.subplots()
    if len(table):
        done = table.dropna(subset=["objective"])
        failure = done["failure"].astype(bool)
        ax.scatter(done["evaluation"][~failure], done["objective"][~failure], s=14, color="tab:blue",
                   label="evaluation")
        ax.scatter(done["evaluation"][failure], done["objective"][failure], s=18, color="tab:red",
                   label="failure")
        ax.step(done["evaluation"], done["objective"].cummin(), where="post", color="black", lw=1.2,
                label="lowest so far")
    if spec.fails_below is not None:
        ax.axhline(spec.fails_below, color="tab:red", ls="--", lw=1, label=f"fails below {spec.fails_below:g}")
    ax.set_xlabel("evaluation")
    ax.set_ylabel(spec.objective, fontsize=8)
    ax.set_title(f"{spec.name}: {spec.sampler}, seed {spec.seed}")
    ax.legend(fontsize=8)
    fig.savefig(target, dpi=100)
    return target


def boundary_summary(spec: SearchSpec, table):
    """Per parameter and bin: runs, lowest and median objective, failures and their fraction."""
    import numpy as np
    import pandas as pd

    rows = []
    for name, declared in spec.space.items():
        column = f"param:{name}"
        if column not in table.columns:
            continue
        values = table[column]
        numeric = (len(declared) == 2 and all(isinstance(v, (int, float)) and not isinstance(v, bool)
                                              for v in declared) and name not in _choices(spec))
        if numeric:
            edges = np.linspace(float(declared[0]), float(declared[1]), BOUNDARY_BINS + 1)
            index = np.clip(np.searchsorted(edges, pd.to_numeric(values), side="right") - 1, 0, BOUNDARY_BINS - 1)
            groups = [(f"[{edges[i]:.4g}, {edges[i + 1]:.4g}]", edges[i], edges[i + 1], values.notna() & (index == i))
                      for i in range(BOUNDARY_BINS)]
        else:
            groups = [(str(option), None, None, values.astype(str) == str(option)) for option in declared]
        for label, low, high, mask in groups:
            chosen = table[mask]
            objective = chosen["objective"].dropna()
            failures = int(chosen["failure"].astype(bool).sum())
            rows.append({"parameter": name, "bin": label, "low": low, "high": high, "runs": len(chosen),
                         "min_objective": float(objective.min()) if len(objective) else None,
                         "median_objective": float(objective.median()) if len(objective) else None,
                         "failures": failures, "failure_fraction": failures / len(chosen) if len(chosen) else None})
    return pd.DataFrame(rows, columns=["parameter", "bin", "low", "high", "runs", "min_objective",
                                       "median_objective", "failures", "failure_fraction"])


def _choices(spec: SearchSpec) -> set[str]:
    """Parameters that are choices between values (even two numbers), not ranges."""
    mc = spec.batch.monte_carlo
    names = set(mc.choice)
    names.update(f"enc{k}.type" for k in range(len(mc.encounters)))
    names.update(f"enc{k}.passing_side" for k in range(len(mc.encounters)))
    return names


def write_boundary_figure(spec: SearchSpec, table, boundary, target: Path) -> Path:
    """One panel per parameter: every evaluation's objective, the lowest per bin, the threshold."""
    import numpy as np
    from matplotlib.figure import Figure

    names = [n for n in spec.space if f"param:{n}" in table.columns]
    columns = min(4, max(1, len(names)))
    rows = max(1, math.ceil(len(names) / columns))
    fig = Figure(figsize=(3.2 * columns, 2.6 * rows), layout="constrained")
    axes = np.atleast_1d(fig.subplots(rows, columns)).ravel()
    for ax, name in zip(axes, names):
        part = boundary[boundary["parameter"] == name]
        done = table.dropna(subset=["objective"])
        failure = done["failure"].astype(bool)
        if part["low"].notna().any():
            x = done[f"param:{name}"].astype(float)
            ax.scatter(x[~failure], done["objective"][~failure], s=8, color="tab:blue", alpha=0.6)
            ax.scatter(x[failure], done["objective"][failure], s=10, color="tab:red")
            centres = (part["low"].astype(float) + part["high"].astype(float)) / 2
            ax.plot(centres, part["min_objective"].astype(float), color="black", marker=".", lw=1)
        else:
            labels = list(part["bin"])
            position = {label: i for i, label in enumerate(labels)}
            x = done[f"param:{name}"].astype(str).map(position)
            ax.scatter(x[~failure], done["objective"][~failure], s=8, color="tab:blue", alpha=0.6)
            ax.scatter(x[failure], done["objective"][failure], s=10, color="tab:red")
            ax.set_xticks(range(len(labels)), labels, fontsize=7, rotation=20)
        if spec.fails_below is not None:
            ax.axhline(spec.fails_below, color="tab:red", ls="--", lw=0.8)
        ax.set_title(name, fontsize=8)
    for ax in axes[len(names):]:
        ax.axis("off")
    fig.suptitle(f"{spec.objective} over each parameter (red: failures; line: lowest per bin)", fontsize=9)
    fig.savefig(target, dpi=90)
    return target


def write_worst(spec: SearchSpec, table, root: Path) -> list[Path]:
    """The ``worst`` evaluations with the lowest objective, as one-run batch files in ``root/worst/``."""
    folder = root / "worst"
    shutil.rmtree(folder, ignore_errors=True)
    folder.mkdir()
    if not len(table) or not spec.worst:
        return []
    ranked = table.dropna(subset=["objective"]).sort_values(["objective", "evaluation"]).head(spec.worst)
    written = []
    manifest = {run["run_id"]: run for run in _journal_runs(root)}
    scenario = os.path.relpath(spec.batch.scenario, folder)
    for rank, (_, row) in enumerate(ranked.iterrows(), start=1):
        entry = manifest[row["run_id"]]
        evaluation = int(row["evaluation"])
        lines = [f"# Evaluation {evaluation} of the search {spec.name}: {spec.objective} = "
                 f"{row['objective']:.6g} (worst {rank} of {len(table)}).",
                 f"# Rerun: python -m orchestrator batch {folder.name}/{rank:02d}-{row['run_id']}.toml",
                 "[batch]", f"name = {_toml(f'{spec.name}_worst{rank:02d}')}", f"scenario = {_toml(scenario)}",
                 f"description = {_toml(f'evaluation {evaluation} of {spec.name}')}", "", "[set]"]
        lines += [f"{_toml(key)} = {_toml(value)}" for key, value in entry["overrides"].items()]
        for criterion in spec.batch.acceptance:
            lines += ["", "[[acceptance]]", f"name = {_toml(criterion.name)}", f"metric = {_toml(criterion.metric)}",
                      f"op = {_toml(criterion.op)}"]
            lines.append(f"ref = {_toml(criterion.ref)}" if criterion.ref is not None
                         else f"value = {_toml(criterion.value)}")
        target = folder / f"{rank:02d}-{row['run_id']}.toml"
        target.write_text("\n".join(lines) + "\n")
        written.append(target)
    return written


def _journal_runs(root: Path) -> list[dict]:
    from orchestrator.search_journal import JOURNAL, read_journal

    return read_journal(root / JOURNAL)


def _toml(value) -> str:
    """A TOML value: strings as basic strings, tables inline, numbers as they are."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, float)):
        if isinstance(value, float) and not math.isfinite(value):
            raise ValueError(f"not a TOML number: {value}")
        return repr(value)
    if isinstance(value, str):
        return json.dumps(value, ensure_ascii=False)
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_toml(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{ " + ", ".join(f"{_toml(str(k))} = {_toml(v)}" for k, v in value.items()) + " }"
    raise ValueError(f"no TOML form for {type(value).__name__}")
