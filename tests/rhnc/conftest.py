import textwrap

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
