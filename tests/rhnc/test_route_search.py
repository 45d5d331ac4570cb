"""The grid-graph search core: moves, obstacles, Dijkstra, times along the tree, shortening."""

import math

import numpy as np
import pytest

from rhnc.routing.route_search import (IMPASSABLE, build_grid_graph, cost_to_go_tree, grid_moves, segment_clearance,
                                       shortcut_path, simplify_polyline,
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


def test_simplifying_drops_the_staircase_and_keeps_the_turns():
    staircase = np.array([[0, 0], [1, 0], [1, 1], [2, 1], [2, 2], [3, 2], [3, 3], [9, 3]])
    simplified = simplify_polyline(staircase, 0.8)
    assert simplified.dtype == float  # integer input, float coordinates
    np.testing.assert_array_equal(simplified, [[0, 0], [3, 3], [9, 3]])
    # a turn at the second vertex, and one of three vertices, are kept; a straight three are not
    np.testing.assert_array_equal(simplify_polyline([[0, 0], [0, 5], [6, 5], [12, 5]], 0.5), [[0, 0], [0, 5], [12, 5]])
    np.testing.assert_array_equal(simplify_polyline([[0, 0], [4, 3], [8, 0]], 0.5), [[0, 0], [4, 3], [8, 0]])
    np.testing.assert_array_equal(simplify_polyline([[0, 0], [4, 0.1], [8, 0]], 0.5), [[0, 0], [8, 0]])
    # distance to the segment, not to its line: a vertex beyond either end, or on a loop back to the start
    np.testing.assert_array_equal(simplify_polyline([[0, 0], [-5, 0], [5, 0]], 1.0), [[0, 0], [-5, 0], [5, 0]])
    np.testing.assert_array_equal(simplify_polyline([[0, 0], [10, 0], [5, 0]], 1.0), [[0, 0], [10, 0], [5, 0]])
    np.testing.assert_array_equal(simplify_polyline([[0, 0], [5, 5], [0, 0]], 1.0), [[0, 0], [5, 5], [0, 0]])
    # two points: as given
    np.testing.assert_array_equal(simplify_polyline([[0, 0], [5, 5]], 1.0), [[0, 0], [5, 5]])


def test_segment_clearance_keeps_the_shape_of_its_batch():
    a = np.zeros((2, 3, 2))
    b = np.stack([np.full((3, 2), 10.0), np.tile([10.0, 0.0], (3, 1))])
    clearance = segment_clearance(a, b, (0.0, 5.0))
    assert clearance.shape == (2, 3)
    np.testing.assert_allclose(clearance, [[5 / np.sqrt(2)] * 3, [5.0] * 3])


def test_an_edge_lookup_refuses_a_move_into_an_obstacle():
    axis = np.arange(0.0, 8.0)
    graph = build_grid_graph(axis, axis, reach=1, obstacles=[(4.0, 4.0, 0.5)])  # node (4, 4) blocked
    ny = 8
    edge = graph.edge_between(np.array([3 * ny + 3]), np.array([3 * ny + 4]))
    assert graph.source[edge[0]] == 3 * ny + 3 and graph.target[edge[0]] == 3 * ny + 4
    with pytest.raises(ValueError, match="no edge between some of the given nodes"):
        graph.edge_between(np.array([3 * ny + 3, 3 * ny + 3]), np.array([3 * ny + 4, 4 * ny + 4]))


@pytest.mark.parametrize("reach, di, dj", [
    (1, 0, 0),     # a node with itself: no move, the look-up's fill
    (1, 0, 2),     # beyond the reach, past the look-up's end
    (1, 0, -2),    # beyond the reach, a negative index that would wrap round
    (1, -2, 1),
    (2, 2, 2),     # within the reach but not primitive (two diagonal moves)
])
def test_an_edge_lookup_refuses_an_offset_that_is_no_move(reach, di, dj):
    axis = np.arange(0.0, 8.0)
    graph = build_grid_graph(axis, axis, reach=reach)
    ny = 8
    source = 3 * ny + 3
    with pytest.raises(ValueError, match="no edge between some of the given nodes"):
        graph.edge_between(np.array([source]), np.array([source + di * ny + dj]))


def test_the_trees_span_every_node_when_the_last_node_lies_in_an_obstacle():
    # node 63, the highest id, has no edge in or out: the sparse matrices must still be 64 x 64
    axis = np.arange(0.0, 8.0)
    graph = build_grid_graph(axis, axis, reach=1, obstacles=[(7.0, 7.0, 0.5)])
    assert not graph.free[63]
    weights = graph.move_length_m[graph.move]
    for tree in (shortest_path_tree(graph, weights, 0), cost_to_go_tree(graph, weights, 0)):
        assert tree.cost.shape == (64,)
        assert math.isinf(tree.cost[63]) and tree.cost[62] == pytest.approx(6.0 * math.sqrt(2.0) + 1.0)


def test_a_two_column_grid_has_its_own_spacing():
    graph = build_grid_graph(np.array([0.0, 100.0, 200.0]), np.array([0.0, 300.0]), reach=1)
    east = int(np.flatnonzero((graph.moves == [0, 1]).all(axis=1))[0])
    north = int(np.flatnonzero((graph.moves == [1, 0]).all(axis=1))[0])
    assert graph.move_length_m[east] == 300.0 and graph.move_length_m[north] == 100.0


class _LandBeyond:
    """A stand-in chart: land beyond ``edge_m`` along one axis (0 north, 1 east), kept clear of by
    ``clearance_m``; every leg clear (only the nodes' clearance counts here)."""

    def __init__(self, axis, edge_m, clearance_m):
        self.axis, self.edge_m, self.clearance_m = axis, edge_m, clearance_m

    def distances_m(self, north, east):
        return np.maximum(self.edge_m - np.asarray((north, east)[self.axis], dtype=float), 0.0)

    def legs_clear(self, a, b, *_):
        return np.ones(np.shape(a)[:-1], dtype=bool)


def test_no_node_lies_within_the_charts_clearance():
    axis = np.arange(0.0, 1001.0, 100.0)
    graph = build_grid_graph(axis, axis, reach=1, obstacles=[(100.0, 100.0, 50.0)], keep_out=_LandBeyond(0, 800.0, 150.0))
    points = graph.node_points()
    np.testing.assert_array_equal(graph.free, (points[:, 0] <= 650.0) & ~((points[:, 0] == 100.0) & (points[:, 1] == 100.0)))


def test_shortening_from_the_first_vertex_counts_from_zero_and_never_takes_an_impassable_segment():
    # three equal legs along a line: the direct segments cost what the legs do, so from 0 the last is taken
    def straight(i, js):
        return (js - i).astype(float)

    assert shortcut_path(4, straight) == [0, 3]
    # a blocked second leg (the path crosses it anyway) and, from the first vertex, direct segments costed
    # as blocked: the path through the blocked leg is as dear, but a blocked segment is never taken
    legs = np.array([1.0, IMPASSABLE, 1.0])

    def blocked(i, js):
        return np.array([legs[i] if j == i + 1 else IMPASSABLE if i == 0 else float(j - i) for j in js])

    assert shortcut_path(4, blocked, consecutive_costs=legs) == [0, 1, 3]


def test_a_reach_below_one_is_refused():
    with pytest.raises(ValueError, match="^reach must be at least 1$"):
        grid_moves(0)


def test_a_two_row_grid_has_its_own_spacing():
    graph = build_grid_graph(np.array([0.0, 100.0]), np.array([0.0, 300.0, 600.0]), reach=1)
    east = int(np.flatnonzero((graph.moves == [0, 1]).all(axis=1))[0])
    north = int(np.flatnonzero((graph.moves == [1, 0]).all(axis=1))[0])
    assert graph.move_length_m[east] == 300.0 and graph.move_length_m[north] == 100.0
    assert graph.heading_rad[north] == 0.0 and graph.heading_rad[east] == pytest.approx(np.pi / 2)


def test_a_node_inside_any_of_several_obstacles_is_not_free():
    axis = np.arange(0.0, 11.0)
    graph = build_grid_graph(axis, axis, reach=1, obstacles=[(2.0, 2.0, 1.5), (8.0, 8.0, 1.5)])
    points = graph.node_points()
    inside = ((np.hypot(points[:, 0] - 2, points[:, 1] - 2) < 1.5)
              | (np.hypot(points[:, 0] - 8, points[:, 1] - 8) < 1.5))
    np.testing.assert_array_equal(graph.free, ~inside)


def test_the_charts_clearance_is_measured_from_each_node_and_a_node_at_exactly_it_is_free():
    axis = np.arange(0.0, 1001.0, 100.0)
    graph = build_grid_graph(axis, axis, reach=1, keep_out=_LandBeyond(1, 800.0, 200.0))
    points = graph.node_points()
    # east 600 m lies exactly 200 m from the land: not within the clearance
    np.testing.assert_array_equal(graph.free, points[:, 1] <= 600.0)


def test_no_edge_starts_or_ends_at_a_node_within_the_clearance_even_where_the_chart_says_the_leg_is_clear():
    axis = np.arange(0.0, 1001.0, 100.0)
    graph = build_grid_graph(axis, axis, reach=2, keep_out=_LandBeyond(1, 800.0, 200.0))
    assert graph.free[graph.source].all() and graph.free[graph.target].all()
    # and every move between two free nodes is an edge: 600 m wide strip, all of it kept
    assert graph.source.size == build_grid_graph(axis, axis[:7], reach=2).source.size


def test_a_node_reached_only_at_the_impassable_weight_cannot_be_reached():
    graph = build_grid_graph(np.array([0.0]), np.array([0.0, 100.0]), reach=1)
    tree = shortest_path_tree(graph, np.full(graph.source.size, IMPASSABLE), 0)
    assert tree.cost[1] == IMPASSABLE
    with pytest.raises(ValueError, match="the goal cannot be reached from the start on the routing grid"):
        tree.path_to(1)
