"""Hostile scenario inputs: each is refused with one line naming the file and the key, exit 2,
before anything is allocated from it; validate checks FMU parameters against the ranges the
FMU declares and imports no code that comes with a scenario unless told to."""

import math
from pathlib import Path

import pytest

from orchestrator.cli import main
from orchestrator.errors import ScenarioError
from orchestrator.master import CoSimulation
from orchestrator.participant_build import build_scenario_table
from orchestrator.scenario import load_scenario
from orchestrator.validate import check_scenario

REPO = Path(__file__).resolve().parents[2]

BASE = """
connections = ["helm.tau_u -> ship.tau_u", "helm.tau_r -> ship.tau_r"]
[simulation]
name = "trial"
stop_s = 60.0
dt_s = 5.0
[participants.helm]
type = "scripted_tau"
[participants.helm.options]
tau_u_N = 7.7e5
tau_r_steps = [[10.0, 3.3e8]]
[participants.ship]
fmu = "KCS"
[participants.ship.parameters]
u0 = 9.26
"""

WEATHER = BASE + """
[metocean]
generator = "paper_default"
"""


def _edit(text, old, new):
    assert old in text, old
    return text.replace(old, new, 1)


def _refused(write_scenario, capsys, text, message, build=False):
    """The scenario is refused with ``message`` by the loader (or the build), and by the CLI
    with exit 2 and exactly one line naming the file."""
    path = write_scenario(text)
    with pytest.raises(ScenarioError, match=message) as caught:
        scenario = load_scenario(path)
        if build:
            CoSimulation(scenario).close()
    assert str(path) in str(caught.value) and "\n" not in str(caught.value)
    capsys.readouterr()
    assert main(["validate", str(path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"error: {path}"), err
    return err[0]


DEEP = "[" * 500 + "1" + "]" * 500

LOADER_CASES = {
    "array nested 500 deep": (lambda t: t + f"\ndeep = {DEEP}\n", r"nested deeper than the limit of 24 levels"),
    "array nested 30 deep": (lambda t: _edit(t, "u0 = 9.26", "u0 = " + "[" * 30 + "1" + "]" * 30),
                             r"'participants.ship.parameters.u0\[0\].*' nests arrays or tables deeper than the limit"),
    "start_s -1e308, stop_s 1e308": (lambda t: _edit(t, "stop_s = 60.0", "start_s = -1e308\nstop_s = 1e308"),
                                     r"'simulation.start_s' must lie within \+-1e\+10 s, got -1e\+308"),
    "dt_s 5e-324": (lambda t: _edit(t, "dt_s = 5.0", "dt_s = 5e-324"),
                    r"'simulation.dt_s' must be at least 1e-06 s, got 5e-324"),
    "dt_s 1e-300": (lambda t: _edit(t, "dt_s = 5.0", "dt_s = 1e-300"), r"'simulation.dt_s' must be at least 1e-06 s"),
    "dt_s 1e-5 over 60 s": (lambda t: _edit(t, "dt_s = 5.0", "dt_s = 1e-5"),
                            r"'simulation.dt_s' = 1e-05 s gives 6e\+06 macro steps, more than the limit of 1000000"),
    "steps 1e300": (lambda t: _edit(t, "stop_s = 60.0", "steps = " + "9" * 300),
                    r"'simulation.steps' = 9{20}.* is more than the limit of 1000000 macro steps"),
    "every 2**62": (lambda t: _edit(t, 'type = "scripted_tau"', 'type = "scripted_tau"\nevery = 4611686018427387904'),
                    r"'participants.helm.every' must be a positive integer \(at most 1000000\)"),
    "type = []": (lambda t: _edit(t, 'type = "scripted_tau"', "type = []"),
                  r"'participants.helm.type' must be a non-empty string, got \[\]"),
    "mapping = 5": (lambda t: _edit(t, 'fmu = "KCS"', 'fmu = "KCS"\nmapping = 5'),
                    r"'participants.ship.mapping' must be a table"),
    "initial = 5": (lambda t: _edit(t, 'fmu = "KCS"', 'fmu = "KCS"\ninitial = 5'),
                    r"'participants.ship.initial' must be a table"),
    "options = 5": (lambda t: _edit(t, "[participants.helm.options]\ntau_u_N = 7.7e5\ntau_r_steps = [[10.0, 3.3e8]]",
                                    "options = 5"),
                    r"'participants.helm.options' must be a table"),
    "parameters = 5": (lambda t: _edit(t, "[participants.ship.parameters]\nu0 = 9.26", "parameters = 5"),
                       r"'participants.ship.parameters' must be a table"),
    "geodetic origin_deg = 5": (lambda t: _edit(t, 'fmu = "KCS"', 'fmu = "KCS"\ngeodetic = { origin_deg = 5 }'),
                                r"'participants.ship.geodetic.origin_deg' must be \[latitude, longitude\] in degrees, "
                                r"got 5"),
    "name NUL": (lambda t: _edit(t, 'name = "trial"', r'name = "a\u0000b"'),
                 r"'simulation.name' must not contain control characters \(NUL, newline, ...\), got 'a\\x00b'"),
    "name 300 characters": (lambda t: _edit(t, 'name = "trial"', f'name = "{"n" * 300}"'),
                            r"'simulation.name' must be at most 100 characters long, got 300"),
    "name ..": (lambda t: _edit(t, 'name = "trial"', 'name = ".."'), r"'simulation.name' must not start with '.'"),
    "name with a slash": (lambda t: _edit(t, 'name = "trial"', 'name = "../elsewhere"'),
                          r"'simulation.name' must be a folder name without slashes"),
    "FMU parameter NaN": (lambda t: _edit(t, "u0 = 9.26", "u0 = nan"),
                          r"'participants.ship.parameters.u0' must be a finite number, boolean or string, got nan"),
    "FMU parameter -inf": (lambda t: _edit(t, "u0 = 9.26", "u0 = -inf"),
                           r"'participants.ship.parameters.u0' must be a finite number, boolean or string, got -inf"),
    "scripted schedule NaN": (lambda t: _edit(t, "[[10.0, 3.3e8]]", "[[10.0, nan]]"),
                              r"'participants.helm.options.tau_r_steps' must be a list of \[time_s, value\] pairs of "
                              r"finite numbers"),
    "unknown key with a newline": (lambda t: _edit(t, "dt_s = 5.0", 'dt_s = 5.0\n"a\\nb" = 1'),
                                   r"unknown key 'simulation.a\\nb'"),
}


@pytest.mark.parametrize("case", list(LOADER_CASES))
def test_the_loader_refuses_with_one_line(write_scenario, capsys, case):
    edit, message = LOADER_CASES[case]
    _refused(write_scenario, capsys, edit(BASE), message, build=True)


BUILD_CASES = {
    "metocean file = 5": ('generator = "paper_default"', "file = 5",
                          r"metocean.file: expected the path of a NetCDF file, got 5"),
    "metocean origin_deg = 5": ('generator = "paper_default"', 'generator = "paper_default"\norigin_deg = 5',
                                r"metocean: unknown key 'origin_deg' for generator 'paper_default'"),
    "x_range_nm = [0, inf]": ('generator = "paper_default"', 'generator = "paper_default"\nx_range_nm = [0, inf]',
                              r"metocean.x_range_nm: expected two numbers \[a, b\], got \[0, inf\]"),
    "x_range_nm = [0, 1e308]": ('generator = "paper_default"', 'generator = "paper_default"\nx_range_nm = [0, 1e308]',
                                r"'metocean\.x_range_nm\[1\]' must lie within \+-10800 nm \(half the Earth's "
                                r"circumference\), got 1e\+308"),
    "resolution_nm = 1e-4": ('generator = "paper_default"', 'generator = "paper_default"\nresolution_nm = 1e-4',
                             r"metocean: resolution_nm gives 1e\+06 grid nodes along an axis"),
    "resolution_nm = 0.02": ('generator = "paper_default"', 'generator = "paper_default"\nresolution_nm = 0.02',
                             r"metocean: resolution_nm gives 5e\+03 grid nodes along an axis"),
    "moving storm of 1e9 hours": ('generator = "paper_default"', 'generator = "moving_storm"\nduration_h = 1e9',
                                  r"metocean: duration_h / time_step_h gives 1e\+09 time steps, more than the limit"),
    "moving storm too fine in time": ('generator = "paper_default"',
                                      'generator = "moving_storm"\ntime_step_h = 0.025\nresolution_nm = 0.1',
                                      r"metocean: the met-ocean grid would hold 1001 x 1001 x 961 time steps"),
    "FMU parameter below its declared minimum": ("u0 = 9.26", "u0 = 9.26\nm11 = -1.0",
                                                 r"participants.ship.parameters.m11: -1.0 is outside the range "
                                                 r"\[0, inf\] that KCS.fmu declares for 'm11'"),
    "FMU Real parameter given a boolean": ("u0 = 9.26", "u0 = true",
                                           r"participants.ship.parameters.u0: 'u0' is a Real parameter of KCS.fmu, "
                                           r"got True"),
}


@pytest.mark.parametrize("case", list(BUILD_CASES))
def test_building_refuses_with_one_line(write_scenario, capsys, case):
    old, new, message = BUILD_CASES[case]
    _refused(write_scenario, capsys, _edit(WEATHER, old, new), message, build=True)


def test_the_shipped_grids_are_within_the_limits():
    """The limits leave every shipped scenario valid (no limit was set below what is used):
    each loads, and each met-ocean table builds its grid."""
    scenarios = [path for path in sorted((REPO / "scenarios").rglob("*.toml")) if "[simulation]" in path.read_text()]
    # a glob that finds nothing (a moved folder) must not pass for a check
    assert len(scenarios) >= 25, scenarios
    assert {"exp2_rhnc.toml", "exp2_routing.toml", "moving_storm_demo.toml", "exp4_full.toml"} <= {
        path.name for path in scenarios}
    with_weather = 0
    for path in scenarios:
        scenario = load_scenario(path)
        if scenario.metocean is not None:
            field = build_scenario_table("metocean", scenario.metocean, scenario.directory, f"{path}: metocean")
            assert field.extent[1] > field.extent[0] and field.extent[3] > field.extent[2]
            with_weather += 1
    assert with_weather >= 10


@pytest.mark.parametrize("file, edit, grid", [
    ("exp2_routing.toml", ("resolution_nm = 1.0 ", "resolution_nm = 0.001 "), "the route search's"),
    ("exp2_rhnc.toml", ('method = "paper"', 'method = "paper"\nresolution_nm = 0.001'), "the planning"),
])
def test_a_planning_grid_finer_than_the_limit_is_refused_before_it_is_built(write_scenario, file, edit, grid):
    path = write_scenario(_edit((REPO / "scenarios" / file).read_text(), *edit), file)
    with pytest.raises(ScenarioError, match=rf"participants.nav.options: {grid} resolution_nm gives "
                                            r"1e\+05 grid nodes along an axis, more than the limit of 2001"):
        CoSimulation(load_scenario(path)).close()


def test_an_nmpc_horizon_beyond_the_limit_is_refused(write_scenario):
    text = (REPO / "scenarios" / "exp3b_head_on.toml").read_text()
    text = _edit(text, "horizon_steps = 15\nown_radius_nm", "horizon_steps = 1000000000\nown_radius_nm")
    path = write_scenario(text, "e.toml")
    with pytest.raises(ScenarioError, match=r"option 'horizon_steps' must be an integer from 1 to 400, "
                                            r"got 1000000000"):
        CoSimulation(load_scenario(path)).close()


def test_an_infinite_nmpc_weight_is_refused(write_scenario):
    text = (REPO / "scenarios" / "exp3b_head_on.toml").read_text()
    path = write_scenario(_edit(text, "et_default = 1.0", "et_default = 1.0\nweights = { r = [1.0, inf] }"), "w.toml")
    with pytest.raises(ScenarioError, match=r"participants.ctrl.weights: 'r' must be a list of 2 finite numbers >= 0"):
        CoSimulation(load_scenario(path)).close()


def test_an_infinite_navigation_goal_is_refused(write_scenario):
    text = (REPO / "scenarios" / "exp2_rhnc.toml").read_text()
    path = write_scenario(text.replace("goal_nm = [100.0, 100.0]", "goal_nm = [inf, 100.0]", 1), "g.toml")
    with pytest.raises(ScenarioError, match=r"participants.nav.options.goal_nm: expected \[north, east\] in nm "
                                            r"\(finite numbers\), got \[inf, 100.0\]"):
        CoSimulation(load_scenario(path)).close()


# -- code that comes with a scenario ---------------------------------------------------------------
LOCAL_CODE = '''
from pathlib import Path
Path(__file__).with_name("imported.marker").write_text("the module ran")
from orchestrator.scripted import ScriptedTau as Helm
'''


def test_validate_imports_no_code_beside_the_scenario_unless_trusted(tmp_path, capsys, monkeypatch):
    (tmp_path / "local_helm_module.py").write_text(LOCAL_CODE)
    path = tmp_path / "s.toml"
    path.write_text(_edit(BASE, 'type = "scripted_tau"', 'type = "python"\nclass = "local_helm_module:Helm"'))
    monkeypatch.chdir(tmp_path)  # as a user validating a downloaded folder from inside it
    monkeypatch.syspath_prepend(str(tmp_path))
    marker = tmp_path / "imported.marker"

    report = check_scenario(path)
    assert report.ok and not marker.exists()
    assert len(report.notes) == 1 and "participants.helm: class 'local_helm_module:Helm' not imported" in \
        report.notes[0] and "--trust-code" in report.notes[0]
    assert main(["validate", str(path)]) == 0
    out = capsys.readouterr().out
    assert out.startswith(f"ok: {path}") and "note:" in out and "--trust-code" in out and not marker.exists()

    assert main(["validate", "--trust-code", str(path)]) == 0
    assert marker.read_text() == "the module ran" and "note:" not in capsys.readouterr().out


def test_an_installed_participant_class_is_still_checked(write_scenario):
    path = write_scenario(_edit(BASE, 'type = "scripted_tau"',
                                'type = "python"\nclass = "orchestrator.scripted:ScriptedTau"').replace(
        "tau_u_N = 7.7e5", "tau_u_N = 7.7e5\ncolour = 1"))
    report = check_scenario(path)
    assert not report.notes and len(report.problems) == 1
    assert "unknown key 'participants.helm.options.colour'" in report.problems[0]


def test_the_step_limit_is_checked_before_the_steps_are_counted(write_scenario):
    """1e300 steps would pass a check made after counting; the limit is checked on the ratio."""
    path = write_scenario(_edit(BASE, "dt_s = 5.0", "dt_s = 1e-6\nstart_s = -1e10").replace(
        "stop_s = 60.0", "stop_s = 1e10"))
    with pytest.raises(ScenarioError, match=r"gives 2e\+16 macro steps"):
        load_scenario(path)
    assert math.isfinite(2e16)


def test_an_error_line_stays_one_line_whatever_the_path_holds(tmp_path, capsys):
    path = tmp_path / "two\nlines.toml"
    path.write_text(BASE.replace("dt_s = 5.0", "dt_s = -1.0"))
    assert main(["validate", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "two\\nlines.toml" in err and "'simulation.dt_s' must be positive" in err


def test_a_netcdf_grid_beyond_the_limit_is_refused_from_its_header(tmp_path):
    """A file declaring a 3000 x 3000 grid (its data never written, so the file is small)."""
    netCDF4 = pytest.importorskip("netCDF4")
    from rhnc.weather.metocean_sources import from_scenario_table

    path = tmp_path / "huge.nc"
    with netCDF4.Dataset(path, "w") as ds:
        ds.createDimension("latitude", 3000)
        ds.createDimension("longitude", 3000)
        ds.createVariable("latitude", "f8", ("latitude",))
        ds.createVariable("longitude", "f8", ("longitude",))
        ds.createVariable("u10", "f4", ("latitude", "longitude"), chunksizes=(100, 100))
    assert path.stat().st_size < 1_000_000
    with pytest.raises(ScenarioError, match=r"s.toml: metocean: the met-ocean grid would hold 3000 x 3000 x 1 "
                                            r"time steps = 9000000 nodes, more than the limit of 4000000"):
        from_scenario_table({"file": str(path)}, tmp_path, "s.toml: metocean")


def test_a_file_name_that_cannot_name_the_results_folder_needs_simulation_name(tmp_path):
    path = tmp_path / "..toml"  # its stem is ".": the results folder itself
    path.write_text(BASE.replace('name = "trial"\n', ""))
    with pytest.raises(ScenarioError, match=r"'simulation.name' is not given and the file name cannot name a results "
                                            r"folder: it must not start with '.'"):
        load_scenario(path)
    path.write_text(BASE)
    assert load_scenario(path).simulation.name == "trial"


@pytest.mark.parametrize("text, message", [
    ("[" + ".".join(["a"] * 100_000) + "]\n", r"line 1: the key 'a\.a\.a.*' has more than the limit of 24 dotted parts"),
    (BASE + "x." * 200_000 + "y = 1\n", r"line \d+: the key 'x\.x\.x.*' has more than the limit of 24 dotted parts"),
    (BASE + '[participants."a". b ."c".' + ".".join(["d"] * 22) + "]\n", r"line 16: the key 'participants\.\"a\"\. b \.\"c\"\.d\.d.*' has more"),
    (BASE + "".join(f"[t{i}]\n" for i in range(25_000)),
     r"holds 250\d\d keys, values and tables \(counted by '=', ',', '\[', '\{'\), more than the limit of 20000"),
], ids=["deep header", "deep dotted key", "quoted parts", "too many tables"])
def test_text_the_parser_would_take_long_over_is_refused_before_it_is_parsed(write_scenario, capsys, monkeypatch,
                                                                                 text, message):
    """Python's TOML parser is quadratic in the parts of one dotted key (a 200 kB header took
    17-20 s to refuse): the pre-scan refuses it without calling the parser."""
    import tomllib

    def parser_called(*args, **kwargs):
        raise AssertionError("the parser was called")

    monkeypatch.setattr(tomllib, "loads", parser_called)
    _refused(write_scenario, capsys, text, message)


def test_keys_of_the_largest_depth_still_reach_the_parser(write_scenario):
    text = BASE + "[participants.helm.options.deep." + ".".join(["d"] * 20) + "]\n"
    with pytest.raises(ScenarioError, match="unknown option 'deep'|unknown key 'participants.helm.options.deep'"):
        CoSimulation(load_scenario(write_scenario(text))).close()


def test_an_integer_of_thousands_of_digits_is_one_line(write_scenario, capsys):
    _refused(write_scenario, capsys, _edit(BASE, "u0 = 9.26", "u0 = " + "9" * 5000),
             r"not valid TOML: Exceeds the limit \(4300 digits\) for integer string conversion")


@pytest.mark.parametrize("edit, message", [
    (lambda t: t.replace("tau_u_N = 7.7e5", "tau_u_N = 7.7e5\nstart_nm = [0, -1e308]"),
     r"'participants\.helm\.options\.start_nm\[1\]' must lie within \+-10800 nm \(half the Earth's circumference\), "
     r"got -1e\+308"),
    (lambda t: t + "\n[participants.helm.options.route]\nwaypoints_nm = [[0.0, 0.0], [20000.0, 5.0]]\n",
     r"'participants\.helm\.options\.route\.waypoints_nm\[1\]\[0\]' must lie within \+-10800 nm"),
    (lambda t: t + "\n[metocean]\ngenerator = \"paper_default\"\nx_range_nm = [0.0, 1e9]\n",
     r"'metocean\.x_range_nm\[1\]' must lie within \+-10800 nm"),
], ids=["start", "nested waypoint", "weather map"])
def test_absurd_distances_in_nautical_miles_are_refused(write_scenario, capsys, edit, message):
    """Every key that names its unit nm is bounded, whichever participant reads it."""
    _refused(write_scenario, capsys, edit(BASE), message)


def test_a_batch_start_beyond_the_bound_is_refused():
    from orchestrator.batch_model import OwnShipTable
    from orchestrator.toml_input import checked

    with pytest.raises(ScenarioError, match=r"'own_ship\.start_nm' must lie within \+-10800 nm"):
        checked(OwnShipTable, {"start_nm": [0.0, -1e308], "course_deg": 45.0, "speed_kn": 16.0}, "b.toml",
                ("own_ship",))


@pytest.mark.parametrize("command", [["validate"], ["validate", "--trust-code"], ["run", "--no-progress"]])
def test_a_module_beside_the_scenario_started_from_elsewhere_is_refused_alike(tmp_path, capsys, monkeypatch,
                                                                              command):
    """The run cannot import it (the scenario's folder is not on the import path): validate must
    not say ok, with or without --trust-code, and all three give the same line."""
    folder = tmp_path / "downloaded"
    folder.mkdir()
    (folder / "local_helm_elsewhere.py").write_text(LOCAL_CODE)
    path = folder / "s.toml"
    path.write_text(_edit(BASE, 'type = "scripted_tau"', 'type = "python"\nclass = "local_helm_elsewhere:Helm"'))
    monkeypatch.chdir(tmp_path)
    results = ["--results", str(tmp_path / "results")] if command[0] == "run" else []
    assert main([*command, *results, str(path)]) == 2
    assert capsys.readouterr().err.strip().splitlines() == [
        f"error: {path}: participants.helm.class: cannot import module 'local_helm_elsewhere': No module named "
        f"'local_helm_elsewhere' (it lies in the scenario's folder {folder}, which is not on the import path: start "
        "the command from that folder, or install the module)"]
    assert not (folder / "imported.marker").exists() and not (tmp_path / "results").exists()


@pytest.mark.parametrize("value, message", [
    ("0", r"option 'iteration_budget' must be an integer from 1 to 100000, got 0"),
    ("500", r"participants.ctrl: iteration_budget must be from 2 to max_iterations \(200\), got 500"),
])
def test_an_nmpc_iteration_budget_out_of_range_is_refused(write_scenario, value, message):
    text = (REPO / "scenarios" / "exp3b_head_on.toml").read_text()
    path = write_scenario(_edit(text, "horizon_steps = 15\nown_radius_nm",
                                f"horizon_steps = 15\niteration_budget = {value}\nown_radius_nm"), "b.toml")
    with pytest.raises(ScenarioError, match=message):
        CoSimulation(load_scenario(path)).close()
