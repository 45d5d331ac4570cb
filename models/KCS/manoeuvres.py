"""Standard manoeuvres of the KCS FMU (turning circle, 10/10 zig-zag) for models/KCS/readme.md.

Run ``python models/KCS/manoeuvres.py [set]`` from the repository root; it builds the FMU
if needed (orchestrator.fmu_build.ensure_built), steps it through fmpy at 1 s and prints the
figures. The plant has no rudder: both manoeuvres command the yaw moment tau_r directly.
The manoeuvre figures (advance, transfer, tactical and steady diameter, overshoots) are those
of the scenarios' analyses, :mod:`rhnc.ship.manoeuvres`; only the figures it does not define
(time to 180 deg, the steady turn's speed, yaw rate and drift, the zig-zag period) are
computed here.
"""

from __future__ import annotations

import argparse
import shutil
import sys
import tempfile
import tomllib

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave

from orchestrator.fmu_build import MODELS_DIR, ensure_built
from orchestrator.geometry import KNOT
from rhnc.ship import manoeuvres

APPROACH_SPEED = 18 * KNOT  # m/s


class Ship:
    """The KCS FMU at 18 kn on heading 0, parameters from one set of parameter_sets.toml."""

    def __init__(self, parameter_set: str, step: float = 1.0):
        with open(MODELS_DIR / "KCS" / "parameter_sets.toml", "rb") as f:
            self.p = tomllib.load(f)[parameter_set]
        fmu = ensure_built("KCS")
        self.unzip = tempfile.mkdtemp(prefix="kcs_manoeuvre_")
        md = read_model_description(str(fmu))
        self.vr = {v.name: v.valueReference for v in md.modelVariables}
        self.fmu = FMU2Slave(guid=md.guid, unzipDirectory=extract(str(fmu), self.unzip),
                             modelIdentifier="KCS")
        self.fmu.instantiate()
        self.fmu.setupExperiment(startTime=0.0)
        self.fmu.enterInitializationMode()
        start = {k: v for k, v in self.p.items() if k not in ("description", "plant_fmu", "plant_guid")}
        start["u0"] = APPROACH_SPEED
        self.set(**start)
        self.fmu.exitInitializationMode()
        self.t, self.step = 0.0, step
        self.cruise_thrust = self.p["d11"] * APPROACH_SPEED  # holds 18 kn on a straight course

    def set(self, **values: float) -> None:
        self.fmu.setReal([self.vr[k] for k in values], list(values.values()))

    def advance(self, tau_r: float) -> dict[str, float]:
        self.set(tau_u=self.cruise_thrust, tau_r=tau_r)
        self.fmu.doStep(self.t, self.step)
        self.t += self.step
        names = ["x", "y", "psi", "u", "v", "r"]
        return dict(zip(names, self.fmu.getReal([self.vr[n] for n in names])))

    def close(self) -> None:
        self.fmu.terminate()
        self.fmu.freeInstance()
        shutil.rmtree(self.unzip, ignore_errors=True)


def turning_circle(parameter_set: str) -> dict[str, float]:
    """Full starboard yaw moment from a straight run at 18 kn; lengths in ship lengths."""
    ship = Ship(parameter_set)
    lpp = ship.p["lpp"]
    heading = 0.0  # the moment applies from t = 0, in straight motion at 18 kn on heading 0
    states = [{"x": 0.0, "y": 0.0, "psi": 0.0, "u": APPROACH_SPEED, "v": 0.0, "r": 0.0, "t": 0.0}]
    while heading < 4 * np.pi and ship.t < 4 * 3600:
        s = ship.advance(ship.p["tau_r_max"])
        heading += np.angle(np.exp(1j * (s["psi"] - states[-1]["psi"])))
        states.append({**s, "t": ship.t})
    ship.close()
    t, x, y, psi = (np.array([s[k] for s in states]) for k in ("t", "x", "y", "psi"))
    figures = manoeuvres.turning_circle(t, x, y, psi, execute_s=0.0, length_m=lpp)
    change = np.abs(np.unwrap(psi))
    last = states[-1]
    return {
        "advance_L": figures["advance_L"],
        "transfer_L": figures["transfer_L"],
        "tactical_diameter_L": figures["tactical_diameter_L"],
        "steady_diameter_L": figures["steady_diameter_L"],
        "time_to_180_s": float(np.interp(np.pi, change, t)),
        "steady_speed_kn": np.hypot(last["u"], last["v"]) / KNOT,
        "steady_yaw_rate_deg_s": np.degrees(last["r"]),
        "drift_angle_deg": np.degrees(np.arctan2(-last["v"], last["u"])),
    }


def zigzag(parameter_set: str, angle_deg: float = 10.0) -> dict[str, float]:
    """angle/angle zig-zag with the yaw moment (+-angle/35 of tau_r_max, the moment of a
    rudder at `angle` if moment is proportional to rudder angle up to 35 deg) switched when
    the heading passes +-angle. Overshoots in degrees, times in seconds."""
    ship = Ship(parameter_set)
    moment = ship.p["tau_r_max"] * angle_deg / 35.0
    limit = np.radians(angle_deg)
    sign, switches = 1.0, []
    t, psi, steering = [0.0], [0.0], [moment]
    while len(switches) < 5 and ship.t < 3 * 3600:
        s = ship.advance(sign * moment)
        if sign * s["psi"] >= limit:  # heading reached +-angle: reverse the moment
            switches.append(ship.t)
            sign = -sign
        t.append(ship.t)
        psi.append(s["psi"])
        steering.append(sign * moment)
    ship.close()
    figures = manoeuvres.zigzag(np.array(t), np.array(psi), np.array(steering), execute_s=0.0)
    return {
        "first_overshoot_deg": figures["first_overshoot_deg"],
        "second_overshoot_deg": figures["second_overshoot_deg"],
        "time_to_first_switch_s": switches[0],
        "period_s": switches[3] - switches[1] if len(switches) > 3 else float("nan"),
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("parameter_set", nargs="?", default="default")
    args = parser.parse_args(argv)
    for name, result in (("turning circle", turning_circle(args.parameter_set)),
                         ("10/10 zig-zag", zigzag(args.parameter_set))):
        sys.stdout.write(f"{name} ({args.parameter_set}):\n")
        for key, value in result.items():
            sys.stdout.write(f"  {key:24s} {value:10.2f}\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
