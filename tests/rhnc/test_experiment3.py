"""Experiment 3 through the orchestrator with the KCS FMU as plant (its acceptance criteria)."""

import json
from pathlib import Path

import pytest

from orchestrator.run import run_scenario

REPO = Path(__file__).resolve().parents[2]


@pytest.mark.parametrize("name", ["exp3a_static", "exp3b_head_on"])
def test_experiment3_is_safe_within_bounds_and_returns_to_track(name, tmp_path, raw_nmpc_inputs):
    report = run_scenario(REPO / "scenarios" / f"{name}.toml", tmp_path, progress=False)
    assert report.ok, report.reason
    summary = json.loads((report.folder / "summary.json").read_text())
    encounter = summary["analyses"]["encounter"]
    for obstacle in encounter["obstacles"]:
        assert obstacle["min_distance_nm"] >= obstacle["required_nm"]
        # also along the chords between the 5 s samples (a lower bound on the true distance)
        assert obstacle["min_distance_between_samples_nm"] >= obstacle["required_nm"] - 1e-6
        # and it really had to avoid: it came close to the circle
        assert obstacle["min_distance_nm"] < obstacle["required_nm"] + 0.2
    assert encounter["tau_u_within_bound"] and encounter["tau_r_within_bound"]
    # the applied input is clipped to the bounds: the optimiser's own plans must keep them too
    assert raw_nmpc_inputs.largest() <= 1.0 + 1e-6
    assert encounter["cross_track_end_nm"] <= 0.2
    assert encounter["back_on_track_s"] is not None
    control = summary["participants"]["ctrl"]
    assert control["fallback_count"] == 0
    assert {"track.png", "controls.png"} <= set(summary["figures"])
