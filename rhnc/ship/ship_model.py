"""The one 3-DOF ship prediction model (docs/method.md, ship model; paper Eq. 11 and 16) for NMPC and tests.

State ``X = [x, y, psi, u, v, r]`` (m, m, rad, m/s, m/s, rad/s; x north, y east, psi
clockwise from north), control ``tau = [tau_u, tau_r]`` (N, N·m).  The prediction model is
the plant without disturbances and without current (paper Eq. 16):

    xdot   = u cos(psi) - v sin(psi)
    ydot   = u sin(psi) + v cos(psi)
    psidot = r
    udot   = ( m22 v r - d11 u + tau_u) / m11
    vdot   = (-m11 u r - d22 v - d23 r) / m22
    rdot   = ((m11 - m22) u v - d32 v - d33 r + tau_r) / m33

The parameters come from ``models/KCS/parameter_sets.toml`` (the plant FMU's single
source), so the controller predicts with exactly the numbers the plant simulates.

Real hulls need more than the paper's diagonal, linear model, and a set may say so with
optional coefficients (zero when absent, giving the equations above): ``m23``, the
sway-yaw coupling of the (symmetric) mass matrix, and the quadratic damping ``d11q``,
``d22q``, ``d33q`` (a resistance ``d11q |u| u``, cross-flow ``d22q |v| v``, ``d33q |r| r``)::

    m11 udot               = (m22 v + m23 r) r - d11 u - d11q |u| u + tau_u
    m22 vdot + m23 rdot    = -m11 u r - d22 v - d23 r - d22q |v| v
    m23 vdot + m33 rdot    = (m11 - m22) u v - m23 u r - d32 v - d33 r - d33q |r| r + tau_r

(the Coriolis terms of Fossen's 3-DOF model with that mass matrix).

Full hull forms (tankers, bulk carriers) need the cubic terms of the MMG hull polynomial:
a set may add the dimensional coefficients of :data:`HULL_POLYNOMIAL` (zero when absent),
forces on the right-hand side as the MMG standard writes them::

    surge += x_vv v^2 + x_vr v r + x_rr r^2
    sway  += y_vvv v^3 + y_vvr v^2 r + y_vrr v r^2 + y_rrr r^3
    yaw   += n_vvv v^3 + n_vvr v^2 r + n_vrr v r^2 + n_rrr r^3

With them the linear part may be course-unstable (as a full hull is) and the cubic terms
steady it at larger drift and yaw rate.  :func:`hull_forces` writes all these terms once;
the equations of motion, the NMPC's feed-forward and the disturbance observer use it.
"""

from __future__ import annotations

import dataclasses
import math
import tomllib
from collections.abc import Mapping
from pathlib import Path
from types import MappingProxyType
from typing import Any

import casadi as ca
import numpy as np

from orchestrator.errors import ScenarioError
from rhnc.ship.model_library import MODELS_DIR

#: The plant's parameter sets, shared with the KCS FMU.
PARAMETER_SETS_FILE = MODELS_DIR / "KCS" / "parameter_sets.toml"

#: The MMG-style hull polynomial: coefficient -> (equation 0 surge / 1 sway / 2 yaw, power of
#: v, power of r); the term ``coefficient * v**a * r**b`` is a force [N] or moment [N m] on
#: the right-hand side.  Units: x_vv kg/m, x_vr kg/rad, x_rr kg m/rad^2; y_vvv kg s/m^2,
#: y_vvr kg s/(m rad), y_vrr kg s/rad^2, y_rrr kg m s/rad^3; the n_ coefficients those times m.
HULL_POLYNOMIAL = {
    "x_vv": (0, 2, 0), "x_vr": (0, 1, 1), "x_rr": (0, 0, 2),
    "y_vvv": (1, 3, 0), "y_vvr": (1, 2, 1), "y_vrr": (1, 1, 2), "y_rrr": (1, 0, 3),
    "n_vvv": (2, 3, 0), "n_vvr": (2, 2, 1), "n_vrr": (2, 1, 2), "n_rrr": (2, 0, 3),
}
HULL_POLYNOMIAL_KEYS = tuple(HULL_POLYNOMIAL)
#: Keys of a parameter set that the prediction model uses.
DYNAMICS_KEYS = ("m11", "m22", "m33", "d11", "d22", "d33", "d23", "d32", "tau_u_max", "tau_r_max",
                 "m23", "d11q", "d22q", "d33q") + HULL_POLYNOMIAL_KEYS + ("damping_speed_mps",)
#: Keys that may be absent (the paper's Eq. 11 has no cross-damping, no coupled mass, no
#: quadratic damping and no hull polynomial).
OPTIONAL_ZERO_KEYS = ("d23", "d32", "m23", "d11q", "d22q", "d33q") + HULL_POLYNOMIAL_KEYS + ("damping_speed_mps",)
#: The optional keys of the wider model classes, written into a set only when not zero.
WIDE_MODEL_KEYS = ("m23", "d11q", "d22q", "d33q") + HULL_POLYNOMIAL_KEYS + ("damping_speed_mps",)

STATE_NAMES = ("x", "y", "psi", "u", "v", "r")
CONTROL_NAMES = ("tau_u", "tau_r")


@dataclasses.dataclass(frozen=True)
class ShipParameters:
    """Rigid-body-plus-added-mass and linear damping coefficients of the 3-DOF model.

    Attributes
    ----------
    m11, m22, m33 : float
        Surge and sway mass [kg], yaw inertia [kg·m²], added mass included.
    d11, d22, d33 : float
        Linear damping in surge [N·s/m], sway [N·s/m], yaw [N·m·s/rad].
    d23 : float
        Sway force per yaw rate [N·s/rad] (0 in the paper's Eq. 11).
    d32 : float
        Yaw moment per sway velocity [N·s] (0 in the paper's Eq. 11).
    tau_u_max, tau_r_max : float
        Bounds of the surge force [N] and yaw moment [N·m]: ``|tau| <= tau_max``.
    m23 : float
        Sway-yaw coupling of the mass matrix [kg·m] (symmetric: m32 = m23).
    d11q, d22q, d33q : float
        Quadratic damping in surge [N·s²/m²], sway [N·s²/m²], yaw [N·m·s²/rad²].
    x_vv, x_vr, x_rr, y_vvv, y_vvr, y_vrr, y_rrr, n_vvv, n_vvr, n_vrr, n_rrr : float
        The hull polynomial's coefficients (:data:`HULL_POLYNOMIAL`, units there).
    damping_speed_mps : float
        Surge speed [m/s] at which the linear sway-yaw damping d22, d23, d32, d33 has the
        values given; they scale with ``u / damping_speed_mps`` at other speeds, as a hull's
        linear forces do (``0.5 rho L T U^2`` times derivatives in ``v / U`` and
        ``r L / U``: proportional to the speed).  0 (the paper's model): constant.
    name : str
        Name of the parameter set the values came from.
    extras : Mapping[str, Any]
        The set's other keys (disturbance coefficients, initial state, ...), read-only.
    """

    m11: float
    m22: float
    m33: float
    d11: float
    d22: float
    d33: float
    d23: float
    d32: float
    tau_u_max: float
    tau_r_max: float
    m23: float = 0.0
    d11q: float = 0.0
    d22q: float = 0.0
    d33q: float = 0.0
    x_vv: float = 0.0
    x_vr: float = 0.0
    x_rr: float = 0.0
    y_vvv: float = 0.0
    y_vvr: float = 0.0
    y_vrr: float = 0.0
    y_rrr: float = 0.0
    n_vvv: float = 0.0
    n_vvr: float = 0.0
    n_vrr: float = 0.0
    n_rrr: float = 0.0
    damping_speed_mps: float = 0.0
    name: str = "custom"
    extras: Mapping[str, Any] = dataclasses.field(default_factory=lambda: MappingProxyType({}))

    @classmethod
    def from_mapping(cls, values: Mapping[str, Any], name: str = "custom", where: str = "") -> "ShipParameters":
        """Build from a mapping holding at least the dynamics keys (``d23``, ``d32`` default 0).

        Raises
        ------
        ScenarioError
            A dynamics key is missing or not a number.
        """
        where = where or f"parameter set '{name}'"
        dynamics: dict[str, float] = {}
        for key in DYNAMICS_KEYS:
            if key not in values:
                if key in OPTIONAL_ZERO_KEYS:
                    dynamics[key] = 0.0
                    continue
                raise ScenarioError(f"{where}: missing key '{key}' (needed: {', '.join(DYNAMICS_KEYS)})")
            value = values[key]
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                raise ScenarioError(f"{where}: key '{key}' must be a number, got {value!r}")
            dynamics[key] = float(value)
        if not (math.isfinite(dynamics["damping_speed_mps"]) and dynamics["damping_speed_mps"] >= 0.0):
            raise ScenarioError(f"{where}: key 'damping_speed_mps' must be a speed of at least 0 m/s "
                                f"(0: constant damping), got {dynamics['damping_speed_mps']!r}")
        extras = {k: v for k, v in values.items() if k not in DYNAMICS_KEYS}
        return cls(**dynamics, name=name, extras=MappingProxyType(extras))

    @property
    def tau_max(self) -> np.ndarray:
        """Input bounds ``[tau_u_max, tau_r_max]`` [N, N·m]."""
        return np.array([self.tau_u_max, self.tau_r_max])

    def equilibrium_tau(self, u: float, r: float = 0.0) -> np.ndarray:
        """Input holding surge speed ``u`` [m/s] and yaw rate ``r`` [rad/s] with zero sway.

        The sway equation is not balanced for ``r != 0`` (a reference with ``v_d = 0``, as
        the paper's Eq. 19 gives, is not an exact trim in a turn).
        """
        surge, _, yaw = hull_forces(self, u, 0.0, r)
        return -np.array([surge, yaw], dtype=float)

    def sway_yaw_accelerations(self, sway_force, yaw_moment):
        """``(vdot, rdot)`` from the sway force [N] and yaw moment [N·m] on the right-hand
        side: the inverse of the sway-yaw block of the mass matrix (numpy or CasADi)."""
        det = self.m22 * self.m33 - self.m23 * self.m23
        return ((self.m33 * sway_force - self.m23 * yaw_moment) / det,
                (self.m22 * yaw_moment - self.m23 * sway_force) / det)

    def straight_line_stable(self, u0: float) -> bool:
        """True if the sway-yaw pair linearised about straight motion at ``u0`` [m/s] is stable."""
        a = self.sway_yaw_matrix(u0)
        return bool(np.all(np.linalg.eigvals(a).real < 0.0))

    def sway_yaw_matrix(self, u0: float) -> np.ndarray:
        """System matrix of ``[v, r]`` linearised about ``v = r = 0``, ``u = u0`` [1/s]."""
        mass = np.array([[self.m22, self.m23], [self.m23, self.m33]])
        scale = u0 / self.damping_speed_mps if self.damping_speed_mps else 1.0   # see hull_forces
        forces = np.array(
            [
                [-self.d22 * scale, -self.m11 * u0 - self.d23 * scale],
                [(self.m11 - self.m22) * u0 - self.d32 * scale, -self.m23 * u0 - self.d33 * scale],
            ]
        )
        return np.linalg.solve(mass, forces)


def available_parameter_sets(path: Path = PARAMETER_SETS_FILE) -> dict[str, dict[str, Any]]:
    """All parameter sets of the TOML file, by name (top-level tables)."""
    if not path.is_file():
        raise ScenarioError(f"{path}: parameter set file not found")
    with path.open("rb") as stream:
        document = tomllib.load(stream)
    return {name: table for name, table in document.items() if isinstance(table, dict)}


def load_parameter_set(
    name: str = "default",
    overrides: Mapping[str, float] | None = None,
    path: Path = PARAMETER_SETS_FILE,
) -> ShipParameters:
    """Read a named set of the plant's parameters, optionally overriding single keys.

    Parameters
    ----------
    name : str
        Table name in ``models/KCS/parameter_sets.toml`` (``default``: full-scale KCS;
        ``paper_table2``: the paper's Table 2, see docs/method.md).
    overrides : mapping, optional
        Key -> value replacing the set's value; keys must exist in the set or be dynamics keys.
    path : pathlib.Path
        The TOML file (tests may point elsewhere).

    Raises
    ------
    ScenarioError
        Unknown set name (message lists the valid ones), unknown override key, or a
        missing/non-numeric dynamics key.
    """
    sets = available_parameter_sets(path)
    if name not in sets:
        raise ScenarioError(
            f"{path}: unknown parameter set '{name}' (valid: {', '.join(sorted(sets)) or 'none'})"
        )
    values = dict(sets[name])
    for key, value in (overrides or {}).items():
        if key not in values and key not in DYNAMICS_KEYS:
            raise ScenarioError(
                f"{path}: override of unknown key '{key}' in set '{name}' "
                f"(valid: {', '.join(sorted(set(values) | set(DYNAMICS_KEYS)))})"
            )
        values[key] = value
    return ShipParameters.from_mapping(values, name=name, where=f"{path}: [{name}]")


# --------------------------------------------------------------------------------------
# numpy model (tests, plant surrogate, linearisation checks)
# --------------------------------------------------------------------------------------


def _present(coefficient) -> bool:
    """False for a coefficient that is the number zero (its terms are left out); True for
    any other number or a symbol (the identification's scaled coefficients)."""
    return not (isinstance(coefficient, (int, float)) and coefficient == 0.0)


def hull_forces(p: ShipParameters, u, v, r) -> tuple:
    """Surge force, sway force [N] and yaw moment [N m] on the right-hand side of the
    equations without the inputs: Coriolis, damping and the hull polynomial, for numbers,
    numpy arrays or CasADi expressions of ``u``, ``v`` [m/s] and ``r`` [rad/s].  The
    accelerations follow from these plus ``tau`` through the mass matrix."""
    d22, d23, d32, d33 = p.d22, p.d23, p.d32, p.d33
    if _present(p.damping_speed_mps):   # the linear sway-yaw damping proportional to the speed
        scale = u / p.damping_speed_mps
        d22, d23, d32, d33 = d22 * scale, d23 * scale, d32 * scale, d33 * scale
    surge = p.m22 * v * r - p.d11 * u
    sway = -p.m11 * u * r - d22 * v - d23 * r
    yaw = (p.m11 - p.m22) * u * v - d32 * v - d33 * r
    if _present(p.m23):
        surge = surge + p.m23 * r * r
        yaw = yaw - p.m23 * u * r
    if _present(p.d11q):
        surge = surge - p.d11q * abs(u) * u
    if _present(p.d22q):
        sway = sway - p.d22q * abs(v) * v
    if _present(p.d33q):
        yaw = yaw - p.d33q * abs(r) * r
    forces = [surge, sway, yaw]
    for key, (equation, v_power, r_power) in HULL_POLYNOMIAL.items():
        coefficient = getattr(p, key)
        if _present(coefficient):
            term = coefficient
            for factor in (v,) * v_power + (r,) * r_power:   # plain products: cheap in CasADi too
                term = term * factor
            forces[equation] = forces[equation] + term
    return tuple(forces)


def equations_of_motion(state, tau, p: ShipParameters, cos, sin, stack):
    """The 3-DOF equations, written once for every backend: ``cos``, ``sin`` and ``stack``
    (a list of six expressions -> a vector) come from numpy or CasADi."""
    psi, u, v, r = state[2], state[3], state[4], state[5]
    surge, sway, yaw = hull_forces(p, u, v, r)
    surge = surge + tau[0]
    yaw = yaw + tau[1]
    if _present(p.m23):
        vdot, rdot = p.sway_yaw_accelerations(sway, yaw)
    else:   # the paper's diagonal mass: the same numbers, fewer operations
        vdot, rdot = sway / p.m22, yaw / p.m33
    return stack([
        u * cos(psi) - v * sin(psi),
        u * sin(psi) + v * cos(psi),
        r,
        surge / p.m11,
        vdot,
        rdot,
    ])


def derivatives(state: np.ndarray, tau: np.ndarray, params: ShipParameters) -> np.ndarray:
    """Time derivative of ``state`` (6,) under ``tau`` (2,) [SI], numpy.

    Works on 1-D arrays; :func:`casadi_derivatives` is the same equations, symbolic.
    """
    return equations_of_motion(state, tau, params, np.cos, np.sin, np.array)


def rk4_states(f, x, h: float, substeps: int, *args) -> list:
    """The classic RK4 scheme, the one integrator of the ship's equations everywhere.

    ``substeps`` steps of ``h`` [s] of ``x' = f(x, *args)`` (the arguments, such as the
    forces, held); returns the state at the end of every step, the last one the result.
    Written in plain arithmetic, so the same lines integrate numpy arrays (a state, or one
    column per state) and CasADi expressions (the NMPC's and the identification's models).
    """
    states = []
    for _ in range(substeps):
        k1 = f(x, *args)
        k2 = f(x + 0.5 * h * k1, *args)
        k3 = f(x + 0.5 * h * k2, *args)
        k4 = f(x + h * k3, *args)
        x = x + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
        states.append(x)
    return states


def rk4_step(state: np.ndarray, tau: np.ndarray, dt: float, substeps: int, params: ShipParameters) -> np.ndarray:
    """Advance ``state`` by ``dt`` [s] with ``tau`` held, ``substeps`` classic RK4 steps (numpy)."""
    x = np.asarray(state, dtype=float)
    return rk4_states(derivatives, x, dt / substeps, substeps, np.asarray(tau, dtype=float), params)[-1]


# --------------------------------------------------------------------------------------
# CasADi model (NMPC)
# --------------------------------------------------------------------------------------


def casadi_derivatives(params: ShipParameters) -> ca.Function:
    """CasADi function ``f(X[6], tau[2]) -> Xdot[6]`` of the prediction model (SX)."""
    state = ca.SX.sym("X", 6)
    tau = ca.SX.sym("tau", 2)
    xdot = equations_of_motion(state, tau, params, ca.cos, ca.sin, lambda rows: ca.vertcat(*rows))
    return ca.Function("ship_f", [state, tau], [xdot], ["X", "tau"], ["Xdot"])


def rk4_function(params: ShipParameters, dt: float, substeps: int, with_substeps: bool = False) -> ca.Function:
    """CasADi RK4 discretisation ``F(X, tau) -> X_next`` over ``dt`` [s] in ``substeps`` steps.

    With ``with_substeps`` the function also returns ``Xs`` (6 x substeps): the states at
    the end of every substep (the last column equals ``X_next``), for path constraints
    between the shooting nodes.
    """
    if substeps < 1:
        raise ValueError("substeps must be >= 1")
    f = casadi_derivatives(params)
    state = ca.SX.sym("X", 6)
    tau = ca.SX.sym("tau", 2)
    columns = rk4_states(f, state, dt / substeps, substeps, tau)
    x = columns[-1]
    if with_substeps:
        return ca.Function("ship_F", [state, tau], [x, ca.horzcat(*columns)], ["X", "tau"], ["X_next", "Xs"])
    return ca.Function("ship_F", [state, tau], [x], ["X", "tau"], ["X_next"])
