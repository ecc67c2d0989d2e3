"""Render issue 14's ninth-pass hair close-ups (docs/images/looks9_*.png): the eighth
pass's sets (``render_looks8_hair.py``) and the grey beard alone, framed on the chin.

    python bench/render_looks9_hair.py beard7|long7|buzz7|beard8|grey9 [--views front,side]
        [--size 360] [--samples 16] [--out DIR]

The docs pictures put the previous commit's render (left) beside this one's (right), at
the same samples. Needs the pip ``bpy`` module.
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))

import render_closeups as rc  # noqa: E402
import render_looks8_hair as looks8  # noqa: E402

SETS = {**looks8.SETS, "grey9": [({"gender": 1.0, "age": 1.0}, ("eyebrows", "beard-short"))]}

if __name__ == "__main__":
    rc.SETS.update(SETS)
    rc.HEAD_SETS = (*rc.HEAD_SETS, *SETS)
    for name in ("beard7", "beard8", "grey9"):  # the chin in the middle of the frame
        rc.FRAMING[name] = (0.22, 1.0, 1.8 - 0.2)
    rc.main()
