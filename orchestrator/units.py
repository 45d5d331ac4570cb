"""Units of FMU variables: what a declared unit means in SI, and whether it fits a port.

An FMI 2.0 modelDescription declares a variable's unit by name (``<Real unit="kn">`` or
through its ``declaredType``) and may define that name in ``<UnitDefinitions>`` as a
``BaseUnit``: exponents of kg, m, s, A, K, mol, cd, rad with ``factor`` and ``offset``
(``SI value = factor * value + offset``).  That definition is exact and is used when
present; a name without one is read by pint (``kn``, ``deg/min``, ``kN.m``, ``km``).  The
radian is kept as a dimension of its own, so a heading in degrees can never be taken for
a dimensionless number.
"""

from __future__ import annotations

import functools
import re
from dataclasses import dataclass

from orchestrator.plant_ports import BASE_UNITS

#: pint's base unit names -> the FMI BaseUnit attribute they stand for
_PINT_BASE = {"kilogram": "kg", "meter": "m", "second": "s", "ampere": "A", "kelvin": "K",
              "mole": "mol", "candela": "cd", "radian": "rad"}


class UnitParseError(ValueError):
    """A unit name that neither the modelDescription nor pint can read."""


@dataclass(frozen=True)
class SiUnit:
    """A unit as ``SI value = factor * value + offset`` in the SI unit of ``dimension``."""

    name: str
    factor: float
    offset: float
    dimension: tuple[int, ...]


def describe_dimension(dimension: tuple[int, ...]) -> str:
    """``m.s-1``-style text of an exponent vector (``1`` for none)."""
    parts = [unit if e == 1 else f"{unit}{e}" for unit, e in zip(BASE_UNITS, dimension) if e]
    return ".".join(parts) or "1"


def declared_unit(variable, model_description) -> str | None:
    """The unit name a variable declares (its own, else its declared type's), or None."""
    unit = getattr(variable, "unit", None)
    if not unit and getattr(variable, "declaredType", None) is not None:
        unit = getattr(variable.declaredType, "unit", None)
    return unit or None


def resolve_unit(name: str, model_description=None) -> SiUnit:
    """Meaning of the unit ``name``: its ``UnitDefinitions`` entry if any, else pint's.

    Raises
    ------
    UnitParseError
        Neither source knows the name.
    """
    if model_description is not None:
        for unit in getattr(model_description, "unitDefinitions", None) or ():
            if unit.name == name and unit.baseUnit is not None:
                base = unit.baseUnit
                return SiUnit(name, float(base.factor), float(base.offset),
                              tuple(int(getattr(base, key)) for key in BASE_UNITS))
    return _pint_unit(name)


@functools.lru_cache(maxsize=None)
def _pint_unit(name: str) -> SiUnit:
    import pint

    if name.strip() in ("1", ""):
        return SiUnit(name, 1.0, 0.0, (0,) * len(BASE_UNITS))
    # FMI-style names: "kN.m" (product), "kg.m2" (power)
    text = re.sub(r"(?<=[A-Za-z])\.(?=[A-Za-z])", "*", name)
    text = re.sub(r"(?<=[A-Za-z])(-?\d+)(?![\d.])", r"**\1", text)
    registry = _registry()
    try:
        zero = registry.Quantity(0.0, text).to_base_units()
        one = registry.Quantity(1.0, text).to_base_units()
    except (pint.errors.PintError, AttributeError, TypeError, ValueError, SyntaxError) as exc:
        raise UnitParseError(f"unknown unit '{name}'") from exc
    exponents = {_PINT_BASE.get(unit): power for unit, power in one._units.items()}
    if None in exponents:
        raise UnitParseError(f"unit '{name}' is not made of SI base units")
    offset = float(zero.magnitude)
    return SiUnit(name, float(one.magnitude) - offset, offset,
                  tuple(int(round(exponents.get(key, 0))) for key in BASE_UNITS))


@functools.lru_cache(maxsize=1)
def _registry():
    import pint

    return pint.UnitRegistry(autoconvert_offset_to_baseunit=True)
