"""Render issue 14's tenth-pass hair close-ups (docs/images/looks10_hair_*.png): the bob on
a man, a woman and a small child (its sides over the ears) and long hair on a woman and a
girl (its width over the ears), front, profile and back.

    python bench/render_looks10_hair.py bob10man|bob10woman|bob10child|long10woman|long10girl
        [--views front,profile,back] [--size 320] [--samples 12] [--out DIR]
    python bench/render_looks10_hair.py sheet BEFORE_DIR AFTER_DIR OUT.png bob10man_front ...

``sheet`` puts the renders of two folders one over the other (before, after). Needs the
pip ``bpy`` module.
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import render_closeups as rc  # noqa: E402
import render_looks9 as looks9  # noqa: E402

FACE = ("eyebrows", "eyelashes")
BODIES = {"man": {"gender": 1.0, "age": 0.5}, "woman": {"gender": 0.0, "age": 0.45},
          "child": {"gender": 0.3, "age": 0.12}, "girl": {"gender": 0.0, "age": 0.25}}
# One head a set (seen straight from the side, heads in a row hide one another): the bob
# on a man, a woman and a small child, long hair on a woman and a girl.
SETS = {f"{style}10{who}": [(BODIES[who], (*FACE, f"hair-{style}"))]
        for style, people in (("bob", ("man", "woman", "child")), ("long", ("woman", "girl")))
        for who in people}

if __name__ == "__main__":
    if sys.argv[1] == "sheet":
        looks9.sheet(sys.argv[2:4], sys.argv[4], sys.argv[5:])
        sys.exit()
    rc.SETS.update(SETS)
    rc.HEAD_SETS = (*rc.HEAD_SETS, *SETS)
    rc.VIEWS["profile"] = (1.0, 0.0, 0.05)  # straight from the side: the ear under the hair
    for name in SETS:  # the bob down to its ends, long hair down to the shoulders
        rc.FRAMING[name] = (0.3, 1.1, rc.CROWN - 0.13) if "bob" in name else (
            0.34, 1.3, rc.CROWN - 0.19)
    rc.main()
