"""Post-run analyses and figures a scenario names in ``[outputs]``.

An analysis is ``function(frame, scenario, cosim, out_dir, **options) -> dict`` returning
key figures for ``summary.json`` (and writing its own figures into ``out_dir``).  A figure
is ``function(frame, scenario, cosim, out_dir) -> list[str]`` of file names written.  Both
are found by name in the entry-point groups ``rhnc_cosim.analyses`` and
``rhnc_cosim.figures`` (:mod:`orchestrator.plugins`), so heavy imports stay lazy and a
user's package adds its own the same way the ship analyses of :mod:`rhnc.cosim` are added.
"""

from __future__ import annotations

import numpy as np

from orchestrator import plugins
from orchestrator.errors import ScenarioError, ToolchainError


def check_outputs(scenario) -> None:
    """Refuse unknown analyses, figures and analysis options before a run starts."""
    import inspect

    def resolve(kind, name, key):
        try:
            return _resolve(kind, name, key)
        except ScenarioError as exc:
            raise ScenarioError(f"{scenario.path}: {exc}") from None

    for name in scenario.outputs.figures:
        resolve("figures", name, "figures")
    for name in scenario.outputs.analyses:
        function = resolve("analyses", name, "analyses")
        accepted = list(inspect.signature(function).parameters)[4:]
        options = scenario.outputs.options.get(name, {})
        for key in options:
            if key not in accepted:
                raise ScenarioError(f"{scenario.path}: unknown option 'outputs.options.{name}.{key}' "
                                    f"(valid: {', '.join(accepted) or 'none'})")
        # an analysis may check its option values too (``function.check_options(options)``
        # raising ValueError), so that a bad value is refused before the run, not after it
        checker = getattr(function, "check_options", None)
        if checker is not None:
            try:
                checker(options)
            except ValueError as exc:
                raise ScenarioError(f"{scenario.path}: 'outputs.options.{name}': {exc}") from None


def run_analysis(name, frame, scenario, cosim, out_dir) -> dict:
    """Run analysis ``name`` with its ``[outputs.options.<name>]`` keywords."""
    function = _resolve("analyses", name, "analyses")
    return function(frame, scenario, cosim, out_dir, **scenario.outputs.options.get(name, {}))


def figure_function(name):
    """The function drawing figure ``name`` (imported on first use)."""
    return _resolve("figures", name, "figures")


def _resolve(kind, name, key):
    registry = plugins.registrations(kind)
    if name not in registry:
        raise ScenarioError(f"'outputs.{key}': unknown name '{name}' (valid: {', '.join(sorted(registry))})")
    return registry[name].load()


def driver_column(scenario, target: str, port: str) -> str:
    """Time-series column of the output connected to ``target.port``."""
    for connection in scenario.connections:
        if connection.target == target and connection.target_port == port:
            return f"{connection.source}.{connection.source_port}"
    raise ToolchainError(f"nothing drives {target}.{port}")


def array_output(frame, column: str) -> np.ndarray:
    """A flattened array output back as (samples, rows, cols) from ``column[i,j]`` columns."""
    prefix = column + "["
    cells = [c for c in frame.columns if c.startswith(prefix)]
    if not cells:
        raise ToolchainError(f"no recorded array output '{column}'")
    indices = [tuple(int(v) for v in c[len(prefix):-1].split(",")) for c in cells]
    shape = tuple(max(index[d] for index in indices) + 1 for d in range(len(indices[0])))
    values = np.full((len(frame),) + shape, np.nan)
    for cell, index in zip(cells, indices):
        values[(slice(None),) + index] = frame[cell].to_numpy()
    return values
