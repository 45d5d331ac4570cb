"""The cost-to-go over the routing grid, searched in pieces spread over navigation updates.

The receding-horizon planner (:mod:`rhnc.navigation.route_navigation`) needs, at every update, the
cost of the cheapest route from each grid node to the goal: one Dijkstra search towards
the goal over edge weights priced in US dollars (:class:`rhnc.routing.weather_routing.RouteSearch`).
On a 100 x 100 nm map at 1 nm with 32 headings that is 10 201 nodes and about 316 000
edges; evaluating the energy model on every (node, heading) and running the search takes
longer than one planning update may.

So a search is cut into ``pieces``: the objective rates of the moves leaving one share of
the nodes per piece (the energy model, the expensive part), then, as the last piece, the
edge weights and Dijkstra's algorithm on a sparse matrix whose structure is built once.
The planner runs one piece per update and keeps routing on the last finished tree in the
meantime: a new search for another planned speed or price of time (static weather) or for
the weather at later times (weather that changes in time) is ready ``pieces`` updates after
it was begun.  Only the first tree, at set-up, is searched in one go.
"""

from __future__ import annotations

import logging

import numpy as np

from rhnc.routing.route_search import ShortestPathTree
from rhnc.routing.weather_routing import RouteSearch

log = logging.getLogger(__name__)

#: Default number of pieces one search is cut into (rates in pieces - 1 shares, then Dijkstra).
DEFAULT_PIECES = 3


class IncrementalCostToGo:
    """Cost-to-go trees towards the search's target, each searched over several calls.

    Parameters
    ----------
    search : RouteSearch
        The grid and its edge weights.
    pieces : int
        Calls of :meth:`advance` per search (at least 2: the rates of the nodes in
        ``pieces - 1`` shares, then the edge weights and Dijkstra).

    Attributes
    ----------
    tree : ShortestPathTree or None
        The last finished tree (``source`` is the target).
    key : hashable or None
        The key the finished tree was searched for.
    searches : int
        Trees finished.
    """

    def __init__(self, search: RouteSearch, pieces: int = DEFAULT_PIECES):
        if pieces < 2:
            raise ValueError("a search needs at least two pieces")
        self.search = search
        graph = search.graph
        n = graph.node_count
        self._order = graph.reverse_order
        from scipy.sparse import csr_matrix  # here, not with the module: most runs never route

        # the reversed graph: its structure never changes, only the weights
        self._matrix = csr_matrix((np.ones(self._order.size), graph.source[self._order].copy(),
                                   graph.reverse_indptr.copy()), shape=(n, n))
        self._shares = np.array_split(np.arange(n), pieces - 1)
        self._moves = len(graph.moves)
        self.tree: ShortestPathTree | None = None
        self.key = None
        self.searches = 0
        self._job: dict | None = None

    @property
    def pending_key(self):
        """Key of the search under way, or None."""
        return None if self._job is None else self._job["key"]

    def begin(self, key, speed_mps: float, time_price_usd_h: float, node_times_s: np.ndarray | None) -> None:
        """Start a new search (dropping one under way) at this speed through water [m/s],
        price of an hour [USD/h] and, for weather that changes in time, node times [s]."""
        n = self.search.graph.node_count
        self._job = {"key": key, "speed": float(speed_mps), "price": float(time_price_usd_h),
                     "times": None if node_times_s is None else np.asarray(node_times_s, dtype=float),
                     "rate": np.empty((n, self._moves)), "over_ground": np.empty((n, self._moves)), "done": 0}

    def advance(self) -> bool:
        """Run the next piece of the search under way; True when it finished a new tree."""
        job = self._job
        if job is None:
            return False
        if job["done"] < len(self._shares):
            nodes = self._shares[job["done"]]
            times = None if job["times"] is None else job["times"][nodes]
            rate, over_ground = self.search.node_rates(job["speed"], job["price"], nodes, times)
            job["rate"][nodes] = rate
            job["over_ground"][nodes] = over_ground
            job["done"] += 1
            return False
        weights, _ = self.search.edge_weights(job["rate"], job["over_ground"])
        self._matrix.data = np.ascontiguousarray(weights[self._order], dtype=float)
        from scipy.sparse.csgraph import dijkstra

        cost, successor = dijkstra(self._matrix, directed=True, indices=int(self.search.target),
                                   return_predecessors=True)
        self.tree = ShortestPathTree(source=int(self.search.target), cost=cost, predecessor=successor)
        self.key = job["key"]
        self.searches += 1
        self._job = None
        return True

    def complete(self) -> None:
        """Run the search under way to its end."""
        while self._job is not None:
            self.advance()
