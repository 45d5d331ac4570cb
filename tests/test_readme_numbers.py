"""The README's numbers are those of a fresh run: the cheap experiments rerun here.

``scripts/reproduce_readme.py`` writes ``docs/readme_numbers.json`` (and the README's
figures) from fresh runs; the lead writes the README from that file.  This test reruns the
manoeuvring trials and Experiments 3a/3b and checks the committed numbers within the
script's stated tolerances, so a change in the code that moves a quoted number fails here
until the numbers (and the README) are regenerated.
"""

import json
from pathlib import Path

import pytest
from script_module import module_of_file

REPO = Path(__file__).resolve().parents[1]


def load_script():
    return module_of_file(REPO / "scripts" / "reproduce_readme.py", "reproduce_readme")


#: kind of each checked number (see TOLERANCES in the script)
KINDS = {
    "advance_L": "geometry_L", "transfer_L": "geometry_L", "tactical_diameter_L": "geometry_L",
    "steady_diameter_L": "geometry_L", "first_overshoot_deg": "angle_deg", "second_overshoot_deg": "angle_deg",
    "min_distance_nm": "distance_nm", "required_nm": "distance_nm", "cross_track_end_nm": "distance_nm",
    "tau_u_max_abs_MN": "force", "tau_r_max_abs_MNm": "force", "back_on_track_s": "time_s",
    "fallback_count": "count", "solver_failures": "count",
}


@pytest.mark.slow
def test_readme_numbers_match_a_fresh_run(tmp_path):
    script = load_script()
    committed = json.loads((REPO / "docs" / "readme_numbers.json").read_text())["experiments"]
    cheap = [e.name for e in script.EXPERIMENTS if e.cheap]
    assert cheap == ["turning_circle", "zigzag_10_10", "exp3a_static", "exp3b_head_on"]
    fresh = script.reproduce(cheap, tmp_path / "results", tmp_path / "figures")
    for name in cheap:
        expected, measured = committed[name], fresh[name]
        assert expected["command"] == measured["command"]
        checked = [key for key in expected if key in KINDS]
        assert checked, name
        for key in checked:
            rel, abs_ = script.TOLERANCES[KINDS[key]]
            assert measured[key] == pytest.approx(expected[key], rel=rel, abs=abs_), f"{name}: {key}"
    # every figure the README shows from these runs was drawn
    assert sorted(p.name for p in (tmp_path / "figures").iterdir()) == sorted(
        target for e in script.EXPERIMENTS if e.cheap for target in e.figures.values())


def test_readme_quotes_the_committed_numbers():
    """The README's key figures are the ones in docs/readme_numbers.json (regenerated together)."""
    numbers = json.loads((REPO / "docs" / "readme_numbers.json").read_text())["experiments"]
    readme = (REPO / "README.md").read_text()
    turning, zigzag = numbers["turning_circle"], numbers["zigzag_10_10"]
    exp3a, exp3b, exp4 = numbers["exp3a_static"], numbers["exp3b_head_on"], numbers["exp4_full"]
    rhnc = numbers["exp2_table3"]["RHNC"]["voyage"]
    spnc = numbers["exp2_table3"]["Offline-SPNC"]["voyage"]
    quoted = [
        f"| advance | {turning['advance_L']:.2f} L |",
        f"| tactical diameter | {turning['tactical_diameter_L']:.2f} L",
        f"| first overshoot | {zigzag['first_overshoot_deg']:.1f}° |",
        f"{exp3a['tau_u_max_abs_MN']:.2f} MN (bound 1.8), {exp3a['tau_r_max_abs_MNm']:.0f} MN m",
        f"within 0.2 nm after {exp3a['back_on_track_s']:.0f} s",
        f"(after {exp3b['back_on_track_s']:.0f} s)",
        f"minimum separation {exp4['min_distance_nm'][1]:.2f} nm against",
        f"| EC per nm made good [USD] | {rhnc['cost_per_made_good_nm_usd']:.2f} | 80.74 | "
        f"{spnc['cost_per_made_good_nm_usd']:.2f} |",
        f"| time [min] | {rhnc['time_min']:.0f} (arrived)",
    ]
    for text in quoted:
        assert text in readme, text


def test_the_final_goal_distance_is_the_ships_last_position_not_the_monitors_held_output(tmp_path):
    # the goal monitor's output in the last row was computed a macro step earlier (its
    # input then): the distance at the end is read from the ship's position in that row
    import pandas as pd

    script = load_script()
    scenario = tmp_path / "voyage.toml"
    scenario.write_text((REPO / "scenarios" / "exp4_full.toml").read_text())
    folder = tmp_path / "run"
    folder.mkdir()
    goal_m = 100.0 * 1852.0
    pd.DataFrame({"time": [0.0, 60.0, 120.0], "ship.x": [0.0, goal_m - 4000.0, goal_m - 3000.0],
                  "ship.y": [0.0, goal_m, goal_m - 4000.0],
                  "goal.goal_distance_m": [2e5, 6000.0, 4000.0]}).to_parquet(folder / "timeseries.parquet")
    assert script.final_goal_distance_m(folder, {"scenario": str(scenario)}) == pytest.approx(5000.0)
