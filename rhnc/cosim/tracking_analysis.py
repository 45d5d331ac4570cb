"""The ``tracking`` analysis: a target tracker's estimates against the true targets of the run.

Registered in ``rhnc_cosim.analyses``; figures from :func:`rhnc.encounters.tracking_errors.tracking_errors`
(position and velocity RMS and maximum, coverage, track breaks), per true target and overall.
"""

from __future__ import annotations

import numpy as np

from orchestrator.analyses import array_output
from orchestrator.errors import ToolchainError
from orchestrator.geometry import NM
from rhnc.cosim.obstacle_ports import estimated_obstacles_participant, true_obstacles_column


def tracking_analysis(frame, scenario, cosim, out_dir, gate_nm: float = 0.5) -> dict:
    """Estimation errors of the tracker feeding the controller (``gate_nm``: largest miss that still counts)."""
    from rhnc.encounters.tracking_errors import tracking_errors

    tracker = estimated_obstacles_participant(scenario, cosim)
    truth_column = true_obstacles_column(scenario, cosim)
    if tracker is None or truth_column is None:
        raise ToolchainError("the tracking analysis needs a tracker feeding an 'obstacles' input and the true "
                             "traffic beside it")
    source = truth_column.split(".")[0]
    targets_column = f"{source}.targets"
    truth = array_output(frame, targets_column if any(c.startswith(targets_column + "[") for c in frame.columns)
                         else truth_column)
    valid = array_output(frame, f"{tracker}.track_valid")
    estimates = array_output(frame, f"{tracker}.obstacles")[:, :valid.shape[1], :]
    result = tracking_errors(frame["time_s"].to_numpy(), truth, estimates, valid, gate_nm * NM)
    result["gate_nm"] = gate_nm
    return result


def _check_options(options) -> None:
    """Refuse a bad ``[outputs.options.tracking]`` before a run (ValueError names the key)."""
    for key, value in dict(options).items():
        if key != "gate_nm":
            raise ValueError(f"unknown option '{key}' (valid: gate_nm)")
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not np.isfinite(value) or value <= 0:
            raise ValueError(f"'gate_nm' must be a number > 0, got {value!r}")


tracking_analysis.check_options = _check_options
