"""Render the eleventh pass's hair close-ups (docs/images/looks11_hair_*.png): the bob's
outline over the ears (front and back) and long hair's side locks on the shoulders
(front, profile and back) on a woman, a man, a child and a heavy woman, at rest or
mid-stride.

    python bench/render_looks11_hair.py bob11|long11 [--views front,back] [--walk]
        [--size 300] [--samples 12] [--out DIR]            # the four bodies in a row
    python bench/render_looks11_hair.py bob11woman|long11heavy|... --views profile
    python bench/render_looks11_hair.py sheet BEFORE_DIR AFTER_DIR OUT.png bob11_back ...

``sheet`` puts the renders of two folders one over the other (before, after). The docs'
pictures: ``bob11 --views front,back --size 260 --samples 10`` then ``sheet ... bob11_front
bob11_back`` (looks11_hair_bob.png); ``long11 --views front`` (looks11_hair_long_front.png)
and ``long11woman --views profile --size 300`` (looks11_hair_long_profile.png). Needs the
pip ``bpy`` module (Cycles on the CPU).
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import render_closeups as rc  # noqa: E402
import render_looks9 as looks9  # noqa: E402

FACE = ("eyebrows", "eyelashes")
BODIES = {"woman": {"gender": 0.0, "age": 0.45}, "man": {"gender": 1.0, "age": 0.5},
          "child": {"age": 0.15}, "heavy": {"gender": 0.0, "weight": 0.9}}
STYLES = ("bob", "long")
# A row of the four bodies a style (front, back), and one head a set (seen straight from
# the side, heads in a row hide one another).
SETS = {f"{style}11": [(params, (*FACE, f"hair-{style}")) for params in BODIES.values()]
        for style in STYLES}
SETS.update({f"{style}11{who}": [(params, (*FACE, f"hair-{style}"))]
             for style in STYLES for who, params in BODIES.items()})


def main() -> None:
    if sys.argv[1] == "sheet":
        looks9.sheet(sys.argv[2:4], sys.argv[4], sys.argv[5:])
        return
    rc.SETS.update(SETS)
    rc.HEAD_SETS = (*rc.HEAD_SETS, *SETS)
    rc.VIEWS["profile"] = (1.0, 0.0, 0.05)  # straight from the side
    for name in SETS:  # the bob down to its ends, long hair down to the chest
        spacing = 0.3 if "bob" in name else 0.46
        rc.FRAMING[name] = (spacing, 1.1, rc.CROWN - 0.13) if "bob" in name else (
            spacing, 1.25, rc.CROWN - 0.24)
    rc.main()


if __name__ == "__main__":
    main()
