"""Render the close-ups of issue 14's straps and cuffs (docs/images/looks10_straps_*.png,
looks10_cuffs_*.png): a woman's shoulders in the dress and the swimsuit, front and back;
a child's wrists in the longsleeve, the hoodie and the cardigan.

    python bench/render_looks10_straps.py straps --views front,back --samples 12 --size 400
    python bench/render_looks10_straps.py cuffs --views front --samples 12 --size 400

Needs the pip ``bpy`` module (Cycles on the CPU).
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import render_closeups as closeups  # noqa: E402

WOMAN = {"gender": 0.0, "age": 0.45}
CHILD = {"age": 0.15}
SETS = {
    "straps": [(WOMAN, ("dress",)), (WOMAN, ("swimsuit",))],
    "cuffs": [(CHILD, ("longsleeve",)), (CHILD, ("hoodie",)), (CHILD, ("tshirt", "cardigan"))],
}
# metres between bodies, frame height / width per body, aim height (m)
FRAMING = {"straps": (0.42, 0.8, 1.2), "cuffs": (0.8, 0.45, 0.8)}


def main() -> None:
    closeups.SETS.update(SETS)
    closeups.FRAMING.update(FRAMING)
    closeups.main()


if __name__ == "__main__":
    main()
