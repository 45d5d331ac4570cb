"""The one definition of the toolchain's units and angle wrap (orchestrator/geometry.py)."""

from __future__ import annotations

import ast
import math
from pathlib import Path

import numpy as np
import pytest

from orchestrator.geometry import DEG, KNOT, NM, local_north_east_m, wrap_angle, wrap_float

REPO = Path(__file__).resolve().parents[2]
#: Packages and scripts that must take the units from orchestrator.geometry.
CHECKED = ("orchestrator", "rhnc", "bench", "scripts", "models")


def test_units():
    assert NM == 1852.0
    assert KNOT * 3600.0 == pytest.approx(1852.0, rel=1e-15)
    assert 180.0 * DEG == pytest.approx(math.pi, rel=1e-15)


def test_wrap_angle_half_open():
    assert wrap_angle(math.pi) == math.pi
    assert wrap_angle(-math.pi) == math.pi
    assert wrap_angle(3 * math.pi / 2) == pytest.approx(-math.pi / 2)
    assert np.allclose(wrap_angle([0.1 + 4 * math.pi, -0.1 - 4 * math.pi]), [0.1, -0.1])


def test_projection_one_minute_of_latitude_is_about_a_nautical_mile():
    north, east = local_north_east_m(np.array([60.0 + 1 / 60]), np.array([10.0]), 60.0, 10.0)
    assert north[0] == pytest.approx(NM, rel=0.002) and east[0] == 0.0
    north, east = local_north_east_m(np.array([60.0]), np.array([10.0 + 1 / 60]), 60.0, 10.0)
    assert east[0] == pytest.approx(NM * 0.5, rel=0.002)  # cos 60 deg


def _unit_definitions(path: Path) -> list[str]:
    found = []
    for node in ast.parse(path.read_text(encoding="utf-8")).body:
        targets = node.targets if isinstance(node, ast.Assign) else []
        for target in targets:
            if isinstance(target, ast.Name) and target.id in ("NM", "KNOT", "DEG"):
                found.append(f"{path.relative_to(REPO)}:{node.lineno} {target.id}")
        if isinstance(node, ast.FunctionDef) and node.name.strip("_") in ("wrap", "wrap_angle"):
            found.append(f"{path.relative_to(REPO)}:{node.lineno} {node.name}")
    return found


def test_units_and_wrap_are_defined_once():
    found = []
    for folder in CHECKED:
        for path in sorted((REPO / folder).rglob("*.py")):
            if path.name != "geometry.py":
                found += _unit_definitions(path)
    assert found == []


def test_degrees_wrap_to_the_half_open_interval_like_radians():
    from orchestrator.geometry import wrap_deg

    assert wrap_deg([-180.0, 180.0, 540.0, -190.0, 359.0]).tolist() == [180.0, 180.0, 180.0, 170.0, -1.0]


@pytest.mark.parametrize("half_turn", [math.pi, 180.0])
def test_a_plain_number_wraps_to_the_same_bits_as_an_array(half_turn):
    rng = np.random.default_rng(7)
    angles = np.concatenate([rng.normal(0.0, 20.0 * half_turn, 5000), rng.normal(0.0, 1e6, 500),
                             [half_turn, -half_turn, 3 * half_turn, -3 * half_turn, 0.0, -0.0, 2 * half_turn]])
    as_numbers = np.array([wrap_angle(float(angle), half_turn) for angle in angles])
    as_array = wrap_angle(angles, half_turn)
    assert as_numbers.tobytes() == as_array.tobytes()
    as_floats = [wrap_float(float(angle), half_turn) for angle in angles]  # what a port's value gets
    assert {type(value) for value in as_floats} == {float}
    assert np.array(as_floats).tobytes() == as_array.tobytes()
    assert wrap_angle(-half_turn, half_turn) == half_turn


def test_no_module_wraps_angles_by_hand():
    # the half-open wrap (-pi, pi] written again (a remainder or a shifted modulo by a full
    # turn) can disagree with wrap_angle at the half turn: every such wrap goes through it
    import re

    by_hand = re.compile(r"remainder\([^)]*2(\.0)? \* (math|np)\.pi\)|\+ (180(\.0)?|(math|np)\.pi)\) % ")
    found = [f"{path.relative_to(REPO)}:{number}"
             for folder in CHECKED for path in sorted((REPO / folder).rglob("*.py")) if path.name != "geometry.py"
             for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1) if by_hand.search(line)]
    assert found == []


def test_the_nearest_point_of_a_segment_is_its_foot_or_the_nearer_end():
    from orchestrator.geometry import nearest_on_segments

    a, b = np.array([0.0, 0.0]), np.array([10.0, 0.0])
    points = np.array([[4.0, 3.0], [-6.0, 8.0], [13.0, -4.0], [10.0, 0.0]])
    nearest, distance = nearest_on_segments(points, a, b)
    assert nearest.tolist() == [[4.0, 0.0], [0.0, 0.0], [10.0, 0.0], [10.0, 0.0]]
    assert distance.tolist() == [3.0, 10.0, 5.0, 0.0]
    # a segment of zero length is its start point
    nearest, distance = nearest_on_segments([3.0, 4.0], [[0.0, 0.0]], [[0.0, 0.0]])
    assert nearest.tolist() == [[0.0, 0.0]] and distance.tolist() == [5.0]


def test_the_nearest_point_of_a_segment_agrees_with_a_dense_walk_along_it():
    from orchestrator.geometry import nearest_on_segments

    rng = np.random.default_rng(3)
    points, a, b = (rng.normal(0.0, 100.0, (200, 2)) for _ in range(3))
    nearest, distance = nearest_on_segments(points, a, b)
    share = np.linspace(0.0, 1.0, 20001)
    walk = a[:, None, :] + share[None, :, None] * (b - a)[:, None, :]
    dense = np.min(np.hypot(*(walk - points[:, None, :]).transpose(2, 0, 1)), axis=1)
    assert np.all(distance <= dense + 1e-9) and np.allclose(distance, dense, atol=0.02)
    assert np.allclose(np.hypot(*(points - nearest).T), distance)
    # one point against the segments, and the segments one by one, give the same
    one = nearest_on_segments(points[0], a, b)[1]
    assert one.shape == (200,)
    assert np.allclose(one, [nearest_on_segments(points[0], a[k], b[k])[1] for k in range(200)])
    assert nearest_on_segments(points[:7], a[0], b[0])[1].shape == (7,)
