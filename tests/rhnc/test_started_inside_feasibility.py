"""Whether a full-force manoeuvre can open the range to a target inside R + R_i within 60 s."""

from pathlib import Path

import numpy as np
import pytest

from rhnc.ship.ship_model import load_parameter_set
from script_module import module_of_file

REPO = Path(__file__).resolve().parents[2]
KNOT = 1852.0 / 3600.0


@pytest.fixture(scope="module")
def feasibility():
    return module_of_file(REPO / "scripts" / "started_inside_feasibility.py", "started_inside_feasibility")


@pytest.fixture(scope="module")
def kcs():
    return load_parameter_set("default")


OWN = np.array([0.0, 0.0, 0.0, 18 * KNOT, 0.0, 0.0])   # x north, y east, 18 kn on 000 deg


def test_a_fast_overtaker_inside_the_domain_cannot_be_opened_in_a_minute(feasibility, kcs):
    # 0.5 nm dead astern, 30 kn on 000 deg: closing at 12 kn; the own ship neither reaches 30 kn
    # nor turns across in a minute, so the range closes for two minutes whatever it does
    target_xy, target_v = np.array([-0.5 * 1852.0, 0.0]), np.array([30 * KNOT, 0.0])
    assert not feasibility.achievable(OWN, target_xy, target_v, kcs)


def test_a_fast_ship_head_on_passes_within_the_minute_whatever_is_done(feasibility, kcs):
    # 0.5 nm dead ahead, 25 kn on 180 deg: 43 kn closing, the closest approach comes in 42 s
    target_xy, target_v = np.array([0.5 * 1852.0, 0.0]), np.array([-25 * KNOT, 0.0])
    assert feasibility.achievable(OWN, target_xy, target_v, kcs)


def test_a_ship_converging_slowly_abeam_can_be_opened_by_turning_away(feasibility, kcs):
    # 0.5 nm on the starboard beam, 18 kn on 355 deg: closing at 1.6 kn; a turn to port opens it
    target_xy = np.array([0.0, 0.5 * 1852.0])
    target_v = 18 * KNOT * np.array([np.cos(np.radians(-5.0)), np.sin(np.radians(-5.0))])
    assert feasibility.achievable(OWN, target_xy, target_v, kcs)


def test_doing_nothing_does_not_open_a_converging_ship(feasibility, kcs):
    target_xy = np.array([0.0, 0.5 * 1852.0])
    target_v = 18 * KNOT * np.array([np.cos(np.radians(-5.0)), np.sin(np.radians(-5.0))])
    # the equilibrium surge force holds 18 kn; with no alteration the range closes for minutes
    hold = kcs.equilibrium_tau(OWN[3]) / kcs.tau_max
    assert feasibility.range_opening_s(OWN, target_xy, target_v, hold, kcs) > 60.0
