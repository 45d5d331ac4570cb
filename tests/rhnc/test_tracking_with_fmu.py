"""The NMPC tracks a straight and a curved reference in calm water with the KCS FMU as plant."""

import textwrap

import numpy as np
import pandas as pd
import pytest

from orchestrator.run import run_scenario
from orchestrator.analyses import array_output
from rhnc.encounter import cross_track_error, reference_at_times

NM = 1852.0

SCENARIO = """
connections = [
  "ref.reference -> ctrl.reference",
  "ship.x -> ctrl.x", "ship.y -> ctrl.y", "ship.psi -> ctrl.psi",
  "ship.u -> ctrl.u", "ship.v -> ctrl.v", "ship.r -> ctrl.r",
  "ctrl.tau_u -> ship.tau_u", "ctrl.tau_r -> ship.tau_r",
]
[simulation]
steps = 90
dt_s = 20.0
[participants.ref]
type = "reference_path"
[participants.ref.options]
start_nm = [0.0, 0.0]
course_deg = 30.0
speed_kn = 16.0
{turn}
[participants.ctrl]
type = "control"
[participants.ctrl.options]
horizon_steps = 15
[participants.ship]
fmu = "KCS"
[participants.ship.parameters]
y0 = {offset_m}     # starts off the reference
u0 = 8.0
psi0 = 0.5236
[outputs]
figures = []
"""


@pytest.mark.parametrize("case, turn, offset_m", [
    ("straight", "", 400.0),
    ("turn_2nm_starboard", "turn_radius_nm = 2.0", 200.0),
])
def test_nmpc_tracks_reference_with_the_plant_fmu(tmp_path, case, turn, offset_m):
    path = tmp_path / f"{case}.toml"
    path.write_text(textwrap.dedent(SCENARIO.format(turn=turn, offset_m=offset_m)))
    report = run_scenario(path, tmp_path / "results", progress=False)
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
