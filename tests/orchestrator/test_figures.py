"""Track figure: obstacles drawn where they were at the own ship's closest approach, time marks."""

import numpy as np
import pandas as pd
import pytest

from rhnc.cosim.figures import closest_approach_rows, comparison_track_styles, time_mark_interval_min

NM = 1852.0


def _frame():
    t = np.arange(0.0, 1801.0, 60.0)
    own_x = 9.26 * t                                   # north at 18 kn
    target_x = np.full_like(t, 5.0 * NM)               # crossing west on x = 5 nm ...
    target_y = 4.0 * NM - 7.0 * t                      # ... passing ahead, closest near t = 571 s
    frame = pd.DataFrame({"time_s": t, "ship.x": own_x, "ship.y": np.zeros_like(t)})
    for column, values in enumerate((target_x, target_y, np.zeros_like(t), np.full_like(t, -7.0),
                                     np.full_like(t, NM))):
        frame[f"traffic.obstacles[0,{column}]"] = values
    for column, values in enumerate((np.full_like(t, 2.0 * NM), np.full_like(t, -1.0 * NM), np.zeros_like(t),
                                     np.zeros_like(t), np.full_like(t, 0.3 * NM))):
        frame[f"traffic.obstacles[1,{column}]"] = values
    return frame


def test_each_obstacle_is_taken_at_the_own_ships_closest_approach_to_it():
    frame = _frame()
    rows = closest_approach_rows(frame, "ship")
    distances = {i: np.hypot(frame[f"traffic.obstacles[{i},0]"] - frame["ship.x"],
                             frame[f"traffic.obstacles[{i},1]"] - frame["ship.y"]) for i in (0, 1)}
    assert [i for i, _, _ in rows] == [0, 1]
    for i, k, distance in rows:
        assert k == int(np.argmin(distances[i])) and distance == pytest.approx(distances[i].min())
    # not the start, middle or end of the run
    assert rows[0][1] not in (0, 15, 30) and rows[1][1] not in (0, 15, 30)


@pytest.mark.parametrize("duration_min, expected", [(20, 2.0), (45, 5.0), (120, 10.0), (480, 60.0)])
def test_time_marks_are_round_and_few(duration_min, expected):
    assert time_mark_interval_min(duration_min * 60.0) == expected


@pytest.mark.parametrize("count", [2, 3, 4, 7])
def test_compared_tracks_stay_visible_where_they_overlap(count):
    # on a viridis wind map, one after another: no white or map-coloured track, every colour
    # its own, and each track narrower than the one drawn before it, so that an earlier track
    # shows on both sides of a later one running over it
    from matplotlib.colors import to_rgb

    styles = comparison_track_styles(count)
    assert len(styles) == count
    looks = [(to_rgb(style["color"]), style["ls"]) for style in styles]
    assert len(set(looks)) == count
    assert all(min(rgb) < 0.9 for rgb, _ in looks)  # nothing white
    widths = [style["lw"] for style in styles]
    assert all(later < earlier for earlier, later in zip(widths, widths[1:]))
    assert widths[-1] >= 1.0


def test_every_colour_bar_says_what_it_shows():
    # a colour bar without a label leaves the reader to guess the quantity and its unit
    import ast
    from pathlib import Path

    repo = Path(__file__).resolve().parents[2]
    unlabelled = []
    for path in [*repo.joinpath("rhnc").rglob("*.py"), *repo.joinpath("orchestrator").rglob("*.py"),
                 *repo.joinpath("scripts").rglob("*.py")]:
        for node in ast.walk(ast.parse(path.read_text())):
            if (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr == "colorbar"
                    and not any(keyword.arg == "label" for keyword in node.keywords)):
                unlabelled.append(f"{path.relative_to(repo)}:{node.lineno}")
    assert unlabelled == []
