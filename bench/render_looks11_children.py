"""Render the close-ups of issue 14's eleventh pass on children's clothes
(docs/images/looks11_children_*.png): loose bottoms and long sleeves on a toddler, a child
and an older child (ages 0.05, 0.15, 0.3), and on a woman and a heavy man to show the
adults unchanged, at rest and mid-stride, front and back, with ``render_closeups``' row
cameras.

    python bench/render_looks11_children.py children --views front,back [--walk] --samples 12 --size 300 --name before
    python bench/render_looks11_children.py adults --views front --samples 12 --size 300 --name after
    python bench/render_looks11_children.py compose OUT.png BEFORE.png AFTER.png [LABEL]

Run it on the code before and after a change (``--name before`` / ``after``) and compose
the pair: before above, after below. Needs the pip ``bpy`` module (Cycles on the CPU).
"""  # noqa: E501

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import render_closeups as closeups  # noqa: E402

TODDLER, CHILD, OLDER = {"age": 0.05}, {"age": 0.15}, {"age": 0.3}
WOMAN, HEAVY = {"gender": 0.0, "age": 0.45}, {"gender": 1.0, "weight": 0.9, "age": 0.6}
SETS = {
    "children": [
        (TODDLER, ("hoodie", "sweatpants")),
        (CHILD, ("hoodie", "sweatpants")),
        (CHILD, ("longsleeve", "trousers")),
        (CHILD, ("cardigan", "jeans")),
        (OLDER, ("jacket", "tshirt", "sweatpants")),
    ],
    "adults": [
        (WOMAN, ("hoodie", "sweatpants")),
        (WOMAN, ("longsleeve", "trousers")),
        (HEAVY, ("cardigan", "jeans")),
        (HEAVY, ("jacket", "tshirt", "sweatpants")),
    ],
    "crotch": [  # the front of loose bottoms at the crotch point
        (CHILD, ("tshirt", "sweatpants")),
        (CHILD, ("tshirt", "trousers")),
        (CHILD, ("tshirt", "shorts")),
        (OLDER, ("tshirt", "sweatpants")),
    ],
}
# set -> (metres between bodies, frame height / width per body, aim height (m))
FRAMING = {"children": (0.56, 2.3, 0.62), "adults": (0.7, 2.6, 0.85), "crotch": (0.34, 1.3, 0.52)}


def compose(out: str, before: str, after: str, label: str = "") -> None:
    """Before above after, each under a one-line caption, into ``out``."""
    from PIL import Image, ImageDraw

    tiles = [Image.open(p).convert("RGB") for p in (before, after)]
    width, line = max(t.width for t in tiles), 18
    sheet = Image.new("RGB", (width, sum(t.height + line for t in tiles)), "white")
    draw, y = ImageDraw.Draw(sheet), 0
    for caption, tile in zip((f"before {label}", "after (clothes.limb_ease)"), tiles,
                             strict=True):  # fmt: skip
        draw.text((4, y + 3), caption, fill="black")
        sheet.paste(tile, (0, y + line))
        y += tile.height + line
    # Noisy renders compress badly: 256 colours keep each sheet under 1.5 MB.
    sheet.quantize(256, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE).save(out)
    print(out)


def main() -> None:
    if sys.argv[1] == "compose":
        compose(*sys.argv[2:])
        return
    closeups.SETS.update(SETS)
    closeups.FRAMING.update(FRAMING)
    closeups.main()


if __name__ == "__main__":
    main()
