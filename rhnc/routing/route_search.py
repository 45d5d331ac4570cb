"""Shortest paths on a grid graph with many headings: the search core of weather routing.

The map is covered by a regular grid of nodes (x north, y east [m]).  Each node links to
the nodes reached by a fixed set of *moves*, integer grid offsets ``(di, dj)`` whose
components have no common divisor: with ``reach = 3`` these are the 32 moves with
``max(|di|, |dj|) <= 3`` (headings 0, 18.4, 26.6, 33.7, 45, ... degrees), so a course
between two of them is followed by alternating the two at most ``1 / cos(9.2 deg) - 1 =
1.3 %`` longer than the straight line (reach 1, the 8 king moves, loses up to 8.2 %).
Nodes inside a circular obstacle and moves whose segment enters one are left out; so are
nodes and moves that come closer than a declared clearance to land or a no-go area
(``keep_out``, e.g. a :class:`rhnc.chart.chart.Chart`), judged over each move's whole length.

The graph knows nothing of ships: the caller gives one weight per edge (for the energy
model: the cost of sailing that edge, see :mod:`rhnc.routing.weather_routing`), and
:func:`shortest_path_tree` runs Dijkstra's algorithm (SciPy's compiled implementation).
Weights may depend on the time a node is reached: :func:`times_along_tree` propagates
edge durations down the shortest-path tree, so the caller can re-evaluate the weights at
those times and search again.

:func:`shortcut_path` removes the graph's zig-zag afterwards: from each kept vertex it
jumps to the farthest later vertex whose direct segment costs no more than the path it
replaces, as judged by a caller-supplied cost of straight segments.  In uniform weather
the path becomes the straight line exactly.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING

import numpy as np

from orchestrator.geometry import nearest_on_segments

if TYPE_CHECKING:
    from scipy.sparse import csr_matrix

#: Weight standing for an impassable edge (SciPy's Dijkstra wants finite weights).
IMPASSABLE = 1e30


def grid_moves(reach: int = 3) -> np.ndarray:
    """Primitive grid offsets (k, 2) with ``max(|di|, |dj|) <= reach``, sorted by heading.

    ``reach = 1`` gives the 8 king moves, 2 gives 16 moves, 3 gives 32.
    """
    if reach < 1:
        raise ValueError("reach must be at least 1")
    moves = [(di, dj) for di in range(-reach, reach + 1) for dj in range(-reach, reach + 1)
             if (di, dj) != (0, 0) and math.gcd(abs(di), abs(dj)) == 1]
    moves.sort(key=lambda m: math.atan2(m[1], m[0]) % (2 * math.pi))
    return np.array(moves, dtype=int)


def segment_clearance(a: np.ndarray, b: np.ndarray, centre: Sequence[float]) -> np.ndarray:
    """Least distance [m] from ``centre`` to the segments a-b (arrays (..., 2))."""
    return nearest_on_segments(np.asarray(centre, dtype=float)[:2], a, b)[1]


@dataclasses.dataclass(frozen=True)
class GridGraph:
    """A grid of nodes and the moves between them, obstacles removed.

    Attributes
    ----------
    x_m, y_m : ndarray
        Node coordinates north (nx,) and east (ny,) [m]; node id ``i * ny + j``.
    moves : ndarray (k, 2)
        Grid offsets of the moves.
    heading_rad : ndarray (k,)
        Heading of each move [rad, clockwise from north] (grid spacing may differ by axis).
    move_length_m : ndarray (k,)
        Length of each move [m].
    free : ndarray (nx * ny,) bool
        Nodes outside every obstacle.
    source, target, move : ndarray (e,)
        Edges, sorted by source node: end nodes and move index.
    indptr : ndarray (nx * ny + 1,)
        CSR row pointer of the edges.
    edge_index : ndarray (nx * ny, k)
        Edge id of each (source node, move), -1 where the move is not an edge.
    reverse_order, reverse_indptr : ndarray
        The edges sorted by target node and their CSR row pointer (the reversed graph,
        for costs-to-go towards one node).
    """

    x_m: np.ndarray
    y_m: np.ndarray
    moves: np.ndarray
    heading_rad: np.ndarray
    move_length_m: np.ndarray
    free: np.ndarray
    source: np.ndarray
    target: np.ndarray
    move: np.ndarray
    indptr: np.ndarray
    edge_index: np.ndarray
    reverse_order: np.ndarray
    reverse_indptr: np.ndarray

    @property
    def shape(self) -> tuple[int, int]:
        return self.x_m.size, self.y_m.size

    @property
    def node_count(self) -> int:
        return self.x_m.size * self.y_m.size

    def node_points(self) -> np.ndarray:
        """(nx * ny, 2) node coordinates [m], north then east."""
        xx, yy = np.meshgrid(self.x_m, self.y_m, indexing="ij")
        return np.column_stack([xx.ravel(), yy.ravel()])

    def nearest_free_node(self, point: Sequence[float]) -> int:
        """Id of the free node nearest to ``point`` (x, y) [m]."""
        points = self.node_points()
        distance = np.hypot(points[:, 0] - point[0], points[:, 1] - point[1])
        distance[~self.free] = np.inf
        node = int(np.argmin(distance))
        if not np.isfinite(distance[node]):
            raise ValueError("every node of the routing grid lies inside an obstacle")
        return node

    def edge_between(self, source: np.ndarray, target: np.ndarray) -> np.ndarray:
        """Edge ids of the moves ``source -> target`` (node id arrays).

        Raises ``ValueError`` when some pair is no edge: a node with itself, an offset that is
        no move (beyond the reach or not primitive), or a move into or out of an obstacle.
        """
        source = np.asarray(source)
        target = np.asarray(target)
        ny = self.y_m.size
        di = target // ny - source // ny
        dj = target % ny - source % ny
        reach = int(np.max(np.abs(self.moves)))
        lookup = np.full((2 * reach + 1, 2 * reach + 1), -1)
        lookup[self.moves[:, 0] + reach, self.moves[:, 1] + reach] = np.arange(len(self.moves))
        if np.any((np.abs(di) > reach) | (np.abs(dj) > reach)):
            raise ValueError("no edge between some of the given nodes")
        move = lookup[di + reach, dj + reach]
        edges = self.edge_index[source, move]
        if np.any((move < 0) | (edges < 0)):
            raise ValueError("no edge between some of the given nodes")
        return edges

    def edge_matrix(self, weights: np.ndarray) -> csr_matrix:
        """The graph as a sparse matrix with one weight per edge (in edge order)."""
        from scipy.sparse import csr_matrix  # scipy.sparse here: 0.09 s a run without routing need not pay

        n = self.node_count
        return csr_matrix((np.asarray(weights, dtype=float), self.target, self.indptr), shape=(n, n))

    def reversed_edge_matrix(self, weights: np.ndarray) -> csr_matrix:
        """The graph with every edge turned round, same weights (edge order of ``weights``)."""
        from scipy.sparse import csr_matrix

        n = self.node_count
        order = self.reverse_order
        return csr_matrix((np.asarray(weights, dtype=float)[order], self.source[order], self.reverse_indptr),
                          shape=(n, n))


def build_grid_graph(x_m: np.ndarray, y_m: np.ndarray, reach: int = 3,
                     obstacles: Sequence[Sequence[float]] = (), keep_out=None) -> GridGraph:
    """Nodes at ``x_m`` x ``y_m`` and the moves of :func:`grid_moves` between free nodes.

    Parameters
    ----------
    x_m, y_m : array_like
        Evenly spaced node coordinates north and east [m].
    reach : int
        Longest move in grid steps (3: 32 headings).
    obstacles : sequence of (north_m, east_m, radius_m)
        Circles no node or edge may enter.
    keep_out : object, optional
        Areas kept clear of (land, no-go) with ``clearance_m``, ``distances_m(north, east)``
        and ``legs_clear(a, b, distance_a, distance_b)``: no node within the clearance, no
        move whose segment comes within it anywhere along its length.
    """
    x_m = np.asarray(x_m, dtype=float)
    y_m = np.asarray(y_m, dtype=float)
    nx, ny = x_m.size, y_m.size
    dx = float(x_m[1] - x_m[0]) if nx > 1 else 1.0
    dy = float(y_m[1] - y_m[0]) if ny > 1 else 1.0
    moves = grid_moves(reach)
    heading = np.arctan2(moves[:, 1] * dy, moves[:, 0] * dx) % (2 * np.pi)
    length = np.hypot(moves[:, 0] * dx, moves[:, 1] * dy)
    ii, jj = np.meshgrid(np.arange(nx), np.arange(ny), indexing="ij")
    points = np.stack([x_m[ii], y_m[jj]], axis=-1)
    free = np.ones((nx, ny), dtype=bool)
    circles = [tuple(float(v) for v in c) for c in obstacles]
    for cx, cy, radius in circles:
        free &= np.hypot(points[..., 0] - cx, points[..., 1] - cy) >= radius
    if keep_out is not None:
        node_distance = keep_out.distances_m(points[..., 0].ravel(), points[..., 1].ravel()).reshape(nx, ny)
        free &= node_distance >= keep_out.clearance_m
    sources, targets, move_ids = [], [], []
    for k, (di, dj) in enumerate(moves):
        ok = (ii + di >= 0) & (ii + di < nx) & (jj + dj >= 0) & (jj + dj < ny)
        ok[ok] &= free[ii[ok], jj[ok]] & free[ii[ok] + di, jj[ok] + dj]
        si, sj = ii[ok], jj[ok]
        for cx, cy, radius in circles:
            clear = segment_clearance(points[si, sj], points[si + di, sj + dj], (cx, cy)) >= radius
            si, sj = si[clear], sj[clear]
        if keep_out is not None and si.size:
            clear = keep_out.legs_clear(points[si, sj], points[si + di, sj + dj], node_distance[si, sj],
                                        node_distance[si + di, sj + dj])
            si, sj = si[clear], sj[clear]
        sources.append(si * ny + sj)
        targets.append((si + di) * ny + sj + dj)
        move_ids.append(np.full(si.size, k))
    source = np.concatenate(sources)
    order = np.argsort(source, kind="stable")
    source = source[order]
    move = np.concatenate(move_ids)[order]
    indptr = np.concatenate([[0], np.cumsum(np.bincount(source, minlength=nx * ny))])
    edge_index = np.full((nx * ny, len(moves)), -1, dtype=np.int64)
    edge_index[source, move] = np.arange(source.size)
    target = np.concatenate(targets)[order]
    reverse_order = np.argsort(target, kind="stable")
    reverse_indptr = np.concatenate([[0], np.cumsum(np.bincount(target, minlength=nx * ny))])
    return GridGraph(x_m=x_m, y_m=y_m, moves=moves, heading_rad=heading, move_length_m=length,
                     free=free.ravel(), source=source, target=target, move=move, indptr=indptr,
                     edge_index=edge_index, reverse_order=reverse_order, reverse_indptr=reverse_indptr)


@dataclasses.dataclass(frozen=True)
class ShortestPathTree:
    """Dijkstra's result from one source: ``cost`` per node (inf where unreachable) and
    ``predecessor`` per node (-9999 at the source and where unreachable)."""

    source: int
    cost: np.ndarray
    predecessor: np.ndarray

    def path_to(self, node: int) -> np.ndarray:
        """Node ids from the source to ``node``."""
        if not np.isfinite(self.cost[node]) or self.cost[node] >= IMPASSABLE:
            raise ValueError("the goal cannot be reached from the start on the routing grid")
        path = [int(node)]
        while path[-1] != self.source:
            path.append(int(self.predecessor[path[-1]]))
        return np.array(path[::-1])


def shortest_path_tree(graph: GridGraph, weights: np.ndarray, source: int) -> ShortestPathTree:
    """Dijkstra from ``source`` with one non-negative weight per edge (edge order)."""
    from scipy.sparse.csgraph import dijkstra

    cost, predecessor = dijkstra(graph.edge_matrix(weights), directed=True, indices=int(source),
                                 return_predecessors=True)
    return ShortestPathTree(source=int(source), cost=cost, predecessor=predecessor)


def cost_to_go_tree(graph: GridGraph, weights: np.ndarray, target: int) -> ShortestPathTree:
    """Dijkstra towards ``target``: ``cost`` is each node's cost to reach it and
    ``predecessor`` the next node on the way (-9999 at the target and where it cannot
    be reached).  ``source`` of the result is the target."""
    from scipy.sparse.csgraph import dijkstra

    cost, successor = dijkstra(graph.reversed_edge_matrix(weights), directed=True, indices=int(target),
                               return_predecessors=True)
    return ShortestPathTree(source=int(target), cost=cost, predecessor=successor)


def times_along_tree(tree: ShortestPathTree, edge_duration_s: np.ndarray, graph: GridGraph,
                     start_time_s: float) -> np.ndarray:
    """Time [s] each node is reached along the shortest-path tree.

    ``edge_duration_s`` holds one duration per edge (edge order).  Unreachable nodes get
    ``start_time_s``.  Vectorised by pointer jumping (log2 of the tree depth passes).
    """
    n = graph.node_count
    own = np.arange(n)
    parent = tree.predecessor.astype(np.int64)
    reached = parent >= 0
    into = np.zeros(n)
    into[reached] = np.asarray(edge_duration_s)[graph.edge_between(parent[reached], own[reached])]
    ancestor = np.where(reached, parent, own)
    elapsed = into
    while np.any(ancestor != ancestor[ancestor]):
        elapsed = elapsed + elapsed[ancestor]
        ancestor = ancestor[ancestor]
    return start_time_s + elapsed


def simplify_polyline(points: np.ndarray, tolerance_m: float) -> np.ndarray:
    """The polyline with every vertex dropped that lies within ``tolerance_m`` [m] of the
    simplified line (Douglas-Peucker); first and last vertex are kept.

    Applied with half a grid step it straightens the staircase a grid path makes along a
    course between two of the grid's headings, and keeps its real turns.
    """
    points = np.asarray(points, dtype=float)
    if len(points) < 3:
        return points.copy()
    keep = np.zeros(len(points), dtype=bool)
    keep[[0, -1]] = True
    stack = [(0, len(points) - 1)]
    while stack:
        first, last = stack.pop()
        if last - first < 2:
            continue
        inner = points[first + 1:last]
        distance = nearest_on_segments(inner, points[first], points[last])[1]
        worst = int(np.argmax(distance))
        if distance[worst] > tolerance_m:
            split = first + 1 + worst
            keep[split] = True
            stack.extend([(first, split), (split, last)])
    return points[keep]


SegmentCosts = Callable[[int, np.ndarray], np.ndarray]


def shortcut_path(vertex_count: int, segment_costs: SegmentCosts, relative_tolerance: float = 1e-9,
                  consecutive_costs: np.ndarray | None = None) -> list[int]:
    """Indices of the vertices kept when the path is shortened where it pays.

    Parameters
    ----------
    vertex_count : int
        Vertices of the path (at least 2).
    segment_costs : callable
        ``segment_costs(i, js)`` returns the cost of the straight segments from vertex i
        to each vertex in ``js`` (``IMPASSABLE`` or inf where a segment is blocked).
    relative_tolerance : float
        A shortcut is taken when it costs at most ``(1 + tol)`` times the path it replaces.
    consecutive_costs : ndarray (vertex_count - 1,), optional
        Costs of the path's own legs when already known (else from ``segment_costs``).

    Returns
    -------
    list of int
        Kept vertex indices, first 0, last ``vertex_count - 1``.  From each kept vertex
        the next is the farthest one whose direct segment is no dearer than the path
        through the vertices between.
    """
    if vertex_count < 2:
        raise ValueError("a path needs at least two vertices")
    last = vertex_count - 1
    if consecutive_costs is not None:
        consecutive = np.asarray(consecutive_costs, dtype=float)
    else:
        consecutive = np.array([float(segment_costs(i, np.array([i + 1]))[0]) for i in range(last)])
    cumulative = np.concatenate([[0.0], np.cumsum(consecutive)])
    kept = [0]
    i = 0
    while i < last:
        js = np.arange(i + 1, last + 1)
        direct = np.asarray(segment_costs(i, js), dtype=float)
        along = cumulative[js] - cumulative[i]
        acceptable = np.isfinite(direct) & (direct < IMPASSABLE) & (direct <= along * (1.0 + relative_tolerance))
        acceptable[0] = True
        i = int(js[np.flatnonzero(acceptable)[-1]])
        kept.append(i)
    return kept
