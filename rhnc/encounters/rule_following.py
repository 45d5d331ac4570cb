"""A target ship that follows the rules of the road itself: a simple reactive COLREG agent.

Each decision (every step of the traffic participant) the target classifies every other
ship (the own ship and the other targets) from its own view, with the same classes and
hysteresis as the own ship's controller and the ``colregs`` analysis
(:class:`rhnc.encounters.colregs.EncounterTracker`), and then:

* **gives way** (Rules 14, 15, 13: head-on, a ship crossing from its starboard side,
  overtaking) once the risk is high: the closest approach at the present velocities is
  below ``SAFE_CPA_FACTOR`` times the separation and at most ``give_way_tcpa_s`` ahead.
  It alters ``alteration_deg`` to starboard from its base course (Rule 8: large enough to
  be readily apparent);
* **stands on** (Rule 17(a)) otherwise, keeping course and speed, until the give-way
  ship's action is clearly not enough (Rule 17(b), the one definition
  :func:`rhnc.encounters.colregs.stand_on_must_act` the controller and the analysis use);
  then it too alters ``alteration_deg`` to starboard (Rule 17(c): not to port for a ship on
  its port side);
* returns to its base course once every ship it acted for is past (TCPA <= 0).

Its separation from another ship is the larger of the two hazard radii (the own ship's
R = 0 in the suites, so the target keeps its R_i from it).  Course changes at
``turn_rate_deg_s``, speed is constant.  The motion is integrated at 1 s steps.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from orchestrator.errors import ScenarioError
from orchestrator.geometry import DEG, NM, wrap_angle
from orchestrator.participant import is_finite_number
from rhnc.encounters.colregs import EncounterTracker, stand_on_must_act

#: Classes in which the target is the give-way ship, and in which it stands on.
GIVE_WAY = ("head_on", "crossing_give_way", "overtaking")
STAND_ON = ("crossing_stand_on", "overtaken")
#: A give-way target acts when the predicted CPA is below this many separations.
SAFE_CPA_FACTOR = 1.5
#: Risk of collision for the classification: CPA below 2 nm within 30 min (the analysis').
RISK_CPA_M = 2.0 * NM
RISK_TCPA_S = 30.0 * 60.0
INTEGRATION_STEP_S = 1.0
RULE_KEYS = ("behaviour", "alteration_deg", "give_way_tcpa_s", "turn_rate_deg_s")


class RuleFollowingTarget:
    """A target that gives way or stands on by the rules (module docstring); SI inside.

    Parameters
    ----------
    start_m, velocity_mps : (2,) arrays
        Position [m] and velocity (north, east) [m/s] at the start; the velocity's
        direction is the base course.
    radius_m : float
        Hazard radius [m].
    alteration_deg, give_way_tcpa_s, turn_rate_deg_s : float
        Alteration to starboard [deg], time to CPA at which a give-way ship acts [s], turn rate [deg/s].
    """

    reactive = True

    def __init__(self, start_m, velocity_mps, radius_m: float, alteration_deg: float = 40.0,
                 give_way_tcpa_s: float = 900.0, turn_rate_deg_s: float = 0.5) -> None:
        self.radius_m = float(radius_m)
        self.alteration_rad = alteration_deg * DEG
        self.give_way_tcpa_s = give_way_tcpa_s
        self.turn_rate_rad_s = turn_rate_deg_s * DEG
        self.start_m = np.asarray(start_m, dtype=float)
        self.start_velocity = np.asarray(velocity_mps, dtype=float)
        self.reset()

    def reset(self) -> None:
        self.position = self.start_m.copy()
        self.base_course = math.atan2(self.start_velocity[1], self.start_velocity[0])
        self.course = self.base_course
        self.commanded_course = self.base_course
        self.speed = float(np.hypot(*self.start_velocity))
        self.time_s = 0.0
        self.tracker = EncounterTracker(RISK_CPA_M, RISK_TCPA_S)
        self.acting: set[int] = set()
        self.actions: list[dict[str, Any]] = []

    @property
    def velocity(self) -> np.ndarray:
        return self.speed * np.array([math.cos(self.course), math.sin(self.course)])

    def state(self, elapsed_s: float) -> np.ndarray:
        """Row (x, y, vx, vy, radius) at ``elapsed_s``: the last integrated state, dead reckoned."""
        position = self.position + self.velocity * (elapsed_s - self.time_s)
        return np.r_[position, self.velocity, self.radius_m]

    def advance(self, elapsed_s: float) -> None:
        """Sail on the commanded course up to ``elapsed_s`` [s]."""
        while self.time_s < elapsed_s - 1e-9:
            dt = min(INTEGRATION_STEP_S, elapsed_s - self.time_s)
            before = self.velocity
            change = float(wrap_angle(self.commanded_course - self.course))
            self.course += float(np.clip(change, -self.turn_rate_rad_s * dt, self.turn_rate_rad_s * dt))
            self.position = self.position + 0.5 * (before + self.velocity) * dt
            self.time_s += dt

    def decide(self, others: np.ndarray) -> None:
        """Choose the course from the other ships' rows (x, y, vx, vy, radius) at the present time."""
        encounters = self.tracker.update((float(self.position[0]), float(self.position[1])), self.course, self.speed, others)
        for index, encounter in enumerate(encounters):
            separation = max(self.radius_m, float(others[index, 4]))
            if index in self.acting:
                if encounter.tcpa_s <= 0.0:
                    self.acting.discard(index)
                continue
            acts = False
            if encounter.encounter_class in GIVE_WAY:
                acts = (encounter.cpa_m < SAFE_CPA_FACTOR * separation
                        and 0.0 < encounter.tcpa_s <= self.give_way_tcpa_s)
            elif encounter.encounter_class in STAND_ON:
                acts = stand_on_must_act(encounter.cpa_m, encounter.tcpa_s, encounter.range_m, separation)
            if acts:
                self.acting.add(index)
                self.actions.append({"time_s": self.time_s, "ship": index, "class": encounter.encounter_class,
                                     "cpa_nm": encounter.cpa_m / NM, "tcpa_s": encounter.tcpa_s})
        self.commanded_course = self.base_course + (self.alteration_rad if self.acting else 0.0)


def rule_following_target(entry: Mapping[str, Any], start_m, velocity_mps, radius_m: float,
                          where: str) -> RuleFollowingTarget:
    """A :class:`RuleFollowingTarget` from a target table with ``behaviour = "rules"``."""
    if entry.get("behaviour") != "rules":
        raise ScenarioError(f"{where}: 'behaviour' must be \"rules\" (a target that gives way or stands on "
                            f"by COLREG Rules 14-17), got {entry.get('behaviour')!r}")
    values = {}
    for key, default, low, high in (("alteration_deg", 40.0, 5.0, 90.0), ("give_way_tcpa_s", 900.0, 0.0, 7200.0),
                                    ("turn_rate_deg_s", 0.5, 0.01, 10.0)):
        value = entry.get(key, default)
        if not is_finite_number(value) or not low <= value <= high:
            raise ScenarioError(f"{where}: '{key}' must be a number within [{low:g}, {high:g}], got {value!r}")
        values[key] = float(value)
    if not np.hypot(*velocity_mps) > 0:
        raise ScenarioError(f"{where}: a target with 'behaviour' = \"rules\" needs a non-zero 'velocity_kn'")
    return RuleFollowingTarget(start_m, velocity_mps, radius_m, **values)
