"""Render issue 14's seventh-pass hair close-ups (docs/images/looks7_*.png): the short
beard young and old, long hair beside short hair of one colour, the grey buzz cut.

    python bench/render_looks7_hair.py beard|long|buzz [--views front,side] [--out DIR]

A thin wrapper over ``bench/render_closeups.py`` (same lights, camera and framing) with
the seventh pass's sets. Needs the pip ``bpy`` module.
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))

import render_closeups as rc  # noqa: E402

SETS = {
    "beard7": [
        ({"gender": 1.0, "age": 0.45}, ("eyebrows", "eyelashes", "hair-short", "beard-short")),
        ({"gender": 1.0, "age": 1.0}, ("eyebrows", "eyelashes", "beard-short")),
    ],
    "long7": [
        ({"gender": 0.0, "age": 0.45}, ("eyebrows", "eyelashes", "hair-long")),
        ({"gender": 0.0, "age": 0.45}, ("eyebrows", "eyelashes", "hair-bob")),
    ],
    "buzz7": [
        ({"gender": 1.0, "age": 0.95}, ("eyebrows", "eyelashes", "hair-buzz")),
        ({"gender": 1.0, "age": 0.5, "african": 1.0, "asian": 0.0, "caucasian": 0.0},
         ("eyebrows", "eyelashes", "hair-buzz")),
    ],
}  # fmt: skip

if __name__ == "__main__":
    rc.SETS.update(SETS)
    rc.HEAD_SETS = (*rc.HEAD_SETS, "beard7", "long7", "buzz7")
    rc.FRAMING["beard7"] = (0.22, 1.0, 1.8 - 0.2)
    rc.main()
