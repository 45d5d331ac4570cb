"""Write the trafficgen55 suite's inputs and, where trafficgen is installed, generate the suite.

The suite: every combination (with repetition, order ignored) of one, two and three targets
over the five encounter classes trafficgen places (head-on, crossing give-way, crossing
stand-on, overtaking give-way, overtaking stand-on): 5 + 15 + 35 = 55 situations. The own
ship sails 18 kn on 000 deg; every target meets it after a vector time drawn uniformly from
10-20 min; trafficgen draws the target's bearing, speed and ship from its own settings.

    python scripts/make_trafficgen55.py --inputs-only      # the definitions only (stdlib)
    python scripts/make_trafficgen55.py --seed 55          # and the situations (needs trafficgen 0.9.1)

trafficgen has no seed option; it draws with Python's ``random`` module, which this script
seeds before calling trafficgen's own command line (files are read in sorted order, so the
seed fixes the draws). A target trafficgen cannot place (its search gives up after 5 vector
times x 5 speeds whose start position passes its classification check) is dropped without an
error. The rule, fixed before any run of the suite: take the first seed from ``--seed`` upward
at which every target of every situation is placed; the script prints each seed it rejected
with the situations that came out short. Every situation is an independent draw, so this is
trafficgen's own rejection sampling with more attempts, not a choice among outcomes.
"""

import argparse
import itertools
import json
import random
import sys
from collections.abc import Callable
from pathlib import Path

SUITE = Path(__file__).resolve().parents[1] / "scenarios" / "situations" / "trafficgen55"

# (trafficgen's encounter type, short name in the titles)
CLASSES = [
    ("head-on", "head-on"),
    ("crossing-give-way", "crossing give-way"),
    ("crossing-stand-on", "crossing stand-on"),
    ("overtaking-give-way", "overtaking"),
    ("overtaking-stand-on", "overtaken"),
]
VECTOR_TIME_MIN = [10.0, 20.0]
OWN_SHIP_START = {"position": {"lat": 58.5, "lon": 4.0}, "sog": 18.0, "cog": 0.0, "heading": 0.0, "navStatus": "Under way using engine"}

OWN_SHIP = {
    "name": "RHNC own ship",
    "mmsi": 257550001,
    "shipType": "Cargo",
    "dimensions": {"length": 230.0, "width": 32.2, "height": 50.0, "draught": 10.8},
    "sogMax": 24.0,
}
TARGET_SHIPS = {
    "container_feeder": {
        "name": "container feeder",
        "mmsi": 257550011,
        "shipType": "Cargo",
        "dimensions": {"length": 172.0, "width": 27.4, "height": 42.0, "draught": 9.5},
        "sogMin": 8.0,
        "sogMax": 24.0,
    },
    "ropax_ferry": {
        "name": "ro-pax ferry",
        "mmsi": 257550012,
        "shipType": "Passenger",
        "dimensions": {"length": 186.0, "width": 28.6, "height": 45.0, "draught": 6.8},
        "sogMin": 10.0,
        "sogMax": 27.0,
    },
    "car_carrier": {
        "name": "car carrier",
        "mmsi": 257550013,
        "shipType": "Cargo",
        "dimensions": {"length": 200.0, "width": 32.3, "height": 46.0, "draught": 9.0},
        "sogMin": 8.0,
        "sogMax": 22.0,
    },
}


def situation_definitions() -> list[dict]:
    """The 55 situation inputs, numbered: one target (1-5), two (6-20), three (21-55)."""
    combos = [c for n in (1, 2, 3) for c in itertools.combinations_with_replacement(range(len(CLASSES)), n)]
    definitions = []
    for number, combo in enumerate(combos, start=1):
        names = [CLASSES[i][1] for i in combo]
        definitions.append(
            {
                "title": f"tg55-{number:02d}: {', '.join(names)}",
                "description": f"{len(combo)} target(s): {', '.join(names)}; own ship 18 kn on 000 deg, "
                f"each target meets it after {VECTOR_TIME_MIN[0]:g}-{VECTOR_TIME_MIN[1]:g} min",
                "numSituations": 1,
                "ownShip": {"initial": OWN_SHIP_START},
                "encounters": [{"desiredEncounterType": CLASSES[i][0], "vectorTime": VECTOR_TIME_MIN} for i in combo],
            }
        )
    return definitions


def write_inputs(suite: Path) -> None:
    """Write own ship, target ships and the 55 situation definitions under ``suite/input/``."""
    inputs = suite / "input"
    (inputs / "situations").mkdir(parents=True, exist_ok=True)
    (inputs / "target_ships").mkdir(parents=True, exist_ok=True)
    (inputs / "own_ship.json").write_text(json.dumps(OWN_SHIP, indent=2) + "\n")
    for stem, ship in TARGET_SHIPS.items():
        (inputs / "target_ships" / f"{stem}.json").write_text(json.dumps(ship, indent=2) + "\n")
    for number, definition in enumerate(situation_definitions(), start=1):
        path = inputs / "situations" / f"tg55_{number:02d}.json"
        path.write_text(json.dumps(definition, indent=2) + "\n")


def generate(trafficgen_main: Callable, suite: Path, seed: int) -> list[str]:
    """Run trafficgen gen-situation on the inputs with ``random`` seeded; return short situations."""
    inputs = suite / "input"
    random.seed(seed)
    trafficgen_main(
        ["gen-situation", "-s", str(inputs / "situations"), "-os", str(inputs / "own_ship.json"), "-t", str(inputs / "target_ships"), "-o", str(suite)],
        standalone_mode=False,
    )
    short = []
    for number, definition in enumerate(situation_definitions(), start=1):
        written = json.loads((suite / f"traffic_situation_{number:02d}.json").read_text())
        asked, placed = len(definition["encounters"]), len(written.get("targetShips") or [])
        if placed != asked:
            short.append(f"traffic_situation_{number:02d}.json ({definition['title']}): {placed} of {asked} targets")
    return short


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=55, help="seed of Python's random module for trafficgen")
    parser.add_argument("--attempts", type=int, default=20, help="seeds to try from --seed upward")
    parser.add_argument("--folder", type=Path, default=SUITE, help="the suite's folder (its inputs in input/)")
    parser.add_argument("--inputs-only", action="store_true", help="write the definitions, do not run trafficgen")
    args = parser.parse_args(argv)
    if args.attempts < 1:
        print(f"make_trafficgen55: --attempts {args.attempts}: give at least 1 seed to try", file=sys.stderr)
        return 2
    trafficgen_main = None
    if not args.inputs_only:
        try:
            from trafficgen.cli import main as trafficgen_main  # not a dependency of this package
        except ImportError:
            print("make_trafficgen55: trafficgen is not installed (pip install trafficgen==0.9.1), or give --inputs-only", file=sys.stderr)
            return 2
    write_inputs(args.folder)
    if trafficgen_main is None:
        return 0
    for seed in range(args.seed, args.seed + args.attempts):
        short = generate(trafficgen_main, args.folder, seed)
        for line in short:
            print(f"seed {seed}: trafficgen could not place every target: {line}")
        if not short:
            print(f"seed {seed}: every target placed; the suite is in {args.folder}")
            return 0
    print(f"make_trafficgen55: no seed in {args.seed}..{args.seed + args.attempts - 1} placed every target", file=sys.stderr)
    return 1


if __name__ == "__main__":
    sys.exit(main())
