"""Planner update time per navigation step on a 100 x 100 nm map at 0.1 nm resolution.

One update = the field rebuild for a new start point (guidance field over the whole map,
its normalisation) + N_L = 16 descent steps, as the navigation participant runs it every
delta.  Prints median and max over the updates, for the normal case (planning speed
unchanged: EC and EM are kept) and for a full rebuild (new speed: EC and EM recomputed).

Then the same for the "routing" method (:mod:`rhnc.route_navigation`) at 1 and 0.5 nm.

Run: ``python bench/bench_planner.py [--updates 20] [--resolution-nm 0.1] [--routing-resolution-nm 1 0.5]``
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np

from rhnc.fields import SuperpositionField, resample_weather
from orchestrator.geometry import KNOT, NM
from rhnc.metocean import MetOceanField
from rhnc.planner import plan_local_path


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--updates", type=int, default=20)
    parser.add_argument("--resolution-nm", type=float, default=0.1)
    parser.add_argument("--horizon", type=int, default=16)
    parser.add_argument("--routing-resolution-nm", type=float, nargs="+", default=[1.0, 0.5])
    args = parser.parse_args()

    metocean = MetOceanField.generate_paper_default(resolution_nm=1.0)
    weather = resample_weather(metocean, args.resolution_nm)
    goal = (100 * NM, 100 * NM)
    field = SuperpositionField(weather, goal)
    speed = 18 * KNOT
    delta = 240.0
    print(f"grid {weather.x.size} x {weather.y.size} nodes ({args.resolution_nm} nm), N_L = {args.horizon}, "
          f"{os.cpu_count()} CPUs")

    start = np.array([0.0, 0.0])
    field.update(start, speed)  # first build: EC/EM
    times = []
    for _ in range(args.updates):
        begin = time.perf_counter()
        field.update(start, speed)
        path = plan_local_path(field, start, speed * delta, args.horizon)
        times.append(time.perf_counter() - begin)
        start = path.points[1]
    print(f"update (G rebuild + {args.horizon} steps): median {1e3 * np.median(times):.1f} ms, "
          f"max {1e3 * np.max(times):.1f} ms over {args.updates}")

    full = []
    for k in range(max(3, args.updates // 4)):
        begin = time.perf_counter()
        field.update(start, speed * (1.0 + 1e-3 * (k + 1)))
        plan_local_path(field, start, speed * delta, args.horizon)
        full.append(time.perf_counter() - begin)
    print(f"full rebuild (EC, EM, G + {args.horizon} steps, new speed): median {1e3 * np.median(full):.1f} ms, "
          f"max {1e3 * np.max(full):.1f} ms over {len(full)}")
    routing_updates(metocean, args)


def routing_updates(metocean, args) -> None:
    """The "routing" method: one update = candidate first nodes, the walk down the cost-to-go
    tree, the shortening over the horizon and the timing of the reference; the cost-to-go
    search itself is timed apart (it runs at set-up and when the planned speed changes step)."""
    from rhnc.route_navigation import RecedingRoutePlanner

    goal = (100 * NM, 100 * NM)
    for resolution_nm in args.routing_resolution_nm:
        planner = RecedingRoutePlanner(metocean, goal, resolution_nm=resolution_nm)
        speed, price, delta = 18 * KNOT, 2000.0, 240.0
        searches = []
        for k in range(3):
            begin = time.perf_counter()
            planner.cost_to_go(0.0, np.zeros(2), speed + k * 0.3, price)
            searches.append(time.perf_counter() - begin)
        start = np.array([0.0, 0.0])
        times = []
        for _ in range(args.updates * 5):
            begin = time.perf_counter()
            plan = planner.plan(0.0, start, speed, speed, price, delta, args.horizon)
            times.append(time.perf_counter() - begin)
            start = plan.points[1]
        print(f"routing method at {resolution_nm} nm ({planner.graph.node_count} nodes, 32 headings): update "
              f"median {1e3 * np.median(times):.1f} ms, max {1e3 * np.max(times):.1f} ms over {len(times)}; "
              f"cost-to-go search (new speed) median {1e3 * np.median(searches):.0f} ms")


if __name__ == "__main__":
    main()
