"""Render issue 14's tenth-pass beard close-ups (docs/images/looks10_beard_*.png): the
chin and cheeks of a young man with a brown short beard (``brown10``) and of the grey old
man (``grey10``, looks9's ``grey9``), framed tighter than looks9 (16 cm across), so the
beard's cheek line and the undercoat's texture show.

    python bench/render_looks10_beard.py brown10|grey10 [--views front,side]
        [--size 360] [--samples 16] [--out DIR] [--name NAME]

The docs pictures put the previous commit's render (left) beside this one's (right), at
the same samples. Needs the pip ``bpy`` module.
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))

import render_closeups as rc  # noqa: E402

SETS = {
    "brown10": [({"gender": 1.0, "age": 0.45},
                 ("eyebrows", "eyelashes", "hair-short", "beard-short"))],
    "grey10": [({"gender": 1.0, "age": 1.0}, ("eyebrows", "beard-short"))],
}  # fmt: skip

if __name__ == "__main__":
    rc.SETS.update(SETS)
    rc.HEAD_SETS = (*rc.HEAD_SETS, *SETS)
    for name in SETS:  # chin and cheeks fill the frame
        rc.FRAMING[name] = (0.16, 1.0, 1.8 - 0.17)
    rc.main()
