"""Physical bounds of the widest model class: the mass matrix from the ship's particulars and
a hull polynomial that can only take energy out of the sway-yaw motion.

An equation-error fit of the cubic hull polynomial can explain the same manoeuvres with a
lighter ship and other damping (the KVLCC2's came out with a fifth of its sway mass), and a
polynomial fitted freely may feed energy into sway and yaw at the amplitudes of a manoeuvre it
did not see, and run away there.  Two bounds close both doors, whatever the ship:

Mass matrix.  The rigid-body mass is the displacement's, ``m = rho V``; the yaw inertia has the
radius of gyration of a merchant hull, a quarter of the length (``I_z = m (L/4)^2``).  The
added masses in sway and yaw and their coupling come from Clarke's regression on hull form
(D. Clarke, P. Gedling, G. Hine, "The application of manoeuvring criteria in hull design
using linear theory", Trans. RINA 125, 1983), with ``k = pi (T/L)^2`` and ``C_B = V / (L B T)``::

    -Y'_vdot = k (1 + 0.16 C_B B/T - 5.1 (B/L)^2)           on 1/2 rho L^3
    -Y'_rdot = k (0.67 B/L - 0.0033 (B/T)^2)                on 1/2 rho L^4
    -N'_vdot = k (1.1 B/L - 0.041 B/T)                      on 1/2 rho L^4
    -N'_rdot = k (1/12 + 0.017 C_B B/T - 0.33 B/L)          on 1/2 rho L^5

and the surge added mass is the rule of thumb of 5 % of the mass (Clarke gives none).  So
``m11 = 1.05 m``, ``m22 = m - Y_vdot``, ``m33 = I_z - N_rdot`` and the coupling
``m23 = -(Y_rdot + N_vdot) / 2`` (symmetric).  The fit keeps m11, m22 and m33 within
:data:`MASS_TOLERANCE` of these, and m23 within the coupling the centre of gravity adds
(``m x_G`` for ``|x_G|`` up to :data:`LCG_FRACTION` of the length, not declared in the
particulars) plus the added coupling's own size.  For the KCS set of this project (built
with Clarke's sway and yaw terms) the estimate is its own; for the KVLCC2 of the MMG standard
it is within 5 % of m11, m22 and m33.

Dissipative polynomial.  The power of the polynomial's sway force and yaw moment,
``P(v, r) = v Y_poly + r N_poly``, is a quartic form in (v, r)::

    P = y_vvv v^4 + (y_vvr + n_vvv) v^3 r + (y_vrr + n_vvr) v^2 r^2 + (y_rrr + n_vrr) v r^3 + n_rrr r^4

(the Coriolis terms do no work, the surge terms only move energy between surge and the
others).  The polynomial is dissipative when ``P <= 0`` for every (v, r); the form is
homogeneous, so that is ``P <= 0`` in every direction of the (v, r) plane, and a check on a
grid of directions scaled to the sailed envelope (:func:`power_rows`) is a set of linear
inequalities in the coefficients, which the fit keeps.  Then the polynomial alone can only
brake sway and yaw, and at large drift and yaw rate, where it outgrows the linear part, so
does the whole hull: no sign pattern of the coefficients can run away.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from rhnc.ship.ships import ShipParticulars

#: Relative half-width of the bounds of m11, m22 and m33 about the estimate.
MASS_TOLERANCE = 0.2
#: Largest distance of the centre of gravity from the reference point, as a fraction of the length.
LCG_FRACTION = 0.05
#: Surge added mass as a fraction of the mass.
SURGE_ADDED_FRACTION = 0.05
WATER_DENSITY_KG_M3 = 1025.0
#: The hull polynomial's sway and yaw terms, in the order of the power's quartic form.
POWER_TERMS = (("y_vvv", 4, 0), ("y_vvr", 3, 1), ("n_vvv", 3, 1), ("y_vrr", 2, 2), ("n_vvr", 2, 2),
               ("y_rrr", 1, 3), ("n_vrr", 1, 3), ("n_rrr", 0, 4))
#: Directions of the (v, r) plane where the power is checked (the form is even: half a turn).
POWER_DIRECTIONS = 90


@dataclasses.dataclass(frozen=True)
class MassBounds:
    """Estimate and bounds of the mass matrix: name (m11, m22, m33, m23) -> value, and (lower, upper).

    Attributes
    ----------
    estimate : dict
        m11, m22 [kg], m33 [kg m^2], m23 [kg m].
    bounds : dict
        The same names -> (lower, upper), the range the fit keeps them in.
    source : str
        Where the estimate came from (a ship file, a known model), for the fit's notes.
    """

    estimate: dict
    bounds: dict
    source: str

    @classmethod
    def around(cls, values: dict, source: str, tolerance: float = MASS_TOLERANCE,
               coupling_bound: float | None = None) -> "MassBounds":
        """Bounds about given masses: m11, m22, m33 within ``tolerance``; m23 within
        ``coupling_bound`` [kg m] (default: a tenth of sqrt(m22 m33))."""
        half = coupling_bound if coupling_bound is not None else 0.1 * math.sqrt(values["m22"] * values["m33"])
        bounds = {name: ((1.0 - tolerance) * values[name], (1.0 + tolerance) * values[name])
                  for name in ("m11", "m22", "m33")}
        bounds["m23"] = (values["m23"] - half, values["m23"] + half)
        return cls({name: float(values[name]) for name in ("m11", "m22", "m33", "m23")}, bounds, source)

    def contains(self, values: dict) -> bool:
        """True when every mass of ``values`` is within its bounds (1e-9 relative slack)."""
        return all(low - 1e-9 * abs(low) <= values[name] <= high + 1e-9 * abs(high)
                   for name, (low, high) in self.bounds.items())


def mass_from_particulars(ship: ShipParticulars, water_density_kg_m3: float = WATER_DENSITY_KG_M3) -> MassBounds:
    """The mass matrix of ``ship`` (rigid body and Clarke's added masses, see the module) and its bounds."""
    length, beam, draught = ship.lpp_m, ship.beam_m, ship.draught_m
    mass = water_density_kg_m3 * ship.displacement_m3
    block = ship.displacement_m3 / (length * beam * draught)
    k = math.pi * (draught / length) ** 2
    half_rho = 0.5 * water_density_kg_m3
    y_vdot = -k * (1.0 + 0.16 * block * beam / draught - 5.1 * (beam / length) ** 2) * half_rho * length ** 3
    y_rdot = -k * (0.67 * beam / length - 0.0033 * (beam / draught) ** 2) * half_rho * length ** 4
    n_vdot = -k * (1.1 * beam / length - 0.041 * beam / draught) * half_rho * length ** 4
    n_rdot = -k * (1.0 / 12.0 + 0.017 * block * beam / draught - 0.33 * beam / length) * half_rho * length ** 5
    added_coupling = -0.5 * (y_rdot + n_vdot)
    values = {"m11": (1.0 + SURGE_ADDED_FRACTION) * mass, "m22": mass - y_vdot,
              "m33": mass * (0.25 * length) ** 2 - n_rdot, "m23": added_coupling}
    coupling_bound = LCG_FRACTION * length * mass + abs(added_coupling)
    return MassBounds.around(values, f"the particulars of {ship.name} (Clarke's added masses)",
                             coupling_bound=coupling_bound)


def power_form(values) -> np.ndarray:
    """Coefficients ``[c0..c4]`` of the polynomial's power ``P = sum c_k v^(4-k) r^k`` [W per
    (m/s)^(4-k) (rad/s)^k]; ``values`` maps (or has attributes) the polynomial's names."""
    get = values.get if isinstance(values, dict) else (lambda name, default=0.0: getattr(values, name, default))
    form = np.zeros(5)
    for name, _, r_power in POWER_TERMS:
        form[r_power] += float(get(name, 0.0))
    return form


def envelope_directions(sway_mps: float, yaw_rate_rad_s: float, count: int = POWER_DIRECTIONS) -> np.ndarray:
    """(count, 2) points ``(v, r)`` on the ellipse of the sailed sway and yaw-rate amplitudes,
    one per direction over half a turn (the power is an even form)."""
    angles = np.linspace(0.0, math.pi, count, endpoint=False)
    return np.column_stack([sway_mps * np.cos(angles), yaw_rate_rad_s * np.sin(angles)])


def power_rows(names: tuple[str, ...], points: np.ndarray) -> np.ndarray:
    """(points, len(names)) matrix ``G`` with ``G @ theta`` the polynomial's power at each point
    (coefficients ``theta`` in the order of ``names``; names outside the power get 0)."""
    rows = np.zeros((len(points), len(names)))
    v, r = points[:, 0], points[:, 1]
    for name, v_power, r_power in POWER_TERMS:
        if name in names:
            rows[:, names.index(name)] = v ** v_power * r ** r_power
    return rows


def is_dissipative(values, sway_mps: float, yaw_rate_rad_s: float, tolerance: float = 1e-9) -> bool:
    """True when the polynomial's power is not positive in any direction of the (v, r) plane.

    Exact, not on a grid: with ``v = sway_mps a`` and ``r = yaw_rate_rad_s b`` (the sailed
    amplitudes, so the coefficients are comparable), the quartic ``p(t) = P(1, t)`` is checked
    at its stationary points and both ends; ``tolerance`` is relative to its largest coefficient.
    """
    form = power_form(values) * sway_mps ** np.arange(4, -1, -1) * yaw_rate_rad_s ** np.arange(5)
    scale = float(np.max(np.abs(form)))
    if scale == 0.0:
        return True
    c = form / scale
    if c[0] > tolerance or c[4] > tolerance:
        return False
    stationary: np.ndarray = (np.polynomial.polynomial.polyroots(np.polynomial.polynomial.polyder(c))
                              if np.any(c[1:]) else np.zeros(0))
    real = np.array([root.real for root in np.atleast_1d(stationary) if abs(root.imag) <= 1e-9 * max(1.0, abs(root))])
    return bool(np.all(np.polynomial.polynomial.polyval(real, c) / (1.0 + real ** 4) <= tolerance))


def make_dissipative(values: dict, sway_mps: float, yaw_rate_rad_s: float) -> tuple[dict, float]:
    """``values`` with the pure cubic damping (y_vvv, n_rrr) strengthened just enough that the
    polynomial is dissipative (:func:`is_dissipative`), and the power that took [W, at the
    sailed amplitudes in the worst direction; 0 when it already was]."""
    if is_dissipative(values, sway_mps, yaw_rate_rad_s):
        return dict(values), 0.0
    points = envelope_directions(sway_mps, yaw_rate_rad_s, 8 * POWER_DIRECTIONS)
    names = tuple(name for name, _, _ in POWER_TERMS)
    power = power_rows(names, points) @ np.array([values.get(name, 0.0) for name in names])
    normalised = (points[:, 0] / sway_mps) ** 4 + (points[:, 1] / yaw_rate_rad_s) ** 4
    excess = max(float(np.max(power / normalised)), 1e-12 * float(np.max(np.abs(power))))
    for factor in (1.001, 1.01, 1.1, 2.0, 10.0):
        repaired = dict(values)
        repaired["y_vvv"] = values.get("y_vvv", 0.0) - factor * excess / sway_mps ** 4
        repaired["n_rrr"] = values.get("n_rrr", 0.0) - factor * excess / yaw_rate_rad_s ** 4
        if is_dissipative(repaired, sway_mps, yaw_rate_rad_s):
            return repaired, factor * excess
    raise ArithmeticError("the hull polynomial could not be made dissipative")   # not reached: 10x the grid's worst
