"""Goal monitor: distance to the destination and arrival, for stop conditions and acceptance."""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from orchestrator.errors import ModelError
from orchestrator.geometry import NM
from orchestrator.participant import BuildContext, Participant, Value, check_options
from orchestrator.toml_input import PairNm, Positive, TomlTable
from rhnc.chart.positions import projected_options


class GoalOptions(TomlTable):
    """Options of ``type = "goal"``."""

    goal_nm: PairNm
    arrival_radius_nm: Positive = 0.5
    chart: str | None = None  # only to project goal_deg


#: Options a scenario may give: the model's, and the goal in latitude and longitude.
GOAL_OPTIONS = (*GoalOptions.model_fields, "goal_deg")


class GoalMonitor(Participant):
    """Watches the ship's position against a destination.

    Options: ``goal_nm = [north, east]`` (or ``goal_deg = [latitude, longitude]`` with
    ``chart``, the chart file whose projection puts it in the plane), ``arrival_radius_nm``
    (default 0.5).
    Inputs: ``x``, ``y`` [m].  Outputs: ``goal_distance_m`` [m] and ``arrived`` (1.0 once
    the ship has come within the arrival radius, and from then on).
    """

    OPTIONS = GOAL_OPTIONS

    def __init__(self, name: str, goal_m: tuple[float, float], radius_m: float) -> None:
        super().__init__(name)
        self.goal_m = goal_m
        self.radius_m = radius_m
        self.arrival_time_s: float | None = None

    @classmethod
    def from_options(cls, name: str, options: Mapping[str, Any], context: BuildContext) -> "GoalMonitor":
        options = projected_options(options, context.where, context.scenario_dir, names=("goal",))
        checked = check_options(GoalOptions, options, context.where)
        return cls(name, (checked.goal_nm[0] * NM, checked.goal_nm[1] * NM), checked.arrival_radius_nm * NM)

    input_names = property(lambda self: ("x", "y"))
    output_names = property(lambda self: ("goal_distance_m", "arrived"))

    def setup(self, start_time: float, inputs: Mapping[str, Value]) -> dict[str, Value]:
        self.arrival_time_s = None
        return self._observe(start_time, inputs) if "x" in inputs and "y" in inputs else {}

    def step(self, time: float, step_size: float, inputs: Mapping[str, Value]) -> dict[str, Value]:
        if "x" not in inputs or "y" not in inputs:
            raise ModelError(f"participant '{self.name}': inputs 'x' and 'y' must be connected")
        return self._observe(time, inputs)

    def _observe(self, time: float, inputs: Mapping[str, Value]) -> dict[str, Value]:
        distance = math.hypot(float(inputs["x"]) - self.goal_m[0], float(inputs["y"]) - self.goal_m[1])
        if distance <= self.radius_m and self.arrival_time_s is None:
            self.arrival_time_s = time
        return {"goal_distance_m": distance, "arrived": 1.0 if self.arrival_time_s is not None else 0.0}

    def summary(self) -> dict[str, Any]:
        return {"arrived": self.arrival_time_s is not None, "arrival_time_s": self.arrival_time_s}
