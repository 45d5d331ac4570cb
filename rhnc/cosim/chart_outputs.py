"""Outputs of a passage on a chart: the clearance analysis (with the track in latitude/longitude) and the map.

Registered in ``rhnc_cosim.analyses`` (``clearance``) and ``rhnc_cosim.figures`` (``chart``).
The chart is the analysis' ``chart`` option (a chart file relative to the scenario,
:mod:`rhnc.chart.chart`), else the one the navigation participant plans on.  A scenario
without a chart gets ``{"evaluated": false}`` from the analysis and no map.

The analysis writes ``track_geographic.csv`` (time, north, east, latitude, longitude of the
ship at every sample) beside the results: a passage's results carry latitude and
longitude beside the local x/y.  With ``[[acceptance]] metric = "analyses.clearance.kept"``
(every shipped passage has it) a run that comes closer to land or a no-go area than the
declared clearance, or crosses one, exits 3 and says so.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from orchestrator.geometry import NM
from rhnc.cosim.plant import find_plant


def _chart_of(scenario, cosim, chart: str | None):
    if chart is not None:
        from rhnc.chart.chart import load_chart

        return load_chart(Path(scenario.directory) / chart)
    return next((p.chart for p in cosim.participants if getattr(p, "chart", None) is not None), None)


def clearance_analysis(frame, scenario, cosim, out_dir, chart: str | None = None) -> dict:
    """Least distance of the sailed track to land and no-go areas along its chords, where and when
    (:func:`rhnc.chart.clearance.track_clearance`), and the track in latitude/longitude."""
    from rhnc.chart.clearance import track_clearance

    the_chart = _chart_of(scenario, cosim, chart)
    plant = find_plant(cosim)
    if the_chart is None or plant is None or f"{plant}.x" not in frame.columns:
        return {"evaluated": False, "note": "no chart (option 'chart' or a navigation with one) or no ship track"}
    t = frame["time_s"].to_numpy(dtype=float)
    north = frame[f"{plant}.x"].to_numpy(dtype=float)
    east = frame[f"{plant}.y"].to_numpy(dtype=float)
    result = track_clearance(the_chart, t, north, east)
    lat, lon = the_chart.to_geographic(north, east)
    table = np.column_stack([t, north, east, lat, lon])
    np.savetxt(Path(out_dir) / "track_geographic.csv", table, delimiter=",", fmt=["%.3f", "%.2f", "%.2f", "%.7f", "%.7f"],
               header="time_s,north_m,east_m,lat_deg,lon_deg", comments="")
    origin = the_chart.projection
    return {"evaluated": True, **result, "origin_deg": [origin.origin_lat_deg, origin.origin_lon_deg],
            "departure_deg": [float(lat[0]), float(lon[0])], "end_deg": [float(lat[-1]), float(lon[-1])],
            "track_file": "track_geographic.csv"}


def _check_clearance_options(options) -> None:
    chart = options.get("chart")
    if chart is not None and (not isinstance(chart, str) or not chart):
        raise ValueError(f"chart: expected the path of a chart file, got {chart!r}")


clearance_analysis.check_options = _check_clearance_options


def chart_figure(frame, scenario, cosim, out_dir) -> list[str]:
    """Land, no-go areas and their clearance (dotted), the reference and the sailed track in nm of
    the local plane (its geographic origin in the title), the track's closest point marked."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    options = scenario.outputs.options.get("clearance", {})
    the_chart = _chart_of(scenario, cosim, options.get("chart"))
    plant = find_plant(cosim)
    if the_chart is None or plant is None or f"{plant}.x" not in frame.columns:
        return []
    fig = Figure(figsize=(7.5, 7.0))
    FigureCanvasAgg(fig)
    ax = fig.subplots()
    colours = {"land": "#c8b88a", "no_go": "#e8a0a0"}
    for area in the_chart.areas:
        buffered = area.geometry.buffer(the_chart.clearance_m)
        for part in getattr(buffered, "geoms", [buffered]):
            if part.geom_type == "Polygon":
                ax.plot(np.asarray(part.exterior.xy[1]) / NM, np.asarray(part.exterior.xy[0]) / NM, ":",
                        color="grey", lw=0.6)
        for part in getattr(area.geometry, "geoms", [area.geometry]):
            if part.geom_type == "Polygon" and not part.is_empty:
                ax.fill(np.asarray(part.exterior.xy[1]) / NM, np.asarray(part.exterior.xy[0]) / NM,
                        color=colours.get(area.kind, "grey"), lw=0)
    sources = [f"{c.source}.{c.source_port}" for c in scenario.connections if c.target_port == "reference"]
    if sources and f"{sources[0]}[0,1]" in frame.columns:
        ax.plot(frame[f"{sources[0]}[0,2]"] / NM, frame[f"{sources[0]}[0,1]"] / NM, "--", color="tab:blue", lw=1,
                label="reference")
    north = frame[f"{plant}.x"].to_numpy(dtype=float)
    east = frame[f"{plant}.y"].to_numpy(dtype=float)
    ax.plot(east / NM, north / NM, color="tab:red", lw=1.5, label=f"{plant} track")
    ax.plot(east[0] / NM, north[0] / NM, "o", color="tab:red")
    from rhnc.chart.clearance import track_clearance

    result = track_clearance(the_chart, frame["time_s"].to_numpy(dtype=float), north, east)
    if result["closest"] is not None:
        closest = result["closest"]
        ax.plot(closest["east_m"] / NM, closest["north_m"] / NM, "x", color="black", ms=9,
                label=f"closest {result['min_clearance_nm']:.2f} nm ({closest['area']}, "
                      f"{closest['time_s'] / 60:.0f} min)")
    pad = 8.0
    ax.set_xlim(east.min() / NM - pad, east.max() / NM + pad)
    ax.set_ylim(north.min() / NM - pad, north.max() / NM + pad)
    ax.set_aspect("equal")
    ax.set_xlabel("east [nm]")
    ax.set_ylabel("north [nm]")
    origin = the_chart.projection
    ax.set_title(f"{scenario.simulation.name}: chart (origin {origin.origin_lat_deg:.3f} N "
                 f"{origin.origin_lon_deg:.3f} E; dotted: clearance {the_chart.clearance_m / NM:.1f} nm)", fontsize=9)
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.1), ncol=2, fontsize=8, framealpha=0.8)
    fig.tight_layout()
    fig.savefig(Path(out_dir) / "chart.png", dpi=120)
    return ["chart.png"]
