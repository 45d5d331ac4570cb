"""The NMPC keeps a chart's clearance from land as constraints: a reference across a headland."""

import json

import numpy as np
import pytest
import shapely

from rhnc.chart.chart import BoundaryIndex, load_chart
from rhnc.control.nmpc import NMPCController, NMPCSettings
from rhnc.navigation.reference_participant import line_or_turn_reference
from rhnc.ship.ship_model import load_parameter_set, rk4_step

NM = 1852.0
KNOT = NM / 3600.0
DT = 20.0
N = 15
ORIGIN = (51.0, 1.5)
CLEARANCE_NM = 0.5
#: a headland in the plane (north, east [m]) pointing west: its tip 300 m west of the line
#: the reference sails (east = 0), which cuts 300 m across it
HEADLAND = [(1000.0, -300.0), (-2000.0, 3000.0), (4000.0, 3000.0)]


def headland_chart(tmp_path):
    from rhnc.chart.projection import LocalProjection

    projection = LocalProjection(*ORIGIN)
    lat, lon = projection.to_geographic(*np.array(HEADLAND + HEADLAND[:1]).T)
    (tmp_path / "headland.geojson").write_text(json.dumps(
        {"type": "Polygon", "coordinates": [[[float(x), float(y)] for x, y in zip(lon, lat)]]}))
    path = tmp_path / "headland.chart.toml"
    path.write_text(f'origin_deg = [{ORIGIN[0]}, {ORIGIN[1]}]\nclearance_nm = {CLEARANCE_NM}\n'
                    'no_go = ["headland.geojson"]\n')
    return load_chart(path)


def sail_past(chart, use_chart: bool):
    """Closed loop (numpy plant) along the line east = 0 northwards across the headland."""
    params = load_parameter_set("default")
    controller = NMPCController(params, NMPCSettings(horizon_steps=N, control_interval_s=DT, coastline_slots=6))
    if use_chart:
        controller.use_chart(chart)
    speed = 14 * KNOT
    start_north = -4000.0

    def reference_at(t):
        return line_or_turn_reference(t + DT * np.arange(N + 1), (start_north, 0.0), 0.0, speed)

    state = np.array([start_north, 0.0, 0.0, speed, 0.0, 0.0])
    track, solutions = [state[:2].copy()], []
    for k in range(60):  # 20 min: 4.5 nm, past the headland's 1.1 nm of depth
        solution = controller.solve(k * DT, state, reference_at(k * DT), None, et=False)
        solutions.append(solution)
        for _ in range(int(DT / 2.0)):
            state = rk4_step(state, solution.tau, 2.0, 1, params)
            track.append(state[:2].copy())
    controller.close()
    track = np.array(track)
    return float(np.min(chart.leg_distances_m(track[:-1], track[1:]))), track, solutions


def test_the_boundary_index_finds_the_nearest_edge_point_inside_and_out(tmp_path):
    chart = headland_chart(tmp_path)
    index = BoundaryIndex(chart)
    points = [[1000.0, -1300.0], [1000.0, 0.0], [-2500.0, 2000.0], [0.0, 3500.0]]
    nearest, distance, inside = index.nearest(points)
    assert inside.tolist() == [False, True, False, False]
    outside = ~inside
    assert distance[outside] == pytest.approx(chart.distances_m(*np.array(points)[outside].T), rel=1e-9)
    assert distance[1] == pytest.approx(chart.hazard.exterior.distance(shapely.Point(points[1])))
    assert nearest[0] == pytest.approx([1000.0, -300.0], abs=1.0)  # the tip
    assert nearest[3] == pytest.approx([0.0, 3000.0], abs=1.0)  # the base, straight west of the point


def test_a_reference_across_a_headland_keeps_the_clearance_with_the_constraint_and_not_without(tmp_path):
    chart = headland_chart(tmp_path)
    kept, track, solutions = sail_past(chart, use_chart=True)
    cut, _, _ = sail_past(chart, use_chart=False)
    assert cut == 0.0  # without the chart the ship follows its reference across the land
    assert kept >= 0.98 * CLEARANCE_NM * NM, kept / NM  # measured: 0.502 nm of 0.5
    assert track[-1, 0] > 3000.0  # and it went on: past the headland, not stopped before it
    assert not any(s.fallback for s in solutions)


def context(tmp_path):
    from orchestrator.participant import BuildContext

    return BuildContext("passage.toml: participants.ctrl", tmp_path, DT, 0.0, 2200.0)


def test_the_control_participant_reads_a_chart_and_gives_the_coastline_its_slots(tmp_path):
    from rhnc.control.control_participant import ControlParticipant

    headland_chart(tmp_path)
    participant = ControlParticipant.from_options("ctrl", {"chart": "headland.chart.toml", "horizon_steps": N},
                                                  context(tmp_path))
    controller = participant.controller
    assert controller.coastline is not None and controller.settings.coastline_slots == 6
    assert controller.coastline.clearance_m == pytest.approx(CLEARANCE_NM * NM)
    controller.close()


@pytest.mark.parametrize("options, message", [
    ({"chart": "missing.chart.toml"}, r"passage.toml: participants.ctrl: option 'chart': .*missing.chart.toml: "
                                      "chart file not found"),
    ({"chart": 3}, r"participants.ctrl: option 'chart' must be the path of a chart file, got 3"),
    ({"coastline_slots": 4}, r"participants.ctrl: option 'coastline_slots' needs option 'chart'"),
    ({"chart": "headland.chart.toml", "coastline_slots": 0},
     r"participants.ctrl: option 'coastline_slots' must be an integer from 1 to 64, got 0"),
])
def test_bad_chart_options_are_refused_naming_the_option(tmp_path, options, message):
    from orchestrator.errors import ScenarioError
    from rhnc.control.control_participant import ControlParticipant

    headland_chart(tmp_path)
    with pytest.raises(ScenarioError, match=message):
        ControlParticipant.from_options("ctrl", options, context(tmp_path))
