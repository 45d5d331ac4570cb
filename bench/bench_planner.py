"""Planner update time per navigation step on a 100 x 100 nm map at 0.1 nm resolution.

One update = the field rebuild for a new start point (guidance field over the whole map,
its normalisation) + N_L = 16 descent steps, as the navigation participant runs it every
delta.  Prints median and max over the updates, for the normal case (planning speed
unchanged: EC and EM are kept) and for a full rebuild (new speed: EC and EM recomputed).

Then the "routing" method (:mod:`rhnc.navigation.route_navigation`) at 1 and 0.5 nm, in CPU time
(``time.process_time``), in the paper's weather and in the moving storm.

Run: ``python bench/bench_planner.py [--updates 20] [--resolution-nm 0.1] [--routing-resolution-nm 1 0.5]``
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np

from rhnc.navigation.fields import SuperpositionField, resample_weather
from orchestrator.geometry import KNOT, NM
from rhnc.weather.weather_generators import paper_default
from rhnc.navigation.planner import plan_local_path


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--updates", type=int, default=20)
    parser.add_argument("--resolution-nm", type=float, default=0.1)
    parser.add_argument("--horizon", type=int, default=16)
    parser.add_argument("--routing-resolution-nm", type=float, nargs="+", default=[1.0, 0.5])
    args = parser.parse_args()

    metocean = paper_default(resolution_nm=1.0)
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
    """The "routing" method, CPU time per planning update (``time.process_time``: the machine
    is shared, and its wall clock says more about the other processes than about the planner).

    One update = candidate first legs, the walk down the cost-to-go tree, the shortening of
    the route, its comparison with the route followed and the straight line, the timing of
    the reference, and one piece of a cost-to-go search when one is under way
    (:mod:`rhnc.routing.cost_to_go`).  The planned speed moves by 0.25 kn every 5 updates, so that
    searches for a new speed run; in the moving storm (weather that changes in time) a search
    is always under way.  The first plan (set-up, one whole search) is timed apart.
    """
    from rhnc.navigation.route_navigation import RecedingRoutePlanner
    from rhnc.weather.weather_generators import moving_storm

    goal = (100 * NM, 100 * NM)
    price, delta = 2000.0, 240.0
    for label, field in (("paper_default", metocean), ("moving_storm", moving_storm())):
        for resolution_nm in args.routing_resolution_nm:
            planner = RecedingRoutePlanner(field, goal, resolution_nm=resolution_nm)
            start = np.array([0.0, 0.0])
            begin = time.process_time()
            plan = planner.plan(0.0, start, 18 * KNOT, 18 * KNOT, price, delta, args.horizon)
            setup = time.process_time() - begin
            times = []
            for k in range(1, args.updates * 5 + 1):
                speed = (18.0 + 0.25 * ((k // 5) % 4)) * KNOT
                start = plan.points[1]
                begin = time.process_time()
                plan = planner.plan(k * delta, start, speed, speed, price, delta, args.horizon)
                times.append(time.process_time() - begin)
            print(f"routing method, {label}, {resolution_nm} nm ({planner.graph.node_count} nodes, 32 headings): "
                  f"CPU per update median {1e3 * np.median(times):.1f} ms, max {1e3 * np.max(times):.1f} ms over "
                  f"{len(times)} ({planner.searches - 1} searches spread over them); set-up (whole search) "
                  f"{1e3 * setup:.0f} ms")


if __name__ == "__main__":
    main()
