"""Charts: the local projection of a passage, land and no-go areas, clearance along a track."""
