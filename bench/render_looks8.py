"""Render the close-ups of issue 14's eighth garment pass (docs/images/looks8_*.png): skirt
and dress hems mid-stride, the hoodie under the arm and the open jacket's front, with
``render_closeups``' cameras.

    python bench/render_looks8.py hems --views front,back --walk --frame 6 --samples 12
    python bench/render_looks8.py armpit --views front,under
    python bench/render_looks8.py opening --views front,side
    python bench/render_looks8.py necks --views front      # band edges: necks, armholes

Needs the pip ``bpy`` module (Cycles on the CPU).
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import render_closeups as closeups  # noqa: E402
import render_looks7 as looks7  # noqa: E402

SETS = {
    "hems": looks7.SETS["hems"],
    "armpit": [  # the hoodie under the arm, man and woman
        ({"gender": 1.0, "age": 0.3, "muscle": 0.8}, ("hair-buzz", "hoodie", "jeans")),
        ({"gender": 0.0, "age": 0.4}, ("hair-bob", "hoodie", "jeans")),
    ],
    "opening": [  # the open jacket's front opening
        ({"gender": 1.0, "age": 0.5}, ("jacket", "tshirt", "jeans")),
        ({"gender": 0.0, "age": 0.45}, ("jacket", "longsleeve", "trousers")),
    ],
    "necks": [  # band edges at the neck and armholes (lone band patches dropped)
        ({"gender": 0.0, "age": 0.45}, ("longsleeve", "jeans")),
        ({"gender": 1.0, "age": 0.5}, ("tshirt", "jeans")),
        ({"gender": 0.0, "age": 0.3}, ("dress",)),
        ({"gender": 0.0, "age": 0.6}, ("cardigan", "tshirt", "skirt")),
    ],
}  # fmt: skip
FRAMING = {"hems": looks7.FRAMING["hems"], "armpit": (0.9, 0.6, 1.05),
           "opening": (1.1, 0.8, 1.05), "necks": (0.8, 0.8, 1.15)}  # fmt: skip

# From the wearer's left, a little below the arm: the underarm (the hoodie's armpit).
VIEWS = {"under": (1.0, -0.35, -0.3)}


def main() -> None:
    if "--frame" in sys.argv:  # a walk frame other than render_closeups' quarter stride
        at = sys.argv.index("--frame")
        frame = int(sys.argv[at + 1])
        del sys.argv[at:at + 2]
        closeups._mid_stride = lambda human, outfit, parts: looks7._walk_frame(
            human, outfit, parts, frame)  # fmt: skip
    closeups.SETS.update(SETS)
    closeups.FRAMING.update(FRAMING)
    closeups.VIEWS.update(VIEWS)
    closeups.main()


if __name__ == "__main__":
    main()
