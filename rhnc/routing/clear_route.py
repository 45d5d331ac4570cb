"""Routes that keep a chart's clearance: the shortest clear path on a grid, and a given route made clear.

A route given from outside (a sea-route network's port-to-port route, a user's waypoints)
knows nothing of a passage's declared clearance: its legs may run closer to land or a no-go
area than the chart allows.  :func:`route_kept_clear` keeps every leg that is clear along its
whole length and replaces each other leg by the shortest clear path between its ends
(:func:`grid_clear_path`: the search grid of the route search over the leg's surroundings,
shortened wherever a straight leg stays clear), so the route keeps the clearance by the same
test as the route search's own routes (``keep_out.legs_clear``).  Inner waypoints inside the
clearance are dropped first (the legs from their neighbours are then made clear).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from orchestrator.geometry import NM
from rhnc.weather.metocean_grid import axis_node_count

#: The grids a leg's repair tries in turn: how far round the leg each reaches [nm] and its
#: spacing as a multiple of the given resolution (wider for a way round, finer for a narrow one).
REPAIR_GRIDS = ((10.0, 1.0), (30.0, 1.0), (10.0, 0.5))


def grid_clear_path(keep_out, start_m: Sequence[float] | np.ndarray, goal_m: Sequence[float] | np.ndarray,
                    extent: Sequence[float], resolution_nm: float, reach: int = 3,
                    avoid: Sequence[Sequence[float]] = ()) -> np.ndarray:
    """The shortest path from ``start_m`` to ``goal_m`` on a search grid that keeps clear of
    ``keep_out`` (and of the ``avoid`` circles), shortened wherever a straight leg stays clear.

    Parameters
    ----------
    keep_out : KeepOut or None
        Areas with their clearance (:class:`rhnc.chart.chart.Chart`); None: none.
    start_m, goal_m : (north, east) [m]
    extent : (north_min, north_max, east_min, east_max) [m]
        Where the grid lies.
    resolution_nm : float
        Spacing of the grid [nm].
    reach : int
        Longest grid move in grid steps.
    avoid : sequence of (north_m, east_m, radius_m)

    Returns
    -------
    ndarray (k, 2)
        The path's points [m], first ``start_m``, last ``goal_m``.

    Raises
    ------
    ValueError
        When the goal cannot be reached from the start on the grid.
    """
    from rhnc.routing.route_search import build_grid_graph, segment_clearance, shortcut_path, shortest_path_tree

    x_min, x_max, y_min, y_max = extent
    step = resolution_nm * NM
    x = np.linspace(x_min, x_max, axis_node_count(x_max - x_min, step, "the route search's resolution_nm"))
    y = np.linspace(y_min, y_max, axis_node_count(y_max - y_min, step, "the route search's resolution_nm"))
    graph = build_grid_graph(x, y, reach, avoid, keep_out)
    tree = shortest_path_tree(graph, graph.move_length_m[graph.move], graph.nearest_free_node(tuple(start_m)))
    path = graph.node_points()[tree.path_to(graph.nearest_free_node(tuple(goal_m)))]
    path = np.vstack([np.asarray(start_m, dtype=float), path, np.asarray(goal_m, dtype=float)])

    def lengths(i, js):
        starts = np.broadcast_to(path[i], (len(js), 2))
        clear = np.ones(len(js), dtype=bool) if keep_out is None else keep_out.legs_clear(starts, path[js])
        for cx, cy, radius in avoid:
            clear &= segment_clearance(starts, path[js], (cx, cy)) >= radius
        return np.where(clear, np.hypot(*(path[js] - path[i]).T), np.inf)

    consecutive = np.hypot(*np.diff(path, axis=0).T)
    return path[shortcut_path(len(path), lengths, consecutive_costs=consecutive)]


def _clear_leg(keep_out, a: np.ndarray, b: np.ndarray, resolution_nm: float) -> np.ndarray:
    """The shortest clear path a -> b on the first of :data:`REPAIR_GRIDS` that gives one clear along every leg."""
    for reach_nm, spacing in REPAIR_GRIDS:
        margin_m, resolution = reach_nm * NM, spacing * resolution_nm
        extent = (min(a[0], b[0]) - margin_m, max(a[0], b[0]) + margin_m,
                  min(a[1], b[1]) - margin_m, max(a[1], b[1]) + margin_m)
        try:
            path = grid_clear_path(keep_out, a, b, extent, resolution)
        except ValueError:
            path = None
        if path is not None and np.all(keep_out.legs_clear(path[:-1], path[1:])):
            return path
    raise ValueError(f"no route keeps the clearance of {keep_out.clearance_m / NM:g} nm between "
                     f"({a[0] / NM:.3f}, {a[1] / NM:.3f}) and ({b[0] / NM:.3f}, {b[1] / NM:.3f}) nm")


def route_kept_clear(keep_out, waypoints_m, resolution_nm: float = 0.25) -> np.ndarray:
    """The route ``waypoints_m`` with every leg keeping the clearance of ``keep_out`` along its length.

    Parameters
    ----------
    keep_out : KeepOut or None
        Areas with their clearance (:class:`rhnc.chart.chart.Chart`); None: none.
    waypoints_m : array_like (k, 2)
        The route's points, north and east [m]; the first and the last are kept as they are.
    resolution_nm : float
        Spacing of the grid a leg is repaired on [nm] (see :data:`REPAIR_GRIDS` when that grid finds no clear path).

    Returns
    -------
    ndarray (m, 2)
        The route: clear legs as given, each other leg replaced by the shortest clear path
        between its ends; inner waypoints inside the clearance left out.

    Raises
    ------
    ValueError
        When some leg cannot be made clear (its ends are cut off from each other).
    """
    points = np.asarray(waypoints_m, dtype=float).reshape(-1, 2)
    if len(points) < 2:
        raise ValueError("a route needs at least two waypoints")
    inner = keep_out.distances_m(points[1:-1, 0], points[1:-1, 1]) >= keep_out.clearance_m
    points = np.vstack([points[:1], points[1:-1][inner], points[-1:]])
    clear = keep_out.legs_clear(points[:-1], points[1:])
    route = [points[:1]]
    for k, leg_clear in enumerate(clear):
        leg = points[k:k + 2] if leg_clear else _clear_leg(keep_out, points[k], points[k + 1], resolution_nm)
        route.append(leg[1:])
    return np.vstack(route)
