"""Example plugin of rhnc-cosim: a sinusoidal helm and the heading swing it causes."""
