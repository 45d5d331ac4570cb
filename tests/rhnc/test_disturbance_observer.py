"""The disturbance observer on short synthetic records, and the reference it trims: what the
slow closed-loop test (``test_nmpc_limits.py``) shows through the NMPC, checked part by part
in milliseconds."""

import dataclasses
import logging
import math

import numpy as np
import pytest

from rhnc.control.disturbance_observer import MAX_SUBSTEP_S, DisturbanceObserver, trimmed_reference
from rhnc.ship.ship_model import derivatives, hull_forces, load_parameter_set, rk4_states

KNOT = 1852.0 / 3600.0
DT = 20.0
COURSE = math.radians(45.0)
#: 0.5 m/s current setting 135 deg (across a track at 45 deg), wind and waves on the starboard bow
DISTURBANCE = np.array([0.5 * math.cos(math.radians(135.0)), 0.5 * math.sin(math.radians(135.0)), -2.0e5, -4.0e5,
                        -2.0e7])


@pytest.fixture(scope="module")
def kcs():
    return load_parameter_set("default")


def scale(kcs):
    L, U = kcs.extras.get("lpp", 230.0), 8.0
    return np.array([L, L, 1.0, U, U, U / L])


def plant_step(kcs, state, tau, disturbance, dt=DT):
    """The plant: the model plus the disturbance, integrated finely (0.5 s steps)."""
    current_n, current_e, w_u, w_v, w_r = disturbance
    sway, yaw = kcs.sway_yaw_accelerations(w_v, w_r)
    extra = np.array([current_n, current_e, 0.0, w_u / kcs.m11, sway, yaw])
    return rk4_states(lambda x: derivatives(x, tau, kcs) + extra, np.asarray(state, float), 0.5, int(dt / 0.5))[-1]


def record(kcs, disturbance, steps, dt=DT, heading=COURSE):
    """(time, measured state, applied input) of a ship steering a slow zig-zag under the disturbance."""
    state = np.array([0.0, 0.0, heading, 18 * KNOT, 0.0, 0.0])
    rows = []
    for k in range(steps):
        tau = np.array([7.0e5, 1.5e7 * (1 if (k // 3) % 2 == 0 else -1)])
        rows.append((k * dt, state, tau))
        state = plant_step(kcs, state, tau, disturbance, dt)
    return rows


def observe(observer, rows):
    for time_s, state, tau in rows:
        observer.update(time_s, state)
        observer.applied(tau)
    return observer.estimate


def test_the_observer_finds_a_constant_current_and_loads_from_a_short_record(kcs):
    estimate = observe(DisturbanceObserver(kcs, scale(kcs), gain=0.5), record(kcs, DISTURBANCE, 20))
    np.testing.assert_allclose(estimate[:2], DISTURBANCE[:2], atol=0.01)
    np.testing.assert_allclose(estimate[2:], DISTURBANCE[2:], rtol=0.05)


def test_with_gain_one_a_single_step_finds_the_disturbance_and_a_smaller_gain_takes_its_share(kcs):
    rows = record(kcs, DISTURBANCE, 2)
    full = observe(DisturbanceObserver(kcs, scale(kcs), gain=1.0), rows)
    np.testing.assert_allclose(full[:2], DISTURBANCE[:2], atol=0.02)
    np.testing.assert_allclose(full[2:], DISTURBANCE[2:], rtol=0.1)
    np.testing.assert_allclose(observe(DisturbanceObserver(kcs, scale(kcs), gain=0.3), rows), 0.3 * full, rtol=1e-9)


def test_without_a_disturbance_the_estimate_stays_near_zero(kcs):
    estimate = observe(DisturbanceObserver(kcs, scale(kcs)), record(kcs, np.zeros(5), 10))
    np.testing.assert_allclose(estimate[:2], 0.0, atol=2e-3)
    assert np.all(np.abs(estimate[2:]) <= 0.02 * np.abs(DISTURBANCE[2:]))  # 2 % of the loads used elsewhere


def test_the_estimate_is_clipped_to_its_physical_bounds(kcs):
    strong = np.array([2.0, -2.0, 5.0e6, 5.0e7, 1.0e9])
    observer = DisturbanceObserver(kcs, scale(kcs), gain=1.0, max_current_mps=0.2)
    estimate = observe(observer, record(kcs, strong, 4))
    force = max(kcs.tau_u_max, kcs.tau_r_max / kcs.extras["lpp"])
    np.testing.assert_array_equal(observer.bound, [0.2, 0.2, kcs.tau_u_max, 2.0 * force, kcs.tau_r_max])
    np.testing.assert_allclose(estimate[:2], [0.2, -0.2])
    assert estimate[2] == kcs.tau_u_max and estimate[4] == kcs.tau_r_max
    assert np.all(np.abs(estimate) <= observer.bound)


def test_a_gap_longer_than_the_limit_or_a_step_back_in_time_updates_nothing(kcs):
    (t0, x0, tau0), (t1, x1, _) = record(kcs, DISTURBANCE, 2)
    for later, limit in ((t1, t1 - t0 - 1.0), (t0, 600.0), (t0 - 5.0, 600.0)):
        observer = DisturbanceObserver(kcs, scale(kcs), max_gap_s=limit)
        observer.update(t0, x0)
        observer.applied(tau0)
        assert np.all(observer.update(later, x1) == 0.0)
        assert not observer.ready()  # the new sample waits for its input
    at_limit = DisturbanceObserver(kcs, scale(kcs), max_gap_s=t1 - t0)  # a gap of the limit itself is used
    at_limit.update(t0, x0)
    at_limit.applied(tau0)
    assert np.any(at_limit.update(t1, x1) != 0.0)


def test_by_default_a_gap_of_up_to_ten_minutes_is_bridged(kcs):
    x0 = np.array([0.0, 0.0, 0.3, 18 * KNOT, 0.0, 0.0])
    tau = np.array([7.0e5, 1.5e7])
    x1 = plant_step(kcs, x0, tau, DISTURBANCE, dt=600.0)
    for gap, updated in ((600.0, True), (600.5, False)):
        observer = DisturbanceObserver(kcs, scale(kcs))
        observer.update(0.0, x0)
        observer.applied(tau)
        assert bool(np.any(observer.update(gap, x1) != 0.0)) is updated


@pytest.mark.parametrize("extras, length", [({"lpp": 100.0}, 100.0), ({}, 230.0)], ids=["own-length", "no-length"])
def test_the_sway_load_bound_follows_the_yaw_moment_over_the_ships_length(kcs, extras, length):
    # a yaw moment bound large for the ship's length: the sway load's bound is twice its lever force
    ship = dataclasses.replace(kcs, tau_r_max=5.0e8, extras=extras)
    observer = DisturbanceObserver(ship, scale(kcs))
    assert observer.bound[3] == 2.0 * 5.0e8 / length


def test_an_update_without_the_applied_input_only_records_the_sample(kcs):
    (t0, x0, tau0), (t1, x1, tau1), (t2, x2, _) = record(kcs, DISTURBANCE, 3)
    observer = DisturbanceObserver(kcs, scale(kcs))
    observer.applied(tau0)  # nothing measured yet: nothing to attach it to
    assert not observer.ready()
    observer.update(t0, x0)
    assert not observer.ready()
    assert np.all(observer.update(t1, x1) == 0.0)  # no input recorded for t0
    observer.applied(tau1)
    assert observer.ready()
    assert np.any(observer.update(t2, x2) != 0.0)


def test_the_estimate_returned_is_a_copy_and_the_measured_state_is_kept_as_measured(kcs):
    (t0, x0, tau0), (t1, x1, tau1), (t2, x2, _) = record(kcs, DISTURBANCE, 3)
    reference = DisturbanceObserver(kcs, scale(kcs))
    expected = observe(reference, [(t0, x0, tau0), (t1, x1, tau1), (t2, x2, tau1)])
    observer = DisturbanceObserver(kcs, scale(kcs))
    measured = x0.copy()
    observer.update(t0, measured)
    applied = tau0.copy()
    observer.applied(applied)
    measured[:] = 0.0  # the caller reuses its arrays
    applied[:] = 0.0
    returned = observer.update(t1, x1)
    returned[:] = 1.0e9
    observer.applied(tau1)
    np.testing.assert_array_equal(observer.update(t2, x2), expected)


def test_a_heading_measured_across_the_wrap_gives_the_same_estimate(kcs):
    rows = record(kcs, DISTURBANCE, 6, heading=math.radians(179.0))
    wrapped = [(t, np.r_[x[:2], math.remainder(x[2], 2 * math.pi), x[3:]], tau) for t, x, tau in rows]
    assert any(x[2] < 0 for _, x, _ in wrapped) and any(x[2] > 0 for _, x, _ in wrapped)
    np.testing.assert_allclose(observe(DisturbanceObserver(kcs, scale(kcs)), wrapped),
                               observe(DisturbanceObserver(kcs, scale(kcs)), rows), rtol=1e-9, atol=1e-9)


def test_a_non_finite_measurement_leaves_the_estimate_as_it_was(kcs, caplog):
    rows = record(kcs, DISTURBANCE, 3)
    observer = DisturbanceObserver(kcs, scale(kcs))
    before = observe(observer, rows[:2])
    with caplog.at_level(logging.WARNING, logger="rhnc.control.disturbance_observer"):
        after = observer.update(rows[2][0], np.full(6, np.nan))
    np.testing.assert_array_equal(after, before)
    assert "non-finite correction ignored" in caplog.text


def test_reset_forgets_the_estimate_and_the_last_sample(kcs):
    rows = record(kcs, DISTURBANCE, 3)
    observer = DisturbanceObserver(kcs, scale(kcs))
    observe(observer, rows)
    observer.reset()
    assert np.all(observer.estimate == 0.0) and not observer.ready()
    assert np.all(observer.update(rows[2][0] + DT, rows[2][1]) == 0.0)


@pytest.mark.parametrize("gain", [0.0, -0.5, 1.5])
def test_a_gain_outside_zero_to_one_is_refused(kcs, gain):
    with pytest.raises(ValueError, match=rf"disturbance observer gain must be in \(0, 1\], got {gain}"):
        DisturbanceObserver(kcs, scale(kcs), gain=gain)


def test_the_prediction_integrates_a_long_step_in_substeps_of_at_most_the_limit(kcs):
    observer = DisturbanceObserver(kcs, scale(kcs))
    state, tau = np.array([0.0, 0.0, 0.3, 18 * KNOT, 0.3, 0.004]), np.array([7.0e5, 2.0e7])
    for dt in (10.0, MAX_SUBSTEP_S, 20.0, 61.0):
        step, _ = observer._model(dt)
        substeps = max(1, math.ceil(dt / MAX_SUBSTEP_S))
        expected = rk4_states(lambda x: derivatives(x, tau, kcs), state, dt / substeps, substeps)[-1]
        np.testing.assert_allclose(np.array(step(state, tau, np.zeros(5))).ravel(), expected, rtol=1e-12, atol=1e-9)
    assert observer._model(20.0 + 1e-9) is observer._model(20.0)  # built once per interval


# -- the trimmed reference ------------------------------------------------------------------------
def straight(kcs, course=COURSE, speed=18 * KNOT, nodes=6, yaw_rate=0.0):
    reference = np.zeros((nodes, 6))
    reference[:, 2] = course + yaw_rate * DT * np.arange(nodes)
    reference[:, 3] = speed
    reference[:, 5] = yaw_rate
    return reference


def test_without_a_disturbance_the_reference_is_kept_and_the_input_balances_the_hull(kcs):
    reference = straight(kcs)
    trimmed, tau = trimmed_reference(reference, np.zeros(5), DT, kcs)
    np.testing.assert_allclose(trimmed, reference, atol=1e-12)
    surge, _, yaw = hull_forces(kcs, reference[:-1, 3], reference[:-1, 4], reference[:-1, 5])
    np.testing.assert_allclose(tau, np.column_stack([-surge, -yaw]))


def test_a_reference_given_in_integers_is_trimmed_as_in_floats(kcs):
    reference = np.tile([0, 0, 1, 9, 0, 0], (4, 1))
    trimmed, tau = trimmed_reference(reference, DISTURBANCE, DT, kcs)
    expected, expected_tau = trimmed_reference(reference.astype(float), DISTURBANCE, DT, kcs)
    np.testing.assert_array_equal(trimmed, expected)
    np.testing.assert_array_equal(tau, expected_tau)


def ground_velocity(states, current=(0.0, 0.0)):
    psi, u, v = states[:, 2], states[:, 3], states[:, 4]
    return np.column_stack([u * np.cos(psi) - v * np.sin(psi) + current[0], u * np.sin(psi) + v * np.cos(psi) + current[1]])


@pytest.mark.parametrize("yaw_rate", [0.0, 0.002])
def test_a_trimmed_reference_keeps_the_ground_velocity_under_the_current_with_the_steady_sway(kcs, yaw_rate):
    reference = straight(kcs, yaw_rate=yaw_rate)
    reference[:, 4] = 0.3  # a reference with a sway of its own: its ground velocity is what is kept
    trimmed, _ = trimmed_reference(reference, DISTURBANCE, DT, kcs)
    np.testing.assert_allclose(ground_velocity(trimmed, DISTURBANCE[:2]), ground_velocity(reference), atol=1e-9)
    np.testing.assert_allclose(trimmed[:, 4], DISTURBANCE[3] / kcs.d22)  # the sway load's steady sway
    np.testing.assert_array_equal(trimmed[:, [0, 1, 5]], reference[:, [0, 1, 5]])  # positions, yaw rates kept
    assert np.all(trimmed[:, 3] > 0.0)


def test_the_feed_forward_input_balances_surge_and_yaw_with_the_loads(kcs):
    reference = straight(kcs, yaw_rate=0.002)
    reference[:, 3] = np.linspace(16, 18, 6) * KNOT  # accelerating
    reference[:, 5] = np.linspace(0.0, 0.003, 6)
    trimmed, tau = trimmed_reference(reference, DISTURBANCE, DT, kcs)
    surge, _, yaw = hull_forces(kcs, trimmed[:-1, 3], trimmed[:-1, 4], trimmed[:-1, 5])
    np.testing.assert_allclose(kcs.m11 * np.diff(trimmed[:, 3]) / DT, surge + tau[:, 0] + DISTURBANCE[2], rtol=1e-9)
    np.testing.assert_allclose(kcs.m33 * np.diff(trimmed[:, 5]) / DT, yaw + tau[:, 1] + DISTURBANCE[4], rtol=1e-9)


@pytest.mark.parametrize("side", [1.0, -1.0])
def test_a_sway_load_beyond_half_the_water_speed_is_capped_and_the_input_clipped(kcs, side):
    reference = straight(kcs, speed=2 * KNOT)
    trimmed, tau = trimmed_reference(reference, np.array([0.0, 0.0, -1.0e8, side * 1.0e9, 1.0e12]), DT, kcs)
    np.testing.assert_allclose(trimmed[:, 4], side * 0.5 * 2 * KNOT)
    np.testing.assert_allclose(np.hypot(trimmed[:, 3], trimmed[:, 4]), 2 * KNOT)  # the water speed kept
    np.testing.assert_array_equal(tau, np.tile([kcs.tau_u_max, -kcs.tau_r_max], (5, 1)))  # at the bounds


def test_a_reference_turning_across_the_wrap_keeps_its_heading_continuous(kcs):
    reference = straight(kcs, course=math.radians(178.0), yaw_rate=0.003)  # from 178 deg past 180
    assert reference[-1, 2] > math.pi
    trimmed, _ = trimmed_reference(reference, DISTURBANCE, DT, kcs)
    assert np.all(np.abs(trimmed[:, 2] - reference[:, 2]) < math.radians(10.0))
