"""fmu_build: error messages and content-hash rebuilds."""

from __future__ import annotations

import re
import shutil
import zipfile

import pytest

from orchestrator import fmu_build
from orchestrator.errors import FmuError


@pytest.fixture
def models_copy(tmp_path):
    target = tmp_path / "models"
    shutil.copytree(fmu_build.MODELS_DIR, target,
                    ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
    return target


def test_model_names():
    assert {"KCS", "KCSVendorB", "MetOcean"} <= set(fmu_build.model_names())
    assert "common" not in fmu_build.model_names()


def test_unknown_model_lists_valid_names(tmp_path):
    with pytest.raises(FmuError, match=r"unknown model 'Titanic'; valid models: .*KCS.*MetOcean"):
        fmu_build.build_fmu("Titanic", tmp_path)


def test_fmu_carries_binary_and_sources(fmus):
    from fmpy import platform, sharedLibraryExtension

    with zipfile.ZipFile(fmus["KCS"]) as z:
        names = set(z.namelist())
        description = z.read("modelDescription.xml").decode()
    assert f"binaries/{platform}/KCS{sharedLibraryExtension}" in names
    assert {"sources/fmu_core.c", "sources/fmi2_api.c", "sources/model.c", "sources/config.h",
            "sources/kcs_dynamics.h", "sources/kcs_parameter_defaults.h"} <= names
    assert "sources/fmi3_api.c" not in names  # the other standard's API is left out
    assert "@" not in description  # every start value placeholder was filled
    # the description lists exactly the C files compiled into it
    listed = set(re.findall(r'<File name="([^"]+)"', description))
    assert listed == {"fmu_core.c", "fmi2_api.c", "model.c"}


def test_ensure_built_rebuilds_only_after_a_source_change(models_copy, tmp_path):
    out = tmp_path / "fmus"
    first = fmu_build.ensure_built("MetOcean", out, models_copy)
    stamp = first.stat().st_mtime_ns
    assert fmu_build.ensure_built("MetOcean", out, models_copy).stat().st_mtime_ns == stamp
    model_c = models_copy / "MetOcean" / "model.c"
    model_c.write_text(model_c.read_text() + "\n/* changed */\n")
    rebuilt = fmu_build.ensure_built("MetOcean", out, models_copy)
    assert rebuilt.stat().st_mtime_ns != stamp
    assert fmu_build.ensure_built("MetOcean", out, models_copy).stat().st_mtime_ns == \
        rebuilt.stat().st_mtime_ns


def test_parameter_set_change_reaches_the_start_values(models_copy, tmp_path):
    from fmpy import read_model_description

    toml = models_copy / "KCS" / "parameter_sets.toml"
    toml.write_text(toml.read_text().replace("tau_r_max = 3.3e8", "tau_r_max = 1.5e8", 1))
    fmu = fmu_build.ensure_built("KCS", tmp_path / "fmus", models_copy)
    variables = {v.name: v for v in read_model_description(str(fmu)).modelVariables}
    assert float(variables["tau_r_max"].start) == 1.5e8
    with zipfile.ZipFile(fmu) as z:
        assert "#define KCS_DEFAULT_tau_r_max (150000000.0)" in \
            z.read("sources/kcs_parameter_defaults.h").decode()


def test_compile_error_names_model_and_first_error(models_copy, tmp_path):
    model_c = models_copy / "KCS" / "model.c"
    model_c.write_text(model_c.read_text() + "\nint broken = ;\n")
    with pytest.raises(FmuError, match=r"^building model KCS failed: .*model\.c.*error") as info:
        fmu_build.build_fmu("KCS", tmp_path, models_copy)
    assert "\n" not in str(info.value)
