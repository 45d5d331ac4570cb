"""Share of the available saving captured by each navigation method, navigation alone.

For each weather (the generators of :mod:`rhnc.weather.weather_generators`; ``storm_set`` members
0..29 by default) the navigation participant plans every 4 min (N_L = 16) from the point its
previous reference reached: the ship is assumed to track the reference exactly, so this
isolates the navigation's decisions from the plant and the NMPC (the co-simulated figures
come from ``python -m orchestrator compare scenarios/weather/storm_set_navigation.toml``).
The sailed track is costed with the routing model at its own times, and set against the
straight line and the optimal route (:mod:`rhnc.routing.weather_routing`) arriving at the same time:

    available = 1 - optimal / straight,   saving = 1 - sailed / straight,   share = saving / available

Methods: ``routing`` with ``arrival_time_min`` (default 480), and ``paper`` (exp2_rhnc.toml's
settings, constant 18 kn over ground).  Also prints the CPU time of each method's planning
updates (``time.process_time``, because the machine is shared and its wall clock says more
about the other processes than about the planner): median and max over the updates after
set-up; set-up (the first plan, with the calibration of the price of time) apart.

Run: ``python bench/bench_navigation_share.py [--members 0 29] [--weather storm_set]``
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import numpy as np

from orchestrator.participant import BuildContext
from rhnc.weather import weather_generators
from orchestrator.geometry import KNOT, NM
from rhnc.navigation.navigation_participant import NavigationParticipant
from rhnc.routing.track_cost import cost_of_track
from rhnc.routing.weather_routing import RoutingProblem, optimal_route, straight_route

DELTA_S = 240.0
GOAL_NM = (100.0, 100.0)
PAPER = {"method": "paper", "speed_kn": 18.0, "horizon_steps": 16, "k1": 1.0, "k2": 1.0, "k3": 16.0}


def sail(field, options: dict, limit_s: float = 12 * 3600.0):
    """Track (points, times) of the navigation followed exactly, and its update times."""
    context = BuildContext("bench: participants.nav", Path("."), DELTA_S, 0.0, limit_s, metocean=field)
    nav = NavigationParticipant.from_options("nav", {"goal_nm": list(GOAL_NM), "start_nm": [0.0, 0.0], **options},
                                             context)
    goal = np.array(GOAL_NM) * NM
    state = {"x": 0.0, "y": 0.0, "psi": np.pi / 4, "u": 9.26}
    begin = time.process_time()
    out = nav.setup(0.0, state)
    updates = [time.process_time() - begin]
    points, times = [np.zeros(2)], [0.0]
    t = 0.0
    while t < limit_s:
        reference = out["reference"]
        nxt = reference[1]
        step_m = np.hypot(*(nxt[1:3] - points[-1]))
        to_goal = np.hypot(*(goal - points[-1]))
        if to_goal < 1.0:
            break
        if to_goal <= step_m + 1.0:  # arrives within this interval
            speed = max(float(out.get("planned_speed_mps", 18 * KNOT)), step_m / DELTA_S)
            fraction = min(to_goal / (speed * DELTA_S), 1.0)
            points.append(goal)
            times.append(t + fraction * DELTA_S)
            break
        t += DELTA_S
        points.append(nxt[1:3].copy())
        times.append(t)
        # u is the speed through water: the planned one when the reference is tracked exactly
        state = {"x": nxt[1], "y": nxt[2], "psi": nxt[3], "u": float(out.get("planned_speed_mps", nxt[4]))}
        begin = time.process_time()
        out = nav.step(t, DELTA_S, state)
        updates.append(time.process_time() - begin)
    return np.array(points), np.array(times), np.array(updates)


def update_figures(updates: np.ndarray) -> dict:
    """CPU milliseconds of the set-up and the median and max of the later updates."""
    return {"setup_ms": 1e3 * float(updates[0]), "update_median_ms": 1e3 * float(np.median(updates[1:])),
            "update_max_ms": 1e3 * float(np.max(updates[1:]))}


def measure(field, label: str, arrival_min: float, methods=("routing", "paper")) -> dict:
    problem = RoutingProblem((0.0, 0.0), (GOAL_NM[0] * NM, GOAL_NM[1] * NM), field)
    row = {"weather": label}
    goal = np.array(GOAL_NM) * NM
    for method, options in (("routing", {"arrival_time_min": arrival_min}), ("paper", PAPER)):
        if method not in methods:
            continue
        points, times, updates = sail(field, options)
        arrival = float(times[-1])
        if np.hypot(*(points[-1] - goal)) > 0.5 * NM:  # did not arrive: no share
            row[method] = {"arrival_h": float("nan"), "available_pct": float("nan"), "saving_pct": float("nan"),
                           "share": float("nan"), **update_figures(updates)}
            continue
        sailed = cost_of_track(field, problem.energy, points, times)["cost_usd"]
        straight = straight_route(problem, arrival_s=arrival).cost_usd
        optimal = optimal_route(problem, arrival_s=arrival).cost_usd
        available = 1.0 - optimal / straight
        saving = 1.0 - sailed / straight
        row[method] = {"arrival_h": arrival / 3600.0, "available_pct": 100 * available, "saving_pct": 100 * saving,
                       "share": saving / available if available > 1e-4 else float("nan"),
                       **update_figures(updates)}
    return row


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--weather", default="storm_set")
    parser.add_argument("--members", type=int, nargs=2, default=(0, 29), metavar=("FIRST", "LAST"))
    parser.add_argument("--arrival-min", type=float, default=480.0)
    parser.add_argument("--resolution-nm", type=float, default=1.0)
    parser.add_argument("--methods", nargs="+", default=["routing", "paper"], choices=["routing", "paper"])
    args = parser.parse_args()
    print(f"{os.cpu_count()} CPUs, load average {os.getloadavg()[0]:.1f}; routing arrives at {args.arrival_min:g} min, "
          f"paper sails 18 kn; each costed against straight and optimal routes at its own arrival")
    if args.weather == "storm_set":
        cases = [(f"storm_set {m}", weather_generators.storm_set(member=m, resolution_nm=args.resolution_nm))
                 for m in range(args.members[0], args.members[1] + 1)]
    else:
        cases = [(args.weather, getattr(weather_generators, args.weather)(resolution_nm=args.resolution_nm))]
    rows = []
    print(f"{'weather':<14} {'method':<8} {'arrival h':>9} {'available %':>11} {'saving %':>9} {'share':>7} "
          f"{'CPU ms: update median / max, set-up':>36}")
    for label, field in cases:
        row = measure(field, label, args.arrival_min, args.methods)
        rows.append(row)
        for method in args.methods:
            r = row[method]
            print(f"{label:<14} {method:<8} {r['arrival_h']:9.2f} {r['available_pct']:11.2f} {r['saving_pct']:9.2f} "
                  f"{r['share']:7.2f} {r['update_median_ms']:14.1f} / {r['update_max_ms']:6.1f}, {r['setup_ms']:7.1f}",
                  flush=True)
    for method in args.methods:
        shares = np.array([row[method]["share"] for row in rows])
        valid = shares[np.isfinite(shares)]
        arrived = [row[method]["saving_pct"] for row in rows if np.isfinite(row[method]["saving_pct"])]
        worst = min(arrived) if arrived else float("nan")
        print(f"{method}: arrived in {len(arrived)} of {len(rows)} weathers; CPU per update after set-up: median "
              f"{np.median([row[method]['update_median_ms'] for row in rows]):.1f} ms, max "
              f"{max(row[method]['update_max_ms'] for row in rows):.1f} ms; set-up max "
              f"{max(row[method]['setup_ms'] for row in rows):.0f} ms")
        if valid.size:
            print(f"{method}: median share {np.median(valid):.2f} over {valid.size} weathers with a saving available "
                  f"(quartiles {np.percentile(valid, 25):.2f} / {np.percentile(valid, 75):.2f}); worst saving against "
                  f"the equal-arrival straight line {worst:+.2f} %")


if __name__ == "__main__":
    main()
