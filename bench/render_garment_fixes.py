"""Render the close-ups of issue 14's fifth garment pass (docs/images/looks5_*.png): shoes,
tops (cap, cardigan, T-shirt, hoodies) and legwear (dress, jeans, trousers), at rest or
mid-stride, with ``render_closeups``' cameras and options.

    python bench/render_garment_fixes.py feet --views front,profile [--walk] [--samples 32]
    python bench/render_garment_fixes.py tops --views front,back
    python bench/render_garment_fixes.py legs --views front,back [--walk]
    python bench/render_garment_fixes.py backs --views back --name looks5b

Needs the pip ``bpy`` module (Cycles on the CPU).
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import render_closeups as closeups  # noqa: E402

SETS = {
    "feet": [  # brown, black, canvas and boot uppers on four feet
        ({"gender": 1.0, "age": 0.5}, ("socks", "shoes", "trousers")),
        ({"gender": 0.0, "age": 0.45}, ("shoes-black", "jeans")),
        ({"gender": 0.3, "age": 0.12}, ("sneakers",)),
        ({"gender": 1.0, "age": 0.9, "weight": 0.9}, ("boots", "jeans")),
    ],
    "tops": [  # cardigan over a T-shirt, the cap, two hoodies
        ({"gender": 0.0, "age": 0.9, "weight": 0.7},
         ("eyebrows", "eyelashes", "hair-bun", "tshirt", "cardigan", "leggings")),
        ({"gender": 1.0, "age": 1.0, "weight": 0.6},
         ("eyebrows", "eyelashes", "tshirt", "cap", "trousers")),
        ({"gender": 1.0, "age": 0.3, "muscle": 0.8},
         ("eyebrows", "eyelashes", "hair-buzz", "hoodie", "jeans")),
        ({"gender": 0.3, "age": 0.12}, ("eyebrows", "eyelashes", "hair-bob", "hoodie", "cap")),
    ],
    "backs": [  # loose tops over the cleft of the buttocks (docs/images/looks5b_backs_*.png)
        ({"gender": 1.0, "age": 0.3, "muscle": 0.8}, ("hair-buzz", "hoodie", "jeans")),
        ({"gender": 1.0, "weight": 1.0}, ("hair-buzz", "hoodie", "trousers")),
        ({"gender": 0.0, "age": 0.9, "weight": 0.7}, ("hair-bun", "cardigan", "leggings")),
        ({"gender": 0.5}, ("jacket", "jeans")),
    ],
    "legs": [  # the dress on three bodies, jeans on a woman, trousers on an old man
        ({"gender": 0.0, "age": 0.3}, ("dress", "shoes-black")),
        ({"gender": 0.3, "age": 0.15}, ("dress", "sneakers")),
        ({"gender": 0.0, "age": 0.6, "weight": 1.0}, ("dress", "shoes")),
        ({"gender": 0.0, "age": 0.45}, ("jeans", "sneakers")),
        ({"gender": 1.0, "age": 0.9}, ("trousers", "shoes-black")),
    ],
}  # fmt: skip
FRAMING = {"tops": (0.6, 1.75, closeups.CROWN_AIM - 0.2), "backs": (0.8, 1.1, 1.0),
           "legs": (0.6, 2.0, 0.75)}  # fmt: skip
VIEWS = {"profile": (0.6, -1.0, 0.12)}  # the shoes three-quarter from the front, low


def main() -> None:
    closeups.SETS.update(SETS)
    closeups.FRAMING.update(FRAMING)
    closeups.VIEWS.update(VIEWS)
    closeups.main()


if __name__ == "__main__":
    main()
