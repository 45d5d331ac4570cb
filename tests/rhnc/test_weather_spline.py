"""The paper weather's spline grid, kept once computed: the very doubles FITPACK gives, read
back without importing scipy.interpolate; a damaged or foreign file is computed again."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.interpolate import RectBivariateSpline

from rhnc.weather import weather_spline
from rhnc.weather.weather_generators import DEFAULT_WIND_CONTROL_POINTS, paper_default

REPO = Path(__file__).resolve().parents[2]


def _lattice(control=DEFAULT_WIND_CONTROL_POINTS, nodes=101):
    control = np.asarray(control, dtype=float)
    x = np.linspace(0.0, 185200.0, nodes)
    y = np.linspace(0.0, 185200.0, nodes)
    return (np.linspace(x[0], x[-1], control.shape[0]), np.linspace(y[0], y[-1], control.shape[1]), control, x, y)


def _fitpack(cx, cy, control, x, y):
    return RectBivariateSpline(cx, cy, control, kx=3, ky=3)(x, y)


@pytest.fixture
def kept(tmp_path, monkeypatch):
    folder = tmp_path / "weather"
    monkeypatch.setenv(weather_spline.CACHE_ENV, str(folder))
    return folder


def test_the_grid_computed_and_the_grid_read_back_are_fitpacks_bit_for_bit(kept):
    lattice = _lattice()
    computed = weather_spline.bicubic_grid(*lattice)
    assert len(list(kept.glob("*.npy"))) == 1
    read = weather_spline.bicubic_grid(*lattice)
    assert np.array_equal(computed, _fitpack(*lattice)) and np.array_equal(read, computed)
    assert read.dtype == np.float64 and read.shape == (101, 101)


def test_each_lattice_and_grid_has_a_file_of_its_own(kept):
    first = weather_spline.bicubic_grid(*_lattice())
    other = np.asarray(DEFAULT_WIND_CONTROL_POINTS, dtype=float)
    other[2, 2] += 1e-9  # the slightest change of one control value
    changed = weather_spline.bicubic_grid(*_lattice(other))
    coarse = weather_spline.bicubic_grid(*_lattice(nodes=51))
    assert len(list(kept.glob("*.npy"))) == 3
    assert np.array_equal(changed, _fitpack(*_lattice(other))) and not np.array_equal(changed, first)
    assert np.array_equal(coarse, _fitpack(*_lattice(nodes=51)))


@pytest.mark.parametrize("damage", ["truncated", "another shape", "integers"])
def test_a_damaged_or_foreign_file_is_computed_again_and_rewritten(kept, damage):
    lattice = _lattice()
    weather_spline.bicubic_grid(*lattice)
    (path,) = kept.glob("*.npy")
    if damage == "truncated":
        path.write_bytes(path.read_bytes()[:200])
    else:
        np.save(path, np.zeros((3, 3)) if damage == "another shape" else np.zeros((101, 101), dtype=np.int64))
    assert np.array_equal(weather_spline.bicubic_grid(*lattice), _fitpack(*lattice))
    assert np.array_equal(np.load(path), _fitpack(*lattice))


def test_off_keeps_nothing(tmp_path, monkeypatch):
    monkeypatch.setenv(weather_spline.CACHE_ENV, "off")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))  # where it would go by default
    monkeypatch.setenv("HOME", str(tmp_path))
    assert weather_spline.cache_dir() is None
    assert np.array_equal(weather_spline.bicubic_grid(*_lattice()), _fitpack(*_lattice()))
    assert list(tmp_path.iterdir()) == []
    monkeypatch.delenv(weather_spline.CACHE_ENV)
    assert weather_spline.cache_dir() == tmp_path / "cache" / "rhnc-cosim" / "weather"


def test_a_run_with_a_kept_grid_never_imports_scipy_interpolate(kept):
    expected = paper_default().wind_speed
    probe = ("import sys, numpy as np\n"
             "from rhnc.weather.weather_generators import paper_default\n"
             "speed = paper_default().wind_speed\n"
             "print('scipy.interpolate' in sys.modules, speed.tobytes().hex())\n")
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, cwd=REPO, timeout=120,
                          env={**os.environ, "PYTHONPATH": str(REPO)})
    assert done.returncode == 0, done.stderr
    imported, speed = done.stdout.split()
    assert imported == "False" and bytes.fromhex(speed) == expected.tobytes()
