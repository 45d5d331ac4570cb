"""The ship models of ``models/`` as the model library the FMU builder compiles.

Registered in the entry-point group ``rhnc_cosim.model_libraries``
(:mod:`orchestrator.fmu_build`): the folder of C models, the ship particulars file whose
content is part of every FMU's source hash, and the check that a ``[default]`` parameter
set gives the particulars (length, beam, windage areas, ...) the values of that file.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

from rhnc.ship.ships import check_parameter_set, load_ship, ship_file


#: The ship whose particulars the built-in plant models carry.
SHIP = "KCS"


def _packaged_or_source(name: str) -> Path:
    """``rhnc/cosim/<name>`` of an installed package, else ``<name>/`` of the source checkout."""
    packaged = Path(__file__).resolve().parents[1] / "cosim" / name
    return packaged if packaged.is_dir() else Path(__file__).resolve().parents[2] / name


#: The C models: package data once installed (pyproject.toml maps ``models/`` there).
MODELS_DIR = _packaged_or_source("models")


class ShipModelLibrary:
    """The built-in models: the 3-DOF and MMG KCS, the S175 test ship, the met-ocean field."""

    models_dir = MODELS_DIR
    #: Every model is built with the KCS set's defaults (``kcs_parameter_defaults.h``).
    shared_parameter_set = "KCS"

    @staticmethod
    def extra_inputs(name: str) -> list[Path]:
        """The ship particulars file: a change of it rebuilds every model."""
        return [ship_file(SHIP)]

    @staticmethod
    def check_parameter_set(values: Mapping[str, float], where: str) -> None:
        """Refuse a set whose particulars differ from ``ships/KCS.toml`` (ScenarioError)."""
        check_parameter_set(values, load_ship(SHIP), where)


SHIP_MODELS = ShipModelLibrary()
