"""The drawn encounter suite: its limits hold for every target, and the committed files are its draw."""

import json
import math
from pathlib import Path

import numpy as np
import pytest

from rhnc.encounters import drawn_suite
from rhnc.encounters.traffic_situation import load_traffic_situation

ROOT = Path(__file__).resolve().parents[2]
COMMITTED = ROOT / "scenarios" / "situations" / "drawn"


def relative_motion(target):
    course = math.radians(target["course_deg"])
    velocity = target["speed_kn"] * np.array([math.cos(course), math.sin(course)])
    return np.asarray(target["start_nm"]), velocity - np.array([drawn_suite.OWN_SPEED_KN, 0.0])


def test_every_drawn_target_keeps_the_stated_limits():
    suite = drawn_suite.draw_suite()
    assert len(suite) == drawn_suite.SITUATIONS
    for number, targets in enumerate(suite, start=1):
        assert 1 <= len(targets) <= 3
        assert (targets[0]["kind"] == "inside") == (number % drawn_suite.INSIDE_EVERY == 0)
        for target in targets:
            start, relative = relative_motion(target)
            assert target["speed_kn"] <= 30.0
            if target["kind"] == "inside":
                assert math.hypot(*start) < 1.0
                continue
            closing = math.hypot(*relative)
            tcpa_min = -60.0 * float(start @ relative) / closing ** 2
            dcpa = math.hypot(*(start + relative * tcpa_min / 60.0))
            assert closing <= drawn_suite.MAX_CLOSING_KN
            assert 2.0 <= math.hypot(*start) <= 8.0
            assert drawn_suite.MIN_TCPA_MIN - 1e-9 <= tcpa_min <= drawn_suite.MAX_TCPA_MIN + 1e-9
            assert dcpa == pytest.approx(target["dcpa_nm"], abs=1e-9) and dcpa <= 0.9


def test_every_kind_is_drawn_with_fast_and_close_ones():
    targets = [target for situation in drawn_suite.draw_suite() for target in situation]
    assert {target["kind"] for target in targets} == {*drawn_suite.KINDS, "inside"}
    closing = [math.hypot(*relative_motion(target)[1]) for target in targets]
    assert max(closing) > 40.0


def test_committed_files_are_the_seeded_draw(tmp_path):
    written = drawn_suite.write_suite(tmp_path)
    assert sorted(path.name for path in COMMITTED.glob("*.json")) == [path.name for path in written]
    for path in written:
        assert json.loads(path.read_text()) == json.loads((COMMITTED / path.name).read_text())


def test_files_load_as_traffic_situations_in_place():
    situation = load_traffic_situation(COMMITTED / "drawn_001.json")
    first = drawn_suite.draw_suite()[0]
    assert len(situation.targets) == len(first)
    assert situation.own_ship.speed_kn == pytest.approx(drawn_suite.OWN_SPEED_KN)
    for ship, target in zip(situation.targets, first):
        assert ship.start_nm == pytest.approx(target["start_nm"], abs=1e-4)
        assert ship.speed_kn == pytest.approx(target["speed_kn"])


def test_a_count_below_one_is_refused(tmp_path, capsys):
    with pytest.raises(SystemExit) as exit_info:
        drawn_suite.main([str(tmp_path / "out"), "--count", "0"])
    assert exit_info.value.code == 2
    assert "--count must be at least 1" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_the_wide_recipe_draws_overtakers_from_abaft_the_beam_and_its_suite_is_committed(tmp_path):
    suite = drawn_suite.draw_suite(2030, 80, "wide")
    quarter = [target for situation in suite for target in situation if target["kind"] == "overtaken_quarter"]
    assert quarter
    for target in quarter:
        start, relative = relative_motion(target)
        assert abs(math.degrees(math.atan2(start[1], start[0]))) > 112.5
        assert 20.0 <= target["speed_kn"] <= 30.0 and float(start @ relative) < 0.0
    for seed in (2030, 2031, 2032, 2033):
        written = drawn_suite.write_suite(tmp_path / str(seed), seed, 80, "wide")
        for path in written:
            assert json.loads(path.read_text()) == json.loads((ROOT / f"scenarios/situations/drawn{seed}" / path.name).read_text())


def test_the_default_recipe_draws_no_quarter_overtaker():
    assert all(target["kind"] != "overtaken_quarter" for situation in drawn_suite.draw_suite() for target in situation)
