"""Render close-ups of faces (mouths open and smiling, facial hair, hair) to check by eye.

    python bench/render_faces.py mouth [--samples 32] [--size 400] [--out /tmp/faces]
    python bench/render_faces.py beards
    python bench/render_faces.py hair

Needs the pip ``bpy`` module. Each set is a row of heads side by side, framed by an 85 mm
camera from the front (``--views front,side``). Cycles on the CPU, modest sizes.
"""

from __future__ import annotations

import argparse
import os
import tempfile
from pathlib import Path

import numpy as np

os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="avatar-blender-"))

SMILE = {"expression/mouthSmileLeft": 0.9, "expression/mouthSmileRight": 0.9,
         "expression/jawOpen": 0.25, "expression/mouthUpperUpLeft": 0.5,
         "expression/mouthUpperUpRight": 0.5}  # fmt: skip
SETS = {
    "mouth": [  # jawOpen and a smile on a young woman and an old man
        ({"gender": 0.0, "age": 0.45, "expression/jawOpen": 0.7}, ("eyebrows", "eyelashes")),
        ({"gender": 0.0, "age": 0.45, **SMILE}, ("eyebrows", "eyelashes")),
        ({"gender": 1.0, "age": 0.9, "african": 1.0, "asian": 0.0, "caucasian": 0.0,
          "expression/jawOpen": 0.6}, ("eyebrows-black", "eyelashes")),
    ],
    "beards": [
        ({"gender": 1.0, "age": 0.5}, ("eyebrows", "eyelashes", "hair-short", "beard-short")),
        ({"gender": 1.0, "age": 0.5, "expression/jawOpen": 0.7},
         ("eyebrows", "eyelashes", "hair-short", "beard-short")),
        ({"gender": 1.0, "age": 0.8, "weight": 0.8}, ("eyebrows", "eyelashes", "moustache")),
        ({"gender": 1.0, "age": 0.4, "african": 1.0, "asian": 0.0, "caucasian": 0.0, **SMILE},
         ("eyebrows-black", "eyelashes", "hair-buzz", "stubble")),
    ],
    "hair": [
        ({"gender": 0.0, "age": 0.45}, ("eyebrows-blond", "eyelashes", "hair-long")),
        ({"gender": 1.0, "age": 0.5}, ("eyebrows", "eyelashes", "hair-short")),
        ({"gender": 0.0, "age": 0.3}, ("eyebrows", "eyelashes", "hair-bob")),
    ],
}  # fmt: skip
VIEWS = {"front": (0.0, -1.0, 0.05), "side": (0.9, -1.0, 0.05), "low": (0.3, -1.0, -0.2)}
SPACING, CROWN = 0.3, 1.8  # metres between heads; where every crown is put


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("set", choices=sorted(SETS))
    parser.add_argument("--views", default="front")
    parser.add_argument("--samples", type=int, default=32)
    parser.add_argument("--out", default="/tmp/faces")
    parser.add_argument("--size", type=int, default=400, help="pixels per head (square)")
    parser.add_argument("--zoom", type=float, default=1.0, help=">1 frames the mouth closer")
    args = parser.parse_args()
    from avatar.blender import render, scene
    from avatar.clothes.library import dress, load_garment, parts
    from avatar.human import Human
    from avatar.io import images, png

    chosen = SETS[args.set]
    chars, mouths = [], []
    for i, (params, names) in enumerate(chosen):
        human = Human(params)
        outfit = dress(human.body, [load_garment(n) for n in names], exact=True)
        top = float(human.vertices[:13380, 2].max())
        location = ((i - (len(chosen) - 1) / 2) * SPACING, 0.0, CROWN - top)
        mouths.append(float(human.part("teeth").vertices[:, 2].mean()) + CROWN - top)
        chars.append(scene.Character(f"head{i}", human.parts() + parts(outfit), human.skeleton,
                                     location=location))  # fmt: skip
    size = (args.size * len(chars), args.size)
    for view in args.views.split(","):
        scene.clear_scene()
        for c in chars:
            scene.build_character(c)
        scene.add_lights()
        out = Path(args.out) / f"faces_{args.set}_{view}.png"
        if args.zoom <= 1:
            _aim(VIEWS[view], SPACING * len(chosen), size, CROWN - 0.12)
            print(render.render(out, samples=args.samples, resolution=size))
            continue
        # Close-ups: one camera per head (the mouth), the pictures side by side.
        tiles = []
        for c, mouth in zip(chars, mouths, strict=True):
            _aim(VIEWS[view], SPACING / args.zoom, (args.size, args.size), mouth + 0.02,
                 c.location[0])  # fmt: skip
            tile = render.render(out.with_suffix(".tile.png"), samples=args.samples,
                                 resolution=args.size)  # fmt: skip
            tiles.append(images.read(tile))
        png.write(out, np.concatenate(tiles, axis=1))
        print(out)


def _aim(direction, width: float, size: tuple[int, int], height: float, x: float = 0.0) -> None:
    """An 85 mm camera looking along -``direction`` at the row of heads, ``width`` across."""
    from avatar.blender.camera import add_camera
    from avatar.camera import CameraModel, look_at

    back = np.asarray(direction, float)
    back /= np.linalg.norm(back)
    distance = width / 2 * 85.0 / 18.0  # half the 36 mm sensor spans width / 2
    centre = np.array([x, -0.08, height])
    add_camera(CameraModel(85.0, 36.0, 24.0, "HORIZONTAL", 0.0, 0.0, size, 100, (1.0, 1.0),
                           look_at(centre + back * distance, centre)))  # fmt: skip


if __name__ == "__main__":
    main()
