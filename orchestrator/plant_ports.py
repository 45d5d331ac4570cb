"""Canonical plant ports: what a port table declares, and the table the installed domain registers.

A *port table* names the canonical ports of a plant (causality, SI unit), the output angles
to wrap, the vector inputs an FMU may take in another form and the ``[participants.<plant>.initial]``
keys.  Every canonical port carries SI values on the co-simulation bus; a mapped FMU
variable is converted to (and from) the port's unit by :mod:`orchestrator.port_mapping`.
The master knows no plant: the table comes from the entry-point group
``rhnc_cosim.port_tables`` (the ship domain registers the ship's, ``rhnc/cosim/plant_ports.py``)
and is read here as ``PLANT_PORTS``, ``WRAPPED_OUTPUTS``, ``VECTOR_PORTS`` and ``INITIAL_KEYS``.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from pathlib import Path
from dataclasses import dataclass, field


#: Order of the exponents of a dimension: the seven SI base units and the radian, as in the
#: ``BaseUnit`` element of an FMI 2.0 modelDescription.
BASE_UNITS = ("kg", "m", "s", "A", "K", "mol", "cd", "rad")


def dimension(**exponents: int) -> tuple[int, ...]:
    """Exponent vector over :data:`BASE_UNITS`, e.g. ``dimension(m=1, s=-1)`` for a speed."""
    return tuple(int(exponents.get(unit, 0)) for unit in BASE_UNITS)


LENGTH = dimension(m=1)
SPEED = dimension(m=1, s=-1)
ANGLE = dimension(rad=1)
ANGULAR_RATE = dimension(rad=1, s=-1)
FORCE = dimension(kg=1, m=1, s=-2)
MOMENT = dimension(kg=1, m=2, s=-2)
POWER = dimension(kg=1, m=2, s=-3)
#: revolutions per second: a frequency; a unit of angle per time (pint's ``rpm``, ``rad/s``)
#: is accepted for it and divided by 2 pi rad per revolution
FREQUENCY = dimension(s=-1)


@dataclass(frozen=True)
class PlantPort:
    """One canonical port of a ship plant.

    Attributes
    ----------
    causality : str
        ``output`` (the plant reports it) or ``input`` (the plant takes it).
    dimension : tuple of int
        Exponents over :data:`BASE_UNITS`; the port's value is in the SI unit of it.
    si_unit : str
        That unit's name, for messages.
    revolutions : bool
        A rate of revolutions (1/s): a unit of angle per time (``rpm``, ``rad/s``) is
        converted at 2 pi rad per revolution.
    """

    causality: str
    dimension: tuple[int, ...]
    si_unit: str
    revolutions: bool = False

    @property
    def is_angle(self) -> bool:
        """Angles and angular rates: a mapping must say their unit (degrees are common)."""
        return self.dimension[BASE_UNITS.index("rad")] != 0


@dataclass(frozen=True)
class PortTable:
    """The canonical ports of a plant and how scenarios address them.

    Attributes
    ----------
    ports : dict of str to PlantPort
        Canonical port name -> causality and SI unit.
    wrapped_outputs : tuple of str
        Output angles reported in (-pi, pi] whatever range the FMU uses.
    vector_ports : dict
        Vector inputs an FMU may take in another form: name -> (form, first port, second
        port); ``cartesian`` (north and east components) or ``polar_from`` (a speed and the
        direction it comes from, clockwise from north).
    initial_keys : dict
        ``[participants.<plant>.initial]`` keys -> (canonical port, factor to its SI unit).
    geographic_initial : callable or None
        ``geographic_initial(table, scenario_dir, where) -> table``: the ``[initial]`` table
        with the domain's geographic keys (a start in latitude and longitude) turned into
        :attr:`initial_keys` ones; raises ScenarioError naming the key.
    """

    ports: dict[str, PlantPort] = field(default_factory=dict)
    wrapped_outputs: tuple[str, ...] = ()
    vector_ports: dict[str, tuple[str, str, str]] = field(default_factory=dict)
    initial_keys: dict[str, tuple[str, float]] = field(default_factory=dict)
    geographic_initial: Callable[[dict, Path, str], dict] | None = None


@functools.lru_cache(maxsize=None)
def port_table() -> PortTable:
    """The registered port table (the first by name); an empty one when none is installed."""
    from orchestrator import plugins

    names = plugins.names("port_tables")
    return plugins.load("port_tables", names[0]) if names else PortTable()


_TABLE_ATTRIBUTES = {"PLANT_PORTS": "ports", "WRAPPED_OUTPUTS": "wrapped_outputs",
                     "VECTOR_PORTS": "vector_ports", "INITIAL_KEYS": "initial_keys"}


def __getattr__(name: str):
    if name in _TABLE_ATTRIBUTES:
        return getattr(port_table(), _TABLE_ATTRIBUTES[name])
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
