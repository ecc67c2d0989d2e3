"""Render the close-ups of the eleventh pass on the dress (docs/images/looks11_dress_*.png):
its waist from behind (the skirt's top over the bodice), its hips mid-stride and its
straps, on a woman, a heavy man, a child and a heavy woman.

    python bench/render_looks11_dress.py waist --views back [--walk] --samples 12 --size 300
    python bench/render_looks11_dress.py straps --views front,back --samples 12 --size 300
    python bench/render_looks11_dress.py pair BEFORE.png AFTER.png OUT.png  # before over after

The before pictures come from the old code (a worktree of main on PYTHONPATH).

Needs the pip ``bpy`` module (Cycles on the CPU).
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import render_closeups as closeups  # noqa: E402

BODIES = {
    "woman": {"gender": 0.0, "age": 0.45},
    "heavy": {"gender": 1.0, "weight": 0.9, "age": 0.6},
    "child": {"age": 0.15},
    "heavywoman": {"gender": 0.0, "weight": 0.9},
}
DRESSED = [(params, ("dress",)) for params in BODIES.values()]
SETS = {"waist": DRESSED, "straps": DRESSED}
# metres between bodies, frame height / width per body, aim height (m)
FRAMING = {"waist": (0.6, 1.5, 0.9), "straps": (0.55, 1.6, 1.2)}


def pair(before: str, after: str, out: str, width: int = 1000) -> None:
    """``before`` over ``after`` in one PNG, ``width`` pixels wide (under 1.5 MB)."""
    from PIL import Image

    def opened(path):
        image = Image.open(path).convert("RGB")
        return image.resize((width, round(image.height * width / image.width)), Image.LANCZOS)

    top, bottom = opened(before), opened(after)
    both = Image.new("RGB", (max(top.width, bottom.width), top.height + bottom.height))
    both.paste(top, (0, 0))
    both.paste(bottom, (0, top.height))
    both.save(out, optimize=True)


def main() -> None:
    if sys.argv[1:2] == ["pair"]:
        pair(*sys.argv[2:5])
        return
    closeups.SETS.update(SETS)
    closeups.FRAMING.update(FRAMING)
    closeups.main()


if __name__ == "__main__":
    main()
