"""A seeded suite of drawn encounters (1-3 targets, fast and close ones) as traffic-situation files.

Written once by a fixed seed and kept beside the other suites, so that it is fixed before any
run of the controller is seen::

    python -m rhnc.encounters.drawn_suite scenarios/situations/drawn

The own ship sails north at ``OWN_SPEED_KN`` from (0, 0).  Each situation has one to three
targets (drawn uniformly), each sailing straight.  A target's kind is drawn uniformly from

``head_on``        course 180 deg +- 10 deg, 6-30 kn;
``crossing``       from starboard: course 270 deg +- 55 deg, 6-30 kn (the own ship gives way);
``crossing_port``  from port: course 090 deg +- 55 deg, 6-30 kn (the own ship stands on);
``overtaking``     the own ship overtakes: course 000 deg +- 15 deg, 3-12 kn;
``overtaken``      a faster ship comes up from astern: course 000 deg +- 15 deg, 24-30 kn,

and, in the ``wide`` recipe (``--recipe wide``; the default ``2027`` recipe drew the committed
suites ``drawn``, ``drawn2028`` and ``drawn2029`` and is kept as it was), also

``overtaken_quarter`` a faster ship converging from either quarter: course 000 deg +- 50 deg,
                  20-30 kn, its start bearing more than 22.5 deg abaft the beam (Rule 13's
                  words; a draw that starts further forward is drawn again),

then its closest approach if nobody manoeuvred (DCPA 0-0.9 nm, on a side drawn at random:
a risk of collision, inside R + R_i = 1 nm) and its start range (2-8 nm).  The start
follows from them (the relative track passes the CPA at the drawn DCPA).  The kind names the
geometry drawn; the encounter class the controller and the analysis give it comes from
:func:`rhnc.encounters.colregs.classify` and may differ near the rules' boundaries.

Limits, stated here and checked for every target: closing speed (the relative speed) at most
``MAX_CLOSING_KN``; time to the CPA at least ``MIN_TCPA_MIN`` (with less, no alteration a
ship can make opens a collision course to R + R_i: a 35 deg turn at 18 kn needs 2-3 min and
then moves the relative track by about 0.18 nm a minute) and at most ``MAX_TCPA_MIN`` (the
encounter happens within the voyage).  A draw outside them is drawn again.

In every ``INSIDE_EVERY``-th situation the first target starts inside R + R_i instead: range
0.3-0.95 nm, bearing, course (any) and speed (4-30 kn) drawn; the others are drawn as above.
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

import numpy as np

from rhnc.encounters.traffic_situation import situation_document

SEED = 2027
SITUATIONS = 170
OWN_SPEED_KN = 18.0
KINDS = ("head_on", "crossing", "crossing_port", "overtaking", "overtaken")
#: kind -> (nominal course [deg], course spread [deg], speed range [kn])
KIND_DRAWS = {"head_on": (180.0, 10.0, (6.0, 30.0)), "crossing": (270.0, 55.0, (6.0, 30.0)),
              "crossing_port": (90.0, 55.0, (6.0, 30.0)), "overtaking": (0.0, 15.0, (3.0, 12.0)),
              "overtaken": (0.0, 15.0, (24.0, 30.0)), "overtaken_quarter": (0.0, 50.0, (20.0, 30.0))}
#: recipe -> the kinds it draws from (uniformly)
RECIPES = {"2027": KINDS, "wide": KINDS + ("overtaken_quarter",)}
#: kind -> its start bearing's least angle from the own ship's bow [deg] (Rule 13: abaft the beam + 22.5)
KIND_ABAFT_DEG = {"overtaken_quarter": 112.5}
DCPA_NM = (0.0, 0.9)
START_RANGE_NM = (2.0, 8.0)
MAX_CLOSING_KN = 50.0
MIN_TCPA_MIN = 8.0
MAX_TCPA_MIN = 45.0
INSIDE_EVERY = 6
INSIDE_RANGE_NM = (0.3, 0.95)
INSIDE_SPEED_KN = (4.0, 30.0)


def _velocity(course_deg: float, speed_kn: float) -> np.ndarray:
    c = math.radians(course_deg)
    return speed_kn * np.array([math.cos(c), math.sin(c)])


def draw_target(rng: np.random.Generator, kinds: tuple[str, ...] = KINDS) -> dict:
    """One target on a collision course: kind, start [nm], course [deg], speed [kn], the draw's DCPA and TCPA."""
    own_velocity = _velocity(0.0, OWN_SPEED_KN)
    while True:
        kind = kinds[int(rng.integers(len(kinds)))]
        nominal, spread, speeds = KIND_DRAWS[kind]
        course = float((nominal + rng.uniform(-spread, spread)) % 360.0)
        speed = float(rng.uniform(*speeds))
        dcpa = float(rng.uniform(*DCPA_NM))
        side = 1.0 if rng.random() < 0.5 else -1.0
        start_range = float(rng.uniform(*START_RANGE_NM))
        relative = _velocity(course, speed) - own_velocity
        closing = float(np.hypot(*relative))
        if closing < 1e-6 or closing > MAX_CLOSING_KN:
            continue
        tcpa_h = math.sqrt(start_range ** 2 - dcpa ** 2) / closing
        if not MIN_TCPA_MIN <= tcpa_h * 60.0 <= MAX_TCPA_MIN:
            continue
        normal = side * np.array([-relative[1], relative[0]]) / closing
        start = dcpa * normal - relative * tcpa_h
        if abs(math.degrees(math.atan2(start[1], start[0]))) <= KIND_ABAFT_DEG.get(kind, 0.0):
            continue
        return {"kind": kind, "start_nm": (float(start[0]), float(start[1])), "course_deg": course,
                "speed_kn": speed, "dcpa_nm": dcpa, "tcpa_min": tcpa_h * 60.0}


def draw_inside_target(rng: np.random.Generator) -> dict:
    """A target that starts inside R + R_i (1 nm): range, bearing, course and speed drawn."""
    start_range = float(rng.uniform(*INSIDE_RANGE_NM))
    bearing = math.radians(float(rng.uniform(-180.0, 180.0)))
    return {"kind": "inside", "start_nm": (start_range * math.cos(bearing), start_range * math.sin(bearing)),
            "course_deg": float(rng.uniform(0.0, 360.0)), "speed_kn": float(rng.uniform(*INSIDE_SPEED_KN)),
            "dcpa_nm": None, "tcpa_min": None}


def draw_suite(seed: int = SEED, count: int = SITUATIONS, recipe: str = "2027") -> list[list[dict]]:
    """The targets of every situation (the own ship is not listed)."""
    kinds = RECIPES[recipe]
    rng = np.random.default_rng(seed)
    suite = []
    for number in range(1, count + 1):
        targets = int(rng.integers(1, 4))
        drawn = [draw_inside_target(rng)] if number % INSIDE_EVERY == 0 else []
        drawn += [draw_target(rng, kinds) for _ in range(targets - len(drawn))]
        suite.append(drawn)
    return suite


def _description(targets: list[dict]) -> str:
    parts = []
    for target in targets:
        text = f"{target['kind']} {target['speed_kn']:.1f} kn on {target['course_deg']:.0f} deg"
        if target["dcpa_nm"] is not None:
            text += f", DCPA {target['dcpa_nm']:.2f} nm in {target['tcpa_min']:.1f} min"
        else:
            text += f", starting {math.hypot(*target['start_nm']):.2f} nm off"
        parts.append(text)
    return "; ".join(parts)


def write_suite(folder, seed: int = SEED, count: int = SITUATIONS, recipe: str = "2027") -> list[Path]:
    """Write ``drawn_001.json`` ... into ``folder``."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    written = []
    own = {"start_nm": (0.0, 0.0), "course_deg": 0.0, "speed_kn": OWN_SPEED_KN}
    for number, targets in enumerate(draw_suite(seed, count, recipe), start=1):
        ships = [own] + [{key: target[key] for key in ("start_nm", "course_deg", "speed_kn")} for target in targets]
        document = situation_document(ships, f"drawn-{number:03d}",
                                      f"drawn encounter {number} (seed {seed}{'' if recipe == '2027' else f', recipe {recipe}'}): "
                                      f"{_description(targets)}")
        path = folder / f"drawn_{number:03d}.json"
        path.write_text(json.dumps(document, indent=2) + "\n")
        written.append(path)
    return written


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description="write the drawn encounter suite as traffic-situation JSON files")
    parser.add_argument("folder")
    parser.add_argument("--seed", type=int, default=SEED)
    parser.add_argument("--count", type=int, default=SITUATIONS)
    parser.add_argument("--recipe", choices=sorted(RECIPES), default="2027",
                        help="the kinds drawn: 2027 (the first suites') or wide (adds overtakers converging from a quarter)")
    args = parser.parse_args(argv)
    if args.count < 1:
        parser.error(f"--count must be at least 1, got {args.count}")
    write_suite(args.folder, args.seed, args.count, args.recipe)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
