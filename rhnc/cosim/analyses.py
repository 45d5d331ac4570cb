"""The ship analyses a scenario names in ``[outputs] analyses``: manoeuvres, voyage, encounter.

Registered in the entry-point group ``rhnc_cosim.analyses`` (``pyproject.toml``); each is
``function(frame, scenario, cosim, out_dir, **options) -> dict`` (:mod:`orchestrator.analyses`).
The plant is the participant whose outputs include the ship state (x, y, psi).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from orchestrator.analyses import array_output, driver_column
from orchestrator.errors import ScenarioError, ToolchainError
from orchestrator.geometry import KNOT, NM
from rhnc.cosim.obstacle_ports import true_obstacles_column
from rhnc.cosim.plant import own_radius_m, plant_name, steering_column, tau_column

#: The ship whose particulars (ships/<name>.toml) apply when the plant does not say.
DEFAULT_SHIP = "KCS"


def _execute_time(frame, column) -> float:
    moving = np.nonzero(np.abs(frame[column].to_numpy()) > 0)[0]
    if moving.size == 0:
        raise ToolchainError(f"{column} is zero throughout: no manoeuvre to analyse")
    return float(frame["time_s"].iloc[moving[0]])


def _ship_length(cosim, plant) -> float:
    """The plant's ``lpp`` parameter when the scenario sets it, else the ship's particulars."""
    from rhnc.ship.ships import load_ship

    parameters = getattr(cosim.participant(plant), "parameters", {})
    return float(parameters.get("lpp", parameters.get("length_m", load_ship(DEFAULT_SHIP).lpp_m)))


def turning_circle_analysis(frame, scenario, cosim, out_dir) -> dict:
    from rhnc.ship.manoeuvres import turning_circle

    plant = plant_name(cosim)
    column, kind = steering_column(frame, scenario, plant)
    execute = _execute_time(frame, column)
    x, y, psi = (frame[f"{plant}.{c}"].to_numpy() for c in ("x", "y", "psi"))
    figures = turning_circle(frame["time_s"].to_numpy(), x, y, psi, execute_s=execute,
                             length_m=_ship_length(cosim, plant))
    figures["execute_s"] = execute
    figures["steered_by"] = kind
    figures["approach_speed_kn"] = float(frame[f"{plant}.u"].iloc[int(np.searchsorted(frame["time_s"], execute))]
                                         / KNOT)
    from rhnc.cosim.figures import manoeuvre_figure

    manoeuvre_figure(frame, plant, figures, out_dir / "turning_circle.png", "Turning circle")
    return figures


def zigzag_analysis(frame, scenario, cosim, out_dir) -> dict:
    from rhnc.ship.manoeuvres import zigzag

    plant = plant_name(cosim)
    column, kind = steering_column(frame, scenario, plant)
    execute = _execute_time(frame, column)
    figures = zigzag(frame["time_s"].to_numpy(), frame[f"{plant}.psi"].to_numpy(), frame[column].to_numpy(),
                     execute_s=execute)
    figures["execute_s"] = execute
    figures["steered_by"] = kind
    from rhnc.cosim.figures import zigzag_figure

    zigzag_figure(frame, plant, column, out_dir / "zigzag.png", kind)
    return figures


def voyage_analysis(frame, scenario, cosim, out_dir, goal_nm=None, arrival_radius_nm: float = 0.5,
                    cii_year: int = 2026) -> dict:
    """Cost, CO2 per nm and CII of the sailed track (:mod:`rhnc.voyage.voyage`).

    The weather is what the plant met: the outputs of the participant driving the
    plant's ``hs`` input (the environment FMU), else the scenario's met-ocean field at the
    ship's positions and times, else calm water.  The energy constants are the navigation
    participant's (so a scenario's overrides apply), else the defaults.

    The brake power is the plant's own when it reports ``delivered_power`` (an
    actuator-level plant: delivered power / shaft efficiency + auxiliary power), else the
    energy model's from speed, heading and weather; ``energy_source`` says which.

    With ``goal_nm = [north, east]`` the voyage ends on arrival, the instant the ship
    crosses ``arrival_radius_nm`` of the goal, interpolated between the samples around it
    (:func:`cut_at_crossing`; time spent waiting there is not sailing); the result says
    whether and when the ship arrived.  ``made_good_nm`` is the straight-line
    distance from the first to the last position of the voyage, the paper's "linear
    mileage" in its Table 3, next to the distance sailed along the track;
    ``mean_speed_made_good_kn`` divides it by the time taken, and
    ``mean_speed_through_water_kn`` is the time-averaged ``hypot(u, v)`` of the plant.
    """
    from rhnc.ship.energy import EnergyParameters
    from rhnc.voyage.voyage import account_voyage, mean_speed_through_water_kn

    plant = plant_name(cosim)
    x, y = frame[f"{plant}.x"].to_numpy(), frame[f"{plant}.y"].to_numpy()
    try:
        environment = driver_column(scenario, plant, "hs").split(".")[0]
        weather = {name: frame[f"{environment}.{name}"].to_numpy() for name in ("wind_north", "wind_east", "hs")}
    except (ToolchainError, KeyError):
        if cosim.metocean is not None:
            weather = cosim.metocean.sample(x, y, t_s=frame["time_s"].to_numpy())
        else:
            weather = {name: np.zeros_like(x) for name in ("wind_north", "wind_east", "hs")}
    energy = next((p.energy for p in cosim.participants if isinstance(getattr(p, "energy", None), EnergyParameters)),
                  EnergyParameters())
    series = {"time_s": frame["time_s"].to_numpy(dtype=float), "x": x, "y": y,
              "u": frame[f"{plant}.u"].to_numpy(dtype=float),
              "v": frame[f"{plant}.v"].to_numpy(dtype=float) if f"{plant}.v" in frame.columns else np.zeros(len(x)),
              "psi": np.unwrap(frame[f"{plant}.psi"].to_numpy(dtype=float)),
              **{name: np.asarray(weather[name], dtype=float) for name in ("wind_north", "wind_east", "hs")}}
    if f"{plant}.delivered_power" in frame.columns:
        series["brake_power"] = (frame[f"{plant}.delivered_power"].to_numpy(dtype=float) / energy.shaft_efficiency
                                 + energy.auxiliary_power_w)
    arrival: dict[str, Any] = {}
    if goal_nm is not None:
        try:
            goal = np.asarray(goal_nm, dtype=float).reshape(2) * NM
        except (TypeError, ValueError) as exc:
            raise ScenarioError(f"{scenario.path}: 'outputs.options.voyage.goal_nm' must be [north, east]") from exc
        distance = np.hypot(x - goal[0], y - goal[1])
        inside = np.nonzero(distance <= arrival_radius_nm * NM)[0]
        arrival["arrived"] = bool(inside.size)
        arrival["goal_distance_end_nm"] = float(distance[-1] / NM)
        if inside.size:
            series = cut_at_crossing(series, distance, inside[0], arrival_radius_nm * NM)
        arrival["arrival_time_min"] = float(series["time_s"][-1] / 60.0) if inside.size else None
    account = account_voyage(series["time_s"], series["x"], series["y"], series["u"], series["psi"],
                             series["wind_north"], series["wind_east"], series["hs"], energy, cii_year=cii_year,
                             brake_power_w=series.get("brake_power"))
    result = account.as_dict()
    result["energy_source"] = ("plant delivered_power" if "brake_power" in series
                               else "energy model (speed, heading, weather)")
    made_good = float(np.hypot(series["x"][-1] - x[0], series["y"][-1] - y[0]) / NM)
    result["made_good_nm"] = made_good
    duration_h = account.time_min / 60.0
    result["mean_speed_through_water_kn"] = mean_speed_through_water_kn(series["time_s"], series["u"], series["v"])
    result["mean_speed_made_good_kn"] = made_good / duration_h if duration_h > 0 else None
    result["cost_per_made_good_nm_usd"] = account.cost_usd / made_good if made_good > 0 else None
    result["co2_per_made_good_nm_kg"] = account.co2_t * 1000.0 / made_good if made_good > 0 else None
    result.update(arrival)
    return result


def cut_at_crossing(series: dict[str, np.ndarray], distance: np.ndarray, first_inside: int,
                    radius_m: float) -> dict[str, np.ndarray]:
    """``series`` (equal-length arrays by name) up to the instant the ship crosses the
    arrival radius: the samples before ``first_inside`` and one more, interpolated
    linearly between the samples around the crossing (by the goal distance).

    The voyage ends on arrival, and on the macro-step grid the first sample inside the
    radius comes up to a step after it: two voyages arriving in the same minute may be
    nearly a minute apart, worth a few tenths of a percent of an 8 h passage's fuel."""
    if first_inside == 0:
        return {name: values[:1] for name, values in series.items()}
    before, after = distance[first_inside - 1], distance[first_inside]
    fraction = 1.0 if before <= after else float(np.clip((before - radius_m) / (before - after), 0.0, 1.0))
    return {name: np.append(values[:first_inside],
                            values[first_inside - 1] + fraction * (values[first_inside] - values[first_inside - 1]))
            for name, values in series.items()}


def encounter_analysis(frame, scenario, cosim, out_dir) -> dict:
    """Minimum separation against R + R_i per obstacle, input bounds, return to the track.

    The obstacles are the true ones (:func:`rhnc.cosim.obstacle_ports.true_obstacles_column`:
    the array feeding an ``obstacles`` input, or the truth behind a tracker feeding it); the
    reference is the array feeding a ``reference`` input, interpolated at each sample's
    time.  Cross-track error is measured from that point across the reference course;
    "back on track" is the first time after the closest approach from which it stays
    within 0.2 nm.
    """
    from rhnc.encounters.encounter import cross_track_error, reference_at_times, separations, time_back_on_track

    plant = plant_name(cosim)
    t = frame["time_s"].to_numpy()
    x, y = frame[f"{plant}.x"].to_numpy(), frame[f"{plant}.y"].to_numpy()
    sources = {c.target_port: f"{c.source}.{c.source_port}" for c in scenario.connections}
    result: dict = {}
    true_obstacles = true_obstacles_column(scenario, cosim)  # a tracker's estimates are not what was passed
    if true_obstacles is not None:
        obstacles = array_output(frame, true_obstacles)
        per_obstacle = separations(t, x, y, obstacles, own_radius_m(cosim))
        result["obstacles"] = per_obstacle
        result["min_clearance_nm"] = min(o["min_clearance_nm"] for o in per_obstacle)
        result["separation_respected"] = bool(result["min_clearance_nm"] >= -1e-6)
        passed_at = max(o["time_of_min_s"] for o in per_obstacle)
    else:
        passed_at = float(t[0])
    for port in ("tau_u", "tau_r"):
        column = tau_column(scenario, port)
        if column is None or column not in frame.columns:
            continue  # steered at actuator level by a script: no tau demanded
        bound = getattr(cosim.participant(plant), "parameters", {}).get(f"{port}_max")
        peak = float(np.max(np.abs(frame[column].to_numpy())))
        result[f"{port}_max_abs"] = peak
        if bound is not None:
            result[f"{port}_within_bound"] = bool(peak <= float(bound) * (1 + 1e-9))
        # an allocation between the NMPC and an actuator-level plant reports what it achieved
        achieved = next((c for c in frame.columns if c.endswith(f".{port}_achieved")), None)
        if achieved is not None:
            result[f"{port}_achieved_max_abs"] = float(np.max(np.abs(frame[achieved].to_numpy())))
    for output, key, scale in (("rudder_angle", "rudder_max_abs_deg", 180.0 / np.pi),
                               ("propeller_rps", "propeller_rps_max", 1.0)):
        if f"{plant}.{output}" in frame.columns:  # what the plant's actuators did
            result[key] = float(np.max(np.abs(frame[f"{plant}.{output}"].to_numpy())) * scale)
    if "reference" in sources:
        reference = reference_at_times(array_output(frame, sources["reference"]), t)
        cross = cross_track_error(x, y, reference[:, 0], reference[:, 1], reference[:, 2])
        after = t >= passed_at
        result["cross_track_end_nm"] = float(abs(cross[-1]) / NM)
        result["cross_track_max_after_passing_nm"] = float(np.max(np.abs(cross[after])) / NM)
        result["back_on_track_s"] = time_back_on_track(t, cross, passed_at, 0.2 * NM)
        result["passed_at_s"] = passed_at
    return result
