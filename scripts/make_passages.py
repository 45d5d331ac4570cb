"""Write the passages of scenarios/passages/: charts, coastline, no-go areas, weather files, scenarios.

    python scripts/make_passages.py [name ...]   # rewrites scenarios/passages/ (needs the 'geo' extra); all by default

Everything a passage needs is derived here from the few lines of PASSAGES below, which
were fixed (ports, clearance, weather parameters) before any passage was run:

* the chart (``<name>.chart.toml``): the local plane's origin, the declared clearance;
* the coastline (``<name>.land.geojson``): global-land-mask's land cells over the whole
  weather map (``rhnc.chart.land.land_geojson``), where the route search may go;
* the no-go areas (``<name>.no_go.geojson``) drawn for the passage (not charted ones);
* the weather in the services' layouts: ``weather/<name>_era5.nc`` (ERA5 single levels)
  and ``weather/<name>_cmems.nc`` (CMEMS surface currents) with synthetic values from the
  closed-form fields below (a depression crossing the map, waves grown from its wind, a
  current), on the services' own grids (0.25 deg hourly; 1/12 deg hourly);
* the baseline route: ``searoute``'s port-to-port route over its offline sea-route
  network (searoute 1.6, the Eurostat/ORNL marnet network), between the start and the goal,
  made to keep the chart's clearance (``rhnc.routing.clear_route.route_kept_clear``: each leg
  that comes within it replaced by the shortest clear path between its ends);
* the scenarios: ``<name>.toml`` (RHNC: routing navigation on the chart, NMPC, KCS plant,
  MetOcean FMU), ``<name>_sea_route.toml`` (Offline-SPNC: the NMPC following the sea-route
  baseline) and ``<name>_compare.toml`` (both at equal arrival time, ``compare``).
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from orchestrator.geometry import NM
from rhnc.chart.chart import Chart, load_chart
from rhnc.chart.land import land_geojson
from rhnc.chart.projection import LocalProjection
from rhnc.routing.clear_route import route_kept_clear
from rhnc.weather.copernicus_layouts import write_cmems_currents, write_era5_single_levels

OUT = Path(__file__).resolve().parent.parent / "scenarios" / "passages"
DEPARTURE = np.datetime64("2025-01-15T06:00", "h")
HOURS = 18

#: The passages (fixed 2026-11-27 before any was run): start and goal (lat, lon) [deg], the
#: chart's bounds (south, west, north, east) [deg], clearance [nm], speed [kn], arrival [min],
#: the depression (centre at departure (lat, lon), velocity [deg/h], peak wind [m/s], radius [deg]),
#: the current (east, north) [m/s] and no-go polygons [(name, [(lat, lon), ...])].
PASSAGES = {
    "biscay_crossing": dict(
        title="an open-sea crossing of the Bay of Biscay",
        start=(45.9, -4.6), goal=(45.0, -2.5), bounds=(44.4, -5.4, 46.5, -1.7), clearance_nm=2.0,
        speed_kn=16.0, arrival_min=420.0,
        low=dict(centre=(45.2, -4.6), velocity=(0.05, 0.15), peak_ms=22.0, radius_deg=0.7),
        current=(0.15, -0.1), no_go=[]),
    # A second open-sea crossing, added after Biscay's sea-route baseline could not make way
    # against its gale (Hs about 11 m: no speed arrives).  Biscay's weather is kept as it was;
    # this crossing's weather was declared by the rule below on 2026-11-27, before any run of
    # it: the same generator (depression, waves grown from its wind, a current); the peak wind
    # the middle of Beaufort 6 (10.8-13.8 m/s: 12.3 m/s, a strong breeze, Hs about 3.8 m at
    # the peak), the sea state in which a merchant ship's service speed is still expected;
    # Biscay's radius (0.7 deg) and drift (0.05, 0.15 deg/h); the centre at departure half a
    # degree west of the midpoint of start and goal; the Ligurian (Northern) Current, about
    # 0.2 m/s towards the west-north-west; Biscay's speed (16 kn) and arrival (420 min, about
    # 8 % over the straight line at 16 kn, as Biscay's); the clearance Biscay's (2 nm).
    "ligurian_crossing": dict(
        title="an open-sea crossing of the Ligurian Sea, Genoa to Calvi",
        start=(44.25, 8.95), goal=(42.62, 8.68), bounds=(42.2, 8.0, 44.5, 9.4), clearance_nm=2.0,
        speed_kn=16.0, arrival_min=420.0,
        low=dict(centre=(43.435, 8.315), velocity=(0.05, 0.15), peak_ms=12.3, radius_deg=0.7),
        current=(-0.18, 0.08), no_go=[]),
    "cyclades_islands": dict(
        title="a coastal passage among the Cyclades islands",
        start=(37.62, 24.12), goal=(36.95, 25.25), bounds=(36.6, 23.8, 37.9, 25.6), clearance_nm=1.0,
        speed_kn=14.0, arrival_min=330.0,
        low=dict(centre=(37.8, 24.3), velocity=(-0.02, 0.06), peak_ms=17.0, radius_deg=0.5),  # a meltemi-like blow
        current=(-0.1, -0.2),
        no_go=[("restricted area off Syros", [(37.36, 24.80), (37.36, 24.86), (37.30, 24.86), (37.30, 24.80)])]),
    "gibraltar_strait": dict(
        title="the Strait of Gibraltar, westbound",
        start=(36.08, -4.95), goal=(35.93, -6.15), bounds=(35.65, -6.45, 36.35, -4.65), clearance_nm=1.0,
        speed_kn=15.0, arrival_min=270.0,
        low=dict(centre=(36.5, -6.4), velocity=(-0.02, 0.1), peak_ms=18.0, radius_deg=0.5),  # a levanter's opposite
        current=(0.8, 0.0),  # the Atlantic inflow, against a westbound ship
        # traffic: an eastbound ship in the strait, nearly head-on (trafficgen's situation format)
        traffic=[dict(position=(36.0, -5.35), course_deg=80.0, speed_kn=12.0, radius_nm=1.0)],
        no_go=[("separation zone (drawn for this scenario)",
                [(35.975, -5.75), (35.975, -5.45), (35.965, -5.45), (35.965, -5.75)])]),
}


def weather(name: str, passage: dict) -> tuple[Path, Path]:
    """ERA5 and CMEMS files over the bounds plus half a degree, with the closed-form fields."""
    south, west, north, east = passage["bounds"]
    times = DEPARTURE + np.arange(HOURS + 1).astype("timedelta64[h]")
    hours = np.arange(HOURS + 1, dtype=float)[:, None, None]
    lat = np.arange(math.floor(south * 4) / 4 - 0.5, math.ceil(north * 4) / 4 + 0.501, 0.25)
    lon = np.arange(math.floor(west * 4) / 4 - 0.5, math.ceil(east * 4) / 4 + 0.501, 0.25)
    la, lo = np.meshgrid(lat, lon, indexing="ij")
    low = passage["low"]
    c_lat = low["centre"][0] + low["velocity"][0] * hours
    c_lon = low["centre"][1] + low["velocity"][1] * hours
    d_north = (la - c_lat)
    d_east = (lo - c_lon) * np.cos(np.radians(la))
    r = np.hypot(d_north, d_east) + 1e-9
    speed = 6.0 + (low["peak_ms"] - 6.0) * (r / low["radius_deg"]) * np.exp(1.0 - r / low["radius_deg"])
    # cyclonic (northern hemisphere: anticlockwise), turned 20 deg in towards the centre
    angle = np.arctan2(d_east, d_north) - np.pi / 2 - np.radians(20.0)  # the bearing the wind blows towards
    v10 = speed * np.cos(angle)  # towards north
    u10 = speed * np.sin(angle)  # towards east
    swh = 0.5 + 0.022 * speed ** 2  # fully grown sea of the local wind, roughly (Pierson-Moskowitz)
    mwd = (np.degrees(np.arctan2(-u10, -v10)) % 360.0)  # waves from where the wind comes from
    era5 = write_era5_single_levels(OUT / "weather" / f"{name}_era5.nc", lat, lon, times, u10, v10, swh, mwd)
    clat = np.arange(math.floor(south * 12) / 12 - 0.25, math.ceil(north * 12) / 12 + 0.26, 1 / 12)
    clon = np.arange(math.floor(west * 12) / 12 - 0.25, math.ceil(east * 12) / 12 + 0.26, 1 / 12)
    cla, clo = np.meshgrid(clat, clon, indexing="ij")
    tide = 1.0 + 0.3 * np.sin(2 * np.pi * np.arange(HOURS + 1) / 12.42)[:, None, None]  # a semi-diurnal swing
    uo = passage["current"][0] * tide + 0 * cla
    vo = passage["current"][1] * tide + 0 * clo
    from global_land_mask import globe

    land = globe.is_land(cla, clo)
    uo = np.where(land, np.nan, uo)
    vo = np.where(land, np.nan, vo)
    cmems = write_cmems_currents(OUT / "weather" / f"{name}_cmems.nc", clat, clon, times, uo, vo,
                                 depths_m=(0.494025, 1.541375, 2.645669))
    return era5, cmems


def sea_route(start, goal, chart: Chart) -> list[tuple[float, float]]:
    """searoute's network route between the two (lat, lon), its ends replaced by start and goal,
    each leg keeping the chart's clearance (the network knows nothing of it)."""
    import searoute

    found = searoute.searoute([start[1], start[0]], [goal[1], goal[0]])
    inner = [(lat, lon) for lon, lat in found.geometry["coordinates"][1:-1]]
    route = [tuple(start)] + inner + [tuple(goal)]
    north, east = chart.projection.to_local(*np.array(route).T)
    plane = np.stack([north, east], axis=1)
    clear = route_kept_clear(chart, plane)
    given = {tuple(point): geographic for point, geographic in zip(plane, route)}  # kept as searoute gave them
    lat, lon = chart.projection.to_geographic(clear[:, 0], clear[:, 1])
    return [given.get(tuple(point), (float(a), float(b))) for point, a, b in zip(clear, lat, lon)]


def write_passage(name: str, passage: dict) -> None:
    south, west, north, east = passage["bounds"]
    origin = (south, west)  # the passage bounds' south-west corner (the weather map reaches half a degree beyond)
    projection = LocalProjection(*origin)
    # the coastline over the whole weather map: the route search may go anywhere on it
    land = land_geojson(math.floor(south * 4) / 4 - 0.5, math.floor(west * 4) / 4 - 0.5,
                        math.ceil(north * 4) / 4 + 0.5, math.ceil(east * 4) / 4 + 0.5)
    (OUT / f"{name}.land.geojson").write_text(json.dumps(land) + "\n")
    no_go_line = ""
    if passage["no_go"]:
        features = [{"type": "Feature", "properties": {"name": label},
                     "geometry": {"type": "Polygon", "coordinates": [[[lon, lat] for lat, lon in corners + corners[:1]]]}}
                    for label, corners in passage["no_go"]]
        (OUT / f"{name}.no_go.geojson").write_text(json.dumps({"type": "FeatureCollection", "features": features},
                                                              indent=1) + "\n")
        no_go_line = f'no_go = ["{name}.no_go.geojson"]\n'
    (OUT / f"{name}.chart.toml").write_text(
        f"# Chart of {passage['title']} (scripts/make_passages.py). Plane: azimuthal equidistant about the origin.\n"
        f"origin_deg = [{origin[0]}, {origin[1]}]\nclearance_nm = {passage['clearance_nm']}\n"
        f'land = "{name}.land.geojson"     # global-land-mask, 30 arc-second cells\n{no_go_line}')
    weather(name, passage)

    def nm(point):
        n, e = projection.to_local(*point)
        return [round(float(n) / NM, 3), round(float(e) / NM, 3)]

    start_nm, goal_nm = nm(passage["start"]), nm(passage["goal"])
    route = sea_route(passage["start"], passage["goal"], load_chart(OUT / f"{name}.chart.toml"))
    route_nm = [nm(p) for p in route]
    psi0 = math.atan2(goal_nm[1] - start_nm[1], goal_nm[0] - start_nm[0])
    distance = math.hypot(goal_nm[0] - start_nm[0], goal_nm[1] - start_nm[1])
    steps = int(math.ceil(2.0 * passage["arrival_min"] / 60.0) * 60)
    common = {"name": name, "title": passage["title"], "start": passage["start"], "goal": passage["goal"],
              "start_deg": json.dumps(list(passage["start"])), "goal_deg": json.dumps(list(passage["goal"])),
              "start_nm": start_nm, "goal_nm": goal_nm, "speed_ms": round(passage["speed_kn"] * NM / 3600, 3),
              "speed_kn": passage["speed_kn"], "psi0": round(psi0, 6), "steps": steps,
              "arrival_min": passage["arrival_min"], "distance": distance,
              "origin": f"{origin[0]}, {origin[1]}", "x0": round(start_nm[0] * NM, 1), "y0": round(start_nm[1] * NM, 1), "max_h": round(steps / 60.0, 1)}
    (OUT / f"{name}.toml").write_text(RHNC.format(**common))
    (OUT / f"{name}_sea_route.toml").write_text(SEA_ROUTE.format(
        **common, route_nm=json.dumps(route_nm), waypoints_deg=json.dumps([list(p) for p in route])))
    (OUT / f"{name}_compare.toml").write_text(COMPARE.format(**common))
    if passage.get("traffic"):
        write_traffic(name, passage, common)


def situation_ship(position, course_deg: float, speed_kn: float, identifier: int, label: str) -> dict:
    """One ship of a trafficgen-format situation (maritime-schema 0.2), sailing straight."""
    return {"initial": {"position": {"lat": position[0], "lon": position[1]}, "sog": speed_kn, "cog": course_deg,
                        "heading": course_deg}, "static": {"id": identifier, "name": label}}


def write_traffic(name: str, passage: dict, common: dict) -> None:
    """The passage with target ships: a trafficgen-format situation file holding each ship's
    latitude and longitude, placed on the passage by the chart (the traffic's ``situation``)."""
    radii = {target["radius_nm"] for target in passage["traffic"]}
    if len(radii) != 1:
        raise ValueError(f"{name}: one hazard radius for the situation's targets, got {sorted(radii)}")
    own = situation_ship(passage["start"], round(math.degrees(common["psi0"]) % 360.0, 3), passage["speed_kn"], 1,
                         "own ship")
    targets = [situation_ship(target["position"], target["course_deg"], target["speed_kn"], k + 2, f"target {k + 1}")
               for k, target in enumerate(passage["traffic"])]
    document = {"schemaVersion": "0.2.0", "title": f"{name}: traffic", "description": passage["title"],
                "ownShip": own, "targetShips": targets}
    situation_file = OUT / f"{name}.situation.json"
    situation_file.write_text(json.dumps(document, indent=1) + "\n")
    text = (OUT / f"{name}.toml").read_text()
    text = text.replace('  "ship.x -> nav.x",', '  "traffic.obstacles -> nav.obstacles", "traffic.obstacles -> ctrl.obstacles",\n  "ship.x -> nav.x",', 1)
    text = text.replace(f'name = "{name}"', f'name = "{name}_traffic"', 1)
    text = text.replace("# Run: python -m orchestrator run scenarios/passages/" + name + ".toml",
                        f"# With traffic from {situation_file.name} (trafficgen's situation format).\n"
                        f"# Run: python -m orchestrator run scenarios/passages/{name}_traffic.toml", 1)
    text = text.replace("[participants.nav]\n", "[participants.traffic]\ntype = \"traffic\"\n"
                        f"[participants.traffic.options]\nchart = \"{name}.chart.toml\"\n"
                        f"situation = \"{situation_file.name}\"      # the targets, placed where their lat/lon lie\n"
                        f"situation_radius_nm = {radii.pop()}\n\n[participants.nav]\n", 1)
    # the COLREG-aware NMPC, with the settings of the traffic suites (batches/trafficgen_nmpc_colregs.toml)
    text = text.replace("disturbance_observer = true\n", "disturbance_observer = true\n"
                        "colregs = true                 # domains by encounter class and role\n"
                        "clearance_margin_nm = 0.05     # a margin for prediction error\n"
                        "clearance_margin_growth_kn = 0.2\n", 1)
    text = text.replace('analyses = ["voyage", "clearance"]', 'analyses = ["voyage", "clearance", "encounter", "colregs"]')
    text += TRAFFIC_ACCEPTANCE
    (OUT / f"{name}_traffic.toml").write_text(text)


TRAFFIC_ACCEPTANCE = '''
[[acceptance]]
name = "separation kept"       # every target: distance >= R + R_i at every sample
metric = "analyses.encounter.min_clearance_nm"
op = ">="
value = 0.0

[[acceptance]]
name = "separation kept between samples"   # along the chords between samples too
metric = "analyses.encounter.obstacles.0.min_distance_between_samples_nm"
op = ">="
ref = "analyses.encounter.obstacles.0.required_nm - 0.000001"
'''


CONNECTIONS = '''connections = [
  "ship.x -> goal.x", "ship.y -> goal.y",
  "ship.x -> ctrl.x", "ship.y -> ctrl.y", "ship.psi -> ctrl.psi", "ship.u -> ctrl.u", "ship.v -> ctrl.v",
  "ship.r -> ctrl.r",
  "ctrl.tau_u -> ship.tau_u", "ctrl.tau_r -> ship.tau_r",
  "env.current_north -> ship.current_north", "env.current_east -> ship.current_east",
  "env.wind_speed -> ship.wind_speed", "env.wind_direction -> ship.wind_direction", "env.hs -> ship.hs",
  "ship.x -> env.x", "ship.y -> env.y",
{extra}]'''

TAIL = '''
[participants.goal]
type = "goal"
[participants.goal.options]
goal_deg = {goal_deg}
chart = "{name}.chart.toml"
arrival_radius_nm = 0.5

[participants.ship]
fmu = "KCS"
parameter_set = "default"
[participants.ship.parameters]
u0 = {speed_ms}                 # m/s
psi0 = {psi0}             # rad, towards the goal
[participants.ship.initial]
start_deg = {start_deg}     # the start, placed by the chart (into x0, y0 through the plant's mapping)
chart = "{name}.chart.toml"

[participants.env]
fmu = "MetOcean"
[participants.env.parameters]
grid_file = "${{metocean.grid}}"

[metocean]                     # ERA5 single levels and CMEMS currents, as the services deliver them
file = "weather/{name}_era5.nc"
currents_file = "weather/{name}_cmems.nc"
origin_deg = [{origin}]        # the chart's origin and projection: one plane for weather, chart and ship
projection = "aeqd"
resolution_nm = 2.0

[outputs]
analyses = ["voyage", "clearance"]
figures = ["chart", "track", "controls"]
[outputs.options.clearance]
chart = "{name}.chart.toml"

[[acceptance]]                 # land and no-go areas kept at the declared clearance, along the chords
name = "clearance kept"
metric = "analyses.clearance.kept"
op = "=="
value = true
'''

RHNC = ('''# Passage: {title} (scripts/make_passages.py).
# From {start} to {goal} (lat, lon): {start_nm} to {goal_nm} nm (north, east) in the chart's plane,
# {distance:.1f} nm apart. RHNC: the routing navigation plans on the chart (land and no-go areas
# at the declared clearance), the NMPC follows; weather from ERA5/CMEMS-layout files.
# Run: python -m orchestrator run scenarios/passages/{name}.toml
''' + CONNECTIONS.format(extra='''  "ship.x -> nav.x", "ship.y -> nav.y", "ship.psi -> nav.psi", "ship.u -> nav.u",
  "ctrl.prediction -> nav.prediction", "nav.reference -> ctrl.reference", "nav.et -> ctrl.et",
''') + '''

[simulation]
name = "{name}"
steps = {steps}                  # up to twice the requested passage time; the run ends on arrival
dt_s = 60.0
stop_when = "goal.arrived > 0.5"

[participants.nav]
type = "navigation"
every = 4
[participants.nav.options]
method = "routing"
chart = "{name}.chart.toml"
start_deg = {start_deg}
goal_deg = {goal_deg}
arrival_time_min = {arrival_min}
max_speed_kn = 22.0
horizon_steps = 16
resolution_nm = 1.0
start_from = "prediction"

[participants.ctrl]
type = "control"
every = 1
[participants.ctrl.options]
horizon_steps = 15
disturbance_observer = true
chart = "{name}.chart.toml"          # land and no-go areas at the declared clearance, as constraints
''' + TAIL)

SEA_ROUTE = ('''# Passage: {title}, Offline-SPNC baseline (scripts/make_passages.py): the NMPC follows
# searoute's port-to-port route over its offline sea-route network, at one constant speed; each leg
# that came within the chart's clearance replaced by the shortest clear path between its ends.
# Route in the chart's plane (north, east) [nm]: {route_nm}
''' + CONNECTIONS.format(extra='''  "route.reference -> ctrl.reference", "ship.x -> route.x", "ship.y -> route.y",
''') + '''

[simulation]
name = "{name}_sea_route"
steps = {steps}
dt_s = 60.0
stop_when = "goal.arrived > 0.5"

[participants.route]
type = "reference_path"
[participants.route.options]
waypoints_deg = {waypoints_deg}
chart = "{name}.chart.toml"
speed_kn = {speed_kn}
horizon_steps = 15
max_lead_nm = 0.25             # waits for a ship the weather holds back: inside the arrival radius at the end

[participants.ctrl]
type = "control"
[participants.ctrl.options]
horizon_steps = 15
disturbance_observer = true
chart = "{name}.chart.toml"          # land and no-go areas at the declared clearance, as constraints
''' + TAIL)

COMPARE = '''# Passage: {title}: RHNC against the sea-route baseline at equal arrival time
# (scripts/make_passages.py; docs/passages.md).
# Run: python -m orchestrator compare scenarios/passages/{name}_compare.toml
name = "passage_{name}"
analysis = "voyage"
metrics = ["cost_usd", "co2_t", "time_min", "distance_nm", "mean_speed_through_water_kn"]

[voyage]
start_deg = {start_deg}
goal_deg = {goal_deg}
chart = "{name}.chart.toml"
arrival_time_min = {arrival_min}
arrival_radius_nm = 0.5
max_duration_h = {max_h}

[voyage.equal_arrival]         # the sea-route baseline, its speed matched to RHNC's arrival
scenario = "{name}_sea_route.toml"

[[runs]]
label = "RHNC"
scenario = "{name}.toml"
'''


def main(argv: list[str] | None = None) -> None:
    import argparse

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("names", nargs="*",
                        help="passages to write (default: all)")
    args = parser.parse_args(argv)
    unknown = [name for name in args.names if name not in PASSAGES]
    if unknown:
        parser.error(f"unknown passage {unknown[0]!r} (valid: {', '.join(PASSAGES)})")
    for name in args.names or list(PASSAGES):
        write_passage(name, PASSAGES[name])
        print(f"wrote {name}")


if __name__ == "__main__":
    main()
