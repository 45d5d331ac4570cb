"""The compare command: runs, the table beside published figures, and its input errors."""

import textwrap

import pandas as pd
import pytest

from orchestrator.cli import main
from orchestrator.compare import comparison_table, load_comparison
from orchestrator.errors import ScenarioError

SCENARIO = """
connections = ["helm.tau_u -> ship.tau_u", "helm.tau_r -> ship.tau_r"]
[simulation]
stop_s = 600.0
dt_s = 10.0
[participants.helm]
type = "scripted_tau"
[participants.helm.options]
tau_u_N = {tau}
[participants.ship]
fmu = "KCS"
[participants.ship.parameters]
u0 = 9.0
[outputs]
analyses = ["voyage"]
figures = []
"""

COMPARISON = """
name = "speeds"
analysis = "voyage"
metrics = ["distance_nm", "cost_usd"]
baseline = "slow"
[[runs]]
label = "slow"
scenario = "slow.toml"
paper = {{ distance_nm = 1.0 }}
[[runs]]
label = "fast"
scenario = "fast.toml"
paper = {{ distance_nm = 2.0 }}
{extra}
"""


def write(tmp_path, extra=""):
    (tmp_path / "slow.toml").write_text(textwrap.dedent(SCENARIO.format(tau=6.0e5)))
    (tmp_path / "fast.toml").write_text(textwrap.dedent(SCENARIO.format(tau=9.0e5)))
    path = tmp_path / "compare.toml"
    path.write_text(textwrap.dedent(COMPARISON.format(extra=extra)))
    return path


def test_compare_runs_both_and_tabulates_changes(tmp_path, capsys):
    assert main(["compare", str(write(tmp_path)), "--results", str(tmp_path / "results"), "--no-progress"]) == 0
    folder = next((tmp_path / "results" / "speeds").iterdir())
    table = pd.read_csv(folder / "table.csv").set_index("metric")
    slow, fast = table.loc["distance_nm", "slow (ours)"], table.loc["distance_nm", "fast (ours)"]
    assert fast > slow > 0
    assert table.loc["distance_nm", "fast vs slow (% ours)"] == pytest.approx(100 * (fast - slow) / slow)
    assert table.loc["distance_nm", "fast vs slow (% paper)"] == pytest.approx(100.0)
    assert (folder / "tracks.png").is_file() and (folder / "table.md").is_file()
    assert "| distance_nm |" in capsys.readouterr().out


def test_table_leaves_missing_figures_empty():
    spec = {"analysis": "voyage", "metrics": ["cost_usd"], "runs": [{"label": "a"}]}
    table = comparison_table(spec, {"a": {"analyses": {}}})
    assert table.loc[0, "a (ours)"] is None


@pytest.mark.parametrize("extra, message", [
    ('colour = "red"', r"compare.toml: unknown key 'runs\[1\].colour' "
                       r"\(valid: label, scenario, set, paper, figures\)"),
    ('[[runs]]\nlabel = "x"\nscenario = "none.toml"', r"runs\[2\].scenario: scenario file not found"),
    ('[[runs]]\nlabel = "x"\nscenario = "slow.toml"\npaper = { speed = 1 }', r"runs\[2\].paper: 'speed' is not one of"),
    ('[[runs]]\nlabel = "x"\nscenario = "slow.toml"\nset = 3',
     r"compare.toml: 'runs\[2\].set' expected a table of dotted-key overrides"),
    ('[[runs]]\nlabel = "x"\nscenario = "slow.toml"\nfigures = 3', r"compare.toml: 'runs\[2\].figures' must be a table"),
])
def test_comparison_file_errors(tmp_path, extra, message):
    with pytest.raises(ScenarioError, match=message):
        load_comparison(write(tmp_path, extra))


def test_unknown_baseline_and_cli_exit_code(tmp_path, capsys):
    path = write(tmp_path)
    path.write_text(path.read_text().replace('baseline = "slow"', 'baseline = "medium"'))
    assert main(["compare", str(path)]) == 2
    assert "baseline 'medium' is not a run label (slow, fast)" in capsys.readouterr().err


def test_sweep_runs_the_comparison_once_per_value(tmp_path):
    from orchestrator.compare import run_comparison

    extra = '[sweep]\nkey = "participants.helm.options.tau_u_N"\nvalues = [5.0e5, 9.0e5]'
    path = write(tmp_path)
    path.write_text(path.read_text().replace('baseline = "slow"', 'baseline = "slow"\n' + extra))
    folder = run_comparison(path, tmp_path / "results", progress=False)
    members = sorted(p.name for p in (folder / "members").iterdir())
    assert members == ["participants.helm.options.tau_u_N=500000.0", "participants.helm.options.tau_u_N=900000.0"]
    distances = [pd.read_csv(folder / "members" / m / "table.csv").set_index("metric").loc["distance_nm", "slow (ours)"]
                 for m in members]
    assert distances[1] > distances[0]   # the swept surge force reached the runs
    summary = (folder / "summary.json").read_text()
    assert '"sweep_key": "participants.helm.options.tau_u_N"' in summary


@pytest.mark.parametrize("extra, message", [
    ('[set]\n"a..b" = 1', r"compare.toml: 'set' key 'a..b' is not a dotted key path"),
    ('[sweep]\nkey = "metocean.member"\nrange = [0, 100000000]', r"'sweep.range' spans 100000001 members, more "
                                                                   r"than the limit of 10000"),
    ('[sweep]\nkey = "simulation.dt_s"', r"give exactly one of 'sweep.values' or 'sweep.range'"),
    ('[sweep]\nkey = "simulation.dt_s"\nvalues = [1.0]\nstep = 2', r"unknown key 'sweep.step'"),
])
def test_set_and_sweep_errors(tmp_path, extra, message):
    path = write(tmp_path)
    path.write_text(path.read_text().replace('baseline = "slow"', 'baseline = "slow"\n' + extra))
    with pytest.raises(ScenarioError, match=message):
        load_comparison(path)


CRASHING_RUN = """
[[runs]]
label = "crashing"
scenario = "crash.toml"
"""


def test_a_failed_run_is_in_the_table_the_summary_and_stderr_and_exits_3(tmp_path, capsys):
    import json

    path = write(tmp_path, CRASHING_RUN)
    crash = SCENARIO.replace("[participants.ship]", '[participants.bug]\ntype = "python"\n'
                             'class = "sample_participants:Crash"\n[participants.bug.options]\nat_s = 100.0\n'
                             "[participants.ship]").format(tau=6.0e5)
    (tmp_path / "crash.toml").write_text(textwrap.dedent(crash))
    assert main(["compare", str(path), "--results", str(tmp_path / "results"), "--no-progress"]) == 3
    captured = capsys.readouterr()
    assert "error: 1 run(s) of the comparison failed: crashing (failed: bug: RuntimeError: boom)" in captured.err
    assert captured.out.startswith("failed: results in ")
    folder = next((tmp_path / "results" / "speeds").iterdir())
    summary = json.loads((folder / "summary.json").read_text())
    assert summary["status"] == "failed"
    assert summary["failed_runs"] == {"crashing": "failed: bug: RuntimeError: boom"}
    assert "## Failed runs (1)" in (folder / "table.md").read_text()
    assert "| crashing | failed: bug: RuntimeError: boom |" in (folder / "table.md").read_text()


def test_an_extensions_failed_runs_join_the_comparisons(tmp_path, monkeypatch):
    """A run an extension made itself (a baseline's trial) counts as one of the comparison's."""
    import json

    from orchestrator import compare

    class Extension:
        def evaluate(self, reports, runner, overrides, out_dir):
            return compare.Section(markdown="## extension", failed_runs={"a trial": "failed: left the map"})

    monkeypatch.setattr(compare, "load_extensions", lambda spec, path: {"extension": Extension()})
    monkeypatch.setattr(compare, "_run_overrides", lambda run, extensions, scenario, overrides, where: {})
    folder = compare.run_comparison(write(tmp_path), tmp_path / "results", progress=False)
    summary = json.loads((folder / "summary.json").read_text())
    assert summary["status"] == "failed" and summary["failed_runs"] == {"a trial": "failed: left the map"}
    assert compare.failed_runs_of(folder) == {"a trial": "failed: left the map"}


def test_file_names_in_overrides_are_resolved_against_the_comparison_file(tmp_path):
    """A NetCDF file named in [set] lies beside the comparison, whatever folder the scenarios are in."""
    (tmp_path / "storm.nc").write_bytes(b"")
    (tmp_path / "scenarios").mkdir()
    path = write(tmp_path / "scenarios")
    comparison = tmp_path / "compare.toml"
    text = path.read_text().replace('scenario = "', 'scenario = "scenarios/')
    comparison.write_text(text + '[set]\n"metocean" = { file = "storm.nc" }\n"participants.helm.options.plan" = "storm.nc"\n'
                                 '"participants.helm.options.method" = "routing"\n')
    spec = load_comparison(comparison)
    assert spec["set"]["metocean"] == {"file": str((tmp_path / "storm.nc").resolve())}
    assert spec["set"]["participants.helm.options.plan"] == str((tmp_path / "storm.nc").resolve())
    assert spec["set"]["participants.helm.options.method"] == "routing"   # not a file name: left as it is
    comparison.write_text(comparison.read_text().replace('file = "storm.nc"', 'file = "gale.nc"'))
    with pytest.raises(ScenarioError, match=r"compare.toml: set.metocean.file: file not found relative to the "
                                            r"comparison file: .*gale.nc"):
        load_comparison(comparison)
