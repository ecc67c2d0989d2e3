"""Render the close-ups of the eleventh pass's top hems (docs/images/looks11_hems_*.png):
the cardigan (over a t-shirt, skirt and leggings) and the hoodie (over sweatpants) (set
"hems"), and the jacket over a t-shirt and jeans (set "jacket"), on a woman, a heavy man
and a child, from the hips up to the chest, at rest and mid-stride, with
``render_closeups``' row cameras; then before and after stacked into one picture.

    python bench/render_looks11_hems.py hems --views front,back --walk --samples 12 --size 300 \
        --out /tmp/after        # and with PYTHONPATH at the old code, --out /tmp/before
    python bench/render_looks11_hems.py stack /tmp/before/X.png /tmp/after/X.png docs/images/Y.png

Needs the pip ``bpy`` module (Cycles on the CPU) for the renders; ``stack`` only Pillow.
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import render_closeups as closeups  # noqa: E402
from render_looks10_garments import BODIES  # noqa: E402

CARDIGAN = ("tshirt", "cardigan", "skirt", "leggings")
HOODIE = ("hoodie", "sweatpants")
JACKET = ("tshirt", "jacket", "jeans")
SETS = {"hems": [(BODIES[body], outfit) for outfit in (CARDIGAN, HOODIE)
                 for body in ("woman", "heavy", "child")],
        "jacket": [(BODIES[body], JACKET) for body in ("woman", "heavy", "child")]}  # fmt: skip
# metres apart, frame height per body, aim height (m)
FRAMING = {"hems": (0.62, 1.75, 0.92), "jacket": (0.62, 1.75, 0.92)}


def stack(before: str, after: str, out: str, width: int = 1440) -> None:
    """``before`` above ``after``, each scaled to ``width`` px across, a grey line between
    them, as a 256-colour PNG (the renders' noise made a full-colour one 3 MB)."""
    from PIL import Image

    shots = []
    for path in (before, after):
        shot = Image.open(path).convert("RGB")
        shots.append(shot.resize((width, round(shot.height * width / shot.width)), Image.LANCZOS))
    sheet = Image.new("RGB", (width, shots[0].height + shots[1].height + 4), (90, 90, 90))
    sheet.paste(shots[0], (0, 0))
    sheet.paste(shots[1], (0, shots[0].height + 4))
    sheet.quantize(256).save(out, optimize=True)


def main() -> None:
    if sys.argv[1:2] == ["stack"]:
        stack(*sys.argv[2:5])
        return
    closeups.SETS.update(SETS)
    closeups.FRAMING.update(FRAMING)
    closeups.main()


if __name__ == "__main__":
    main()
