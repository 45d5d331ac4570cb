"""The initial guess pushed clear of the collision domains, node by node against the geometry:
a guessed position inside a domain moves perpendicular to the reference course onto the
domain's (grown, inflated) rim, to the side it lies on, or to starboard for a give-way domain."""

import math

import numpy as np
import pytest

from rhnc.control.nmpc_warm_start import push_guess_clear

DT = 1.0


def domain(centre, velocity=(0.0, 0.0), offset=(0.0, 0.0), rho=2.0, growth=0.0, inflation=0.0):
    """One active slot (cx, cy, vx, vy, ox, oy, rho, growth, inflation, active) as a (10, 1) array."""
    return np.array([[*centre, *velocity, *offset, rho, growth, inflation, 1.0]]).T


def guess(points):
    """Scaled states (N+1, 6) with the given positions, other states zero."""
    z = np.zeros((len(points), 6))
    z[:, :2] = points
    return z


def north(nodes):
    """A reference course of 0 (north, along x) at every node; starboard is +y."""
    return np.zeros((6, nodes))


def test_a_node_inside_a_static_domain_moves_onto_its_rim_to_the_side_it_lies_on():
    z = guess([(0.0, 0.0), (9.0, 0.5), (10.5, -1.0), (20.0, 0.5)])
    push_guess_clear(z, domain((10.0, 0.0)), north(4), DT)
    r_push = 1.1 * 2.0
    # along the course the node keeps its place; across it, it goes to the rim on its side
    np.testing.assert_allclose(z[1, :2], [9.0, math.sqrt(r_push ** 2 - 1.0)])
    np.testing.assert_allclose(z[2, :2], [10.5, -math.sqrt(r_push ** 2 - 0.25)])
    np.testing.assert_array_equal(z[[0, 3], :2], [(0.0, 0.0), (20.0, 0.5)])  # the start, and a node outside


def test_a_moving_domain_is_met_where_it_is_at_the_nodes_time():
    # the target runs east at 1 per second from 10 west of the course: at node k it is at y = -10 + k
    start, velocity = (5.0, -10.0), (0.0, 1.0)
    z = guess([(0.0, 0.0)] + [(5.0, -10.0 + k + 0.5) for k in (1, 2, 3)])
    push_guess_clear(z, domain(start, velocity, growth=0.5, inflation=0.21), north(4), DT)
    for k in (1, 2, 3):
        r_push = 1.1 * (2.0 + 0.5 * k) * 1.1
        np.testing.assert_allclose(z[k, :2], [5.0, -10.0 + k + r_push])


@pytest.mark.parametrize("offset, pushed_to_starboard", [((0.0, 1.0), True), ((0.0, 0.0), False)])
def test_a_domain_moved_to_the_targets_starboard_pushes_every_node_to_starboard(offset, pushed_to_starboard):
    # the target heads north; its domain centre is shifted half a radius to its starboard (give way)
    z = guess([(0.0, 0.0), (10.0, -1.0)])
    target = (9.0, -offset[1])  # the shifted centre at (10, 0): the node lies 1 to its port
    push_guess_clear(z, domain(target, velocity=(1.0, 0.0), offset=offset), north(2), DT)
    rim = 1.1 * 2.0
    assert z[1, 1] == pytest.approx(rim if pushed_to_starboard else -rim)


def test_inactive_slots_push_nothing():
    z = guess([(0.0, 0.0), (10.0, 0.5)])
    slot = domain((10.0, 0.0))
    slot[9] = 0.0
    push_guess_clear(z, slot, north(2), DT)
    np.testing.assert_array_equal(z[1, :2], [10.0, 0.5])


@pytest.mark.parametrize("course_deg", [30.0, 90.0, -135.0])
def test_the_push_turns_with_the_reference_course(course_deg):
    # the first test's geometry turned to another course: the nodes move across that course,
    # onto the same rim points turned with it
    turn = math.radians(course_deg)
    rotation = np.array([[math.cos(turn), -math.sin(turn)], [math.sin(turn), math.cos(turn)]])
    points = np.array([(0.0, 0.0), (9.0, 0.5), (10.5, -1.0), (20.0, 0.5)])
    z = guess(points @ rotation.T)
    push_guess_clear(z, domain(rotation @ np.array([10.0, 0.0])), np.full((6, 4), turn), DT)
    r_push = 1.1 * 2.0
    expected = np.array([(0.0, 0.0), (9.0, math.sqrt(r_push ** 2 - 1.0)), (10.5, -math.sqrt(r_push ** 2 - 0.25)),
                         (20.0, 0.5)])
    np.testing.assert_allclose(z[:, :2], expected @ rotation.T, atol=1e-12)


def test_a_plan_stored_without_multipliers_keeps_none():
    from rhnc.control.nmpc_warm_start import PlanMemory

    memory = PlanMemory(5, 20.0, lambda *args: None)
    memory.store(0.0, np.zeros((6, 6)), np.zeros((5, 2)))
    assert memory.lam_x is None and memory.lam_g is None
    memory.store(20.0, np.zeros((6, 6)), np.zeros((5, 2)), lam_x=np.ones(3), lam_g=np.ones(4))
    assert memory.lam_g.shape == (4,)
