"""Write the late-manoeuvre suites: a target that turns towards the own ship late, and whether physics allows avoiding it.

Own ship: 18 kn on 000 deg from (0, 0) nm (scenarios/encounter_nmpc.toml).  Each target
sails clear at 18 kn and, 10 min into the run, turns ``TURN_DEG`` at 0.5 deg/s onto a
collision course (CPA 0) whose closest approach comes ``T`` minutes after the turn ends:
a head-on target, one crossing from starboard, one crossing from port, for T in
``TCPA_AFTER_TURN_MIN``.  The turn's side is the one whose pre-turn course was clear of
the own ship (the larger straight-line CPA).

Physics criterion, stated before any run: an encounter is *avoidable* when a ship that
starts turning one NMPC interval (20 s) after the target's turn ends, at the KCS model's
steady rate under its largest yaw moment (0.73 deg/s, models/KCS/readme.md), for at most
90 deg to either side, its speed falling linearly from 18 kn to 9 kn over 207 s (the
turning circle's time to 180 deg and its steady speed), would keep at least R + R_i = 1 nm
from the target sailing straight on.  Avoidable cases go into
``batches/late_manoeuvre.toml`` (separation judged; ``late_manoeuvre_ais.toml``: the same
through AIS and the tracker), the others into
``batches/late_manoeuvre_too_late.toml`` (reported only)::

    python scripts/late_manoeuvre_cases.py
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from orchestrator.geometry import KNOT, NM
from rhnc.encounters.target_motion import Manoeuvre, ScriptedTarget

REPO = Path(__file__).resolve().parents[1]
OWN_SPEED_KN = 18.0
TARGET_SPEED_KN = 18.0
TURN_AT_S = 600.0
TURN_DEG = 60.0
TURN_RATE_DEG_S = 0.5
TCPA_AFTER_TURN_MIN = (3.0, 5.0, 7.0, 10.0)
FINAL_RELATIVE_COURSE_DEG = {"head_on": 180.0, "crossing": -90.0, "crossing_port": 90.0}
SEPARATION_NM = 1.0
REACTION_S = 20.0
OWN_TURN_RATE_DEG_S = 0.73
OWN_SLOW_DOWN_S, OWN_TURN_SPEED_KN = 207.0, 9.0


def own_position(t: float) -> np.ndarray:
    return np.array([OWN_SPEED_KN * KNOT * t, 0.0])


def case(kind: str, tcpa_min: float) -> dict:
    """The target table and the turn's end for one case."""
    turn_s = TURN_DEG / TURN_RATE_DEG_S
    end = TURN_AT_S + turn_s
    final = math.radians(FINAL_RELATIVE_COURSE_DEG[kind])
    v1 = TARGET_SPEED_KN * KNOT * np.array([math.cos(final), math.sin(final)])
    p_end = own_position(end + tcpa_min * 60.0) - v1 * tcpa_min * 60.0
    best = None
    for side in (1.0, -1.0):
        before = final - side * math.radians(TURN_DEG)
        v0 = TARGET_SPEED_KN * KNOT * np.array([math.cos(before), math.sin(before)])
        arc = ScriptedTarget([0.0, 0.0], v0, [Manoeuvre(0.0, side * math.radians(TURN_DEG),
                                                       math.radians(TURN_RATE_DEG_S), None, 0.02)], 0.0, turn_s)
        start = p_end - arc.state(turn_s)[:2] - v0 * TURN_AT_S
        times = np.linspace(0.0, 3600.0, 3601)
        straight_cpa = min(np.hypot(*(start + v0 * t - own_position(t))) for t in times)
        if best is None or straight_cpa > best[0]:
            best = (straight_cpa, side, start, v0)
    straight_cpa, side, start, v0 = best
    target = {"start_nm": [round(float(v) / NM, 6) for v in start],
              "velocity_kn": [round(float(v) / KNOT, 6) for v in v0], "radius_nm": SEPARATION_NM,
              "manoeuvres": [{"at_s": TURN_AT_S, "course_change_deg": side * TURN_DEG,
                              "turn_rate_deg_s": TURN_RATE_DEG_S}]}
    return {"kind": kind, "tcpa_min": tcpa_min, "target": target, "end_s": end, "p_end": p_end, "v1": v1,
            "clear_cpa_nm": straight_cpa / NM}


def best_escape_nm(entry: dict) -> float:
    """Largest separation the own ship could keep by a hard turn to either side (module docstring)."""
    start = entry["end_s"] + REACTION_S
    best = 0.0
    for side in (1.0, -1.0):
        position, heading, t, closest = own_position(start), 0.0, start, math.inf
        while t < start + 1800.0:
            elapsed = t - start
            speed = (OWN_SPEED_KN - (OWN_SPEED_KN - OWN_TURN_SPEED_KN) * min(elapsed / OWN_SLOW_DOWN_S, 1.0)) * KNOT
            if abs(heading) < math.radians(90.0):
                heading += side * math.radians(OWN_TURN_RATE_DEG_S)
            position = position + speed * np.array([math.cos(heading), math.sin(heading)])
            t += 1.0
            target = entry["p_end"] + entry["v1"] * (t - entry["end_s"])
            closest = min(closest, float(np.hypot(*(position - target))))
        # before the turn starts the own ship sails straight: the range then counts too
        for s in np.arange(entry["end_s"], start, 1.0):
            target = entry["p_end"] + entry["v1"] * (s - entry["end_s"])
            closest = min(closest, float(np.hypot(*(own_position(s) - target))))
        best = max(best, closest / NM)
    return best


def toml_target(target: dict) -> str:
    manoeuvre = target["manoeuvres"][0]
    return (f"[{{ start_nm = {target['start_nm']}, velocity_kn = {target['velocity_kn']}, radius_nm = "
            f"{target['radius_nm']}, manoeuvres = [{{ at_s = {manoeuvre['at_s']}, course_change_deg = "
            f"{manoeuvre['course_change_deg']}, turn_rate_deg_s = {manoeuvre['turn_rate_deg_s']} }}] }}]")


HEADER = """# {title}
# Written by scripts/late_manoeuvre_cases.py (its docstring states the physics criterion);
# do not edit by hand.  Own ship 18 kn on 000 deg with the COLREG-aware NMPC of
# batches/imazu_nmpc_colregs.toml, on scenarios/{base}.toml.
# Each target sails clear, turns {turn:g} deg at 10 min onto a collision course and would meet
# the own ship T min after its turn ends.  R = 0, R_i = 1 nm.
#   python -m orchestrator batch batches/{name}.toml
# case: kind, T [min], clear CPA before the turn [nm], best escape by a hard turn [nm]
{cases}
[batch]
name = "{name}"
scenario = "../scenarios/{base}.toml"
description = "{title}"

[set]
"participants.ctrl.options.colregs" = true
"participants.ctrl.options.clearance_margin_nm" = 0.05
"participants.ctrl.options.clearance_margin_growth_kn" = 0.2
"outputs.figures" = ["track"]

[grid]
"participants.traffic.options.targets" = [
{targets}
]

[[acceptance]]
name = "finished"
metric = "status"
op = "=="
value = "finished"
{acceptance}
[report]
columns = ["analyses.encounter.min_clearance_nm", "analyses.colregs.side_correct", "analyses.colregs.verdict",
           "participants.ctrl.fallback_count"]
"""

SEPARATION = """
[[acceptance]]                       # physics allows it: minimum separation >= R + R_i
name = "separation >= R + R_i"
metric = "analyses.encounter.min_clearance_nm"
op = ">="
value = 0.0
"""


def main() -> int:
    entries = [case(kind, tcpa) for kind in FINAL_RELATIVE_COURSE_DEG for tcpa in TCPA_AFTER_TURN_MIN]
    for entry in entries:
        entry["escape_nm"] = best_escape_nm(entry)
    avoidable = lambda e: e["escape_nm"] >= SEPARATION_NM  # noqa: E731
    for name, title, keep, acceptance, base in (
            ("late_manoeuvre", "A target turning towards the own ship late, where physics allows avoiding it",
             avoidable, SEPARATION, "encounter_nmpc"),
            ("late_manoeuvre_ais", "The same late turns, the target seen through AIS and a tracker",
             avoidable, SEPARATION, "encounter_nmpc_ais"),
            ("late_manoeuvre_too_late", "A target turning towards the own ship too late to be avoided (reported)",
             lambda e: not avoidable(e), "", "encounter_nmpc")):
        chosen = [entry for entry in entries if keep(entry)]
        if not chosen:
            continue
        cases = "\n".join(f"#   {e['kind']}, T = {e['tcpa_min']:g}, clear CPA {e['clear_cpa_nm']:.2f}, escape "
                          f"{e['escape_nm']:.2f}" for e in chosen)
        targets = ",\n".join(f"  {toml_target(e['target'])}" for e in chosen)
        text = HEADER.format(title=title, turn=TURN_DEG, name=name, cases=cases, targets=targets,
                             acceptance=acceptance, base=base)
        (REPO / "batches" / f"{name}.toml").write_text(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
