"""Sea trials of a plant FMU for the identification: the standard manoeuvres a trial captain sails.

The plant is the scenario's ship FMU, stepped through its mapping (so in canonical SI
ports whatever its own names and units) with the weather inputs at zero.  Standard
manoeuvres are sailed from straight motion at the service speed:

- ``trim``: a PI speed controller finds the surge force holding the service speed;
- ``speed_steps``: surge force stepped to 130 %, 60 % and back to 100 % of that trim;
- ``turn_starboard``, ``turn_port``: turning circles at full helm either way;
- ``zigzag_10``: a 10/10 zig-zag, helm 10/35 of full switched at +-10 deg;
- ``zigzag_20``: a 20/20 zig-zag, held out to choose the model class and to validate.

These are the trials a captain runs, and they stay in the ship's real range: the helm
is a fraction of the largest yaw moment *at the service speed*, and like a rudder's it
falls with the square of the speed the ship keeps (:func:`helm_moment`), so a turning
circle does not spin a ship that has slowed in it under the moment its rudder gave at
full speed.  A manoeuvre is cut short, not failed, when the plant leaves the range the
model is for (non-finite states, the ship slower than a fifth of the service speed).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable

import numpy as np

from orchestrator.errors import ToolchainError
from orchestrator.geometry import KNOT
from rhnc.ship.ship_model import STATE_NAMES

#: A manoeuvre stops when the ship is slower than this fraction of the service speed.
SLOWEST_FRACTION = 0.2
WEATHER_PORTS = ("current_north", "current_east", "wind_speed", "wind_direction", "hs")
FIT_MANOEUVRES = ("speed_steps", "turn_starboard", "turn_port", "zigzag_10")
VALIDATION_MANOEUVRE = "zigzag_20"
SAMPLE_S = 1.0


@dataclasses.dataclass
class Record:
    """One sailed manoeuvre: times (n,), states (n, 6) and the inputs held after each sample (n, 2)."""

    name: str
    t: np.ndarray
    states: np.ndarray
    tau: np.ndarray


class PlantRunner:
    """Sails manoeuvres on a fresh instance of the plant FMU participant each time.

    Parameters
    ----------
    build : callable
        ``build(initial) -> FmuParticipant`` with ``initial`` the ``[initial]`` table
        (canonical units) the manoeuvre starts from.
    speed_mps : float
        Service speed the manoeuvres start at [m/s].
    """

    def __init__(self, build: Callable, speed_mps: float) -> None:
        self.build = build
        self.speed_mps = speed_mps
        self.notes: list[str] = []

    def sail(self, name: str, duration_s: float, policy: Callable[[float, np.ndarray], tuple[float, float]]) -> Record:
        plant = self.build({"x_m": 0.0, "y_m": 0.0, "psi_rad": 0.0, "u_mps": self.speed_mps})
        weather = {port: 0.0 for port in WEATHER_PORTS if port in plant.input_names}
        times, states, taus = [], [], []
        try:
            outputs = plant.setup(0.0, weather)
            steps = int(round(duration_s / SAMPLE_S))
            for k in range(steps + 1):
                t = k * SAMPLE_S
                state = np.array([outputs[port] for port in STATE_NAMES], dtype=float)
                if not np.all(np.isfinite(state)) or state[3] < SLOWEST_FRACTION * self.speed_mps:
                    self.notes.append(f"{name}: stopped after {t:.0f} s (the ship "
                                      + ("reported non-finite states)" if not np.all(np.isfinite(state)) else
                                         f"slowed to {state[3]:.2f} m/s)"))
                    break
                tau = policy(t, state)
                times.append(t)
                states.append(state)
                taus.append(tau)
                if k < steps:
                    outputs = plant.step(t, SAMPLE_S, {"tau_u": tau[0], "tau_r": tau[1], **weather})
        finally:
            plant.terminate()
        sailed = np.array(states)
        sailed[:, 2] = np.unwrap(sailed[:, 2])
        return Record(name, np.array(times), sailed, np.array(taus, dtype=float))


def helm_moment(helm: float, u: float, service_speed: float, tau_r_max: float) -> float:
    """Yaw moment [N m] of a helm order as a rudder gives it: ``helm`` (1 = hard over) of the
    largest moment at the service speed, falling with the square of the surge speed ``u``
    [m/s] (a rudder's lift goes with its inflow speed squared), never above the largest."""
    return helm * tau_r_max * min((max(u, 0.0) / service_speed) ** 2, 1.0)


def sail_manoeuvres(runner: PlantRunner, tau_u_max: float, tau_r_max: float) -> tuple[float, dict[str, Record]]:
    """The trim search and the standard manoeuvres; returns the trim surge force [N] and the records."""
    speed = runner.speed_mps
    gain = tau_u_max / 2.0                      # N per m/s: full force for 2 m/s of error
    state = {"integral": 0.5 * tau_u_max}

    def hold_speed(t, x):
        error = speed - x[3]
        state["integral"] = min(max(state["integral"] + gain / 100.0 * error * SAMPLE_S, 0.0), tau_u_max)
        return min(max(state["integral"] + gain * error, -tau_u_max), tau_u_max), 0.0

    trim_record = runner.sail("trim", 1500.0, hold_speed)
    trim = float(np.mean(trim_record.tau[trim_record.t >= 1200.0, 0]))
    if abs(trim_record.states[-1, 3] - speed) > 0.05 * speed:
        raise ToolchainError(f"identify: the plant does not hold {speed / KNOT:.1f} kn with a surge force up to "
                             f"{tau_u_max:g} N (reached {trim_record.states[-1, 3] / KNOT:.1f} kn)")

    def steps(t, x):
        factor = 1.0 if t < 60 else 1.3 if t < 660 else 0.6 if t < 1260 else 1.0
        return min(factor * trim, tau_u_max), 0.0

    def turn(sign):
        return lambda t, x: (trim, 0.0 if t < 60 else sign * helm_moment(1.0, x[3], speed, tau_r_max))

    def zigzag(angle_deg):
        helm = angle_deg / 35.0
        limit = math.radians(angle_deg)
        memory = {"sign": 1.0}

        def policy(t, x):
            if t < 60:
                return trim, 0.0
            if memory["sign"] > 0 and x[2] >= limit:
                memory["sign"] = -1.0
            elif memory["sign"] < 0 and x[2] <= -limit:
                memory["sign"] = 1.0
            return trim, memory["sign"] * helm_moment(helm, x[3], speed, tau_r_max)
        return policy

    records = {
        "speed_steps": runner.sail("speed_steps", 1860.0, steps),
        "turn_starboard": runner.sail("turn_starboard", 660.0, turn(1.0)),
        "turn_port": runner.sail("turn_port", 660.0, turn(-1.0)),
        "zigzag_10": runner.sail("zigzag_10", 900.0, zigzag(10.0)),
        VALIDATION_MANOEUVRE: runner.sail(VALIDATION_MANOEUVRE, 900.0, zigzag(20.0)),
    }
    return trim, records


