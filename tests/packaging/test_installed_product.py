"""The product runs from a wheel install alone: models and ships are package data, FMUs go
to the per-user cache keyed by their source hash.

A fresh virtual environment (reading the running interpreter's site-packages for the heavy
dependencies, whether that interpreter is the system's or a virtual environment's) gets
``pip install <copy of the repository>`` (a normal, non-editable install built by
pip), then ``python -m orchestrator run`` runs a copied scenario from a folder outside any
source tree.  An editable install of another checkout in the system's site-packages cannot
stand in for the installed package: its import finder comes after the path-based one, and
the test checks where ``orchestrator`` and ``rhnc`` were imported from.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import venv
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
#: What a source distribution of the project holds (no tests, results or built FMUs).
SOURCES = ("pyproject.toml", "README.md", "orchestrator", "rhnc", "models", "ships")


def running_site_directories() -> list[str]:
    """The site-packages folders of the running interpreter, in import order."""
    return [entry for entry in sys.path if Path(entry).name in ("site-packages", "dist-packages")]


def make_environment_with_running_packages(env_dir: Path) -> Path:
    """A fresh virtual environment that imports the running interpreter's packages after its own.

    ``system_site_packages=True`` would take the base interpreter's packages, which in a
    virtual environment are not the ones installed: instead a ``.pth`` file adds each site
    folder of the running interpreter (processing its ``.pth`` files too) behind the new
    environment's own site-packages.  Returns the new environment's ``python``.
    """
    venv.EnvBuilder(system_site_packages=False, with_pip=False).create(env_dir)
    python = env_dir / "bin" / "python"
    own = subprocess.run([str(python), "-c", "import sysconfig; print(sysconfig.get_path('purelib'))"],
                         capture_output=True, text=True, check=True).stdout.strip()
    lines = [f"import site; site.addsitedir({entry!r})" for entry in running_site_directories()]
    (Path(own) / "_running_interpreter_packages.pth").write_text("\n".join(lines) + "\n")
    return python


def test_environment_reads_the_running_interpreters_packages(tmp_path):
    # what the installed-product test relies on: every package the running interpreter
    # imports (casadi among them, in a virtual environment too) imports in the new one
    python = make_environment_with_running_packages(tmp_path / "venv")
    found = subprocess.run([str(python), "-c", "import casadi, fmpy, numpy; print(casadi.__file__)"],
                           capture_output=True, text=True, env={k: v for k, v in os.environ.items() if k != "PYTHONPATH"})
    assert found.returncode == 0, found.stderr
    import casadi
    assert Path(found.stdout.strip()) == Path(casadi.__file__)


@pytest.mark.slow
def test_wheel_install_runs_a_scenario_outside_the_tree(tmp_path):
    source = tmp_path / "source"
    source.mkdir()
    for name in SOURCES:
        if (REPO / name).is_dir():
            shutil.copytree(REPO / name, source / name, ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
        else:
            shutil.copy2(REPO / name, source / name)
    env_dir = tmp_path / "venv"
    python = make_environment_with_running_packages(env_dir)
    environment = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    environment["XDG_CACHE_HOME"] = str(tmp_path / "cache")
    # pip from the system (the venv has none of its own); --ignore-installed: the system's
    # editable rhnc-cosim must not satisfy the requirement
    subprocess.run([sys.executable, "-m", "pip", "--python", str(python), "install", "--quiet", "--no-deps",
                    "--ignore-installed", str(source)], check=True, env=environment, timeout=900)

    outside = tmp_path / "elsewhere"
    outside.mkdir()
    scenario = outside / "turning.toml"
    scenario.write_text((REPO / "scenarios" / "turning_circle.toml").read_text().replace(
        "stop_s = 1800.0", "stop_s = 600.0"))
    # every data file the domain reads at import resolves inside the installed package
    where = subprocess.run([str(python), "-c", "import orchestrator, rhnc, rhnc.ship.ships as s, rhnc.ship.ship_model as m, "
                            "rhnc.control.allocation as a, rhnc.ship.model_library as lib; "
                            "print(orchestrator.__file__); print(rhnc.__file__); print(s.SHIPS_DIR / 'KCS.toml'); "
                            "print(m.PARAMETER_SETS_FILE); print(a.PARAMETER_SETS_FILE); print(lib.MODELS_DIR)"],
                           capture_output=True, text=True, cwd=outside, env=environment, check=True)
    for line in where.stdout.splitlines():
        assert Path(line).is_relative_to(env_dir) and Path(line).exists(), where.stdout

    done = subprocess.run([str(python), "-m", "orchestrator", "run", "turning.toml", "--no-progress"],
                          capture_output=True, text=True, cwd=outside, env=environment, timeout=900)
    assert done.returncode == 0, done.stderr
    summary = json.loads(next((outside / "results").rglob("summary.json")).read_text())
    assert summary["analyses"]["turning_circle"]["advance_m"] > 0
    built = list((tmp_path / "cache" / "rhnc-cosim" / "fmus").glob("*/KCS.fmu"))
    assert len(built) == 1 and len(built[0].parent.name) == 16
    assert not (source / "fmus").exists()
