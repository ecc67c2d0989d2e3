"""Render the close-ups of issue 14's tenth garment pass (docs/images/looks10_garments_*.png):
the everyday garments in seven outfits on a woman, a heavy man and a child, at rest and
mid-stride, front and back, with ``render_closeups``' row cameras.

    python bench/render_looks10_garments.py woman --views front,back [--walk] --samples 12
    python bench/render_looks10_garments.py heavy ...; python ... child ...
    python bench/render_looks10_garments.py fly --views front --samples 12 --size 300
    python bench/render_looks10_garments.py flywalk --views front --walk --samples 16 --size 400

Needs the pip ``bpy`` module (Cycles on the CPU).
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import render_closeups as closeups  # noqa: E402

OUTFITS = (
    ("tshirt", "jeans", "socks", "cap"),
    ("hoodie", "sweatpants"),
    ("longsleeve", "trousers"),
    ("tanktop", "shorts", "socks"),
    ("tshirt", "cardigan", "skirt", "leggings"),
    ("dress",),
    ("swimsuit",),
)
BODIES = {
    "woman": {"gender": 0.0, "age": 0.45},
    "heavy": {"gender": 1.0, "weight": 0.9, "age": 0.6},
    "child": {"age": 0.15},
}
SETS = {name: [(params, outfit) for outfit in OUTFITS] for name, params in BODIES.items()}
SETS["fly"] = [  # loose bottoms across the front of the crotch: woman, child, heavy man
    (BODIES["woman"], ("tshirt", "sweatpants")),
    (BODIES["woman"], ("tshirt", "trousers")),
    (BODIES["woman"], ("tanktop", "shorts")),
    (BODIES["woman"], ("tshirt", "jeans")),
    (BODIES["child"], ("tshirt", "sweatpants")),
    (BODIES["heavy"], ("tshirt", "shorts")),
]
SETS["flywalk"] = [  # the fly mid-stride, zoomed: the heavy man's shorts and sweatpants
    (BODIES["heavy"], ("tshirt", "shorts")),
    (BODIES["heavy"], ("tshirt", "sweatpants")),
]
FRAMING = {"fly": (0.5, 1.0, 0.7), "flywalk": (0.34, 1.0, 0.76), "woman": (0.62, 3.0, 0.84),
           "heavy": (0.75, 2.8, 0.88), "child": (0.5, 2.6, 0.58)}  # fmt: skip


def main() -> None:
    closeups.SETS.update(SETS)
    closeups.FRAMING.update(FRAMING)
    closeups.main()


if __name__ == "__main__":
    main()
