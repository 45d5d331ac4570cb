"""A reference the ship can catch (rhnc/control/reachable_reference.py): a lag that the speed
reserve cannot make up within the horizon no longer bends the course away from the track."""

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

from orchestrator.errors import ScenarioError
from orchestrator.participant import BuildContext
from rhnc.control.control_participant import ControlParticipant
from rhnc.control.nmpc import NMPCController, NMPCSettings
from rhnc.control.reachable_reference import reachable_lead_m, reachable_reference, top_speed_mps
from rhnc.navigation.reference_participant import line_or_turn_reference
from rhnc.ship.ship_model import load_parameter_set

NM = 1852.0
KNOT = NM / 3600.0
N = 15
DT = 20.0
COURSE = math.radians(45.0)


@pytest.fixture(scope="module")
def kcs():
    return load_parameter_set("default")


def lead_of(reference, position):
    """Along-track lead [m] of the reference's first node over ``position``."""
    offset = reference[0, :2] - np.asarray(position)
    return offset[0] * math.cos(reference[0, 2]) + offset[1] * math.sin(reference[0, 2])


def test_the_top_speed_is_where_full_surge_force_balances_the_resistance(kcs):
    top = top_speed_mps(kcs)
    assert kcs.equilibrium_tau(top)[0] == pytest.approx(kcs.tau_u_max, rel=1e-9)
    assert top_speed_mps(kcs, surge_load_N=2.0e5) > top > top_speed_mps(kcs, surge_load_N=-2.0e5)


def test_a_lag_beyond_reach_is_cut_to_the_reserve_and_a_smaller_one_is_kept(kcs):
    reference = line_or_turn_reference(np.arange(N + 1) * DT, (0.0, 0.0), COURSE, 18 * KNOT)
    behind = -2.0 * NM * np.array([math.cos(COURSE), math.sin(COURSE)])  # 2 nm behind the schedule
    moved = reachable_reference(reference, behind, 300.0)
    assert lead_of(moved, behind) == pytest.approx(300.0)
    np.testing.assert_allclose(moved[:, 2:], reference[:, 2:])             # only the positions move
    np.testing.assert_allclose(np.diff(moved[:, :2], axis=0), np.diff(reference[:, :2], axis=0))
    near = -100.0 * np.array([math.cos(COURSE), math.sin(COURSE)])
    assert reachable_reference(reference, near, 300.0) is reference          # within reach: as it was
    ahead = 500.0 * np.array([math.cos(COURSE), math.sin(COURSE)])
    assert reachable_reference(reference, ahead, 300.0) is reference          # never pulled forward
    # the reserve is the model's: (top speed - reference speed) over the horizon
    horizon = N * DT
    assert reachable_lead_m(kcs, reference, horizon) == pytest.approx((top_speed_mps(kcs) - 18 * KNOT) * horizon)
    assert reachable_lead_m(kcs, line_or_turn_reference(np.arange(N + 1) * DT, (0.0, 0.0), COURSE, 50 * KNOT),
                            horizon) == 0.0


def first_heading_toward_track(params, reachable: bool) -> float:
    """Heading [deg] the plan holds at its end, measured from the track towards it, for a ship
    1 nm to starboard of the track and 2 nm behind a schedule at nearly its top speed."""
    speed = top_speed_mps(params) - 0.5 * KNOT
    controller = NMPCController(params, NMPCSettings(horizon_steps=N, control_interval_s=DT, codegen=False,
                                                     max_speed_mps=top_speed_mps(params),
                                                     reachable_reference=reachable))
    along, across = np.array([math.cos(COURSE), math.sin(COURSE)]), np.array([-math.sin(COURSE), math.cos(COURSE)])
    position = -2.0 * NM * along + 1.0 * NM * across
    state = np.array([*position, COURSE, speed, 0.0, 0.0])
    reference = line_or_turn_reference(np.arange(N + 1) * DT, (0.0, 0.0), COURSE, speed)
    solution = controller.solve(0.0, state, reference, previous_tau=params.equilibrium_tau(speed))
    controller.close()
    assert solution.success
    return math.degrees(COURSE - min(np.asarray(solution.states)[:, 2]))


def test_a_ship_behind_an_unreachable_schedule_heads_back_to_the_track_more_steeply(kcs):
    """Without the option the plan splits its heading between the 2 nm of lag it cannot make up
    and the 1 nm of cross-track error; with it, the lag it cannot make up no longer counts.
    The KCS model with the surge force of a ship at its sea speed: 16.5 kn at full force."""
    slow = dataclasses.replace(kcs, tau_u_max=float(kcs.equilibrium_tau(16.5 * KNOT)[0]))
    timed = first_heading_toward_track(slow, reachable=False)
    caught = first_heading_toward_track(slow, reachable=True)
    assert caught > timed + 5.0


def test_the_option_is_off_by_default_and_must_be_true_or_false():
    context = BuildContext("exp.toml: participants.ctrl", Path("."), 20.0, 0.0, 2200.0)
    assert ControlParticipant.from_options("ctrl", {}, context).controller.settings.reachable_reference is False
    with pytest.raises(ScenarioError, match=r"participants.ctrl: option 'reachable_reference' must be true or false"):
        ControlParticipant.from_options("ctrl", {"reachable_reference": "yes"}, context)
