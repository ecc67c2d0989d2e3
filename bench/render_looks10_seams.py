"""Render the close-ups of issue 14's seams pass (docs/images/looks10_seams_*.png): the
jacket's shoulder and side seams, a man in jacket, T-shirt and jeans, seen from behind his
left shoulder at rest and mid-stride, and from his left at the waist (the side seam).

    python bench/render_looks10_seams.py --samples 12 --size 320 --name after [--out DIR]

The framing is ``render_looks10_armhole``'s (35 mm, looking at a point below the left
shoulder joint), the side view lower and further off; run it on the code before and after
a change for a before/after pair. Needs the pip ``bpy`` module.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import render_looks10_armhole as armhole  # noqa: E402

# (label, animation, frame, camera, drop m below the shoulder joint, distance m)
POSES = (("rest", "rest", 0, "back", 0.05, 0.42), ("walk", "walk", 6, "back", 0.05, 0.42),
         ("side", "rest", 0, "side", 0.3, 0.6))


def main() -> None:
    from PIL import Image

    parser = argparse.ArgumentParser()
    parser.add_argument("--samples", type=int, default=12)
    parser.add_argument("--size", type=int, default=320)
    parser.add_argument("--out", default="docs/images")
    parser.add_argument("--name", default="after")
    args = parser.parse_args()
    out = Path(args.out)
    tiles = []
    for label, kind, frame, camera, drop, distance in POSES:
        armhole.SIDE_DROP, armhole.SIDE_DISTANCE = drop, distance
        tiles.append(armhole._render(label, kind, frame, camera,
                                     out / f"looks10_seams_{args.name}_{label}.png",
                                     args.samples, args.size))  # fmt: skip
    sheet = Image.new("RGB", (args.size * len(tiles), args.size), "white")
    for c, path in enumerate(tiles):
        sheet.paste(Image.open(path).convert("RGB"), (c * args.size, 0))
        path.unlink()
    final = out / f"looks10_seams_{args.name}.png"
    sheet.save(final)
    print(final)


if __name__ == "__main__":
    main()
