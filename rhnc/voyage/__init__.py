"""Voyages accounted and compared: totals along a sailed track, equal-arrival baselines, the compare command."""
