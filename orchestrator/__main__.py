"""``python -m orchestrator``: see :mod:`orchestrator.cli`."""

from orchestrator.cli import console_main

console_main()
