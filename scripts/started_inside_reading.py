"""Rules 8 and 16 of stored suite runs re-read for targets that started inside R + R_i.

The ``colregs`` analysis judges such a target's Rules 8 and 16 by the range opening within
60 s alone (immediate danger, Rule 2(b)); runs judged before that reading stored a size and
timing verdict for them.  This counts, from the stored per-target fields, how many of those
verdicts the reading turns: a started-inside target whose range opened in time and that
failed Rule 8 or 16 (on size or timing; its range opening is in both verdicts already).

    python scripts/started_inside_reading.py results/suites_df9ef13/*
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path


def count(folders) -> dict:
    """Per rule: (passed, applicable, failed by a started-inside target whose range opened in time)."""
    totals = {rule: [0, 0, 0] for rule in ("rule_8", "rule_16")}
    for folder in folders:
        for summary in sorted(Path(folder).glob("runs/*/summary.json")):
            colregs = json.loads(summary.read_text()).get("analyses", {}).get("colregs") or {}
            for target in colregs.get("targets", []):
                for rule, total in totals.items():
                    if target.get(rule) in ("pass", "fail"):
                        total[1] += 1
                        total[0] += target[rule] == "pass"
                        total[2] += (target[rule] == "fail" and bool(target.get("started_inside"))
                                     and bool(target.get("range_opened_in_time")))
    return {rule: tuple(total) for rule, total in totals.items()}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folders", nargs="+", help="batch result folders (results/<batch>)")
    args = parser.parse_args(argv)
    missing = [folder for folder in args.folders if not Path(folder).is_dir()]
    if missing:
        parser.error(f"not a folder: {missing[0]}")
    for rule, (passed, applicable, turned) in count(args.folders).items():
        print(f"{rule}: {passed}/{applicable} as stored; {passed + turned}/{applicable} "
              f"({100 * (passed + turned) / max(applicable, 1):.1f} %) with started-inside targets "
              f"judged by the range opening ({turned} turned)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
