"""Stand-ins for an NMPC controller's NLP solvers, for the tests that make a solve end in a
particular way (an acceptable point, the end of an iteration budget, ...)."""

import contextlib


@contextlib.contextmanager
def solvers_replaced(controller, stand_in):
    """While the block runs, each of ``controller``'s solvers is ``stand_in(name, solver)``
    (the real solver passed to wrap); the real ones are back afterwards, also on failure."""
    real = dict(controller.solvers._solvers)
    for name, solver in real.items():
        controller.solvers._solvers[name] = stand_in(name, solver)
    try:
        yield
    finally:
        controller.solvers._solvers.update(real)
