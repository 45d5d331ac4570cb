"""Principal particulars of a ship, declared once in ``ships/<name>.toml``.

The plant FMUs' parameter sets, the energy model (:mod:`rhnc.ship.energy`) and the analyses
(ship length of the turning-circle figures, deadweight of the CII) all read the same file,
so the ship simulated, the ship whose fuel is counted and the ship whose manoeuvres are
measured are one ship.  ``PLANT_PARAMETERS`` names the plant-FMU parameters that are
particulars: a parameter set must give them the file's value (checked when an FMU is built
and by :func:`check_parameter_set`).
"""

from __future__ import annotations

import copy
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


def _read_ship_file(path: Path) -> dict:
    """The tables of the ship file ``path`` (ScenarioError naming it when it is no TOML): a copy
    of what was parsed, so that a reader taking tables out of it leaves them for the next."""
    return copy.deepcopy(_parsed_ship_file(path))


@functools.lru_cache(maxsize=None)
def _parsed_ship_file(path: Path) -> dict:
    try:
        with path.open("rb") as handle:
            return tomllib.load(handle)
    except tomllib.TOMLDecodeError as exc:
        raise ScenarioError(f"{path}: {exc}") from None


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
    values = _read_ship_file(path)
    values.pop("description", None)
    actuators = values.pop("actuators", None)
    if actuators is not None:
        check_actuators(actuators, path)
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


def check_parameter_set(values: Mapping[str, float], ship: ShipParticulars, where: str) -> None:
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


#: ``[actuators]`` of a ship file: key -> (meaning with its unit, required).  The allocation
#: participant builds its force model from them (``rhnc/control/allocation.py``).
ACTUATOR_KEYS = {
    "rudder_area_m2": ("rudder area (movable part) [m^2]", True),
    "rudder_lift_slope_per_rad": ("slope of the rudder normal-force coefficient with the angle of attack [1/rad]", True),
    "rudder_stall_deg": ("angle of the largest normal force; beyond it the force falls [deg]", True),
    "rudder_post_stall_fraction": ("normal force beyond stall as a fraction of its peak [-] (default 0.6)", False),
    "rudder_max_deg": ("largest rudder angle of the steering gear [deg]", True),
    "rudder_rate_deg_s": ("largest rudder rate of the steering gear [deg/s]", True),
    "rudder_lever_m": ("lever of the rudder normal force about midship, hull interaction included [m]", True),
    "rudder_inflow_factor": ("rudder inflow over the propeller's advance speed outside the slipstream [-] "
                             "(default 1)", False),
    "rudder_in_slipstream": ("share of the rudder span in the propeller slipstream [-] (default 0.8)", False),
    "slipstream_factor": ("slipstream speed-up at the rudder, kappa of the MMG form [-] (default 0.5)", False),
    "propeller_diameter_m": ("propeller diameter [m]", True),
    "thrust_coefficients": ("K_T(J) = k0 + k1 J + k2 J^2: [k0, k1, k2] [-]", True),
    "wake_fraction": ("effective wake fraction at the propeller in straight motion [-]", True),
    "thrust_deduction": ("thrust deduction fraction [-]", True),
    "propeller_rpm_max": ("largest propeller revolutions, ahead [1/min]", True),
    "shaft_time_constant_s": ("time constant of the shaft's revolutions following a command [s]", True),
    "propeller_rate_rpm_s": ("largest rate of change of the revolutions [1/min per s]", True),
}


def check_actuators(table: object, path: Path) -> dict:
    """The ``[actuators]`` table of a ship file, checked: every key known, every required one
    given, numbers finite (angles, areas, times positive; fractions within [0, 1))."""
    import math

    if not isinstance(table, dict):
        raise ScenarioError(f"{path}: 'actuators' must be a table")
    for key in table:
        if key not in ACTUATOR_KEYS:
            raise ScenarioError(f"{path}: unknown key 'actuators.{key}' (valid: {', '.join(ACTUATOR_KEYS)})")
    for key, (_, required) in ACTUATOR_KEYS.items():
        if key not in table:
            if required:
                raise ScenarioError(f"{path}: missing key 'actuators.{key}' ({ACTUATOR_KEYS[key][0]})")
            continue
        value = table[key]
        if key == "thrust_coefficients":
            if (not isinstance(value, list) or len(value) != 3
                    or not all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
                               for v in value) or not value[0] > 0):
                raise ScenarioError(f"{path}: 'actuators.thrust_coefficients' must be [k0, k1, k2], finite, k0 > 0, "
                                    f"got {value!r}")
            continue
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise ScenarioError(f"{path}: 'actuators.{key}' must be a finite number, got {value!r}")
        fraction = key in ("wake_fraction", "thrust_deduction", "rudder_in_slipstream", "rudder_post_stall_fraction")
        if fraction and not 0.0 <= value < 1.0 + (key == "rudder_in_slipstream"):
            raise ScenarioError(f"{path}: 'actuators.{key}' must be within [0, 1), got {value!r}")
        if not fraction and not value > 0:
            raise ScenarioError(f"{path}: 'actuators.{key}' must be positive, got {value!r}")
    return dict(table)


def load_actuators(name_or_path: str, ships_dir: Path = SHIPS_DIR, base: Path | None = None) -> tuple[Path, dict]:
    """``(file, table)``: the ``[actuators]`` of ship ``name`` (``ships/<name>.toml``) or of a
    ship file given by path (relative to ``base``).

    Raises
    ------
    ScenarioError
        The file is missing, has no ``[actuators]`` table, or a key is wrong (named).
    """
    candidate = Path(name_or_path)
    if candidate.suffix == ".toml":
        path = candidate if candidate.is_absolute() or base is None else Path(base) / candidate
    else:
        path = ship_file(name_or_path, ships_dir)
    if not path.is_file():
        raise ScenarioError(f"{path}: ship file not found")
    values = _read_ship_file(path)
    if "actuators" not in values:
        raise ScenarioError(f"{path}: no [actuators] table (rudder and propeller data: {', '.join(ACTUATOR_KEYS)})")
    return path, check_actuators(values["actuators"], path)
