"""Render issue 14's eighth-pass hair close-ups (docs/images/looks8_*.png): the seventh
pass's sets (``render_looks7_hair.py``: the short beard young and old, long hair beside a
bob, the buzz cut on two men) and one bearded young man close up.

    python bench/render_looks8_hair.py beard7|long7|buzz7|beard8 [--views front,side]
        [--size 360] [--samples 16] [--out DIR]

The docs pictures put the previous commit's render (left) beside this one's (right), at
the same samples: Cycles denoises from 16 samples up, so compare like with like. Needs the
pip ``bpy`` module.
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))

import render_closeups as rc  # noqa: E402
import render_looks7_hair as looks7  # noqa: E402

CLOSE = ("eyebrows", "eyelashes", "hair-short", "beard-short")
SETS = {**looks7.SETS, "beard8": [({"gender": 1.0, "age": 0.45}, CLOSE)]}

if __name__ == "__main__":
    rc.SETS.update(SETS)
    rc.HEAD_SETS = (*rc.HEAD_SETS, *SETS)
    for name in ("beard7", "beard8"):  # the chin in the middle of the frame
        rc.FRAMING[name] = (0.22, 1.0, 1.8 - 0.2)
    rc.main()
