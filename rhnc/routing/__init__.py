"""Route search and weather routing: the graph search, the optimal route, cost along a track, cost-to-go."""
