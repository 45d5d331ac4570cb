"""The processor time of a whole control step: the controller's own work plus its solver calls,
wherever they ran, without the building of new solver objects (done between steps)."""

import time

import numpy as np
import pytest

from rhnc.control.nmpc import NMPCController, NMPCSettings
from rhnc.navigation.reference_participant import line_or_turn_reference
from rhnc.ship.ship_model import load_parameter_set

KNOT = 1852.0 / 3600.0
DT = 20.0
N = 10
BURN_S = 0.2  # far above a step's own processor time (a few ms)


def burn(seconds):
    end = time.process_time() + seconds
    while time.process_time() < end:
        pass


class Burning:
    """A solver that spends ``BURN_S`` of processor time before solving."""

    def __init__(self, solver):
        self.solver = solver

    def __call__(self, **arguments):
        burn(BURN_S)
        return self.solver(**arguments)

    def stats(self):
        return self.solver.stats()


@pytest.fixture(scope="module")
def kcs():
    return load_parameter_set("default")


def step(controller):
    state = np.array([0.0, 0.0, 0.3, 18 * KNOT, 0.0, 0.0])
    reference = line_or_turn_reference(DT * np.arange(N + 1), (0.0, 0.0), 0.3, 18 * KNOT)
    return controller.solve(0.0, state, reference)


@pytest.mark.parametrize("wall_time_s", [None, 30.0], ids=["in-process", "worker"])
def test_the_step_counts_the_solver_wherever_it_ran(kcs, wall_time_s):
    controller = NMPCController(kcs, NMPCSettings(horizon_steps=N, control_interval_s=DT, max_obstacles=1,
                                                  wall_time_limit_s=wall_time_s, cpu_time_limit_s=None))
    controller.solvers._solvers["hard"] = Burning(controller.solvers._solvers["hard"])  # before the fork
    try:
        solution = step(controller)
    finally:
        controller.close()
    assert solution.success
    assert solution.solve_cpu_time_s >= BURN_S
    assert solution.step_cpu_time_s >= solution.solve_cpu_time_s


def test_new_solver_objects_built_in_process_are_left_out_of_the_step(kcs):
    controller = NMPCController(kcs, NMPCSettings(horizon_steps=N, control_interval_s=DT, max_obstacles=1,
                                                  wall_time_limit_s=None, cpu_time_limit_s=None))
    real = controller.solvers._solvers["hard"]

    def slow_factory():
        burn(BURN_S)
        return real

    controller.solvers.renew = lambda outcome: True
    controller.solvers.factories["hard"] = slow_factory
    solution = step(controller)
    assert solution.preparation_cpu_s >= BURN_S
    assert solution.step_cpu_time_s < BURN_S, "the new solver object's building was counted in the step"
    assert solution.step_cpu_time_s >= solution.solve_cpu_time_s > 0.0
