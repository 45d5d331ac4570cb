"""Figures of a run (matplotlib, Agg backend): east on the horizontal axis, north vertical.

matplotlib is imported with this module: the orchestrator imports a figure's function
before it forks the process drawing it (:mod:`orchestrator.figure_processes`), so that the
figures of a run share one import.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from orchestrator.geometry import NM


def _figure(width_in: float, height_in: float, margins_in: tuple[float, float, float, float] | None = None,
            **spacing) -> Figure:
    """A figure drawn by the Agg canvas alone (pyplot is never imported: no global figure list to close).

    ``margins_in``: (left, bottom, right, top) [in] fixed around the axes grid, with
    ``spacing`` (``wspace``, ``hspace``) between its cells: a fixed layout costs nothing
    to draw, where ``tight_layout`` measures every text of the figure once more.  None:
    the caller lays the figure out itself.
    """
    figure = Figure(figsize=(width_in, height_in))
    FigureCanvasAgg(figure)
    if margins_in is not None:
        left, bottom, right, top = margins_in
        figure.subplots_adjust(left=left / width_in, bottom=bottom / height_in, right=1.0 - right / width_in,
                               top=1.0 - top / height_in, **spacing)
    return figure


def track_figure(frame, scenario, cosim, out_dir) -> list[str]:
    """The ship's track over the met-ocean wind speed (when the run has a field).

    Time marks every few minutes along every track; each obstacle drawn (with its hazard
    circle) where it was when the own ship came closest to it, and the closest-approach
    segment marked with its range and time.
    """
    from rhnc.cosim.plant import find_plant

    plant = find_plant(cosim)
    if plant is None:
        return []  # no ship in this scenario: no track to draw
    if f"{plant}.x" not in frame.columns:
        return []  # the run failed before the ship reported a position
    field = cosim.metocean
    fig = _figure(7, 6, (0.75, 0.5, 0.2, 0.3))
    ax = fig.subplots()
    if field is not None:
        departure_s = float(frame["time_s"].iloc[0])
        mesh = ax.pcolormesh(field.y / NM, field.x / NM, field.snapshot(departure_s).wind_speed, shading="auto",
                             cmap="viridis")
        fig.colorbar(mesh, ax=ax, label="wind speed at departure [m/s]" if field.is_time_varying
                     else "wind speed [m/s]")
    _draw_reference(ax, frame, scenario)
    ax.plot(frame[f"{plant}.y"] / NM, frame[f"{plant}.x"] / NM, color="tab:red", lw=2, label=f"{plant} track")
    ax.plot(frame[f"{plant}.y"].iloc[0] / NM, frame[f"{plant}.x"].iloc[0] / NM, "o", color="tab:red")
    _draw_encounters(ax, frame, plant)
    ax.set_xlabel("east [nm]")
    ax.set_ylabel("north [nm]")
    if field is not None:  # the map is the frame (traffic beyond it is not drawn) ...
        x_min, x_max, y_min, y_max = (v / NM for v in field.extent)
        if _obstacle_columns(frame) is not None:  # ... or, with traffic, the encounter within it
            north, east = _encounter_extent_nm(frame, plant)
            x_min, x_max = max(x_min, north[0]), min(x_max, north[1])
            y_min, y_max = max(y_min, east[0]), min(y_max, east[1])
        ax.set_xlim(y_min, y_max)
        ax.set_ylim(x_min, x_max)
        ax.set_aspect("equal")
    else:
        ax.set_aspect("equal", adjustable="datalim")
    ax.set_title(f"{scenario.simulation.name}: track")
    ax.legend(loc="best", fontsize=8, framealpha=0.8)
    fig.savefig(out_dir / "track.png", dpi=120)
    return ["track.png"]


def _draw_reference(ax, frame, scenario) -> None:
    """The reference path: the first point of each recorded reference trajectory."""
    sources = [f"{c.source}.{c.source_port}" for c in scenario.connections if c.target_port == "reference"]
    if not sources or f"{sources[0]}[0,1]" not in frame.columns:
        return
    ax.plot(frame[f"{sources[0]}[0,2]"] / NM, frame[f"{sources[0]}[0,1]"] / NM, "--", color="tab:blue",
            lw=1, label="reference")


def _obstacle_columns(frame) -> tuple[str, int] | None:
    columns = [c for c in frame.columns if c.endswith("]") and ".obstacles[" in c]
    if not columns:
        return None
    prefix = columns[0].split("[")[0]
    return prefix, 1 + max(int(c.split("[")[1].split(",")[0]) for c in columns)


def _draw_obstacles(ax, frame) -> None:
    """Obstacle circles where each obstacle is at the frame's last row, and the tracks so far."""
    found = _obstacle_columns(frame)
    if found is None:
        return
    prefix, count = found
    for i in range(count):
        x, y, radius = (frame[f"{prefix}[{i},{k}]"].to_numpy() for k in (0, 1, 4))
        ax.plot(y / NM, x / NM, ":", color="grey", lw=1)
        circle = _circle(x[-1], y[-1], radius[-1])
        ax.plot(circle[1] / NM, circle[0] / NM, color="black", lw=1)


def _encounter_extent_nm(frame, plant, margin_nm: float = 1.5):
    """(north, east) ranges [nm] holding the own track and each obstacle's circle at its CPA."""
    own_x, own_y = frame[f"{plant}.x"].to_numpy(), frame[f"{plant}.y"].to_numpy()
    north = [own_x.min(), own_x.max()]
    east = [own_y.min(), own_y.max()]
    found = _obstacle_columns(frame)
    prefix = found[0] if found is not None else ""  # (no obstacle columns: no closest approach either)
    for i, k, _ in closest_approach_rows(frame, plant):
        x, y, radius = (frame[f"{prefix}[{i},{c}]"].to_numpy() for c in (0, 1, 4))
        north = [min(north[0], x[k] - radius[k]), max(north[1], x[k] + radius[k])]
        east = [min(east[0], y[k] - radius[k]), max(east[1], y[k] + radius[k])]
    margin = margin_nm * NM
    north, east = [north[0] - margin, north[1] + margin], [east[0] - margin, east[1] + margin]
    # a square frame: a long narrow track would otherwise leave no room for the legend
    half = max(north[1] - north[0], east[1] - east[0]) / 2.0
    centre_north, centre_east = sum(north) / 2.0, sum(east) / 2.0
    return (((centre_north - half) / NM, (centre_north + half) / NM),
            ((centre_east - half) / NM, (centre_east + half) / NM))


def time_mark_interval_min(duration_s: float) -> float:
    """A round interval [min] giving about 4-12 time marks over ``duration_s``."""
    for minutes in (1, 2, 5, 10, 15, 30, 60, 120):
        if duration_s / (60.0 * minutes) <= 12:
            return float(minutes)
    return 240.0


def _draw_time_marks(ax, t, x, y, interval_min: float, color, label_marks: bool) -> None:
    marks = np.arange(t[0], t[-1] + 1e-9, interval_min * 60.0)[1:]
    if marks.size == 0:
        return
    mx, my = np.interp(marks, t, x), np.interp(marks, t, y)
    ax.plot(my / NM, mx / NM, "|", color=color, ms=7, mew=1.5)
    if label_marks:
        for mark, north, east in zip(marks, mx, my):
            ax.annotate(f"{mark / 60.0:.0f}'", (east / NM, north / NM), textcoords="offset points", xytext=(4, 2),
                        fontsize=7, color=color)


def closest_approach_rows(frame, plant) -> list[tuple[int, int, float]]:
    """Per obstacle of the recorded ``obstacles`` output: (obstacle, sample, range [m]) where
    the own ship came closest to it."""
    found = _obstacle_columns(frame)
    if found is None:
        return []
    prefix, count = found
    own_x, own_y = frame[f"{plant}.x"].to_numpy(), frame[f"{plant}.y"].to_numpy()
    rows = []
    for i in range(count):
        distance = np.hypot(frame[f"{prefix}[{i},0]"].to_numpy() - own_x, frame[f"{prefix}[{i},1]"].to_numpy() - own_y)
        k = int(np.argmin(distance))
        rows.append((i, k, float(distance[k])))
    return rows


def _draw_encounters(ax, frame, plant) -> None:
    """Tracks with time marks; each obstacle drawn where it was at the own ship's closest approach.

    The hazard circle sits at the obstacle's position at the moment the own ship came
    closest to it, the own ship's position then is marked on its track, and the segment
    joining the two is the CPA (labelled with its range and time).  Time marks (minutes
    since the start) on every track let positions at the same instant be matched.
    """
    t = frame["time_s"].to_numpy()
    own_x, own_y = frame[f"{plant}.x"].to_numpy(), frame[f"{plant}.y"].to_numpy()
    interval = time_mark_interval_min(t[-1] - t[0])
    _draw_time_marks(ax, t, own_x, own_y, interval, "tab:red", True)
    found = _obstacle_columns(frame)
    if found is None:
        return
    prefix, count = found
    for i, k, distance in closest_approach_rows(frame, plant):
        x, y, vx, vy, radius = (frame[f"{prefix}[{i},{c}]"].to_numpy() for c in range(5))
        moving = bool(np.any(np.hypot(vx, vy) > 0.1))
        if moving:
            ax.plot(y / NM, x / NM, "-.", color="dimgrey", lw=1,
                    label=f"target tracks (marks every {interval:g} min)" if i == 0 else None)
            _draw_time_marks(ax, t, x, y, interval, "grey", False)
            ax.plot(y[k] / NM, x[k] / NM, "^", color="black", ms=5)
        circle = _circle(x[k], y[k], radius[k])
        ax.plot(circle[1] / NM, circle[0] / NM, color="black", lw=1)
        ax.plot([own_y[k] / NM, y[k] / NM], [own_x[k] / NM, x[k] / NM], "--", color="tab:orange", lw=1.2,
                label="closest approach (circles drawn then)" if i == 0 else None)
        ax.plot(own_y[k] / NM, own_x[k] / NM, "o", color="tab:orange", ms=4)
        ax.annotate(f"{'T' if moving else 'O'}{i + 1}: {distance / NM:.2f} nm at {t[k] / 60.0:.1f}'",
                    ((own_y[k] + y[k]) / (2 * NM), (own_x[k] + x[k]) / (2 * NM)), textcoords="offset points",
                    xytext=(5, -10), fontsize=8, color="tab:orange")


def _circle(x, y, radius):
    angle = np.linspace(0, 2 * np.pi, 90)
    return x + radius * np.cos(angle), y + radius * np.sin(angle)


def manoeuvre_figure(frame, plant, figures, path, title) -> None:
    fig = _figure(6, 6)
    ax = fig.subplots()
    ax.plot(frame[f"{plant}.y"], frame[f"{plant}.x"], color="tab:blue")
    ax.set_xlabel("east [m]")
    ax.set_ylabel("north [m]")
    ax.set_aspect("equal", adjustable="datalim")
    text = "\n".join(f"{k.replace('_', ' ')}: {v:.2f}" for k, v in figures.items()
                     if k.endswith("_L") and v is not None)
    ax.text(0.02, 0.98, text, transform=ax.transAxes, va="top", fontsize=9,
            bbox={"facecolor": "white", "alpha": 0.8})
    ax.set_title(title)
    ax.grid(True, alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def zigzag_figure(frame, plant, steering_column, path, kind: str = "yaw moment") -> None:
    """Heading change and what steered: the rudder angle [deg] (command and, when the plant
    reports it, the actual angle) or the yaw moment scaled to +-10."""
    fig = _figure(8, 4)
    ax = fig.subplots()
    t = frame["time_s"] / 60
    psi = np.degrees(np.unwrap(frame[f"{plant}.psi"].to_numpy()))
    ax.plot(t, psi - psi[0], label="heading change [deg]")
    steering = frame[steering_column].to_numpy()
    if kind == "rudder":
        ax.plot(t, np.degrees(steering), "--", label=f"{steering_column} [deg]")
        if f"{plant}.rudder_angle" in frame.columns and steering_column != f"{plant}.rudder_angle":
            ax.plot(t, np.degrees(frame[f"{plant}.rudder_angle"]), ":", label="rudder angle (plant) [deg]")
        title = "Zig-zag (rudder)"
    else:
        scale = np.max(np.abs(steering)) or 1.0
        ax.plot(t, 10 * steering / scale, "--", label="yaw moment (scaled to +-10)")
        title = "Zig-zag 10/10 (yaw moment)"
    ax.set_xlabel("time [min]")
    ax.set_ylabel("deg")
    ax.legend()
    ax.grid(True, alpha=0.3)
    ax.set_title(title)
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def controls_figure(frame, scenario, cosim, out_dir) -> list[str]:
    """Surge force and yaw moment demanded (and achieved, behind an allocation) over time,
    with their bounds; below them the plant's rudder angle and propeller revolutions when it
    reports them (an actuator-level plant)."""
    from rhnc.cosim.plant import find_plant, tau_column

    plant = find_plant(cosim)
    if plant is None:
        return []
    parameters = getattr(cosim.participant(plant), "parameters", {})
    actuators = [(name, unit, scale) for name, unit, scale in
                 (("rudder_angle", "deg", 180.0 / np.pi), ("propeller_rps", "1/s", 1.0))
                 if f"{plant}.{name}" in frame.columns]
    ports = [(port, unit) for port, unit in (("tau_u", "MN"), ("tau_r", "MN m"))
             if tau_column(scenario, port) in frame.columns]
    if not ports and not actuators:
        return []
    rows = len(ports) + len(actuators)
    fig = _figure(8, 2.5 * rows, (0.85, 0.6, 0.25, 0.45), hspace=0.15)
    axes = fig.subplots(rows, 1, sharex=True, squeeze=False)[:, 0]
    t = frame["time_s"] / 60.0
    for ax, (name, unit, scale) in zip(axes[len(ports):], actuators):
        ax.plot(t, frame[f"{plant}.{name}"] * scale, label=f"{plant}.{name}")
        ax.set_ylabel(f"{name} [{unit}]")
        ax.grid(True, alpha=0.3)
        ax.legend(loc="upper right", fontsize=8)
    for ax, (port, unit) in zip(axes, ports):
        scale = 1e-6
        column = tau_column(scenario, port)
        ax.step(t, frame[column] * scale, where="post", label=f"{column} (demanded)")
        achieved = next((c for c in frame.columns if c.endswith(f".{port}_achieved")), None)
        if achieved is not None:
            ax.plot(t, frame[achieved] * scale, lw=1, label=f"{achieved}")
        bound = parameters.get(f"{port}_max")
        if bound is not None:
            for sign in (1, -1):
                ax.axhline(sign * float(bound) * scale, color="grey", ls="--", lw=1)
        ax.set_ylabel(f"{port} [{unit}]")
        ax.grid(True, alpha=0.3)
        ax.legend(loc="upper right", fontsize=8)
    axes[-1].set_xlabel("time [min]")
    fig.suptitle(f"{scenario.simulation.name}: control history")
    fig.savefig(out_dir / "controls.png", dpi=120)
    return ["controls.png"]


def navigation_fields_figure(frame, scenario, cosim, out_dir, panels: int = 6) -> list[str]:
    """The superposed field U and the track at six instants (the paper's Fig. 10 and 17).

    For each instant the navigation participant's field is rebuilt from the ship's
    position (and, when it varies in time, the weather) then, as the navigation did at that
    planning instant; the panel shows U (or
    G alone while the event trigger was on), the track sailed so far and the local plan.
    """
    from rhnc.cosim.plant import plant_name

    navigation = next((p for p in cosim.participants if hasattr(p, "field") and hasattr(p.field, "potential")), None)
    if navigation is None:
        return []
    plant = plant_name(cosim)
    if f"{plant}.x" not in frame.columns or len(frame) < 2:
        return []
    every = next(spec.every for spec in scenario.participants if spec.name == navigation.name)
    nav_steps = (len(frame) - 1) // every
    instants = [int(round(nav_steps * (i + 1) / panels)) * every for i in range(panels)]
    field = navigation.field
    x_nm, y_nm = field.weather.x / NM, field.weather.y / NM
    # each column read once for the six panels
    t, own_x, own_y = (frame[c].to_numpy() for c in ("time_s", f"{plant}.x", f"{plant}.y"))
    et = frame[f"{navigation.name}.et"].to_numpy() if f"{navigation.name}.et" in frame.columns else np.zeros(len(t))
    ref = f"{navigation.name}.reference"
    plan = None  # (samples, points, north/east) of the local plan
    if f"{ref}[0,1]" in frame.columns:
        count = 1 + max(int(c.split("[")[1].split(",")[0]) for c in frame.columns if c.startswith(ref + "["))
        plan = frame[[f"{ref}[{k},{c}]" for k in range(count) for c in (1, 2)]].to_numpy().reshape(len(t), count, 2)
    obstacles = _obstacle_columns(frame) is not None
    fig = _figure(14, 9, (0.75, 0.4, 0.2, 0.7), wspace=0.2, hspace=0.2)
    axes = fig.subplots(2, 3)
    for ax, row in zip(axes.ravel(), instants):
        row = min(row, len(frame) - 1)
        avoidance = bool(et[row] > 0.5)
        if navigation.metocean.is_time_varying:  # the weather the navigation planned in then
            from rhnc.navigation.fields import resample_weather

            field.set_weather(resample_weather(navigation.metocean, navigation.resolution_nm, t_s=float(t[row])))
        field.update((own_x[row], own_y[row]), navigation.speed)
        mesh = ax.pcolormesh(y_nm, x_nm, field.potential(avoidance), shading="auto", cmap="viridis")
        ax.plot(own_y[: row + 1] / NM, own_x[: row + 1] / NM, color="tab:red", lw=1.5)
        if plan is not None:
            ax.plot(plan[row, :, 1] / NM, plan[row, :, 0] / NM, "w.", ms=3)
        if obstacles:
            _draw_obstacles(ax, frame.iloc[: row + 1])
        # y given: the title sits on the map's top edge, as the automatic placement would put
        # it (no tick labels above), without measuring every tick label of the panel first
        ax.set_title(f"step {row // every} ({t[row] / 60.0:.0f} min){' ET = 1: G only' if avoidance else ''}",
                     fontsize=10, y=1.0)
        ax.set_xlabel("east [nm]")
        ax.set_ylabel("north [nm]")
        ax.set_aspect("equal")
        fig.colorbar(mesh, ax=ax, shrink=0.8,
                     label="normalised guidance field G [-]" if avoidance else "superposed field U [-]")
    fig.suptitle(f"{scenario.simulation.name}: superposed field U and track at six planning instants")
    fig.savefig(out_dir / "navigation_fields.png", dpi=110)
    return ["navigation_fields.png"]


#: colours of the compared runs' tracks: none white or in viridis's own hues, so each stands
#: out from the wind-speed map and from the others
TRACK_COLOURS = ("tab:red", "black", "magenta", "tab:cyan", "tab:orange", "tab:brown")


def comparison_track_styles(count: int) -> list[dict]:
    """Line styles of ``count`` compared tracks, drawn in that order.

    Each is narrower than the one before, so where tracks run together (at the start and
    the goal, or along a common stretch) the earlier ones still show on both sides of the
    later ones; colours repeat past :data:`TRACK_COLOURS`, dashed then.
    """
    widths = np.linspace(3.5, 1.2, count) if count > 1 else np.array([2.0])
    return [{"color": TRACK_COLOURS[i % len(TRACK_COLOURS)], "lw": float(widths[i]),
             "ls": "-" if i < len(TRACK_COLOURS) else "--"} for i in range(count)]


def comparison_tracks_figure(spec, reports, out_dir) -> list[str]:
    """``tracks.png`` of a comparison: every run's track over the first run's met-ocean field.

    Registered in ``rhnc_cosim.comparison_figures``; ``reports`` maps each run's label to its
    run report (``folder`` holds its time series and ``metocean.nc``).
    """
    import pandas as pd

    from rhnc.weather.metocean_sources import from_netcdf

    target = Path(out_dir) / "tracks.png"
    fig = _figure(7, 6)
    ax = fig.subplots()
    first = next(iter(reports.values())).folder / "metocean.nc"
    if first.is_file():
        field = from_netcdf(first).snapshot(0.0)  # at departure when it varies in time
        mesh = ax.pcolormesh(field.y / NM, field.x / NM, field.wind_speed, shading="auto", cmap="viridis")
        fig.colorbar(mesh, ax=ax, label="wind speed [m/s]")
    for (label, report), style in zip(reports.items(), comparison_track_styles(len(reports))):
        frame = pd.read_parquet(report.folder / "timeseries.parquet") if (
            report.folder / "timeseries.parquet").is_file() else pd.read_csv(report.folder / "timeseries.csv")
        plant = next(c[:-2] for c in frame.columns if c.endswith(".x") and f"{c[:-2]}.psi" in frame.columns)
        ax.plot(frame[f"{plant}.y"] / NM, frame[f"{plant}.x"] / NM, label=label, **style)
    ax.set_xlabel("east [nm]")
    ax.set_ylabel("north [nm]")
    ax.set_aspect("equal")
    ax.legend(loc="lower right")
    ax.set_title(f"{spec['name']}: tracks")
    fig.tight_layout()
    fig.savefig(target, dpi=120)
    return [target.name]
