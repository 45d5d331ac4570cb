"""The fair voyage comparison: equal-arrival baselines, the headline, flags, sweeps and input errors."""

import json
import textwrap
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest

from orchestrator.cli import main
from orchestrator.compare import Section, load_comparison, load_extensions, run_comparison
from orchestrator.errors import ScenarioError
from rhnc.voyage.equal_arrival import ArrivalTrial, EqualArrival
from rhnc.voyage.voyage_comparison import SailedVoyage
from rhnc.voyage.voyage_comparison_tables import evaluation_section, sweep_section

# A 4 nm passage north, the NMPC tracking a waypoint reference on the KCS every 20 s, in a
# small paper-style weather field sampled by the MetOcean FMU.
SCENARIO = """
connections = [
  "ship.x -> goal.x", "ship.y -> goal.y",
  "route.reference -> ctrl.reference",
  "ship.x -> ctrl.x", "ship.y -> ctrl.y", "ship.psi -> ctrl.psi",
  "ship.u -> ctrl.u", "ship.v -> ctrl.v", "ship.r -> ctrl.r",
  "ctrl.tau_u -> ship.tau_u", "ctrl.tau_r -> ship.tau_r",
  "env.current_north -> ship.current_north", "env.current_east -> ship.current_east",
  "env.wind_speed -> ship.wind_speed", "env.wind_direction -> ship.wind_direction", "env.hs -> ship.hs",
  "ship.x -> env.x", "ship.y -> env.y",
]
[simulation]
steps = 30
dt_s = 20.0
[metocean]
generator = "paper_default"
x_range_nm = [-1.0, 5.0]
y_range_nm = [-3.0, 3.0]
resolution_nm = 0.25
[participants.route]
type = "reference_path"
[participants.route.options]
waypoints_nm = {waypoints}
speed_kn = {speed}
[participants.ctrl]
type = "control"
[participants.ctrl.options]
horizon_steps = 10
[participants.goal]
type = "goal"
[participants.goal.options]
goal_nm = [4.0, 0.0]
[participants.ship]
fmu = "KCS"
[participants.ship.parameters]
u0 = 9.26
[participants.env]
fmu = "MetOcean"
[participants.env.parameters]
grid_file = "${{metocean.grid}}"
[outputs]
analyses = ["voyage"]
figures = []
"""

COMPARISON = """
name = "fair"
analysis = "voyage"
metrics = ["cost_usd", "time_min", "mean_speed_through_water_kn"]
{top}
[voyage]
start_nm = [0.0, 0.0]
goal_nm = [4.0, 0.0]
max_duration_h = 1.0
{voyage}
[voyage.equal_arrival]
scenario = "straight.toml"
{equal}
[[runs]]
label = "detour"
scenario = "detour.toml"
[[runs]]
label = "straight"
scenario = "straight.toml"
"""


def write(tmp_path: Path, top="", voyage="", equal="") -> Path:
    (tmp_path / "straight.toml").write_text(textwrap.dedent(SCENARIO.format(
        waypoints="[[0.0, 0.0], [4.0, 0.0]]", speed=18.0)))
    (tmp_path / "detour.toml").write_text(textwrap.dedent(SCENARIO.format(
        waypoints="[[0.0, 0.0], [2.0, 0.6], [4.0, 0.0]]", speed=16.5)))
    path = tmp_path / "compare.toml"
    path.write_text(textwrap.dedent(COMPARISON.format(top=top, voyage=voyage, equal=equal)))
    return path


HEADLINE_COLUMNS = ["system", "arrival [min]", "cost [USD]", "baseline cost [USD]", "saving cost [%]", "CO2 [t]",
                    "baseline CO2 [t]", "saving CO2 [%]", "baseline speed [kn]", "baseline arrival [min]",
                    "available cost [%]", "share cost [%]"]


@pytest.mark.slow
def test_equal_arrival_baseline_crosses_the_arrival_radius_within_two_seconds_of_the_system(tmp_path, capsys):
    # only the detour gets a baseline; the straight run sails faster without one: flagged
    path = write(tmp_path, voyage='[voyage.optimal_route]\nresolution_nm = 0.5', equal='systems = ["detour"]')
    assert main(["compare", str(path), "--results", str(tmp_path / "results"), "--no-progress"]) == 0
    folder = next((tmp_path / "results" / "fair").iterdir())
    headline = pd.read_csv(folder / "voyage_headline.csv").set_index("system")
    assert set(HEADLINE_COLUMNS[1:]) <= set(headline.columns)
    detour = headline.loc["detour"]
    assert abs(detour["baseline arrival [min]"] - detour["arrival [min]"]) <= 2.0 / 60.0 + 1e-9
    assert detour["arrival [min]"] * 60.0 % 20.0 != 0.0        # the crossing, not a 20 s sample
    # the straight line is shorter than the detour: it arrives as late at a lower speed, and cheaper
    assert detour["baseline speed [kn]"] < 16.5
    assert detour["saving cost [%]"] < 0
    runs = pd.read_csv(folder / "voyage_runs.csv").set_index("voyage")
    assert runs.loc["detour", "arrived"] and runs.loc["detour equal-arrival baseline", "arrived"]
    assert runs.loc["optimal route at detour's arrival", "cost [USD]"] <= runs.loc[
        "straight route at detour's arrival", "cost [USD]"] + 1e-6
    # a costed route arrives when the system did
    assert runs.loc["straight route at detour's arrival", "arrival [min]"] == pytest.approx(detour["arrival [min]"])
    # the weather's own available saving: straight line at the baseline scenario's 18 kn through water
    nominal = json.loads((folder / "summary.json").read_text())["voyage"]["nominal"]
    assert nominal["speed_kn"] == 18.0
    assert 4.0 / 18.6 * 60 < nominal["arrival_min"] < 4.0 / 17.4 * 60   # 4 nm at 18 kn, +- the 0.5 kn current
    assert nominal["optimal_cost_usd"] <= nominal["straight_cost_usd"] + 1e-6
    out = capsys.readouterr().out
    assert "Headline: the passage at equal arrival time" in out
    assert "**FLAG**: mean speeds through water differ" in out and "straight has no equal-arrival baseline" in out


def voyage(label, speed_kn, arrival_s=3600.0, cost=100.0, co2=1.0, arrived=True):
    return SailedVoyage(label=label, status="finished", arrived=arrived, arrival_s=arrival_s if arrived else None,
                        cost_usd=cost, co2_t=co2, mean_speed_through_water_kn=speed_kn, distance_nm=18.0,
                        made_good_nm=18.0, track_m=np.zeros((2, 2)))


def matched(system, speed_kn=17.0, cost=100.0, co2=1.0):
    result = EqualArrival(system.arrival_s, 60.0)
    result.trials.append(ArrivalTrial(speed_kn, system.arrival_s,
                                      voyage(f"{system.label} equal-arrival baseline", speed_kn, system.arrival_s,
                                             cost, co2)))
    return result


COMPARISON_STUB = SimpleNamespace(straight_distance_nm=18.0, published={}, equal_arrival=None)


@pytest.mark.parametrize("speeds, with_baselines, flagged", [
    ((17.5, 18.0), False, True),     # 2.9 % apart, no baseline: flagged
    ((17.95, 18.0), False, False),   # 0.28 % apart: comparable as they are
    ((17.5, 18.0), True, False),     # apart, but each has its equal-arrival baseline
])
def test_mean_speed_flag(tmp_path, speeds, with_baselines, flagged):
    systems = {"RHNC": voyage("RHNC", speeds[0]), "Offline-SPNC": voyage("Offline-SPNC", speeds[1])}
    baselines = {label: matched(s) for label, s in systems.items()} if with_baselines else {}
    section = evaluation_section(COMPARISON_STUB, systems, baselines, {}, tmp_path)
    speed_flags = [f for f in section.flags if f.startswith("mean speeds through water differ")]
    assert bool(speed_flags) == flagged
    assert ("**FLAG**: mean speeds" in section.markdown) == flagged


def test_share_of_available_saving_and_headline(tmp_path):
    system = voyage("RHNC", 17.5, cost=95.0, co2=0.9)
    routes = {"RHNC": {"straight": SimpleNamespace(cost_usd=100.0, co2_t=1.0, duration_s=3600.0, distance_nm=18.0,
                                                   speed_through_water_mps=9.0),
                       "optimal": SimpleNamespace(cost_usd=90.0, co2_t=0.8, duration_s=3600.0, distance_nm=18.5,
                                                  speed_through_water_mps=9.2)}}
    section = evaluation_section(COMPARISON_STUB, {"RHNC": system}, {"RHNC": matched(system)}, routes, tmp_path)
    figures = section.summary["systems"]["RHNC"]
    assert figures["saving_cost_percent"] == pytest.approx(5.0)
    assert figures["available_cost_percent"] == pytest.approx(10.0)
    assert figures["share_cost_percent"] == pytest.approx(50.0)
    assert figures["share_co2_percent"] == pytest.approx(100.0 * 10.0 / 20.0)
    assert list(section.tables["voyage_headline"].columns[:len(HEADLINE_COLUMNS)]) != []
    assert set(HEADLINE_COLUMNS) <= set(section.tables["voyage_headline"].columns)


def test_run_that_does_not_arrive_is_left_out_of_the_headline(tmp_path):
    systems = {"RHNC": voyage("RHNC", 17.5, arrived=False), "Offline-SPNC": voyage("Offline-SPNC", 18.0)}
    section = evaluation_section(COMPARISON_STUB, systems, {"Offline-SPNC": matched(systems["Offline-SPNC"])}, {},
                                 tmp_path)
    assert list(section.tables["voyage_headline"]["system"]) == ["Offline-SPNC"]
    assert "RHNC did not arrive: left out of the headline" in section.flags
    failed = SailedVoyage(**{**systems["RHNC"].__dict__, "status": "failed", "reason": "left the map"})
    section = evaluation_section(COMPARISON_STUB, {"RHNC": failed}, {}, {}, tmp_path)
    assert "RHNC did not arrive (the run failed: left the map): left out of the headline" in section.flags


def test_sweep_puts_the_available_saving_first_and_gives_the_distribution(tmp_path):
    members = []
    # the last member offers less than the 0.5 % a share needs, the one before did not arrive
    for member, (available, share) in enumerate([(2.0, 10.0), (4.0, 30.0), (1.0, 50.0), (0.3, -500.0), (None, None)]):
        figures = {"arrived": available is not None, "arrival_min": 480.0}
        if available is not None:
            figures.update(available_cost_percent=available, saving_cost_percent=available * share / 100)
        nominal = {"available_cost_percent": 1.5 * member, "arrival_min": 471.0}
        members.append((member, Section(summary={"systems": {"RHNC": figures}, "nominal": nominal})))
    section = sweep_section("metocean.member", members, tmp_path)
    table = section.tables["voyage_sweep"]
    assert list(table.columns[:2]) == ["metocean.member", "available cost saving at the nominal speed [%]"]
    assert table.columns[3] == "RHNC available cost saving [%]"
    assert list(table["available cost saving at the nominal speed [%]"]) == pytest.approx([0.0, 1.5, 3.0, 4.5, 6.0])
    assert list(table["RHNC share cost [%]"].iloc[:3]) == pytest.approx([10.0, 30.0, 50.0])
    stats = section.summary["distribution"]["RHNC"]["share cost [%]"]
    assert stats["median"] == pytest.approx(30.0) and stats["count"] == 3
    assert section.summary["distribution"]["RHNC"]["arrived"] == 4
    assert (tmp_path / "voyage_sweep.png").is_file()


@pytest.mark.parametrize("top, voyage_extra, equal, message", [
    ("", "colour = 1", "", r"compare.toml: voyage: unknown key 'colour'"),
    ("", "", 'systems = ["RHNC"]', r"voyage.equal_arrival.systems: 'RHNC' is not a run label \(detour, straight\)"),
    ("", "", 'scenario = "none.toml"', None),
    ("", "", "max_trials = 0", r"voyage.equal_arrival.max_trials: expected a positive integer, got 0"),
    ("", "[voyage.optimal_route]\nresolution_nm = -1", "", r"voyage.optimal_route.resolution_nm: expected a positive"),
    ("", "[voyage.optimal_route]\navoid = [{ center_nm = [1, 1] }]", "",
     r"voyage.optimal_route.avoid\[0\].radius_nm: expected a positive number"),
    ('[sweep]\nkey = "metocean.member"\nrange = [3, 1]', "", "", r"'sweep.range' must be \[first, last\]"),
])
def test_comparison_file_errors(tmp_path, top, voyage_extra, equal, message):
    path = write(tmp_path, top=top, voyage=voyage_extra, equal=equal)
    if message is None:   # a second 'scenario' key is a TOML error naming the key
        with pytest.raises(ScenarioError, match=r"compare.toml: not valid TOML"):
            load_extensions(load_comparison(path), path)
        return
    with pytest.raises(ScenarioError, match=message):
        load_extensions(load_comparison(path), path)


def test_a_route_that_does_not_sail_the_voyage_is_refused_before_any_run(tmp_path):
    # the detour's polyline ends at (4, 0): it cannot be moved to another goal without rerouting it
    path = write(tmp_path)
    path.write_text(path.read_text().replace("goal_nm = [4.0, 0.0]", "goal_nm = [4.5, 0.0]"))
    with pytest.raises(ScenarioError, match=r"detour.toml: participants.route.options.waypoints_nm runs from "
                                            r"\[0.0, 0.0\] to \[4.0, 0.0\], not from the \[voyage\] start "
                                            r"\[0.0, 0.0\] to its goal \[4.5, 0.0\]"):
        run_comparison(path, tmp_path / "results", progress=False)
    assert not (tmp_path / "results" / "fair").exists() or not any((tmp_path / "results" / "fair").iterdir())


def test_the_voyage_sets_every_participants_start_and_goal(tmp_path):
    """[voyage] start and goal reach the goal monitor, the plant's initial state and a straight
    reference route; the scenario's own values are replaced."""
    from orchestrator.geometry import NM
    from orchestrator.scenario import load_scenario

    path = write(tmp_path)
    path.write_text(path.read_text().replace("start_nm = [0.0, 0.0]\ngoal_nm = [4.0, 0.0]",
                                             "start_nm = [0.5, -0.5]\ngoal_nm = [3.5, 0.5]"))
    path.write_text(path.read_text().replace('label = "detour"\nscenario = "detour.toml"',
                                             'label = "detour"\nscenario = "straight.toml"'))
    spec = load_comparison(path)
    voyage = load_extensions(spec, path)["voyage"]
    overrides = voyage.run_overrides(tmp_path / "straight.toml", {}, "here")
    loaded = load_scenario(tmp_path / "straight.toml", overrides)
    options = {p.name: p for p in loaded.participants}
    assert options["goal"].options["goal_nm"] == [3.5, 0.5]
    assert options["route"].options["waypoints_nm"] == [[0.5, -0.5], [3.5, 0.5]]
    heading = np.degrees(np.arctan2(1.0, 3.0))
    assert options["ship"].initial == pytest.approx({"x_nm": 0.5, "y_nm": -0.5, "psi_deg": heading})
    assert overrides["outputs.options.voyage.goal_nm"] == [3.5, 0.5]
    assert np.allclose(voyage.start_m, [0.5 * NM, -0.5 * NM])


def test_the_voyage_sets_the_navigation_and_its_arrival_time():
    from orchestrator.scenario import load_scenario
    from rhnc.voyage.voyage_geometry import geometry_overrides

    loaded = load_scenario(Path(__file__).parents[2] / "scenarios" / "exp2_routing.toml")
    nm = 1852.0
    overrides = geometry_overrides(loaded, np.array([10.0, 90.0]) * nm, np.array([80.0, 5.0]) * nm, 500.0, "here")
    assert overrides["participants.nav.options.start_nm"] == [10.0, 90.0]
    assert overrides["participants.nav.options.goal_nm"] == [80.0, 5.0]
    assert overrides["participants.nav.options.arrival_time_min"] == 500.0
    assert overrides["participants.goal.options.goal_nm"] == [80.0, 5.0]
    # psi0 is the scenario's own parameter: set there, in rad; x and y through [initial]
    assert overrides["participants.ship.parameters.psi0"] == pytest.approx(np.arctan2(-85.0, 70.0))
    assert overrides["participants.ship.initial.x_nm"] == pytest.approx(10.0)
    assert overrides["participants.ship.initial.y_nm"] == pytest.approx(90.0)


def test_an_override_that_contradicts_the_voyage_is_refused_naming_both(tmp_path, capsys):
    path = write(tmp_path, top='[set]\n"participants.goal.options.goal_nm" = [3.0, 0.0]')
    assert main(["compare", str(path), "--results", str(tmp_path / "results")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert ("detour.toml: 'participants.goal.options.goal_nm' = [3.0, 0.0] (set in the comparison) is not the "
            "[voyage] passage's [4.0, 0.0]") in err
    assert not (tmp_path / "results" / "fair").exists()


@pytest.mark.parametrize("voyage_line, key", [("start_nm = [-2.0, 0.0]", "start_nm"),
                                              ("goal_nm = [4.0, 3.5]", "goal_nm")])
def test_a_start_or_goal_off_the_weather_map_is_refused(tmp_path, capsys, voyage_line, key):
    path = write(tmp_path)
    old = "start_nm = [0.0, 0.0]" if key == "start_nm" else "goal_nm = [4.0, 0.0]\nmax_duration_h"
    path.write_text(path.read_text().replace(old, voyage_line if key == "start_nm" else voyage_line + "\nmax_duration_h"))
    assert main(["compare", str(path), "--results", str(tmp_path / "results")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert f"voyage.{key}" in err and "lies outside the met-ocean map (north -1..5 nm, east -3..3 nm)" in err


def test_control_options_naming_files_across_folders_are_refused_before_any_run(tmp_path, capsys, monkeypatch):
    # the system's scenario in a folder of its own, its NMPC naming its model by a string:
    # handed to the baseline in another folder, the name would point elsewhere
    path = write(tmp_path)
    (tmp_path / "systems").mkdir()
    detour = (tmp_path / "detour.toml").read_text().replace("horizon_steps = 10",
                                                            'horizon_steps = 10\nparameter_set = "default"')
    (tmp_path / "systems" / "detour.toml").write_text(detour)
    path.write_text(path.read_text().replace('scenario = "detour.toml"', 'scenario = "systems/detour.toml"'))
    started = []
    monkeypatch.setattr("orchestrator.compare.ScenarioRunner.__call__",
                        lambda self, scenario, overrides, label: started.append(label))
    assert main(["compare", str(path), "--results", str(tmp_path / "results")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "voyage.equal_arrival.same_control" in err and "different folders" in err
    assert started == [], "runs were started before the input error"
    assert not (tmp_path / "results" / "fair").exists() or not any((tmp_path / "results" / "fair").iterdir())


def test_bad_voyage_table_exits_2_from_the_cli(tmp_path, capsys):
    path = write(tmp_path, voyage="arrival_radius_nm = 0")
    assert main(["compare", str(path), "--results", str(tmp_path / "results")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "voyage.arrival_radius_nm: expected a positive number, got 0" in err


def test_routing_failure_is_flagged_not_fatal(tmp_path):
    system = voyage("RHNC", 17.5)
    routes = {"RHNC": {"routing_error": "arrival at 600 s needs more than 30 m/s through water"}}
    section = evaluation_section(COMPARISON_STUB, {"RHNC": system}, {"RHNC": matched(system)}, routes, tmp_path)
    assert section.summary["systems"]["RHNC"].get("share_cost_percent") is None
    assert any(f.startswith("no optimal route at RHNC's arrival time (arrival at 600 s") for f in section.flags)


def test_run_from_another_start_is_flagged(tmp_path):
    systems = {"RHNC": voyage("RHNC", 17.5)}
    systems["RHNC"].track_m[:] = [[1852.0, 0.0], [3704.0, 0.0]]
    comparison = SimpleNamespace(straight_distance_nm=18.0, published={}, equal_arrival=None, start_m=np.zeros(2))
    section = evaluation_section(comparison, systems, {}, {}, tmp_path)
    assert "RHNC started 1.00 nm from voyage.start_nm: not the same passage" in section.flags
    systems["RHNC"].track_m[0] = [10.0, 0.0]
    assert not evaluation_section(comparison, systems, {}, {}, tmp_path).flags


def test_run_that_failed_after_arriving_counts_and_is_flagged(tmp_path):
    arrived_then_failed = SailedVoyage(**{**voyage("RHNC", 17.5).__dict__, "status": "failed",
                                          "reason": "left the map"})
    section = evaluation_section(COMPARISON_STUB, {"RHNC": arrived_then_failed},
                                 {"RHNC": matched(arrived_then_failed)}, {}, tmp_path)
    assert list(section.tables["voyage_headline"]["system"]) == ["RHNC"]
    assert ("RHNC arrived at 60 min, then the run ended 'failed' (left the map): its totals up to arrival are used"
            in section.flags)


class _Recorded(Exception):
    pass


def first_baseline_overrides(comparison, system_scenario: Path) -> dict:
    """The overrides of the first equal-arrival trial run for a system sailed from ``system_scenario``."""
    seen = []

    def runner(scenario, overrides, label):
        seen.append(dict(overrides))
        raise _Recorded

    report = SimpleNamespace(summary={"scenario": str(system_scenario), "overrides": {}})
    with pytest.raises(_Recorded):
        comparison._equal_arrival_baseline(voyage("detour", 16.5), runner, {}, report)
    return seen[0]


@pytest.mark.parametrize("same_control", [None, True, False])
def test_the_baseline_sails_with_the_systems_control_options(tmp_path, same_control):
    # the system's NMPC runs an offset-free observer; the baseline's scenario has none
    path = write(tmp_path, equal="" if same_control is None else f"same_control = {str(same_control).lower()}")
    detour = tmp_path / "detour.toml"
    detour.write_text(detour.read_text().replace("horizon_steps = 10", "horizon_steps = 12\ndisturbance_observer = true"))
    comparison = load_extensions(load_comparison(path), path)["voyage"]
    overrides = first_baseline_overrides(comparison, detour)
    if same_control is False:
        assert not any(key.startswith("participants.ctrl") for key in overrides)
    else:
        assert overrides["participants.ctrl.options"] == {"horizon_steps": 12, "disturbance_observer": True}
    assert overrides["participants.route.options.speed_kn"] > 0      # the speed search goes on as before


def test_same_control_must_be_true_or_false(tmp_path):
    path = write(tmp_path, equal='same_control = "yes"')
    with pytest.raises(ScenarioError, match=r"compare.toml: voyage.equal_arrival.same_control: expected true or "
                                            r"false, got 'yes'"):
        load_extensions(load_comparison(path), path)


def test_a_failed_equal_arrival_trial_is_reported(tmp_path):
    """A trial that failed (the ship left the weather map) is named in the trials table and
    handed to the comparison as a failed run, even when the search found its speed."""
    system = voyage("RHNC", 17.5)
    equal = matched(system)
    left = SailedVoyage(**{**voyage("RHNC equal-arrival baseline", 17.0, arrival_s=None, arrived=False).__dict__,
                           "status": "failed", "reason": "env (MetOcean.fmu): point x is outside the grid"})
    equal.trials.insert(0, ArrivalTrial(16.0, None, left))
    section = evaluation_section(COMPARISON_STUB, {"RHNC": system}, {"RHNC": equal}, {}, tmp_path)
    assert section.failed_runs == {"RHNC equal-arrival baseline at 16.0000 kn":
                                   "failed: env (MetOcean.fmu): point x is outside the grid"}
    trials = section.tables["voyage_trials"]
    assert list(trials["status"]) == ["failed", "finished"]
    assert "## Equal-arrival trials" in section.markdown and "point x is outside the grid" in section.markdown


@pytest.mark.parametrize("goal_nm, hold", [((4.0, 0.0), None),      # 1 nm inside: circle and band on the map
                                           ((4.6, 0.0), 1.0),       # 0.4 nm from the north edge
                                           ((5.0, 3.0), 1.0)])      # on the corner
def test_a_goal_near_the_maps_edge_has_the_runs_hold_the_edges_weather(tmp_path, goal_nm, hold):
    """The arrival circle (and half a mile beyond it) must lie where the ship finds weather:
    near an edge, every run holds the edge's values that far beyond the map."""
    from orchestrator.geometry import NM
    from orchestrator.scenario import load_scenario
    from rhnc.weather.metocean_sources import from_scenario_table

    path = write(tmp_path)
    path.write_text(path.read_text().replace("goal_nm = [4.0, 0.0]\nmax", f"goal_nm = {list(goal_nm)}\nmax"))
    voyage = load_extensions(load_comparison(path), path)["voyage"]
    overrides = voyage.run_overrides(tmp_path / "straight.toml", {}, "here")
    assert overrides.get("metocean.hold_edges_nm") == hold
    loaded = load_scenario(tmp_path / "straight.toml", overrides)
    field = from_scenario_table(loaded.metocean, tmp_path, "here")
    angles = np.linspace(0.0, 2.0 * np.pi, 73)
    circle = np.asarray(goal_nm)[:, None] + 1.0 * np.vstack([np.cos(angles), np.sin(angles)])
    assert field.contains(circle[0] * NM, circle[1] * NM).all()
    # a band the comparison gives itself is kept
    own = voyage.run_overrides(tmp_path / "straight.toml", {"metocean.hold_edges_nm": 2.0}, "here")
    assert "metocean.hold_edges_nm" not in own


def test_the_edge_band_is_what_the_arrival_circle_needs():
    from orchestrator.geometry import NM
    from rhnc.voyage.voyage_geometry import EDGE_ALLOWANCE_NM, edge_hold_nm
    from rhnc.weather.weather_generators import paper_default

    field = paper_default(x_range_nm=(0.0, 10.0), y_range_nm=(0.0, 10.0), resolution_nm=1.0)
    radius = 0.5
    needed = radius + EDGE_ALLOWANCE_NM
    assert edge_hold_nm(field, np.array([10.0, 10.0]) * NM, radius) == needed
    assert edge_hold_nm(field, np.array([5.0, 0.2]) * NM, radius) == needed
    assert edge_hold_nm(field, np.array([5.0, 10.0 - needed + 0.01]) * NM, radius) == needed
    assert edge_hold_nm(field, np.array([5.0, 10.0 - needed - 0.01]) * NM, radius) is None
    assert edge_hold_nm(field, np.array([5.0, 5.0]) * NM, 2.0) is None
    assert edge_hold_nm(field, np.array([5.0, 5.0]) * NM, 4.6) == 4.6 + EDGE_ALLOWANCE_NM


EDGE_COMPARISON = """
name = "edge"
analysis = "voyage"
metrics = ["cost_usd", "time_min"]
[voyage]
start_nm = [0.0, 0.0]
goal_nm = [4.0, 0.0]
max_duration_h = 1.0
[[runs]]
label = "beyond"
scenario = "beyond.toml"
"""


@pytest.mark.slow
def test_a_ship_sails_the_arrival_circles_part_beyond_the_maps_edge(tmp_path):
    """The goal on the map's north edge; the route leaves the map 0.7 nm from the goal and
    comes back to it from beyond the edge: the run arrives instead of failing off the map."""
    from orchestrator.geometry import NM

    scenario = textwrap.dedent(SCENARIO.format(
        waypoints="[[0.0, 0.0], [3.0, 0.7], [4.4, 0.7], [4.4, 0.0], [4.0, 0.0]]", speed=12.0))
    (tmp_path / "beyond.toml").write_text(scenario.replace("x_range_nm = [-1.0, 5.0]", "x_range_nm = [-1.0, 4.0]"))
    (tmp_path / "compare.toml").write_text(EDGE_COMPARISON)
    folder = run_comparison(tmp_path / "compare.toml", tmp_path / "results", progress=False)
    summary = json.loads((folder / "summary.json").read_text())
    assert summary["status"] == "finished", summary["failed_runs"]
    run = next((folder / "runs").rglob("summary.json"))
    frame = pd.read_parquet(run.parent / "timeseries.parquet")
    assert frame["ship.x"].max() > 4.0 * NM + 0.2 * NM   # it sailed beyond the edge
    assert json.loads(run.read_text())["analyses"]["voyage"]["arrived"]


def test_a_baseline_that_cannot_arrive_is_reported_as_the_outcome_without_a_saving(tmp_path):
    system = voyage("RHNC", 15.0, arrival_s=25_050.0)
    held_back = EqualArrival(system.arrival_s, 2.0, top_speed_kn=30.0)
    for speed in (14.85, 23.21, 30.0):
        held_back.trials.append(ArrivalTrial(speed, None, voyage("RHNC equal-arrival baseline", 6.0, arrived=False)))
    section = evaluation_section(COMPARISON_STUB, {"RHNC": system}, {"RHNC": held_back}, {}, tmp_path)
    figures = section.summary["systems"]["RHNC"]
    assert figures["baseline_outcome"] == "cannot arrive"
    assert "saving_cost_percent" not in figures and "saving_co2_percent" not in figures
    headline = section.tables["voyage_headline"].set_index("system")
    assert headline.loc["RHNC", "baseline"] == "cannot arrive" and headline.loc["RHNC", "saving cost [%]"] is None
    assert section.summary["outcomes"] == [
        "RHNC arrives at 417.5 min; its equal-arrival baseline arrives at no reference speed up to the fastest "
        "allowed, 30 kn (trials at 14.85, 23.21, 30.00 kn): in this weather the baseline cannot make the "
        "passage, so there is no saving at equal arrival time to give"]
    assert "**Outcome**: RHNC arrives at 417.5 min" in section.markdown
    assert not any("missed its arrival time" in flag for flag in section.flags)
    # a search that stopped short of the fastest speed is a flag, not this outcome
    held_back.trials.pop()
    section = evaluation_section(COMPARISON_STUB, {"RHNC": system}, {"RHNC": held_back}, {}, tmp_path)
    assert section.summary["outcomes"] == [] and section.summary["systems"]["RHNC"]["baseline_outcome"] == "unmatched"
    assert any("missed its arrival time" in flag and "no trial arrived" in flag for flag in section.flags)
