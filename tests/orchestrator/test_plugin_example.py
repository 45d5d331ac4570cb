"""A user's package adds a participant type and an analysis through entry points alone.

The example package ``examples/sine_helm_plugin`` is installed into a temporary folder (not
into the environment) as an installer lays it out: the package and a ``.dist-info`` folder
with its ``METADATA`` and the ``entry_points.txt`` written from its ``pyproject.toml`` (what
``importlib.metadata`` reads; no build backend or network needed).  Then a scenario using its ``sine_helm`` type and ``heading_swing``
analysis runs through ``python -m orchestrator run``; without the package on the path the
same scenario is refused as naming an unknown type.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
EXAMPLE = REPO / "examples" / "sine_helm_plugin"


def install_without_building(project: Path, site: Path) -> Path:
    """Lay out ``project`` (a pyproject.toml package) in ``site`` as ``pip install --target`` does."""
    with (project / "pyproject.toml").open("rb") as handle:
        meta = tomllib.load(handle)
    name, version = meta["project"]["name"], meta["project"]["version"]
    for package in meta["tool"]["setuptools"]["packages"]:
        shutil.copytree(project / package, site / package)
    info = site / f"{name.replace('-', '_')}-{version}.dist-info"
    info.mkdir(parents=True)
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {name}\nVersion: {version}\n")
    groups = meta["project"].get("entry-points", {})
    (info / "entry_points.txt").write_text("".join(
        f"[{group}]\n" + "".join(f"{key} = {value}\n" for key, value in entries.items()) + "\n"
        for group, entries in groups.items()))
    return info


def _orchestrator(args, pythonpath, cwd):
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(str(p) for p in pythonpath))
    return subprocess.run([sys.executable, "-m", "orchestrator", *args], capture_output=True, text=True,
                          env=env, cwd=cwd, timeout=600)


@pytest.mark.slow
def test_installed_plugin_runs_its_participant_and_analysis(tmp_path):
    site = tmp_path / "site"
    install_without_building(EXAMPLE, site)
    scenario = EXAMPLE / "scenario.toml"

    refused = _orchestrator(["run", str(scenario), "--results", str(tmp_path / "none"), "--no-progress"],
                            [REPO], tmp_path)
    assert refused.returncode == 2
    assert "'outputs.analyses': unknown name 'heading_swing'" in refused.stderr  # checked before the participants
    assert not (tmp_path / "none").exists()

    done = _orchestrator(["run", str(scenario), "--results", str(tmp_path / "results"), "--no-progress"],
                         [REPO, site], tmp_path)
    assert done.returncode == 0, done.stderr
    summary = json.loads(next((tmp_path / "results").rglob("summary.json")).read_text())
    swing = summary["analyses"]["heading_swing"]
    assert swing["samples"] == (600 - 60) // 5 + 1
    assert swing["heading_swing_deg"] > 1.0  # the sine yaw moment turned the ship both ways


@pytest.mark.parametrize("left_by_pip", ["build/lib/sine_helm/helm.py", "build/bdist.linux-x86_64/x",
                                         "sine_helm_plugin.egg-info/PKG-INFO"])
def test_installing_the_example_leaves_nothing_untracked_in_the_checkout(left_by_pip):
    # `python -m pip install examples/sine_helm_plugin` (the readme's command) builds in the
    # example's folder: what setuptools leaves there is ignored, not shown as untracked
    path = (EXAMPLE / left_by_pip).relative_to(REPO)
    ignored = subprocess.run(["git", "check-ignore", "-q", "--no-index", str(path)], cwd=REPO)
    assert ignored.returncode == 0, f"{path} would be left untracked"
