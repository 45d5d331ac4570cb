"""Could the own ship have opened the range to a target that started inside R + R_i within 60 s?

The `colregs` analysis asks that the range to a target starting inside R + R_i open at once:
its closest approach within 60 s of the start.  Whether any ship could do that depends on
the geometry and on the ship: a fast target closing on a ship that cannot stop or turn in a
minute keeps closing whatever the ship does.  This script answers it, per target, with the
ship's own equations of motion (the parameter set the plant and the NMPC share, calm water,
no disturbance; the target at its recorded constant velocity):

* manoeuvres: the nine corners of the input box, surge force -1, 0, +1 and yaw moment -1, 0,
  +1 times their bounds (full astern included: Rule 8(e) names reversing), each held for the
  whole window, and each held for 60 s with the yaw moment zero after it (a turn that goes on
  can bring the ship back towards the target);
* the range opens within 60 s under a manoeuvre when the range over the window (300 s,
  sampled every second) is smallest within the first 60 s.

The corners are the extreme manoeuvres, not every manoeuvre: a target for which none opens
the range is one no full-force manoeuvre held from the start can open, "not achievable"
below; it is a judgement by the ship's model, not a proof.  Reads the run folders of batch
results (``runs/*/summary.json`` and ``timeseries.parquet``) and prints one line per target
and the counts:

    python scripts/started_inside_feasibility.py results/suites/drawn_rhnc_colregs ...
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
import pandas as pd

from rhnc.ship.ship_model import ShipParameters, load_parameter_set, rk4_step

WINDOW_S = 300.0
OPEN_WITHIN_S = 60.0
DT_S = 1.0
OWN_STATE = ["ship.x", "ship.y", "ship.psi", "ship.u", "ship.v", "ship.r"]


def range_opening_s(own0: np.ndarray, target_xy: np.ndarray, target_v: np.ndarray, tau: np.ndarray,
                    params: ShipParameters, hold_s: float = WINDOW_S) -> float:
    """Time [s] of the closest approach within the window when the own ship, from ``own0``
    (x, y, psi, u, v, r), applies ``tau`` (fractions of the bounds) for ``hold_s`` and then the
    same surge force with no yaw moment; the target sails at ``target_v`` from ``target_xy``."""
    state = np.asarray(own0, dtype=float)
    times = np.arange(0.0, WINDOW_S + DT_S / 2, DT_S)
    ranges = np.empty(times.size)
    for k, t in enumerate(times):
        ranges[k] = np.hypot(*(target_xy + target_v * t - state[:2]))
        fraction = tau if t < hold_s else np.array([tau[0], 0.0])
        state = rk4_step(state, fraction * params.tau_max, DT_S, 1, params)
    return float(times[int(np.argmin(ranges))])


def achievable(own0: np.ndarray, target_xy: np.ndarray, target_v: np.ndarray, params: ShipParameters) -> bool:
    """Whether a corner manoeuvre (held, or held for 60 s) opens the range within 60 s."""
    for surge in (-1.0, 0.0, 1.0):
        for yaw in (-1.0, 0.0, 1.0):
            tau = np.array([surge, yaw])
            for hold in (WINDOW_S, OPEN_WITHIN_S):
                if range_opening_s(own0, target_xy, target_v, tau, params, hold) <= OPEN_WITHIN_S:
                    return True
    return False


def targets_of(run: Path, params: ShipParameters) -> list[dict]:
    summary = json.loads((run / "summary.json").read_text())
    targets = (summary.get("analyses", {}).get("colregs") or {}).get("targets") or []
    inside = [(k, target) for k, target in enumerate(targets) if target.get("started_inside")]
    if not inside:
        return []
    first = pd.read_parquet(run / "timeseries.parquet").iloc[0]
    own0 = first[OWN_STATE].to_numpy(dtype=float)
    rows = []
    for k, target in inside:
        index = target.get("obstacle", k)
        xy = np.array([first[f"traffic.obstacles[{index},0]"], first[f"traffic.obstacles[{index},1]"]])
        v = np.array([first[f"traffic.obstacles[{index},2]"], first[f"traffic.obstacles[{index},3]"]])
        rows.append({"run": run.name, "obstacle": index, "initial_range_nm": target["initial_range_nm"],
                     "opened": bool(target["range_opened_in_time"]), "opening_s": target["range_opening_s"],
                     "achievable": achievable(own0, xy, v, params),
                     "situation": summary.get("params", {}).get("situation", "")})
    return rows


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folders", nargs="+", type=Path)
    parser.add_argument("--parameter-set", default="default", help="the ship's parameter set (default: default)")
    args = parser.parse_args(argv)
    params = load_parameter_set(args.parameter_set)
    for folder in args.folders:
        rows = [row for run in sorted(folder.glob("runs/*")) if (run / "summary.json").exists()
                for row in targets_of(run, params)]
        for row in rows:
            print(f"{folder.name} {row['run']} {row['situation']} obstacle {row['obstacle']}: "  # noqa: T201
                  f"{row['initial_range_nm']:.2f} nm, opened after {row['opening_s']:.0f} s, "
                  f"achievable by a full-force manoeuvre: {'yes' if row['achievable'] else 'no'}")
        achievable_rows = [row for row in rows if row["achievable"]]
        print(f"{folder.name}: {len(rows)} targets started inside; opened within {OPEN_WITHIN_S:.0f} s: "  # noqa: T201
              f"{sum(row['opened'] for row in rows)}; achievable: {len(achievable_rows)}, of which opened: "
              f"{sum(row['opened'] for row in achievable_rows)}; not achievable: {len(rows) - len(achievable_rows)}, "
              f"of which opened: {sum(row['opened'] for row in rows if not row['achievable'])}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
