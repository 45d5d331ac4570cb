"""Benchmark: COLREG-aware NMPC solve times with one, two and three targets (N_c = 15).

Own ship northbound at 18 kn on a straight reference; targets on collision courses
meeting it after 15 min: head-on (slightly to starboard), crossing from starboard, and a
slower ship ahead being overtaken, added one by one.  R = 0, R_i = 1 nm, clearance margin
0.05 nm growing by 0.2 kn, disturbance observer on; plant = the numpy model (RK4, 0.5 s).
Prints per case the median and maximum wall time per control step (pipe to the solver
worker included) and processor time of the solver, the iterations, the worst solve (by
processor time: its iterations and time per iteration), the stops at an acceptable point,
the median processor time of the fresh fatrop object built outside the solve, fallbacks and
the smallest separation.  Run with the control interval of the full loop (60 s) and of the
close-quarters experiments (20 s):

    python bench/bench_nmpc_colregs.py [--interval-s 60] [--steps 30]
"""

from __future__ import annotations

import argparse
import math

import numpy as np

from orchestrator.geometry import KNOT, NM
from rhnc.control.nmpc import NMPCController, NMPCSettings
from rhnc.navigation.reference_participant import line_or_turn_reference
from rhnc.ship.ship_model import load_parameter_set, rk4_step

N = 15
SPEED = 18 * KNOT
MEETING_S = 900.0


def target(course_deg: float, speed_kn: float, lateral_nm: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    velocity = speed_kn * KNOT * np.array([math.cos(math.radians(course_deg)), math.sin(math.radians(course_deg))])
    return np.array([SPEED * MEETING_S, lateral_nm * NM]) - velocity * MEETING_S, velocity


TARGETS = [
    target(180.0, 12.0, 0.3),                                                   # head-on
    target(270.0, 15.0),                                                        # crossing from starboard
    (np.array([(SPEED - 8 * KNOT) * MEETING_S, 0.0]), np.array([8 * KNOT, 0.0])),  # overtaken by us
]


def closed_loop(targets: int, interval_s: float, steps: int) -> dict:
    params = load_parameter_set("default")
    settings = NMPCSettings(horizon_steps=N, control_interval_s=interval_s, max_obstacles=3, colregs=True,
                            clearance_margin_m=0.05 * NM, clearance_margin_growth_mps=0.2 * KNOT,
                            disturbance_observer=True)
    controller = NMPCController(params, settings)
    state = np.array([0.0, 0.0, 0.0, SPEED, 0.0, 0.0])
    positions = np.array([start for start, _ in TARGETS[:targets]])
    velocities = np.array([velocity for _, velocity in TARGETS[:targets]])
    wall, cpu, iterations, separation, preparation, acceptable = [], [], [], np.inf, [], 0
    for k in range(steps):
        t = k * interval_s
        obstacles = np.column_stack([positions, velocities, np.full(targets, NM)])
        reference = line_or_turn_reference(t + interval_s * np.arange(N + 1), (0.0, 0.0), 0.0, SPEED)
        solution = controller.solve(t, state, reference, obstacles, et=True)
        wall.append(solution.solve_time_s)
        cpu.append(solution.solve_cpu_time_s)
        iterations.append(solution.iterations)
        preparation.append(solution.preparation_cpu_s)
        acceptable += solution.status == "Solved_To_Acceptable_Level"
        for _ in range(int(interval_s / 0.5)):
            state = rk4_step(state, solution.tau, 0.5, 1, params)
            positions = positions + velocities * 0.5
            separation = min(separation, float(np.min(np.hypot(*(positions - state[:2]).T))))
    controller.close()
    return {"wall": np.array(wall), "cpu": np.array(cpu), "iterations": np.array(iterations),
            "preparation": np.array(preparation), "acceptable": acceptable,
            "fallbacks": controller.fallback_count, "separation_nm": separation / NM}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--interval-s", type=float, default=60.0)
    parser.add_argument("--steps", type=int, default=30)
    args = parser.parse_args()
    print(f"COLREG NMPC, N_c = {N}, interval {args.interval_s:.0f} s, {args.steps} closed-loop steps")
    print(f"{'targets':>8s} {'wall med/max ms':>16s} {'cpu med/max ms':>15s} {'iter med/max':>13s} "
          f"{'worst: iter, ms/iter':>21s} {'acceptable':>10s} {'prep ms':>7s} {'fallbacks':>10s} {'min sep nm':>11s}")
    for targets in (1, 2, 3):
        run = closed_loop(targets, args.interval_s, args.steps)
        wall, cpu = run["wall"] * 1e3, run["cpu"] * 1e3
        worst = int(np.argmax(cpu))
        worst_iterations = int(run["iterations"][worst])
        print(f"{targets:8d} {np.median(wall):7.1f}/{np.max(wall):<8.1f} {np.median(cpu):6.1f}/{np.max(cpu):<8.1f} "
              f"{np.median(run['iterations']):5.0f}/{np.max(run['iterations']):<7d} "
              f"{worst_iterations:12d}, {cpu[worst] / max(worst_iterations, 1):6.2f} {run['acceptable']:10d} "
              f"{np.median(run['preparation']) * 1e3:7.2f} {run['fallbacks']:10d} {run['separation_nm']:11.3f}")
    print("goal: max solve within 200 ms on 2 cores")


if __name__ == "__main__":
    main()
