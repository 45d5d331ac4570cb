import textwrap

import numpy as np
import pytest

# A reference_path participant "ref" tracked by the NMPC "ctrl" on the KCS FMU "ship", every
# 20 s; the reference's options and the ship's initial state are filled in per test.
TRACKING_SCENARIO = """
connections = [
  "ref.reference -> ctrl.reference",
  "ship.x -> ctrl.x", "ship.y -> ctrl.y", "ship.psi -> ctrl.psi",
  "ship.u -> ctrl.u", "ship.v -> ctrl.v", "ship.r -> ctrl.r",
  "ctrl.tau_u -> ship.tau_u", "ctrl.tau_r -> ship.tau_r",
]
[simulation]
steps = {steps}
dt_s = 20.0
[participants.ref]
type = "reference_path"
[participants.ref.options]
{reference}
[participants.ctrl]
type = "control"
[participants.ship]
fmu = "KCS"
[participants.ship.parameters]
{initial_state}
[outputs]
figures = []
"""


@pytest.fixture
def tracking_scenario(tmp_path):
    """Write the tracking scenario with the given reference options and initial state."""

    def write(name: str, steps: int, reference: str, initial_state: str):
        path = tmp_path / f"{name}.toml"
        path.write_text(TRACKING_SCENARIO.format(steps=steps, reference=textwrap.dedent(reference).strip(),
                                                 initial_state=textwrap.dedent(initial_state).strip()))
        return path

    return write



class RawInputs:
    """The input plans successful NLP solves returned, in units of tau_max, before any clip.

    The applied input is clipped to tau_max after the solve, so a bound check on the applied
    input holds whatever bounds the optimiser was given; these plans show whether the
    optimiser's own solution kept |w| <= 1.
    """

    def __init__(self):
        self.plans: list[np.ndarray] = []

    def attach(self, controller):
        """Record the solves (both attempts) of an already built controller."""
        solvers = controller.solvers
        solve = getattr(solvers, "_unrecorded_solve", solvers.solve)  # a module-scoped controller seen before
        plans = self.plans

        def recording(name, **arguments):
            outcome = solve(name, **arguments)
            if outcome.success and outcome.x is not None:
                plans.append(np.asarray(outcome.x).ravel()[controller.problem.w_index].copy())
            return outcome

        solvers._unrecorded_solve = solve
        solvers.solve = recording
        return controller

    def largest(self) -> float:
        """Largest |w| over the recorded plans (1 = the bound tau_max)."""
        assert self.plans, "no successful NMPC solve was recorded"
        return float(max(np.max(np.abs(w)) for w in self.plans))


@pytest.fixture
def raw_nmpc_inputs(monkeypatch):
    """RawInputs of every NMPCController built (or attached) during the test."""
    from rhnc.control.nmpc import NMPCController

    raw = RawInputs()
    original_init = NMPCController.__init__

    def init(self, *args, **kwargs):
        original_init(self, *args, **kwargs)
        raw.attach(self)

    monkeypatch.setattr(NMPCController, "__init__", init)
    return raw
