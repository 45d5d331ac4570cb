"""The grid-graph search core: moves, obstacles, Dijkstra, times along the tree, shortening."""

import math

import numpy as np
import pytest

from rhnc.routing.route_search import (build_grid_graph, cost_to_go_tree, grid_moves, segment_clearance, shortcut_path,
                               shortest_path_tree, times_along_tree)


def test_moves_are_the_primitive_offsets_with_their_headings():
    for reach, count in ((1, 8), (2, 16), (3, 32)):
        moves = grid_moves(reach)
        assert len(moves) == count == len({tuple(m) for m in moves})
        assert all(math.gcd(abs(a), abs(b)) == 1 for a, b in moves)
    headings = np.degrees(np.arctan2(grid_moves(3)[:, 1], grid_moves(3)[:, 0]) % (2 * np.pi))
    assert np.all(np.diff(headings) > 0)
    assert np.max(np.diff(np.concatenate([headings, [360.0]]))) == pytest.approx(np.degrees(np.arctan(1 / 3)))


def test_no_node_or_edge_enters_an_obstacle():
    axis = np.arange(0.0, 21.0)
    circle = (10.0, 10.0, 3.0)
    graph = build_grid_graph(axis, axis, reach=3, obstacles=[circle])
    points = graph.node_points()
    assert not np.any(graph.free & (np.hypot(points[:, 0] - 10, points[:, 1] - 10) < 3.0))
    clearance = segment_clearance(points[graph.source], points[graph.target], circle[:2])
    assert np.min(clearance) >= 3.0
    # a move from (7, 11) to (10, 13) has both ends outside the circle but cuts it
    a, b = 7 * 21 + 11, 10 * 21 + 13
    assert graph.free[a] and graph.free[b]
    assert not np.any((graph.source == a) & (graph.target == b))


def test_dijkstra_and_the_times_along_its_tree():
    axis = np.arange(0.0, 12.0) * 100.0
    graph = build_grid_graph(axis, axis, reach=2)
    length = graph.move_length_m[graph.move]
    tree = shortest_path_tree(graph, length, source=0)
    ny = axis.size
    # on-grid bearings are reached at their straight-line length
    for i, j in ((11, 11), (0, 7), (10, 5), (4, 8)):
        assert tree.cost[i * ny + j] == pytest.approx(100.0 * math.hypot(i, j))
    # times: each node's time is the sum of its tree edges' durations (speed 2 m/s here)
    times = times_along_tree(tree, length / 2.0, graph, start_time_s=50.0)
    np.testing.assert_allclose(times, 50.0 + tree.cost / 2.0)
    path = tree.path_to(11 * ny + 5)
    assert path[0] == 0 and path[-1] == 11 * ny + 5


def test_shortening_takes_the_farthest_segment_that_is_no_dearer():
    # vertices on a zig-zag; a straight segment costs its length, except that segments
    # ending at vertex 4 or beyond from vertex 0 or 1 cost a penalty
    vertices = np.array([[0, 0], [1, 1], [2, 0], [3, 1], [4, 0], [5, 1]], dtype=float)

    def costs(i, js):
        direct = np.hypot(*(vertices[js] - vertices[i]).T)
        return np.where((i < 2) & (js >= 4), direct + 10.0, direct)

    assert shortcut_path(len(vertices), costs) == [0, 3, 5]
    with pytest.raises(ValueError, match="at least two vertices"):
        shortcut_path(1, costs)


def test_cost_to_go_is_the_cost_of_the_path_from_each_node():
    axis = np.arange(0.0, 9.0) * 100.0
    graph = build_grid_graph(axis, axis, reach=3, obstacles=[(400.0, 400.0, 150.0)])
    rng = np.random.default_rng(1)
    weights = graph.move_length_m[graph.move] * rng.uniform(1.0, 2.0, graph.source.size)  # direction-dependent
    target = 8 * 9 + 8
    backward = cost_to_go_tree(graph, weights, target)
    for start in (0, 4, 36, 8 * 9):
        forward = shortest_path_tree(graph, weights, start)
        assert backward.cost[start] == pytest.approx(forward.cost[target])
        # following the successors from the start reaches the target at that cost
        node, total = start, 0.0
        while node != target:
            nxt = int(backward.predecessor[node])
            total += weights[graph.edge_between(np.array([node]), np.array([nxt]))[0]]
            node = nxt
        assert total == pytest.approx(backward.cost[start])
