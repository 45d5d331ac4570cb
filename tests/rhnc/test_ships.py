"""Ship particulars declared once: the file's checks, and every plant parameter set agrees with it."""

from __future__ import annotations

import tomllib

import pytest

from orchestrator.errors import ScenarioError
from orchestrator.fmu_build import MODELS_DIR
from rhnc.ship.ships import PLANT_PARAMETERS, SHIPS_DIR, check_parameter_set, load_actuators, load_ship

GOOD = (SHIPS_DIR / "KCS.toml").read_text()


@pytest.mark.parametrize("model", ["KCS", "KCSMMG"])
def test_every_plant_parameter_set_carries_the_ships_particulars(model):
    ship = load_ship("KCS")
    with open(MODELS_DIR / model / "parameter_sets.toml", "rb") as handle:
        default = tomllib.load(handle)["default"]
    assert {"lpp", "beam", "wind_area_frontal", "wind_area_lateral"} <= set(default)
    check_parameter_set(default, ship, f"{model} [default]")  # raises on a difference
    for parameter in set(PLANT_PARAMETERS) & set(default):
        assert default[parameter] == getattr(ship, PLANT_PARAMETERS[parameter])


def test_a_different_particular_is_refused_naming_the_key_and_the_file():
    with pytest.raises(ScenarioError, match=r"set X: beam = 40 differs from beam_m = 32.2 in .*ships/KCS.toml"):
        check_parameter_set({"beam": 40.0, "lpp": 230.0}, load_ship("KCS"), "set X")


@pytest.mark.parametrize("edit, message", [
    (lambda text: text.replace("beam_m = 32.2", "beam_m = -32.2"), r"'beam_m' must be a positive number"),
    (lambda text: text.replace("beam_m = 32.2", "beam_m = \"wide\""), r"'beam_m' must be a positive number"),
    (lambda text: text.replace("beam_m = 32.2", "breadth_m = 32.2"), r"unknown key 'breadth_m'"),
    (lambda text: text.replace("deadweight_t = 40000.0", ""), r"missing key 'deadweight_t'"),
    (lambda text: text.replace('name = "KCS"', 'name = "KVLCC2"'), r"name = 'KVLCC2' does not match the file name"),
])
def test_bad_particulars_files_give_one_line_errors(tmp_path, edit, message):
    (tmp_path / "KCS.toml").write_text(edit(GOOD))
    with pytest.raises(ScenarioError, match=rf"KCS.toml: {message}"):
        load_ship("KCS", tmp_path)


def test_an_unknown_ship_names_the_known_ones(tmp_path):
    (tmp_path / "KCS.toml").write_text(GOOD)
    with pytest.raises(ScenarioError, match=r"no particulars for ship 'Emma' \(known: KCS\)"):
        load_ship("Emma", tmp_path)


@pytest.mark.parametrize("read", [lambda folder: load_ship("KCS", folder), lambda folder: load_actuators("KCS", folder)])
def test_a_ship_file_that_is_no_toml_is_named_in_one_line(tmp_path, read):
    (tmp_path / "KCS.toml").write_text("beam_m = = 32.2\n")
    with pytest.raises(ScenarioError, match=r"KCS.toml: Invalid value \(at line 1, column 10\)$"):
        read(tmp_path)


def test_the_particulars_and_the_actuators_read_from_one_file_in_either_order():
    # both readers share one parsed copy of the file: taking the particulars must leave the
    # [actuators] table for the allocation (a run's voyage analysis reads the particulars first)
    from rhnc.ship.ships import ship_file

    assert load_ship("KCS").lpp_m > 0
    path, table = load_actuators("KCS")
    assert path == ship_file("KCS") and table["rudder_area_m2"] > 0
    assert load_ship("KCS") == load_ship("KCS")
