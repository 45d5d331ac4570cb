"""Principal particulars of a ship, declared once in ``ships/<name>.toml``.

The plant FMUs' parameter sets, the energy model (:mod:`rhnc.ship.energy`) and the analyses
(ship length of the turning-circle figures, deadweight of the CII) all read the same file,
so the ship simulated, the ship whose fuel is counted and the ship whose manoeuvres are
measured are one ship.  ``PLANT_PARAMETERS`` names the plant-FMU parameters that are
particulars: a parameter set must give them the file's value (checked when an FMU is built
and by :func:`check_parameter_set`).
"""

from __future__ import annotations

import dataclasses
import functools
import tomllib
from collections.abc import Mapping
from pathlib import Path

from orchestrator.errors import ScenarioError
from orchestrator.geometry import KNOT

#: The particulars files: package data of an installed toolchain (``rhnc/cosim/ships``, mapped
#: from ``ships/`` by pyproject.toml), else ``ships/`` of the source checkout.
SHIPS_DIR = next(p for p in (Path(__file__).resolve().parents[1] / "cosim" / "ships",
                             Path(__file__).resolve().parents[2] / "ships") if p.is_dir())


#: Plant-FMU parameter name -> particulars attribute.
PLANT_PARAMETERS = {
    "lpp": "lpp_m",
    "beam": "beam_m",
    "draught": "draught_m",
    "displacement": "displacement_m3",
    "wind_area_frontal": "wind_area_frontal_m2",
    "wind_area_lateral": "wind_area_lateral_m2",
}


@dataclasses.dataclass(frozen=True)
class ShipParticulars:
    """Principal particulars (SI unless the name says otherwise).

    Attributes
    ----------
    name : str
    lpp_m, beam_m, draught_m, depth_m : float
        Length between perpendiculars, breadth, design draught, moulded depth [m].
    displacement_m3 : float
        Volume displacement [m^3].
    wetted_surface_m2 : float
        Wetted surface [m^2].
    deadweight_t : float
        Deadweight [t].
    design_speed_kn : float
        Service speed [kn].
    wind_area_frontal_m2, wind_area_lateral_m2 : float
        Transverse and lateral projected areas above the waterline [m^2].
    """

    name: str
    lpp_m: float
    beam_m: float
    draught_m: float
    depth_m: float
    displacement_m3: float
    wetted_surface_m2: float
    deadweight_t: float
    design_speed_kn: float
    wind_area_frontal_m2: float
    wind_area_lateral_m2: float

    @property
    def design_speed_m_s(self) -> float:
        return self.design_speed_kn * KNOT

    def mass_kg(self, water_density_kg_m3: float = 1025.0) -> float:
        return self.displacement_m3 * water_density_kg_m3


def ship_file(name: str, ships_dir: Path = SHIPS_DIR) -> Path:
    return Path(ships_dir) / f"{name}.toml"


@functools.lru_cache(maxsize=None)
def load_ship(name: str = "KCS", ships_dir: Path = SHIPS_DIR) -> ShipParticulars:
    """The particulars of ship ``name`` from ``ships/<name>.toml``.

    Raises
    ------
    ScenarioError
        Naming the file and key: missing file, missing or unknown key, a value that is not a
        positive number.
    """
    path = ship_file(name, ships_dir)
    if not path.is_file():
        known = sorted(p.stem for p in Path(ships_dir).glob("*.toml"))
        raise ScenarioError(f"{path}: no particulars for ship '{name}' (known: {', '.join(known)})")
    try:
        with path.open("rb") as handle:
            values = tomllib.load(handle)
    except tomllib.TOMLDecodeError as exc:
        raise ScenarioError(f"{path}: {exc}") from None
    values.pop("description", None)
    fields = [f.name for f in dataclasses.fields(ShipParticulars)]
    for key in values:
        if key not in fields:
            raise ScenarioError(f"{path}: unknown key '{key}' (valid: {', '.join(fields)})")
    for key in fields:
        if key not in values:
            raise ScenarioError(f"{path}: missing key '{key}'")
        if key == "name":
            continue
        value = values[key]
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not value > 0:
            raise ScenarioError(f"{path}: '{key}' must be a positive number, got {value!r}")
        values[key] = float(value)
    if values["name"] != name:
        raise ScenarioError(f"{path}: name = {values['name']!r} does not match the file name")
    return ShipParticulars(**values)


def check_parameter_set(values: Mapping[str, object], ship: ShipParticulars, where: str) -> None:
    """Refuse a plant parameter set whose particulars differ from the ship's file.

    Only the keys of ``PLANT_PARAMETERS`` the set has are compared (relative 1e-9).
    """
    for parameter, attribute in PLANT_PARAMETERS.items():
        if parameter not in values:
            continue
        declared = getattr(ship, attribute)
        value = float(values[parameter])
        if abs(value - declared) > 1e-9 * max(1.0, abs(declared)):
            raise ScenarioError(
                f"{where}: {parameter} = {value:g} differs from {attribute} = {declared:g} in "
                f"{ship_file(ship.name)} (the particulars are declared once, there)"
            )
