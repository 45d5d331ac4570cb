"""Optimal weather routing on a 100 x 100 nm map at 0.5 nm: time, saving, discretisation error.

Prints, for the generated weathers of :mod:`rhnc.weather.weather_generators` (``paper_default``,
``storm_off_route``, ``cyclone``, ``moving_storm``: see docs/weather.md), the straight line's
cost at 18 kn and the optimum at that speed and at the
straight line's arrival time, with the optimiser's wall time (goal: within 5 s on 2
cores; the whole call, graph built).  Then the residual error of the discretisation in
uniform weather: the cost of the graph's own path (before shortening) against the exact
straight line, for 8, 16 and 32 headings and several bearings.

Run: ``python bench/bench_weather_routing.py [--resolution-nm 0.5] [--repeat 3] [--weather NAME ...]``
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np

from rhnc.weather import weather_generators
from orchestrator.geometry import KNOT, NM
from rhnc.weather.metocean import MetOceanField
from rhnc.routing.route_search import shortest_path_tree
from rhnc.routing.track_cost import constant_speed_times, cost_of_track, densify
from rhnc.routing.weather_routing import RouteSearch, RoutingProblem, optimal_route, straight_route


def timed(call, repeat: int):
    """Result, median and max wall time [s], median CPU time of this process [s] (on a
    loaded machine the CPU time is what the wall time would be on an idle one)."""
    times, cpu, result = [], [], None
    for _ in range(repeat):
        begin, begin_cpu = time.perf_counter(), time.process_time()
        result = call()
        times.append(time.perf_counter() - begin)
        cpu.append(time.process_time() - begin_cpu)
    return result, float(np.median(times)), float(np.max(times)), float(np.median(cpu))


def weather_case(name: str, field: MetOceanField, resolution_nm: float, repeat: int) -> None:
    problem = RoutingProblem((0.0, 0.0), (100 * NM, 100 * NM), field, resolution_nm=resolution_nm)
    speed = 18 * KNOT
    straight = straight_route(problem, speed_mps=speed)
    fixed_speed, median_s, max_s, cpu_s = timed(lambda: optimal_route(problem, speed_mps=speed), repeat)
    print(f"{name}: straight line at 18 kn: {straight.cost_usd:,.0f} USD, {straight.duration_s / 3600:.2f} h")
    print(f"  optimum at 18 kn:           {fixed_speed.cost_usd:,.0f} USD ({100 * (fixed_speed.cost_usd / straight.cost_usd - 1):+.2f} %), "
          f"{fixed_speed.duration_s / 3600:.2f} h, {fixed_speed.distance_nm:.1f} nm; "
          f"time median {median_s:.2f} s, max {max_s:.2f} s, CPU {cpu_s:.2f} s")
    fixed_arrival, median_s, max_s, cpu_s = timed(lambda: optimal_route(problem, arrival_s=straight.arrival_s),
                                                  repeat)
    print(f"  optimum at equal arrival:   {fixed_arrival.cost_usd:,.0f} USD ({100 * (fixed_arrival.cost_usd / straight.cost_usd - 1):+.2f} %), "
          f"{fixed_arrival.speed_through_water_mps / KNOT:.2f} kn, {fixed_arrival.distance_nm:.1f} nm; "
          f"time median {median_s:.2f} s, max {max_s:.2f} s, CPU {cpu_s:.2f} s")


def discretisation_error(resolution_nm: float) -> None:
    x = np.linspace(0.0, 100.0, int(round(100.0 / resolution_nm)) + 1) * NM
    zero = np.zeros((x.size, x.size))
    field = MetOceanField(x, x, {"wind_north": zero - 8.0, "wind_east": zero - 4.0, "hs": zero + 1.5,
                                 "current_north": zero, "current_east": zero})
    speed = 18 * KNOT
    print("uniform weather: graph path (no shortening) against the exact straight line, extra cost [%]")
    goals = {"045": (100, 100), "020": (100, 36.4), "006": (100, 10), "059": (60, 100)}
    print("  headings " + "".join(f"{bearing:>9}" for bearing in goals))
    after = {}
    for reach in (1, 2, 3):
        row = []
        for goal in goals.values():
            problem = RoutingProblem((0.0, 0.0), (goal[0] * NM, goal[1] * NM), field, resolution_nm=resolution_nm,
                                     reach=reach)
            search = RouteSearch(problem)
            weight, _ = search.weights(speed, problem.energy.running_cost_usd_day / 24.0, None)
            path = densify(search.nodes[shortest_path_tree(search.graph, weight, search.source).path_to(search.target)],
                           resolution_nm * NM / 2)
            graph_cost = cost_of_track(field, problem.energy, path, constant_speed_times(field, path, speed))["cost_usd"]
            row.append(100.0 * (graph_cost / straight_route(problem, speed_mps=speed).cost_usd - 1.0))
            shortened = search.route(speed, problem.energy.running_cost_usd_day / 24.0, passes=1)
            shortened = densify(shortened, resolution_nm * NM / 2)
            after[goal] = 100.0 * (cost_of_track(field, problem.energy, shortened, constant_speed_times(
                field, shortened, speed))["cost_usd"] / straight_route(problem, speed_mps=speed).cost_usd - 1.0)
        print(f"  {len(search.graph.moves):>8} " + "".join(f"{value:9.3f}" for value in row))
    print("  shortened" + "".join(f"{value:9.3f}" for value in after.values()) + "   (32 headings)")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--resolution-nm", type=float, default=0.5)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--weather", nargs="+", default=["paper_default", "storm_off_route", "cyclone", "moving_storm"])
    args = parser.parse_args()
    print(f"100 x 100 nm at {args.resolution_nm} nm, {os.cpu_count()} CPUs, load average "
          f"{os.getloadavg()[0]:.1f}")
    for name in args.weather:
        field = getattr(weather_generators, name)(resolution_nm=args.resolution_nm)
        weather_case(name, field, args.resolution_nm, args.repeat)
    discretisation_error(args.resolution_nm)


if __name__ == "__main__":
    main()
