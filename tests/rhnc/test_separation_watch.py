"""The separation watch: its range bound holds for every own-ship path within the speed limit, and
the watch settles only when the bound allows, giving up when a premise breaks."""

import math
from pathlib import Path

import numpy as np
import pytest

from orchestrator.errors import ScenarioError
from orchestrator.geometry import KNOT, NM
from orchestrator.participant import BuildContext
from rhnc.encounters.separation_watch import SeparationWatch, least_future_range_m


def _cases(count=300, seed=4):
    rng = np.random.default_rng(seed)
    for _ in range(count):
        relative = rng.uniform(-6, 6, 2) * NM
        velocity = rng.uniform(-30, 30, 2) * KNOT
        speed = rng.uniform(5, 30) * KNOT
        yield relative, velocity, speed, rng.uniform(60, 3600)


def _range_along(relative, velocity, own_velocity_at, left, samples=2000):
    """Least range [m] over ``left`` s when the own ship sails ``own_velocity_at(tau, relative)`` (Euler)."""
    dt = left / samples
    own = np.zeros(2)
    least = math.inf
    for k in range(samples + 1):
        tau = k * dt
        now = relative + velocity * tau - own
        least = min(least, float(np.hypot(*now)))
        own = own + own_velocity_at(tau, now) * dt
    return least


@pytest.mark.parametrize("strategy", ["pursuit", "intercept", "still", "away"])
def test_no_own_ship_path_within_the_speed_limit_comes_closer_than_the_bound(strategy):
    for relative, velocity, speed, left in _cases(60):
        bound = least_future_range_m(relative, velocity, speed, left)

        def steer(tau, now, speed=speed, velocity=velocity, relative=relative, left=left):
            if strategy == "pursuit":  # straight at the obstacle, at full speed
                return speed * now / max(np.hypot(*now), 1e-9)
            if strategy == "intercept":  # straight at where it will be at the end of the run
                aim = relative + velocity * left
                return speed * aim / max(np.hypot(*aim), 1e-9)
            if strategy == "away":
                return -speed * now / max(np.hypot(*now), 1e-9)
            return np.zeros(2)

        assert _range_along(relative, velocity, steer, left) >= bound - 1.0  # 1 m: the Euler steps


def test_the_bound_is_the_least_of_its_function_and_a_ship_that_heads_for_that_point_reaches_it():
    # not needlessly low: the closed form is the minimum of |r + v tau| - U tau over the time left,
    # and a ship sailing at U straight for the obstacle's position at that time is there
    for relative, velocity, speed, left in _cases():
        taus = np.linspace(0.0, left, 20001)
        on_grid = np.min(np.hypot(*(relative[:, None] + velocity[:, None] * taus)) - speed * taus)
        bound = least_future_range_m(relative, velocity, speed, left)
        assert bound <= on_grid + 1e-6
        assert bound == pytest.approx(on_grid, abs=0.05 * speed * left / 20000 + 1e-6)


def _watch(max_kn=26.0, stop_s=3600.0):
    context = BuildContext("s.toml: participants.watch", None, 20.0, 0.0, stop_s)
    return SeparationWatch.from_options("watch", {"max_own_speed_kn": max_kn}, context)


def _obstacle(x_nm, y_nm, vx_kn, vy_kn):
    return np.array([[x_nm * NM, y_nm * NM, vx_kn * KNOT, vy_kn * KNOT, NM]])


def _sail(watch, own_kn, target, start_nm, steps, dt=20.0, start_s=0.0, turn_at=None):
    """Own ship north at ``own_kn``; a constant-velocity target; the outputs per step."""
    outputs = []
    for k in range(steps + 1):
        t = start_s + k * dt
        own = np.array([start_nm[0] * NM + own_kn * KNOT * t, start_nm[1] * NM])
        velocity = target[2:4] if turn_at is None or t < turn_at else target[2:4][::-1]
        position = target[:2] + target[2:4] * min(t, turn_at or t) + velocity * max(t - (turn_at or t), 0.0)
        inputs = {"x": own[0], "y": own[1], "obstacles": np.r_[position, velocity, NM][None, :]}
        outputs.append(watch.setup(t, inputs) if k == 0 else watch.step(t, dt, inputs))
    return outputs


def test_a_fast_head_on_target_settles_soon_after_its_closest_approach_and_never_before():
    watch = _watch()
    target = _obstacle(8.0, 0.3, -30.0, 0.0)[0]  # closing at 48 kn: CPA 0.3 nm at 10 min
    outputs = _sail(watch, 18.0, target, (0.0, 0.0), 60)
    settled = [k for k, out in enumerate(outputs) if out["settled"] == 1.0]
    assert settled and settled[0] * 20.0 > 600.0  # not before the closest approach
    assert settled[0] * 20.0 < 900.0  # the target runs away faster than the own ship can follow
    assert watch.summary()["closest_nm"][0] == pytest.approx(0.3, abs=0.01)
    assert watch.summary()["settled_at_s"] == settled[0] * 20.0


def test_a_target_slower_than_the_own_ship_is_not_settled_while_the_ship_could_catch_it():
    watch = _watch(stop_s=3600.0)
    target = _obstacle(8.0, 0.3, -10.0, 0.0)[0]
    outputs = _sail(watch, 18.0, target, (0.0, 0.0), 120)  # 40 min of the hour; CPA 0.3 nm at 17 min
    settled = [k for k, out in enumerate(outputs) if out["settled"] == 1.0]
    # behind and running away at 28 kn, the ship could turn and close at 26 - 10 kn for the rest of
    # the hour: settled once the range is the closest approach plus 16 kn times the time left
    first = next(k for k in range(len(outputs))
                 if 28.0 * (k * 20.0 / 60 - 8.0 / 28 * 60) / 60 >= 0.3 + 16.0 * (3600.0 - k * 20.0) / 3600)
    assert settled and settled[0] == pytest.approx(first, abs=1)
    assert all(out["least_future_margin_m"] < 0.0 for out in outputs[:settled[0]])


@pytest.mark.parametrize("case, reason", [
    ("manoeuvre", "an obstacle changed its velocity at t = 900 s"),
    ("fast", "the own ship sailed 30.00 kn over ground at t = 20 s, more than max_own_speed_kn = 26"),
])
def test_the_watch_gives_up_when_a_premise_of_its_bound_breaks(case, reason):
    watch = _watch()
    target = _obstacle(8.0, 0.3, -30.0, 0.0)[0]
    if case == "manoeuvre":  # the target turns after passing: its future is not its velocity
        outputs = _sail(watch, 18.0, target, (0.0, 0.0), 60, turn_at=900.0)
    else:
        outputs = _sail(watch, 30.0, target, (0.0, 0.0), 60)
    assert watch.summary()["gave_up"] == reason
    assert all(math.isfinite(value) for out in outputs for value in out.values())  # the master refuses others
    assert all(out["settled"] == 0.0 for out in outputs[int(900 / 20) if case == "manoeuvre" else 1:])


def test_without_obstacles_nothing_is_settled_and_every_output_is_finite():
    watch = _watch()
    outputs = [watch.setup(0.0, {"x": 0.0, "y": 0.0, "obstacles": np.zeros((0, 5))}),
               watch.step(20.0, 20.0, {"x": 100.0, "y": 0.0, "obstacles": np.zeros((0, 5))})]
    assert outputs == [{"settled": 0.0, "least_future_margin_m": 0.0}] * 2
    assert watch.setup(0.0, {}) == {}  # before the ship has published its state


@pytest.mark.parametrize("options, message", [
    ({}, r"s.toml: missing key 'participants.watch.options.max_own_speed_kn'"),
    ({"max_own_speed_kn": -1.0}, r"'participants.watch.options.max_own_speed_kn' must be positive"),
    ({"max_own_speed_kn": 20.0, "speed": 1}, r"unknown key 'participants.watch.options.speed'"),
])
def test_option_errors(options, message):
    context = BuildContext("s.toml: participants.watch", None, 20.0, 0.0, 600.0)
    with pytest.raises(ScenarioError, match=message):
        SeparationWatch.from_options("watch", options, context)


@pytest.mark.parametrize("skew", [-1, 0, 1])
def test_once_settled_no_later_sample_comes_closer_for_own_ships_that_turn_away_and_come_back(skew):
    # the property a stop relies on, over random voyages within the speed limit: a ship that
    # turns away (the range opens) and back (it closes again), and targets at constant velocity;
    # the watch sees the own ship a step ahead of the obstacles (as in the master's Gauss-Seidel
    # order, where the ship has stepped when the watch steps), a step behind, or at their time
    rng = np.random.default_rng(7)
    dt, steps, limit_kn = 20.0, 180, 26.0
    settled_runs = 0
    for _ in range(150):
        watch = _watch(max_kn=limit_kn, stop_s=steps * dt)
        targets = np.column_stack([rng.uniform(-4, 4, (3, 2)) * NM, rng.uniform(-30, 30, (3, 2)) * KNOT,
                                   np.full(3, NM)])
        own, heading = [np.zeros(2)], rng.uniform(0, 2 * np.pi)
        for _ in range(steps + 1):
            heading += rng.choice([-1.0, 0.0, 1.0]) * rng.uniform(0, 0.6)  # turns away and back
            own.append(own[-1] + rng.uniform(0.3, 1.0) * limit_kn * KNOT * dt * np.array([np.cos(heading),
                                                                                          np.sin(heading)]))
        ranges, flags = [], []
        for k in range(steps + 1):
            t = k * dt
            rows = targets.copy()
            rows[:, :2] += targets[:, 2:4] * t
            seen = own[min(max(k + skew, 0), steps)]
            inputs = {"x": seen[0], "y": seen[1], "obstacles": rows}
            flags.append((watch.setup(t, inputs) if k == 0 else watch.step(t, dt, inputs))["settled"])
            ranges.append(np.hypot(*(rows[:, :2] - own[k]).T))  # what is recorded: both at t
        ranges = np.array(ranges)
        for k in np.flatnonzero(flags):  # the run ends after this step: its samples up to k + 1 are recorded
            assert np.all(ranges[k + 2:].min(axis=0, initial=np.inf) >= ranges[:k + 2].min(axis=0) - 1e-6)
        settled_runs += bool(np.any(flags))
    assert settled_runs >= 30  # the property was put to the test, not met by never settling


# -- full runs against runs ended by the watch ------------------------------------------------------
REPO = Path(__file__).resolve().parents[2]
#: A fixed sample of the search's space: a head-on target at 30 kn timed against the 4-min trigger
#: (a loss below half the domain in the paper's loop), a slow crossing target from starboard, and three
#: targets (an overtaken one, a fast crossing one from port, a head-on one).
SAMPLE = {
    "fast head-on, a loss": [{"radius_nm": 1.0, "start_nm": [60.96, 50.0], "velocity_kn": [-30.0, 0.0]}],
    "slow crossing": [{"radius_nm": 1.0, "start_nm": [55.4, 45.0], "velocity_kn": [0.0, 6.0]}],
    "three targets": [{"radius_nm": 1.0, "start_nm": [51.5, 50.2], "velocity_kn": [8.0, 0.0]},
                      {"radius_nm": 1.0, "start_nm": [55.0, 59.0], "velocity_kn": [-3.0, -28.0]},
                      {"radius_nm": 1.0, "start_nm": [62.0, 49.7], "velocity_kn": [-16.0, 0.0]}],
}


@pytest.mark.slow
@pytest.mark.parametrize("case", list(SAMPLE))
def test_a_run_ended_by_the_watch_is_judged_as_its_full_run(case, tmp_path):
    # the search file's own stop: its [set] block, with and without which the same run is made
    import tomllib

    from orchestrator.run import run_scenario

    watched = tomllib.loads((REPO / "batches" / "search_rhnc_watched.toml").read_text())["set"]
    targets = {"participants.traffic.options.targets": SAMPLE[case]}
    scenario = REPO / "scenarios" / "encounter_rhnc.toml"
    full = run_scenario(scenario, tmp_path, progress=False, run_id="full", overrides=targets, group="runs").summary
    ended = run_scenario(scenario, tmp_path, progress=False, run_id="ended", overrides={**targets, **watched},
                         group="runs").summary
    assert full["status"] == ended["status"] == "finished"
    assert ended["simulation"]["steps_done"] <= full["simulation"]["steps_done"]
    judged, again = full["analyses"]["colregs"], ended["analyses"]["colregs"]
    assert again["separation_margin_nm"] == judged["separation_margin_nm"]
    assert again["separation_kept"] == judged["separation_kept"]
    assert [t["cpa_nm"] for t in again["targets"]] == [t["cpa_nm"] for t in judged["targets"]]
    if case == "fast head-on, a loss":
        assert judged["separation_margin_nm"] < -0.5  # the loss the comparison counts, kept
        assert ended["simulation"]["steps_done"] < full["simulation"]["steps_done"] / 2
