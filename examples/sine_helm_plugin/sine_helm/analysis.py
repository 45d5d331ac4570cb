"""The heading swing of a run: the range of the heading of a participant that reports ``psi``."""

from __future__ import annotations

import math

from orchestrator.errors import ToolchainError


def heading_swing(frame, scenario, cosim, out_dir, after_s: float = 0.0) -> dict:
    """Largest minus smallest heading [deg] from ``after_s`` [s] on.

    The heading is the ``psi`` output [rad] of the first participant that has one.
    """
    column = next((f"{p.name}.psi" for p in cosim.participants if "psi" in p.output_names), None)
    if column is None:
        raise ToolchainError("heading_swing: no participant outputs psi")
    heading = frame.loc[frame["time_s"] >= after_s, column].to_numpy()
    return {"heading_swing_deg": math.degrees(float(heading.max() - heading.min())),
            "samples": int(heading.size)}
