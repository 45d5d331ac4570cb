"""Experiment 1: offline planning, cost-only (k2 = 0) against cost + emission (k2 = 1).

The fields are built once from the start point (offline: the guidance field's ship-goal
bearing is the start's) and each case descends its own superposition (Algorithm 1) for
N_L steps of ``step_nm``.  Results go to ``results/<name>/<run-id>/``:

* ``figure8_paths.png``: both paths over each case's field U (east horizontal, north
  vertical);
* ``figure9_field_energy.png``: U along each path (in its own case's field), and the
  normalised energy part k1 EC_bar + k2 EM_bar;
* ``paths.csv``: the path points of every case;
* ``table.csv``: per case, path length, sums of the field values EC [USD/h], EM [kg/h]
  and U at the path points (as the paper sums field energy along a path), and the
  voyage totals EC [USD] and EM [t] by the trapezoid rule in time along the path;
* ``summary.json``.

Scenario file (TOML, strict keys)::

    name = "exp1_cost_vs_emission"        # optional, default: the file's stem
    [metocean]                            # rhnc.weather.metocean_sources.from_scenario_table
    generator = "paper_default"
    [planner]
    start_nm = [0.0, 0.0]                 # north, east
    goal_nm = [100.0, 100.0]
    step_nm = 1.2                         # alpha
    horizon_steps = 110                   # N_L
    speed_kn = 18.0                       # v for the fields; delta = step / speed
    resolution_nm = 0.5                   # planning grid (default 1)
    guidance_eps = 1.0                    # optional
    guidance_c_rad = 1.0                  # optional
    [planner.energy]                      # optional EnergyParameters overrides
    [[cases]]
    name = "cost_only"
    k1 = 1.0
    k2 = 0.0
    k3 = 16.0
"""

from __future__ import annotations

import csv
import hashlib
import logging
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from orchestrator.participant import is_finite_number
from orchestrator.errors import ScenarioError
from orchestrator.scenario import read_toml
from rhnc.ship.energy import EnergyParameters
from rhnc.navigation.fields import FieldWeights, GuidanceParameters, SuperpositionField, resample_weather
from orchestrator.geometry import KNOT, NM
from rhnc.weather.metocean_sources import from_scenario_table
from rhnc.navigation.planner import plan_local_path

log = logging.getLogger(__name__)

TOP_KEYS = ("name", "metocean", "planner", "cases")
PLANNER_KEYS = ("start_nm", "goal_nm", "step_nm", "horizon_steps", "speed_kn", "resolution_nm",
                "guidance_eps", "guidance_c_rad", "energy")
CASE_KEYS = ("name", "k1", "k2", "k3")


def _reject(table: Mapping[str, Any], allowed, where: str) -> None:
    for key in table:
        if key not in allowed:
            raise ScenarioError(f"{where}: unknown key '{key}' (valid: {', '.join(sorted(allowed))})")


def _number(table: Mapping[str, Any], key: str, where: str, default=None, positive=False) -> float:
    if key not in table:
        if default is None:
            raise ScenarioError(f"{where}: missing key '{key}'")
        return float(default)
    value = table[key]
    if not is_finite_number(value):
        raise ScenarioError(f"{where}.{key}: expected a number, got {value!r}")
    if (positive and not value > 0) or value < 0:
        raise ScenarioError(f"{where}.{key}: must be {'positive' if positive else 'non-negative'}, got {value!r}")
    return float(value)


def _point(table: Mapping[str, Any], key: str, where: str) -> np.ndarray:
    value = table.get(key)
    if (not isinstance(value, list) or len(value) != 2
            or not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value)):
        raise ScenarioError(f"{where}.{key}: expected [north, east] in nm, got {value!r}")
    return np.array(value, dtype=float) * NM


def load_offline_scenario(path: Path) -> dict[str, Any]:
    """Read and check an offline planning TOML; errors name the file and the key."""
    path = Path(path)
    data, _ = read_toml(path, "scenario")
    where = str(path)
    _reject(data, TOP_KEYS, where)
    for key in ("metocean", "planner", "cases"):
        if key not in data:
            raise ScenarioError(f"{where}: missing table '{key}'")
    planner = data["planner"]
    pw = f"{where}: planner"
    if not isinstance(planner, dict):
        raise ScenarioError(f"{pw}: expected a table")
    _reject(planner, PLANNER_KEYS, pw)
    horizon = planner.get("horizon_steps")
    if isinstance(horizon, bool) or not isinstance(horizon, int) or horizon < 1:
        raise ScenarioError(f"{pw}.horizon_steps: expected a positive integer, got {horizon!r}")
    energy_table = planner.get("energy", {})
    if not isinstance(energy_table, dict):
        raise ScenarioError(f"{pw}.energy: expected a table")
    settings = {
        "name": data.get("name", path.stem),
        "start": _point(planner, "start_nm", pw),
        "goal": _point(planner, "goal_nm", pw),
        "step_m": _number(planner, "step_nm", pw, positive=True) * NM,
        "horizon_steps": horizon,
        "speed": _number(planner, "speed_kn", pw, positive=True) * KNOT,
        "resolution_nm": _number(planner, "resolution_nm", pw, default=1.0, positive=True),
        "guidance": GuidanceParameters(eps=_number(planner, "guidance_eps", pw, default=1.0, positive=True),
                                       c_rad=_number(planner, "guidance_c_rad", pw, default=1.0, positive=True)),
        "energy": EnergyParameters().with_overrides(energy_table, f"{pw}.energy"),
        "metocean": data["metocean"],
    }
    if not isinstance(settings["name"], str) or not settings["name"]:
        raise ScenarioError(f"{where}: name: expected a non-empty string")
    cases = data["cases"]
    if not isinstance(cases, list) or not cases:
        raise ScenarioError(f"{where}: cases: expected at least one [[cases]] table")
    parsed = []
    for index, case in enumerate(cases):
        cw = f"{where}: cases[{index}]"
        _reject(case, CASE_KEYS, cw)
        if not isinstance(case.get("name"), str) or not case["name"]:
            raise ScenarioError(f"{cw}.name: expected a non-empty string")
        parsed.append({"name": case["name"],
                       "weights": FieldWeights(k1=_number(case, "k1", cw), k2=_number(case, "k2", cw),
                                               k3=_number(case, "k3", cw))})
    names = [c["name"] for c in parsed]
    if len(set(names)) != len(names):
        raise ScenarioError(f"{where}: cases: names must be unique, got {names}")
    settings["cases"] = parsed
    settings["hash"] = hashlib.sha256(path.read_bytes()).hexdigest()
    return settings


def _path_length(points: np.ndarray) -> float:
    return float(np.linalg.norm(np.diff(points, axis=0), axis=1).sum())


def _plan_case(weather, settings: dict, case: dict) -> dict:
    """One case's field, planned path and the fields sampled along it."""
    field = SuperpositionField(weather, settings["goal"], settings["energy"], settings["guidance"],
                               case["weights"])
    field.update(settings["start"], settings["speed"])
    path = plan_local_path(field, settings["start"], settings["step_m"], settings["horizon_steps"])
    potential = field.potential()
    xs, ys = path.points[:, 0], path.points[:, 1]
    ec_field, em_field = field.ec, field.em
    assert ec_field is not None and em_field is not None  # built by the update above
    ec = field.sample(ec_field, xs, ys)
    em = field.sample(em_field, xs, ys)
    u = field.sample(potential, xs, ys)
    w = case["weights"]
    energy_part = field.sample(w.k1 * _normalised(ec_field) + w.k2 * _normalised(em_field), xs, ys)
    log.info("case %s: %d points, reached goal %s", case["name"], len(xs), path.reached_goal)
    return {"case": case, "path": path, "field": field, "potential": potential,
            "ec": ec, "em": em, "u": u, "energy_part": energy_part}


def run_offline_planning(scenario_path: Path, results_root: Path) -> Path:
    """Run an offline planning experiment (Experiment 1) and write its results.

    Parameters
    ----------
    scenario_path : Path
        The TOML file (format in this module's docstring).
    results_root : Path
        The ``results`` folder; the run goes to ``<results_root>/<name>/<run-id>/``.

    Returns
    -------
    Path
        The published run folder.
    """
    from orchestrator.results import RunFolder, new_run_id, versions

    scenario_path = Path(scenario_path)
    settings = load_offline_scenario(scenario_path)
    metocean = from_scenario_table(settings["metocean"], scenario_path.parent,
                                                 f"{scenario_path}: metocean")
    for label in ("start", "goal"):
        if not bool(metocean.contains(*settings[label])):
            raise ScenarioError(f"{scenario_path}: planner.{label}_nm lies outside the met-ocean map")
    weather = resample_weather(metocean, settings["resolution_nm"], t_s=0.0)  # planned before departure
    delta = settings["step_m"] / settings["speed"]

    results = [_plan_case(weather, settings, case) for case in settings["cases"]]

    run_id = new_run_id(settings["hash"])
    folder = RunFolder(results_root, settings["name"], run_id)
    try:
        rows = _write_tables(folder, results, settings, delta)
        _figure_paths(folder.path("figure8_paths.png"), weather, results, settings)
        _figure_energy(folder.path("figure9_field_energy.png"), results)
        folder.write_json("summary.json", {
            "scenario": str(scenario_path),
            "scenario_sha256": settings["hash"],
            "run_id": run_id,
            "kind": "offline_planning",
            "metocean": metocean.source,
            "planner": {
                "start_nm": (settings["start"] / NM).tolist(),
                "goal_nm": (settings["goal"] / NM).tolist(),
                "step_nm": settings["step_m"] / NM,
                "horizon_steps": settings["horizon_steps"],
                "speed_kn": settings["speed"] / KNOT,
                "delta_s": delta,
                "resolution_nm": settings["resolution_nm"],
                "guidance": vars(settings["guidance"]),
            },
            "energy_parameters": vars(settings["energy"]),
            "cases": rows,
            "versions": versions(),
        })
        return folder.publish()
    except BaseException:
        folder.discard()
        raise


def _normalised(field: np.ndarray) -> np.ndarray:
    from rhnc.navigation.fields import normalise

    return normalise(field)


def _write_tables(folder, results, settings, delta: float) -> list[dict[str, Any]]:
    rows = []
    with open(folder.path("paths.csv"), "w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(["case", "k", "t_s", "x_nm", "y_nm", "ec_usd_h", "em_kg_h", "u"])
        for res in results:
            for k, (point, ec, em, u) in enumerate(zip(res["path"].points, res["ec"], res["em"], res["u"])):
                writer.writerow([res["case"]["name"], k, f"{k * delta:.1f}", f"{point[0] / NM:.5f}",
                                 f"{point[1] / NM:.5f}", f"{ec:.3f}", f"{em:.3f}", f"{u:.6f}"])
    for res in results:
        points = res["path"].points
        moving = np.r_[True, np.any(np.diff(points, axis=0) != 0, axis=1)]
        last = int(np.nonzero(moving)[0][-1])  # stop accounting when the path rests at the goal
        hours = delta / 3600.0
        w = res["case"]["weights"]
        rows.append({
            "case": res["case"]["name"], "k1": w.k1, "k2": w.k2, "k3": w.k3,
            "path_length_nm": _path_length(points) / NM,
            "reached_goal": bool(res["path"].reached_goal),
            "final_goal_distance_nm": float(np.hypot(*(settings["goal"] - points[-1]))) / NM,
            "sum_ec_usd_h": float(res["ec"].sum()),
            "sum_em_kg_h": float(res["em"].sum()),
            "sum_u": float(res["u"].sum()),
            "voyage_ec_usd": float(np.trapezoid(res["ec"][: last + 1], dx=hours)),
            "voyage_em_t": float(np.trapezoid(res["em"][: last + 1], dx=hours)) / 1000.0,
            "trapped_at_step": res["path"].trapped_at,
            "border_steps": res["path"].border_steps,
        })
    with open(folder.path("table.csv"), "w", newline="") as handle:
        table = csv.DictWriter(handle, fieldnames=list(rows[0]))
        table.writeheader()
        table.writerows(rows)
    return rows


COLOURS = ("tab:red", "tab:blue", "tab:green", "tab:orange")


def _figure_paths(target: Path, weather, results, settings) -> None:
    from matplotlib.figure import Figure

    fig = Figure(figsize=(6.0 * len(results), 5.2), constrained_layout=True)
    axes = fig.subplots(1, len(results), squeeze=False)[0]
    east, north = weather.y / NM, weather.x / NM
    for ax, res in zip(axes, results):
        mesh = ax.pcolormesh(east, north, res["potential"], shading="auto", cmap="viridis")
        fig.colorbar(mesh, ax=ax, label="superposed field U [-]")
        for colour, other in zip(COLOURS, results):
            pts = other["path"].points / NM
            ax.plot(pts[:, 1], pts[:, 0], color=colour, lw=2.0 if other is res else 1.2,
                    label=f"{other['case']['name']} (k2 = {other['case']['weights'].k2:g})")
        ax.plot(*(settings["start"][::-1] / NM), "wo", ms=6)
        ax.plot(*(settings["goal"][::-1] / NM), "w*", ms=12)
        ax.set_xlabel("east [nm]")
        ax.set_ylabel("north [nm]")
        ax.set_aspect("equal")
        ax.set_title(f"U of case {res['case']['name']}")
        ax.legend(loc="lower right", fontsize=8)
    fig.suptitle("Experiment 1 (paper Fig. 8): paths planned offline")
    fig.savefig(target, dpi=120)


def _figure_energy(target: Path, results) -> None:
    from matplotlib.figure import Figure

    fig = Figure(figsize=(7.0, 6.0), constrained_layout=True)
    top, bottom = fig.subplots(2, 1, sharex=True)
    for colour, res in zip(COLOURS, results):
        label = f"{res['case']['name']} (k2 = {res['case']['weights'].k2:g})"
        top.plot(res["u"], color=colour, label=label)
        bottom.plot(res["energy_part"], color=colour, label=label)
    top.set_ylabel("U at path point [-]")
    bottom.set_ylabel("k1 EC_bar + k2 EM_bar [-]")
    bottom.set_xlabel("path point k")
    top.legend()
    top.set_title("Experiment 1 (paper Fig. 9): field energy along each path")
    fig.savefig(target, dpi=120)
