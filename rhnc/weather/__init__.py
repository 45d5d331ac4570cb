"""Met-ocean fields: gridded and spline weather, NetCDF sources, synthetic weather generators."""
