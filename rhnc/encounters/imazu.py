"""The 22 classic encounter situations of Imazu (1987) as maritime-schema traffic situations.

H. Imazu's benchmark set ("Computation of ship collision avoidance", 1987; as tabulated by
R. Sawada, K. Sato and T. Majima, J. Mar. Sci. Technol. 26 (2021) 509-524) places the own
ship and one to three target ships so that all of them would meet at one common point if
nobody manoeuvred: problems 1-4 have one target, 5-12 two and 13-22 three.  The own ship
sails north; each problem is given by the targets' courses (below, in degrees).  Every
ship sails at the own ship's speed except a target being overtaken, which sails at
``overtaken_speed_kn``.

In the tabulation we follow, problems 5 and 8 list the same courses (a head-on ship and
one crossing from starboard), and so do problems 15 and 22; we keep them as tabulated
rather than guess what the original figures distinguish.

The geometry is fixed by the meeting time ``tcpa_min``: each ship starts its own speed
times ``tcpa_min`` before the common point on its course.  :func:`write_situations` stores
the problems as maritime-schema JSON (positions in WGS-84 through the inverse of the
azimuthal equidistant projection about the own ship's start), so they run through the same
``[situations]`` import as DNV trafficgen's files::

    python -m rhnc.encounters.imazu scenarios/situations/imazu
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

from rhnc.encounters.traffic_situation import situation_document

#: Target courses [deg] per problem (own ship on 000 deg); "slow" marks a ship overtaken.
PROBLEMS: dict[int, tuple[tuple[float, bool], ...]] = {
    1: ((180.0, False),),
    2: ((270.0, False),),
    3: ((0.0, True),),
    4: ((45.0, False),),
    5: ((180.0, False), (270.0, False)),
    6: ((350.0, False), (315.0, False)),
    7: ((0.0, True), (315.0, False)),
    8: ((180.0, False), (270.0, False)),
    9: ((330.0, False), (270.0, False)),
    10: ((270.0, False), (15.0, False)),
    11: ((90.0, False), (330.0, False)),
    12: ((315.0, False), (350.0, False)),
    13: ((180.0, False), (10.0, False), (45.0, False)),
    14: ((350.0, False), (315.0, False), (270.0, False)),
    15: ((0.0, True), (315.0, False), (270.0, False)),
    16: ((45.0, False), (90.0, False), (270.0, False)),
    17: ((0.0, True), (10.0, False), (315.0, False)),
    18: ((225.0, False), (345.0, False), (330.0, False)),
    19: ((15.0, False), (345.0, False), (225.0, False)),
    20: ((0.0, True), (345.0, False), (270.0, False)),
    21: ((345.0, False), (15.0, False), (270.0, False)),
    22: ((0.0, True), (315.0, False), (270.0, False)),
}


def problem_geometry(number: int, speed_kn: float = 18.0, overtaken_speed_kn: float = 9.0,
                     tcpa_min: float = 25.0) -> list[dict]:
    """Ships of problem ``number`` in the plane (own ship first): start (north, east) [nm] relative
    to the own ship's start, course [deg], speed [kn]."""
    if number not in PROBLEMS:
        raise ValueError(f"Imazu problem {number} does not exist (1-22)")
    hours = tcpa_min / 60.0
    meeting = (speed_kn * hours, 0.0)
    ships = [{"start_nm": (0.0, 0.0), "course_deg": 0.0, "speed_kn": speed_kn}]
    for course, slow in PROBLEMS[number]:
        speed = overtaken_speed_kn if slow else speed_kn
        c = math.radians(course)
        start = (meeting[0] - speed * hours * math.cos(c), meeting[1] - speed * hours * math.sin(c))
        ships.append({"start_nm": start, "course_deg": course, "speed_kn": speed})
    return ships


def situation_json(number: int, latitude_deg: float = 57.0, longitude_deg: float = 3.0, **geometry) -> dict:
    """Problem ``number`` as a maritime-schema traffic situation (own ship at the given position)."""
    ships = problem_geometry(number, **geometry)
    courses = ", ".join(f"{entry['course_deg']:g}" for entry in ships[1:])
    return situation_document(ships, f"imazu-{number:02d}",
                              f"Imazu (1987) problem {number}: {len(ships) - 1} target(s) meeting the own ship at "
                              f"one point; courses {courses} deg", latitude_deg, longitude_deg)


def write_situations(folder, **geometry) -> list[Path]:
    """Write ``imazu_01.json`` ... ``imazu_22.json`` into ``folder``."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    written = []
    for number in PROBLEMS:
        path = folder / f"imazu_{number:02d}.json"
        path.write_text(json.dumps(situation_json(number, **geometry), indent=2) + "\n")
        written.append(path)
    return written


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description="write the 22 Imazu problems as traffic-situation JSON files")
    parser.add_argument("folder")
    parser.add_argument("--tcpa-min", type=float, default=25.0, help="time to the common meeting point [min]")
    parser.add_argument("--speed-kn", type=float, default=18.0, help="own ship's (and targets') speed [kn]")
    parser.add_argument("--overtaken-speed-kn", type=float, default=9.0, help="speed of a ship being overtaken")
    args = parser.parse_args(argv)
    write_situations(args.folder, tcpa_min=args.tcpa_min, speed_kn=args.speed_kn,
                     overtaken_speed_kn=args.overtaken_speed_kn)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
