"""The encounter suites end to end: a situation file through a base scenario, judged by the colregs analysis."""

import json
from pathlib import Path

import pytest

from orchestrator.run import run_scenario
from orchestrator.scenario import read_toml
from rhnc.encounters.traffic_situation import load_traffic_situation, scenario_overrides

REPO = Path(__file__).resolve().parents[2]


@pytest.mark.slow
def test_imazu_head_on_through_the_nmpc_is_judged_from_its_tracks(tmp_path):
    base = REPO / "scenarios" / "encounter_nmpc.toml"
    situation = load_traffic_situation(REPO / "scenarios" / "situations" / "imazu" / "imazu_01.json")
    overrides = scenario_overrides(situation, read_toml(base, "scenario")[0], radius_nm=1.0, route_nm=15.0)
    overrides["simulation.steps"] = 240  # 20 min: the ships meet after 25 min if nobody acts
    report = run_scenario(base, tmp_path, progress=False, overrides=overrides)
    assert report.ok, report.reason
    summary = json.loads((report.folder / "summary.json").read_text())
    (target,) = summary["analyses"]["colregs"]["targets"]
    (obstacle,) = summary["analyses"]["encounter"]["obstacles"]
    assert target["encounter_class"] == "head_on" and target["onset_s"] == 0.0
    # the CPA refined along the chords lies between the sampled minimum and the chord bound
    assert obstacle["min_distance_between_samples_nm"] - 1e-9 <= target["cpa_nm"] <= obstacle["min_distance_nm"] + 1e-9
    assert target["separation_kept"] == (obstacle["min_distance_nm"] >= 1.0 - 1e-6)
    assert target["rule_14"] in ("pass", "fail") and target["rule_15"] == "not applicable"
    assert summary["analyses"]["colregs"]["verdict"] == target["verdict"]
    assert "track.png" in summary["figures"]


COLREGS_SUITES = sorted(path.name.removesuffix("_rhnc_colregs_calm.toml") for path in (REPO / "batches").glob("*_rhnc_colregs_calm.toml"))
TRAFFICGEN55_SUITES = sorted(path.name for path in (REPO / "scenarios" / "situations").glob("trafficgen55*") if path.is_dir())


def test_the_suites_are_found():
    assert {"imazu", "trafficgen", "drawn", "drawn2028", "trafficgen55"} <= set(COLREGS_SUITES)
    assert "trafficgen55" in TRAFFICGEN55_SUITES and len(TRAFFICGEN55_SUITES) > 1


@pytest.mark.parametrize("suite", COLREGS_SUITES)
def test_every_colregs_suite_has_a_calm_twin_and_runs_until_arrival(suite):
    from orchestrator.batch_spec import load_batch

    weather = load_batch(REPO / "batches" / f"{suite}_rhnc_colregs.toml").runs()
    calm = load_batch(REPO / "batches" / f"{suite}_rhnc_colregs_calm.toml").runs()
    assert [run.parameters["situation"] for run in calm] == [run.parameters["situation"] for run in weather]
    for run in weather:
        assert run.overrides["simulation.steps"] == 450  # 150 min: every run ends on arrival
        assert run.overrides["participants.ctrl.options.iteration_budget"] == 200
        assert run.overrides["participants.ctrl.options.cpu_time_limit_s"] == 0.2  # the 200 ms bound
        assert "metocean.current_kn" not in run.overrides
    for run in calm:
        assert run.overrides["metocean.current_kn"] == 0.0
        assert all(value == 0.0 for row in run.overrides["metocean.wind_control_points_ms"] for value in row)
        same = {key: value for key, value in run.overrides.items() if not key.startswith("metocean.")}
        twin = next(other for other in weather if other.parameters["situation"] == run.parameters["situation"])
        assert same == twin.overrides


@pytest.mark.parametrize("suite", TRAFFICGEN55_SUITES)
def test_trafficgen55_holds_every_combination_of_one_to_three_classes_with_every_target_placed(suite):
    """DNV's baseline mix: 1, 2 and 3 targets over the five classes, each combination once."""
    import itertools

    folder = REPO / "scenarios" / "situations" / suite
    classes = ["head-on", "crossing-give-way", "crossing-stand-on", "overtaking-give-way", "overtaking-stand-on"]
    asked = {}
    for path in sorted((folder / "input" / "situations").glob("*.json")):
        definition = json.loads(path.read_text())
        asked[definition["title"]] = [encounter["desiredEncounterType"] for encounter in definition["encounters"]]
    every = [list(combo) for n in (1, 2, 3) for combo in itertools.combinations_with_replacement(classes, n)]
    assert sorted(sorted(kinds) for kinds in asked.values()) == sorted(sorted(kinds) for kinds in every)
    generated = sorted(folder.glob("*.json"))
    assert len(generated) == 55
    titles = set()
    for path in generated:
        situation = json.loads(path.read_text())
        titles.add(situation["title"])
        assert len(situation["targetShips"]) == len(asked[situation["title"]]), path.name
        assert len(load_traffic_situation(path).targets) == len(asked[situation["title"]]), path.name
    assert titles == set(asked)
