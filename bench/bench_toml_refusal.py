"""How long reading an input file takes for the hardest texts below the size limit.

Each case is a text built to cost the TOML parser as much as possible per byte: keys of
many dotted parts (quadratic in the parser), many tables, keys or array items, long
strings.  :func:`orchestrator.toml_input.read_toml` either refuses it with one line (the
pre-scan's limits, before the parser sees it) or parses it; either way the time to the
answer is printed, the slowest last.  ``--before`` times Python's parser alone on the same
texts (what reading cost without the pre-scan).

    python bench/bench_toml_refusal.py [--before]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
import tomllib
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from orchestrator.errors import ScenarioError  # noqa: E402
from orchestrator.toml_input import MAX_FILE_BYTES, MAX_ITEMS, MAX_NESTING, read_toml  # noqa: E402

LIMIT = MAX_FILE_BYTES - 1024


def cases() -> dict[str, str]:
    """The texts, by what they hold (each below the size limit)."""
    deep_part = ".".join(["k"] * (MAX_NESTING - 1))  # with the last part: the most the pre-scan lets through
    return {
        "one dotted header of 100,000 parts (200 kB)": "[" + ".".join(["a"] * 100_000) + "]\n",
        "one dotted key of 200,000 parts (400 kB)": "x." * 200_000 + "y = 1\n",
        f"{MAX_ITEMS - 1} headers of {MAX_NESTING} parts": "".join(f"[{deep_part}.t{i}]\n"
                                                                    for i in range(MAX_ITEMS - 1)),
        f"{MAX_ITEMS - 1} keys of {MAX_NESTING} parts": "".join(f"{deep_part}.k{i} = 1\n"
                                                                 for i in range(MAX_ITEMS - 1)),
        f"an array of {MAX_ITEMS - 2} numbers": "x = [" + "1," * (MAX_ITEMS - 2) + "]\n",
        "16 MiB of tables (over the item limit)": "".join(f"[t.k{i}]\n" for i in range(LIMIT // 12))[:LIMIT],
        "16 MiB array of numbers (over the item limit)": ("x = [" + "1," * (LIMIT // 2))[:LIMIT],
        "a 16 MiB string": 'x = "' + "a" * (LIMIT - 10) + '"\n',
        "a 16 MiB comment": "#" * LIMIT + "\n",
        "an integer of 5,000 digits": "x = " + "1" * 5000 + "\n",
    }


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--before", action="store_true", help="also time tomllib alone (slow: minutes)")
    args = parser.parse_args(argv)
    rows = []
    with tempfile.TemporaryDirectory() as folder:
        for name, text in cases().items():
            path = Path(folder) / "case.toml"
            path.write_text(text)
            start = time.perf_counter()
            try:
                read_toml(path, "scenario")
                answer = "parsed"
            except ScenarioError as exc:
                answer = "refused: " + str(exc).split(": ", 1)[1][:70]
            seconds = time.perf_counter() - start
            before = ""
            if args.before:
                start = time.perf_counter()
                try:
                    tomllib.loads(text)
                except (tomllib.TOMLDecodeError, ValueError, RecursionError):
                    pass
                before = f", tomllib alone {time.perf_counter() - start:.2f} s"
            rows.append((seconds, f"{seconds:6.2f} s  {name} ({len(text) / 1e6:.1f} MB): {answer}{before}"))
            print(rows[-1][1], flush=True)
    print(f"slowest: {max(rows)[1].strip()}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
