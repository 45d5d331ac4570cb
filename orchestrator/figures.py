"""Figures of a run (matplotlib, Agg backend): east on the horizontal axis, north vertical."""

from __future__ import annotations

import numpy as np

NM = 1852.0


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def track_figure(frame, scenario, cosim, out_dir) -> list[str]:
    """The ship's track over the met-ocean wind speed (when the run has a field)."""
    from orchestrator.analyses import find_plant

    plant = find_plant(cosim)
    if plant is None:
        return []  # no ship in this scenario: no track to draw
    if f"{plant}.x" not in frame.columns:
        return []  # the run failed before the ship reported a position
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(7, 6))
    field = cosim.metocean
    if field is not None:
        departure_s = float(frame["time_s"].iloc[0])
        mesh = ax.pcolormesh(field.y / NM, field.x / NM, field.snapshot(departure_s).wind_speed, shading="auto",
                             cmap="viridis")
        fig.colorbar(mesh, ax=ax, label="wind speed at departure [m/s]" if field.is_time_varying
                     else "wind speed [m/s]")
    _draw_reference(ax, frame, scenario)
    ax.plot(frame[f"{plant}.y"] / NM, frame[f"{plant}.x"] / NM, color="tab:red", lw=2, label=f"{plant} track")
    ax.plot(frame[f"{plant}.y"].iloc[0] / NM, frame[f"{plant}.x"].iloc[0] / NM, "o", color="tab:red")
    _draw_obstacles(ax, frame)
    ax.set_xlabel("east [nm]")
    ax.set_ylabel("north [nm]")
    if field is not None:  # the map is the frame; traffic beyond it is not drawn
        x_min, x_max, y_min, y_max = (v / NM for v in field.extent)
        ax.set_xlim(y_min, y_max)
        ax.set_ylim(x_min, x_max)
        ax.set_aspect("equal")
    else:
        ax.set_aspect("equal", adjustable="datalim")
    ax.set_title(f"{scenario.simulation.name}: track")
    ax.legend(loc="best")
    fig.tight_layout()
    fig.savefig(out_dir / "track.png", dpi=120)
    plt.close(fig)
    return ["track.png"]


def _draw_reference(ax, frame, scenario) -> None:
    """The reference path: the first point of each recorded reference trajectory."""
    sources = [f"{c.source}.{c.source_port}" for c in scenario.connections if c.target_port == "reference"]
    if not sources or f"{sources[0]}[0,1]" not in frame.columns:
        return
    ax.plot(frame[f"{sources[0]}[0,2]"] / NM, frame[f"{sources[0]}[0,1]"] / NM, "--", color="tab:blue",
            lw=1, label="reference")


def _draw_obstacles(ax, frame) -> None:
    """Obstacle circles from an ``obstacles`` array output (columns x, y, vx, vy, radius)."""
    columns = [c for c in frame.columns if c.endswith("]") and ".obstacles[" in c]
    if not columns:
        return
    prefix = columns[0].split("[")[0]
    count = 1 + max(int(c.split("[")[1].split(",")[0]) for c in columns)
    for i in range(count):
        x, y, radius = (frame[f"{prefix}[{i},{k}]"].to_numpy() for k in (0, 1, 4))
        ax.plot(y / NM, x / NM, ":", color="grey", lw=1)
        for index in (0, len(x) // 2, len(x) - 1):
            circle = _circle(x[index], y[index], radius[index])
            ax.plot(circle[1] / NM, circle[0] / NM, color="black", lw=1)


def _circle(x, y, radius):
    angle = np.linspace(0, 2 * np.pi, 90)
    return x + radius * np.cos(angle), y + radius * np.sin(angle)


def manoeuvre_figure(frame, plant, figures, path, title) -> None:
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(6, 6))
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
    plt.close(fig)


def zigzag_figure(frame, plant, moment_column, path) -> None:
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(8, 4))
    t = frame["time_s"] / 60
    psi = np.degrees(np.unwrap(frame[f"{plant}.psi"].to_numpy()))
    ax.plot(t, psi - psi[0], label="heading change [deg]")
    moment = frame[moment_column].to_numpy()
    scale = np.max(np.abs(moment)) or 1.0
    ax.plot(t, 10 * moment / scale, "--", label="yaw moment (scaled to +-10)")
    ax.set_xlabel("time [min]")
    ax.set_ylabel("deg")
    ax.legend()
    ax.grid(True, alpha=0.3)
    ax.set_title("Zig-zag 10/10 (yaw moment)")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def controls_figure(frame, scenario, cosim, out_dir) -> list[str]:
    """Surge force and yaw moment applied to the plant over time, with their bounds."""
    from orchestrator.analyses import driver_column, find_plant

    plant = find_plant(cosim)
    if plant is None:
        return []
    parameters = getattr(cosim.participant(plant), "parameters", {})
    plt = _pyplot()
    fig, axes = plt.subplots(2, 1, figsize=(8, 5), sharex=True)
    t = frame["time_s"] / 60.0
    for ax, port, unit, scale in ((axes[0], "tau_u", "MN", 1e-6), (axes[1], "tau_r", "MN m", 1e-6)):
        column = driver_column(scenario, plant, port)
        ax.step(t, frame[column] * scale, where="post", label=column)
        bound = parameters.get(f"{port}_max")
        if bound is not None:
            for sign in (1, -1):
                ax.axhline(sign * float(bound) * scale, color="grey", ls="--", lw=1)
        ax.set_ylabel(f"{port} [{unit}]")
        ax.grid(True, alpha=0.3)
        ax.legend(loc="upper right", fontsize=8)
    axes[1].set_xlabel("time [min]")
    fig.suptitle(f"{scenario.simulation.name}: control history")
    fig.tight_layout()
    fig.savefig(out_dir / "controls.png", dpi=120)
    plt.close(fig)
    return ["controls.png"]


def navigation_fields_figure(frame, scenario, cosim, out_dir, panels: int = 6) -> list[str]:
    """The superposed field U and the track at six instants (the paper's Fig. 10 and 17).

    For each instant the navigation participant's field is rebuilt from the ship's
    position (and, when it varies in time, the weather) then, as the navigation did at that
    planning instant; the panel shows U (or
    G alone while the event trigger was on), the track sailed so far and the local plan.
    """
    from orchestrator.analyses import plant_name

    navigation = next((p for p in cosim.participants if hasattr(p, "field") and hasattr(p.field, "potential")), None)
    if navigation is None:
        return []
    plant = plant_name(cosim)
    if f"{plant}.x" not in frame.columns or len(frame) < 2:
        return []
    plt = _pyplot()
    every = next(spec.every for spec in scenario.participants if spec.name == navigation.name)
    nav_steps = (len(frame) - 1) // every
    instants = [int(round(nav_steps * (i + 1) / panels)) * every for i in range(panels)]
    field = navigation.field
    x_nm, y_nm = field.weather.x / NM, field.weather.y / NM
    fig, axes = plt.subplots(2, 3, figsize=(14, 9))
    for ax, row in zip(axes.ravel(), instants):
        row = min(row, len(frame) - 1)
        x, y = frame[f"{plant}.x"].iloc[row], frame[f"{plant}.y"].iloc[row]
        avoidance = bool(frame.get(f"{navigation.name}.et", np.zeros(len(frame))).iloc[row] > 0.5)
        if navigation.metocean.is_time_varying:  # the weather the navigation planned in then
            from rhnc.fields import resample_weather

            field.set_weather(resample_weather(navigation.metocean, navigation.resolution_nm,
                                               t_s=float(frame["time_s"].iloc[row])))
        field.update((x, y), navigation.speed)
        mesh = ax.pcolormesh(y_nm, x_nm, field.potential(avoidance), shading="auto", cmap="viridis")
        ax.plot(frame[f"{plant}.y"].iloc[: row + 1] / NM, frame[f"{plant}.x"].iloc[: row + 1] / NM,
                color="tab:red", lw=1.5)
        ref = f"{navigation.name}.reference"
        if f"{ref}[0,1]" in frame.columns:
            count = 1 + max(int(c.split("[")[1].split(",")[0]) for c in frame.columns if c.startswith(ref + "["))
            ax.plot([frame[f"{ref}[{k},2]"].iloc[row] / NM for k in range(count)],
                    [frame[f"{ref}[{k},1]"].iloc[row] / NM for k in range(count)], "w.", ms=3)
        _draw_obstacles(ax, frame.iloc[: row + 1])
        minutes = frame["time_s"].iloc[row] / 60.0
        ax.set_title(f"step {row // every} ({minutes:.0f} min){' ET = 1: G only' if avoidance else ''}", fontsize=10)
        ax.set_xlabel("east [nm]")
        ax.set_ylabel("north [nm]")
        ax.set_aspect("equal")
        fig.colorbar(mesh, ax=ax, shrink=0.8)
    fig.suptitle(f"{scenario.simulation.name}: superposed field U and track at six planning instants")
    fig.tight_layout()
    fig.savefig(out_dir / "navigation_fields.png", dpi=110)
    plt.close(fig)
    return ["navigation_fields.png"]
