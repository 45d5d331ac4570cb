"""The NMPC tracks a straight and a curved reference in calm water with the KCS FMU as plant."""

import numpy as np
import pandas as pd
import pytest

from orchestrator.analyses import array_output
from orchestrator.run import run_scenario
from rhnc.encounters.encounter import cross_track_error, reference_at_times

NM = 1852.0


@pytest.mark.parametrize("case, turn, offset_m", [
    ("straight", "", 400.0),
    ("turn_2nm_starboard", "turn_radius_nm = 2.0", 200.0),
])
def test_nmpc_tracks_reference_with_the_plant_fmu(tmp_path, tracking_scenario, case, turn, offset_m, raw_nmpc_inputs):
    reference = f"start_nm = [0.0, 0.0]\ncourse_deg = 30.0\nspeed_kn = 16.0\n{turn}"
    initial = f"y0 = {offset_m}\nu0 = 8.0\npsi0 = 0.5236"  # starts off the reference
    report = run_scenario(tracking_scenario(case, 90, reference, initial), tmp_path / "results", progress=False)
    assert report.ok, report.reason
    frame = pd.read_parquet(report.folder / "timeseries.parquet")
    reference = reference_at_times(array_output(frame, "ref.reference"), frame["time_s"])
    cross = cross_track_error(frame["ship.x"], frame["ship.y"], reference[:, 0], reference[:, 1], reference[:, 2])
    along = np.hypot(frame["ship.x"] - reference[:, 0], frame["ship.y"] - reference[:, 1])
    assert abs(cross[0]) > 0.9 * offset_m * np.cos(np.radians(30))  # it really started off the track
    settled = frame["time_s"] >= 1200.0  # after a 20 min transient
    assert np.max(np.abs(cross[settled])) < 0.02 * NM  # within 37 m of the path
    assert np.max(along[settled]) < 0.05 * NM  # and on schedule along it
    assert report.summary["participants"]["ctrl"]["fallback_count"] == 0
    for port, bound in (("tau_u", 1.8e6), ("tau_r", 3.3e8)):
        assert np.max(np.abs(frame[f"ctrl.{port}"])) <= bound
    assert raw_nmpc_inputs.largest() <= 1.0 + 1e-6  # the optimiser's own plans, before the clip
