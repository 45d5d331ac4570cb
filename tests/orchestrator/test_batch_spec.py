"""Batch files: expansion into runs, Monte Carlo encounters as traffic options, acceptance criteria."""

import re
import textwrap
from pathlib import Path

import pytest

from orchestrator.acceptance import evaluate, lookup, reference_value
from orchestrator.batch_spec import Criterion, load_batch
from rhnc.cosim.encounters import ShipMotion, cpa_tcpa
from orchestrator.errors import ScenarioError

REPO = Path(__file__).resolve().parents[2]


def _batch(tmp_path, text):
    path = tmp_path / "b.toml"
    path.write_text(textwrap.dedent(text).replace("SCENARIO", str(REPO / "scenarios" / "turning_circle.toml")))
    return load_batch(path)


def test_grid_is_a_cartesian_product_with_every_draw(tmp_path):
    spec = _batch(tmp_path, """
        [batch]
        scenario = "SCENARIO"
        [set]
        "simulation.stop_s" = 600.0
        [grid]
        "simulation.dt_s" = [1.0, 5.0]
        "participants.ship.parameter_set" = ["default", "paper_table2"]
        [monte_carlo]
        seed = 5
        runs = 3
        [monte_carlo.normal]
        "participants.ship.parameters.u0" = [9.0, 0.5]
        [monte_carlo.choice]
        "participants.helm.options.tau_u_N" = [5.0e5, 7.0e5]
    """)
    runs = spec.runs()
    assert spec.name == "b" and len(runs) == 12 and len({r.run_id for r in runs}) == 12
    assert [r.overrides["simulation.dt_s"] for r in runs[:6]] == [1.0] * 6
    assert all(r.overrides["simulation.stop_s"] == 600.0 for r in runs)
    # common random numbers: each grid point sees the same three draws
    draws = [r.overrides["participants.ship.parameters.u0"] for r in runs]
    assert draws[:3] == draws[3:6] == draws[9:12] and len(set(draws[:3])) == 3


def test_encounter_draws_become_traffic_targets_at_the_drawn_cpa_and_tcpa(tmp_path):
    spec = _batch(tmp_path, """
        [batch]
        scenario = "SCENARIO"
        [monte_carlo]
        seed = 2023
        runs = 20
        [monte_carlo.own_ship]
        start_nm = [1.0, 2.0]
        course_deg = 45.0
        speed_kn = 18.0
        [[monte_carlo.encounters]]
        type = ["head_on", "crossing", "overtaking"]
        cpa_nm = [0.0, 0.5]
        tcpa_min = [10.0, 15.0]
        speed_kn = [6.0, 10.0]
        radius_nm = 0.5
        [monte_carlo.obstacles]
        count = [1, 2]
        along_track_nm = 4.0
        cross_track_nm = 1.0
        radius_nm = [0.2, 0.4]
    """)
    own = ShipMotion.from_course((1.0, 2.0), 45.0, 18.0)
    types = set()
    for run in spec.runs():
        (target,) = run.overrides["participants.traffic.options.targets"]
        assert set(target) == {"start_nm", "velocity_kn", "radius_nm"} and target["radius_nm"] == 0.5
        cpa, tcpa = cpa_tcpa(own, ShipMotion(tuple(target["start_nm"]), tuple(target["velocity_kn"])))
        assert cpa == pytest.approx(run.parameters["enc0.cpa_nm"], abs=1e-5)
        assert tcpa == pytest.approx(run.parameters["enc0.tcpa_min"], abs=1e-3)
        types.add(run.parameters["enc0.type"])
        obstacles = run.overrides["participants.traffic.options.static_obstacles"]
        assert 1 <= len(obstacles) <= 2
        # 4 nm along 045 deg and 1 nm to starboard (135 deg) of the start
        assert obstacles[0]["center_nm"] == pytest.approx([1.0 + 3.0 / 2 ** 0.5, 2.0 + 5.0 / 2 ** 0.5], abs=1e-5)
    assert types == {"head_on", "crossing", "overtaking"}


@pytest.mark.parametrize("text, message", [
    ('[monte_carlo]\nseed = 1\nruns = 2\n[[monte_carlo.encounters]]\ntype = "head_on"\ncpa_nm = 0.1\ntcpa_min = 5.0\n'
     'speed_kn = 5.0\nradius_nm = 0.1\n', "'monte_carlo.own_ship' (start_nm, course_deg, speed_kn) is needed"),
    ('[monte_carlo]\nseed = 1\nruns = 2\n[monte_carlo.own_ship]\nstart_nm = [0, 0]\ncourse_deg = 0\nspeed_kn = 10\n'
     '[[monte_carlo.encounters]]\ntype = "overtaking"\ncpa_nm = 0.1\ntcpa_min = 5.0\nspeed_kn = [5.0, 12.0]\n'
     'radius_nm = 0.1\n', "'monte_carlo.encounters[0].speed_kn': an overtaken target must be slower"),
    ('[monte_carlo]\nseed = 1\nruns = 2\n[monte_carlo.own_ship]\nstart_nm = [0, 0]\ncourse_deg = 0\nspeed_kn = 10\n'
     '[[monte_carlo.encounters]]\ntype = "merge"\n', "'monte_carlo.encounters[0].type' must be one of head_on"),
    ('[grid]\n"simulation.dt_s" = 5.0\n', "'grid.\"simulation.dt_s\"' must be a non-empty list of values"),
    ('[set]\n"simulation.dt_s" = 5.0\n[grid]\n"simulation.dt_s" = [1.0]\n',
     "'set.\"simulation.dt_s\"' and 'grid.\"simulation.dt_s\"' set the same scenario value"),
    ('[monte_carlo]\nseed = 1\nruns = 2\n[monte_carlo.scale]\n"metocean.current_kn" = [0.5, 1.5]\n',
     "the base scenario must set this key to a number or a list of numbers"),
    ('[[acceptance]]\nmetric = "status"\nop = "=="\n', "give exactly one of 'value' (a literal) or 'ref'"),
    ('[monte_carlo]\nseed = 1\nruns = 2\nuniform = 5\n', "'monte_carlo.uniform' must be a table"),
])
def test_batch_file_errors_name_the_key(tmp_path, text, message):
    with pytest.raises(ScenarioError, match="^" + re.escape(str(tmp_path / "b.toml")) + ": .*" + re.escape(message)):
        _batch(tmp_path, '[batch]\nscenario = "SCENARIO"\n' + text)


def test_lookup_follows_dotted_keys_and_list_indices():
    summary = {"overrides": {"participants.traffic.options.targets": [{"radius_nm": 0.7}]},
               "analyses": {"encounter": {"min_distance_nm": 1.2}}, "status": "finished"}
    assert lookup(summary, "overrides.participants.traffic.options.targets.0.radius_nm") == 0.7
    assert reference_value(summary, "overrides.participants.traffic.options.targets.0.radius_nm + 0.25 - 0.05") == \
        pytest.approx(0.9)
    verdicts = evaluate((
        Criterion("sep", "analyses.encounter.min_distance_nm", ">=", ref="overrides.participants.traffic.options.targets.0.radius_nm + 0.25"),
        Criterion("too far", "analyses.encounter.min_distance_nm", ">=", value=2.0),
        Criterion("missing", "participants.ctrl.fallback_count", "==", value=0),
        Criterion("text", "status", ">=", value=1.0),
    ), summary)
    assert [v.passed for v in verdicts] == [True, False, False, False]
    assert verdicts[1].reason == "analyses.encounter.min_distance_nm = 1.2, not >= 2"
    assert verdicts[2].reason == "'participants.ctrl.fallback_count' not in summary.json (no 'participants' at '<top>')"
    assert "is not a number" in verdicts[3].reason
