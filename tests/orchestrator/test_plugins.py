"""Entry points: how registrations are found, and the errors when they clash or are missing."""

from __future__ import annotations

import sys

import pytest

from orchestrator import plugins
from orchestrator.errors import ScenarioError
from orchestrator.master import CoSimulation
from orchestrator.scenario import load_scenario


@pytest.fixture
def fresh_registrations():
    """Registrations read again from the current sys.path (and again after the test)."""
    plugins.registrations.cache_clear()
    yield
    plugins.registrations.cache_clear()


def _distribution(site, name: str, group: str, entries: dict[str, str]) -> None:
    info = site / f"{name}-1.0.dist-info"
    info.mkdir(parents=True)
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {name}\nVersion: 1.0\n")
    (info / "entry_points.txt").write_text(f"[{group}]\n" + "".join(f"{k} = {v}\n" for k, v in entries.items()))


def test_the_projects_own_registrations_are_found(fresh_registrations):
    participants = plugins.registrations("participants")
    assert participants["scripted_tau"].target == "orchestrator.scripted:ScriptedTau"
    assert participants["navigation"].distribution == plugins.DISTRIBUTION
    assert plugins.load("analyses", "turning_circle").__name__ == "turning_circle_analysis"


def test_a_name_registered_by_two_packages_is_refused(tmp_path, monkeypatch, fresh_registrations):
    for name in ("first-plugin", "second-plugin"):
        _distribution(tmp_path, name, "rhnc_cosim.figures", {"wake": f"{name.replace('-', '_')}:wake_figure"})
    monkeypatch.setattr(sys, "path", [str(tmp_path), *sys.path])
    with pytest.raises(ScenarioError, match=r"entry point 'wake' of group rhnc_cosim.figures is registered twice: "
                                            r"by first-plugin \(first_plugin:wake_figure\) and by second-plugin"):
        plugins.registrations("figures")


def test_a_domain_table_nobody_handles_is_refused(tmp_path, monkeypatch):
    scenario = tmp_path / "s.toml"
    scenario.write_text('[simulation]\nstop_s = 10.0\ndt_s = 5.0\n[metocean]\ngenerator = "paper_default"\n'
                        '[participants.helm]\ntype = "scripted_tau"\n')
    real = plugins.registrations

    def without_tables(kind):
        return {} if kind == "scenario_tables" else real(kind)

    monkeypatch.setattr(plugins, "registrations", without_tables)
    with pytest.raises(ScenarioError, match=r"s.toml: metocean: no installed package handles a \[metocean\] table "
                                            r"\(entry-point group rhnc_cosim.scenario_tables\)"):
        CoSimulation(load_scenario(scenario), work_dir=tmp_path)


def test_a_batch_helper_nobody_provides_is_refused(monkeypatch):
    monkeypatch.setattr(plugins, "registrations", lambda kind: {})
    helper = plugins.LazyModule("batch", "encounters")
    with pytest.raises(ScenarioError, match=r"no installed package provides 'encounters' "
                                            r"\(entry-point group rhnc_cosim.batch\)"):
        helper.place_target  # noqa: B018 (the attribute lookup is what is tested)
