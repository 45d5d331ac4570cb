"""The ship domain behind the co-simulation master's entry points.

What :mod:`orchestrator` finds by name through the groups declared in ``pyproject.toml``
(:mod:`orchestrator.plugins`) and that is not a participant of its own: the ship analyses
and figures, the ``plan`` and ``identify`` commands, encounter geometry for Monte Carlo
batches, the model library of ``models/``.  The orchestrator never imports this package.
"""
