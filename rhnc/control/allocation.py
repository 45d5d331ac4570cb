"""Control allocation: the NMPC's tau = [surge force, yaw moment] to rudder angle and
propeller revolutions, for plants at actuator level (``models/KCSMMG``).

The force model is the plant's propeller and rudder in straight motion (v = r = 0), the
MMG standard form of ``models/KCSMMG/readme.md``::

    u_a   = u (1 - w_P0)                                   propeller advance speed
    T     = rho D^2 (k_t0 (nD)^2 + k_t1 (nD) u_a + k_t2 u_a^2)     = rho n^2 D^4 K_T(J)
    tau_u = (1 - t_P) T
    u_R   = eps sqrt(eta (u_a + kappa (s - u_a))^2 + (1 - eta) u_a^2),  s^2 = u_a^2 + 8 T / (pi rho D^2)
    F_N   = 1/2 rho A_R u_R^2 f_alpha sin(delta)
    tau_r = -(x_R + a_H x_H) Lpp F_N cos(delta)

and the allocation is its inverse: n from the quadratic in nD for the thrust (1 - t_P) T =
tau_u, then delta from sin(2 delta) / 2 = tau_r / (lever 1/2 rho A_R u_R^2 f_alpha) with the
slipstream of that n.  Both are limited to the actuators' ranges (|delta| <= rudder_max,
0 <= n <= propeller_rps_max; the propeller turns ahead only) and rates (per step of this
participant), so a command never asks more of the plant than it can do.  The achieved tau
(the same force model at the plant's reported rudder angle and revolutions when they are
connected, else at the commands) is an output, so the analyses show demanded against
achieved.  Every coefficient is an option; the defaults are the ``[default]`` set of
``models/KCSMMG/parameter_sets.toml`` (the plant this participant is meant for).

For another ship the option ``ship`` takes the coefficients from the ``[actuators]`` table
of its ship file (``ships/<name>.toml`` or a path; keys and units in
:data:`rhnc.ship.ships.ACTUATOR_KEYS` and docs/actuator-plants.md): rudder area, lift slope,
stall angle, lever, steering-gear limits, propeller diameter and thrust curve, wake and
thrust deduction, revolutions and their rate.  The rudder then **stalls**: its normal-force
coefficient ``f_alpha sin(delta)`` holds up to the stall angle and beyond it falls, over
5 deg, to ``rudder_post_stall_fraction`` of its peak::

    C_N(delta) = f_alpha sin(delta)                                   |delta| <= delta_s
               = f_alpha sin(delta_s) (1 - (1 - f_post) min((|delta| - delta_s) / 5 deg, 1)) sign(delta)

so the largest yaw moment is the one at the stall angle, and the allocation never commands
beyond it (a larger angle would give less).
"""

from __future__ import annotations

import math
import tomllib
from collections.abc import Mapping, Sequence
from typing import Any

from orchestrator.errors import ModelError, ScenarioError
from orchestrator.participant import BuildContext, Participant, Value, is_finite_number, reject_unknown_options
from rhnc.ship.model_library import MODELS_DIR

PARAMETER_SETS_FILE = MODELS_DIR / "KCSMMG" / "parameter_sets.toml"

#: Coefficients of the force model (names and units as the KCSMMG plant's parameters).
COEFFICIENTS = (
    "lpp", "rho_water", "prop_diameter", "w_p0", "t_p", "k_t0", "k_t1", "k_t2", "rudder_area",
    "f_alpha", "rudder_eta", "epsilon", "kappa", "a_h", "x_h", "x_r", "rudder_max", "rudder_rate_max",
    "propeller_rps_max", "propeller_rate_max",
)
POSITIVE = ("lpp", "rho_water", "prop_diameter", "rudder_area", "f_alpha", "k_t0", "rudder_max",
            "rudder_rate_max", "propeller_rps_max", "propeller_rate_max")
OPTIONS = ("parameter_set", "ship", *COEFFICIENTS)
#: Post-stall drop of the rudder's normal force: over this angle beyond the stall [rad].
STALL_DROP_RAD = math.radians(5.0)


def coefficients_from_ship(ship: str, where: str, base=None) -> dict[str, float]:
    """The force model's coefficients from the ``[actuators]`` of a ship file (module header)."""
    from rhnc.ship.ships import load_actuators

    _, a = load_actuators(ship, base=base)
    k0, k1, k2 = (float(v) for v in a["thrust_coefficients"])
    values = {
        "lpp": 1.0, "x_r": 0.0, "a_h": 0.0, "x_h": 0.0,        # the lever is given whole
        "rudder_lever": float(a["rudder_lever_m"]),
        "rho_water": 1025.0,
        "prop_diameter": float(a["propeller_diameter_m"]),
        "w_p0": float(a["wake_fraction"]), "t_p": float(a["thrust_deduction"]),
        "k_t0": k0, "k_t1": k1, "k_t2": k2,
        "rudder_area": float(a["rudder_area_m2"]), "f_alpha": float(a["rudder_lift_slope_per_rad"]),
        "rudder_eta": float(a.get("rudder_in_slipstream", 0.8)), "epsilon": float(a.get("rudder_inflow_factor", 1.0)),
        "kappa": float(a.get("slipstream_factor", 0.5)),
        "rudder_max": math.radians(float(a["rudder_max_deg"])),
        "rudder_rate_max": math.radians(float(a["rudder_rate_deg_s"])),
        "rudder_stall": math.radians(float(a["rudder_stall_deg"])),
        "rudder_post_stall_fraction": float(a.get("rudder_post_stall_fraction", 0.6)),
        "propeller_rps_max": float(a["propeller_rpm_max"]) / 60.0,
        "propeller_rate_max": float(a["propeller_rate_rpm_s"]) / 60.0,
        "shaft_time_constant": float(a["shaft_time_constant_s"]),
    }
    return values


def load_coefficients(set_name: str = "default", overrides: Mapping[str, Any] | None = None,
                      where: str = "allocation") -> dict[str, float]:
    """The force model's coefficients: a KCSMMG parameter set with ``overrides`` applied."""
    with PARAMETER_SETS_FILE.open("rb") as handle:
        sets = tomllib.load(handle)
    if set_name not in sets:
        raise ScenarioError(f"{where}: option 'parameter_set': no set '{set_name}' in {PARAMETER_SETS_FILE} "
                            f"(valid: {', '.join(sets)})")
    values = {key: float(sets[set_name][key]) for key in COEFFICIENTS}
    for key, value in (overrides or {}).items():
        if not is_finite_number(value):
            raise ScenarioError(f"{where}: option '{key}' must be a finite number, got {value!r}")
        values[key] = float(value)
    for key in POSITIVE:
        if not values[key] > 0.0:
            raise ScenarioError(f"{where}: option '{key}' must be positive, got {values[key]!r}")
    if not 0.0 <= values["rudder_eta"] <= 1.0:
        raise ScenarioError(f"{where}: option 'rudder_eta' must be within [0, 1], got {values['rudder_eta']!r}")
    if not -(values["x_r"] + values["a_h"] * values["x_h"]) > 0.0:
        raise ScenarioError(f"{where}: options 'x_r', 'a_h', 'x_h' must put the rudder's lever aft "
                            "(-(x_r + a_h x_h) > 0)")
    return values


class ForceModel:
    """The propeller and rudder forces in straight motion, and their inverse (module header)."""

    def __init__(self, coefficients: Mapping[str, float]) -> None:
        self.c = dict(coefficients)

    def thrust(self, rps: float, u: float) -> float:
        """Propeller thrust T [N] at ``rps`` [1/s] and surge speed ``u`` [m/s]."""
        c = self.c
        ua, nd = u * (1.0 - c["w_p0"]), rps * c["prop_diameter"]
        return c["rho_water"] * c["prop_diameter"] ** 2 * (c["k_t0"] * nd * nd + c["k_t1"] * nd * ua + c["k_t2"] * ua * ua)

    def rudder_inflow(self, rps: float, u: float) -> float:
        """Rudder inflow speed u_R [m/s] in the slipstream of the propeller."""
        c = self.c
        ua = u * (1.0 - c["w_p0"])
        loading = 8.0 * self.thrust(rps, u) / (math.pi * c["rho_water"] * c["prop_diameter"] ** 2)
        slip = math.sqrt(ua * ua + max(loading, 0.0))
        inner = ua + c["kappa"] * (slip - ua)
        return c["epsilon"] * math.sqrt(c["rudder_eta"] * inner * inner + (1.0 - c["rudder_eta"]) * ua * ua)

    @property
    def stall(self) -> float:
        """Angle of the rudder's largest normal force [rad] (the largest angle when no stall is given)."""
        return self.c.get("rudder_stall", self.c["rudder_max"])

    @property
    def usable_rudder(self) -> float:
        """Largest angle the allocation commands [rad]: the range, or the stall angle if smaller."""
        return min(self.c["rudder_max"], self.stall)

    def normal_force_shape(self, rudder_angle: float) -> float:
        """C_N(delta) / f_alpha [-]: sin(delta) up to the stall, then falling (module header)."""
        size = abs(rudder_angle)
        if size <= self.stall:
            return math.sin(rudder_angle)
        drop = min((size - self.stall) / STALL_DROP_RAD, 1.0)
        fraction = self.c.get("rudder_post_stall_fraction", 0.6)
        return math.copysign(math.sin(self.stall) * (1.0 - (1.0 - fraction) * drop), rudder_angle)

    def _moment_per_sin2(self, rps: float, u: float) -> float:
        """tau_r = this * sin(2 delta) / 2 [N m] below the stall."""
        c = self.c
        lever = c["rudder_lever"] if "rudder_lever" in c else -(c["x_r"] + c["a_h"] * c["x_h"]) * c["lpp"]
        return lever * 0.5 * c["rho_water"] * c["rudder_area"] * self.rudder_inflow(rps, u) ** 2 * c["f_alpha"]

    def tau(self, rudder_angle: float, rps: float, u: float) -> tuple[float, float]:
        """[tau_u N, tau_r N m] of the actuators at ``rudder_angle`` [rad] and ``rps``."""
        return ((1.0 - self.c["t_p"]) * self.thrust(rps, u),
                self._moment_per_sin2(rps, u) * self.normal_force_shape(rudder_angle) * math.cos(rudder_angle))

    def rps_for(self, tau_u: float, u: float) -> float:
        """Revolutions [1/s] whose thrust gives ``tau_u``, within [0, propeller_rps_max]."""
        c = self.c
        ua = max(u, 0.0) * (1.0 - c["w_p0"])
        target = tau_u / (1.0 - c["t_p"]) / (c["rho_water"] * c["prop_diameter"] ** 2)
        a, b, cc = c["k_t0"], c["k_t1"] * ua, c["k_t2"] * ua * ua - target
        discriminant = b * b - 4.0 * a * cc
        nd = (-b + math.sqrt(discriminant)) / (2.0 * a) if discriminant > 0.0 else 0.0
        return min(max(nd / c["prop_diameter"], 0.0), c["propeller_rps_max"])

    def rudder_for(self, tau_r: float, rps: float, u: float) -> float:
        """Rudder angle [rad] whose moment gives ``tau_r`` at ``rps``, within +-rudder_max."""
        limit = self.usable_rudder
        scale = self._moment_per_sin2(rps, u)
        if scale <= 0.0:
            return math.copysign(limit, tau_r) if tau_r else 0.0
        ratio = 2.0 * tau_r / scale
        if abs(ratio) >= math.sin(2.0 * limit):
            return math.copysign(limit, tau_r)
        return 0.5 * math.asin(ratio)


def tau_rate_limits(coefficients: Mapping[str, float], speed_mps: float) -> tuple[float, float]:
    """Largest rates [N/s, N m/s] at which the actuators can change tau at ``speed_mps``.

    Surge force: the thrust's slope with the revolutions at full revolutions times their
    largest rate, or the full thrust over the shaft's time constant when that is slower.
    Yaw moment: the moment's slope with the rudder angle at midships, in the slipstream of
    full revolutions (the largest slope), times the steering gear's rate.  Upper bounds of
    what the actuators can do, so the NMPC's bounds never make a feasible plan infeasible.
    """
    model = ForceModel(coefficients)
    c = model.c
    full = c["propeller_rps_max"]
    step = 1e-3 * full
    slope = (model.tau(0.0, full, speed_mps)[0] - model.tau(0.0, full - step, speed_mps)[0]) / step
    surge = slope * c["propeller_rate_max"]
    if "shaft_time_constant" in c:
        surge = min(surge, model.tau(0.0, full, speed_mps)[0] / c["shaft_time_constant"])
    yaw = model._moment_per_sin2(full, speed_mps) * c["rudder_rate_max"]   # d/d(delta) of sin(2 delta)/2 at 0: 1
    return float(surge), float(yaw)


def _rate_limited(target: float, previous: float, rate: float, step_s: float) -> float:
    return previous + min(max(target - previous, -rate * step_s), rate * step_s)


class AllocationParticipant(Participant):
    """tau -> rudder angle and propeller revolutions, rate-limited (module header).

    Inputs: ``tau_u`` [N], ``tau_r`` [N m], ``u`` [m/s] (measured surge speed); optional
    ``rudder_angle`` [rad] and ``propeller_rps`` [1/s] reported by the plant.
    Outputs: ``rudder_angle_cmd`` [rad], ``propeller_rps_cmd`` [1/s], ``tau_u_achieved`` [N],
    ``tau_r_achieved`` [N m], ``saturated`` (1 when the demand exceeded what the actuators
    could give within their ranges and rates this step).
    """

    OPTIONS = OPTIONS

    def __init__(self, name: str, coefficients: Mapping[str, float], step_s: float) -> None:
        super().__init__(name)
        self.model = ForceModel(coefficients)
        self.step_s = step_s
        self._rudder = 0.0
        self._rps = 0.0
        self._actuators_known = False
        self._steps = 0
        self._saturated_steps = 0

    @classmethod
    def from_options(cls, name: str, options: Mapping[str, Any], context: BuildContext) -> "AllocationParticipant":
        where = context.where
        reject_unknown_options(options, OPTIONS, where)
        if "ship" in options:
            others = sorted(key for key in options if key != "ship")
            if others:
                raise ScenarioError(f"{where}: option 'ship' takes every coefficient from the ship file; "
                                    f"give it alone (also given: {', '.join(others)})")
            if not isinstance(options["ship"], str):
                raise ScenarioError(f"{where}: option 'ship' must be a ship name or a ship file path")
            return cls(name, coefficients_from_ship(options["ship"], where, context.scenario_dir), context.step_size)
        set_name = options.get("parameter_set", "default")
        if not isinstance(set_name, str):
            raise ScenarioError(f"{where}: option 'parameter_set' must be a string")
        overrides = {key: value for key, value in options.items() if key != "parameter_set"}
        return cls(name, load_coefficients(set_name, overrides, where), context.step_size)

    @property
    def input_names(self) -> Sequence[str]:
        return ("tau_u", "tau_r", "u", "rudder_angle", "propeller_rps")

    @property
    def output_names(self) -> Sequence[str]:
        return ("rudder_angle_cmd", "propeller_rps_cmd", "tau_u_achieved", "tau_r_achieved", "saturated")

    def setup(self, start_time: float, inputs: Mapping[str, Value]) -> dict[str, Value]:
        """Start from the plant's actuators when already reported (no jump at the first step).

        Declared before the plant (the usual order), the plant's rudder angle and revolutions
        are not known yet at set-up; the first step then starts from them instead.
        """
        self._actuators_known = "rudder_angle" in inputs and "propeller_rps" in inputs
        self._rudder = float(inputs.get("rudder_angle", 0.0))
        self._rps = float(inputs.get("propeller_rps", 0.0))
        self._steps = self._saturated_steps = 0
        u = float(inputs.get("u", 0.0))
        tau_u, tau_r = self.model.tau(self._rudder, self._rps, u)
        return self._outputs(tau_u, tau_r, False)

    def step(self, time: float, step_size: float, inputs: Mapping[str, Value]) -> dict[str, Value]:
        missing = [port for port in ("tau_u", "tau_r", "u") if port not in inputs]
        if missing:
            raise ModelError(f"{self.name}: inputs not connected: {', '.join(missing)}")
        tau_u, tau_r, u = (float(inputs[port]) for port in ("tau_u", "tau_r", "u"))
        if not all(math.isfinite(v) for v in (tau_u, tau_r, u)):
            raise ModelError(f"{self.name}: non-finite input at t = {time} s: tau = ({tau_u}, {tau_r}), u = {u}")
        c = self.model.c
        rps_wanted = self.model.rps_for(tau_u, u)
        if not self._actuators_known:  # first step: start where the plant's actuators are
            self._rps = float(inputs.get("propeller_rps", rps_wanted))
            self._rudder = float(inputs.get("rudder_angle", self.model.rudder_for(tau_r, self._rps, u)))
            self._actuators_known = True
        self._rps = _rate_limited(rps_wanted, self._rps, c["propeller_rate_max"], step_size)
        rudder_wanted = self.model.rudder_for(tau_r, self._rps, u)
        self._rudder = _rate_limited(rudder_wanted, self._rudder, c["rudder_rate_max"], step_size)
        rudder = float(inputs.get("rudder_angle", self._rudder))
        rps = float(inputs.get("propeller_rps", self._rps))
        achieved_u, achieved_r = self.model.tau(rudder, rps, u)
        commanded_u, commanded_r = self.model.tau(self._rudder, self._rps, u)
        saturated = (abs(commanded_u - tau_u) > 1e-3 * max(abs(tau_u), 1e3)
                     or abs(commanded_r - tau_r) > 1e-3 * max(abs(tau_r), 1e5))
        self._steps += 1
        self._saturated_steps += int(saturated)
        return self._outputs(achieved_u, achieved_r, saturated)

    def _outputs(self, tau_u: float, tau_r: float, saturated: bool) -> dict[str, Value]:
        return {
            "rudder_angle_cmd": self._rudder,
            "propeller_rps_cmd": self._rps,
            "tau_u_achieved": float(tau_u),
            "tau_r_achieved": float(tau_r),
            "saturated": 1.0 if saturated else 0.0,
        }

    def summary(self) -> dict[str, Any]:
        return {"steps": self._steps, "saturated_steps": self._saturated_steps}
