"""Encounter geometry: the placed target meets the own ship at the requested CPA and TCPA."""

import math

import numpy as np
import pytest

from rhnc.cosim.encounters import ENCOUNTER_TYPES, ShipMotion, cpa_tcpa, place_target


def _side(own: ShipMotion, target: ShipMotion, tcpa_min: float) -> str:
    t = tcpa_min / 60.0
    r = np.add(target.start_nm, np.multiply(target.velocity_kn, t)) - np.add(own.start_nm, np.multiply(own.velocity_kn, t))
    h = np.asarray(own.velocity_kn)
    return "starboard" if h[0] * r[1] - h[1] * r[0] > 0 else "port"


def test_cpa_tcpa_by_hand():
    own = ShipMotion((0.0, 0.0), (10.0, 0.0))  # 10 kn north
    target = ShipMotion((5.0, 1.0), (-10.0, 0.0))  # 10 kn south, 1 nm east of the track
    cpa, tcpa = cpa_tcpa(own, target)
    assert cpa == pytest.approx(1.0)
    assert tcpa == pytest.approx(15.0)  # 5 nm at 20 kn closing
    assert cpa_tcpa(own, ShipMotion((3.0, 4.0), (10.0, 0.0))) == (5.0, math.inf)


@pytest.mark.parametrize("encounter", ENCOUNTER_TYPES)
@pytest.mark.parametrize("side", ["port", "starboard"])
def test_placed_target_has_requested_cpa_and_tcpa(encounter, side):
    rng = np.random.default_rng(3)
    for _ in range(50):
        own = ShipMotion.from_course(rng.uniform(-5, 5, 2), rng.uniform(0, 360), rng.uniform(10, 20))
        cpa, tcpa = rng.uniform(0.0, 1.5), rng.uniform(5.0, 40.0)
        speed = rng.uniform(3.0, 0.8 * own.speed_kn) if encounter == "overtaking" else rng.uniform(5.0, 25.0)
        offset = rng.uniform(-10.0, 10.0)
        target = place_target(own, encounter, cpa, tcpa, speed, offset, side)
        got_cpa, got_tcpa = cpa_tcpa(own, target)
        assert got_cpa == pytest.approx(cpa, abs=1e-9)
        assert got_tcpa == pytest.approx(tcpa, rel=1e-9)
        assert target.speed_kn == pytest.approx(speed)
        if cpa > 1e-3:
            assert _side(own, target, tcpa) == side


def test_encounter_types_put_the_target_where_colreg_expects_it():
    own = ShipMotion.from_course((0.0, 0.0), 0.0, 18.0)  # north
    head_on = place_target(own, "head_on", 0.2, 20.0, 12.0)
    assert head_on.course_deg == pytest.approx(180.0)
    assert head_on.start_nm[0] == pytest.approx(30.0 / 60 * 20.0, abs=0.25)  # ahead, closing at 30 kn
    crossing = place_target(own, "crossing", 0.0, 20.0, 12.0)
    assert crossing.course_deg == pytest.approx(270.0)
    assert crossing.start_nm[1] > 0 and crossing.start_nm[0] > 0  # on the starboard bow
    port = place_target(own, "crossing_port", 0.0, 20.0, 12.0)
    assert port.start_nm[1] < 0  # on the port bow
    overtaken = place_target(own, "overtaking", 0.0, 30.0, 10.0)
    assert overtaken.start_nm == pytest.approx((4.0, 0.0))  # 8 kn closing for 0.5 h, dead ahead


def test_place_target_rejects_impossible_requests():
    own = ShipMotion.from_course((0.0, 0.0), 0.0, 10.0)
    with pytest.raises(ValueError, match="keeps station"):
        place_target(own, "overtaking", 0.5, 10.0, 10.0)
    with pytest.raises(ValueError, match="tcpa_min > 0"):
        place_target(own, "head_on", 0.5, 0.0, 10.0)
    with pytest.raises(ValueError, match="unknown encounter type 'merging'"):
        place_target(own, "merging", 0.5, 10.0, 10.0)
