"""Render close-ups of heads or feet (docs/images/closeup_*.png) to check skin, mouth,
brows, hair and shoes by eye.

    python bench/render_closeups.py heads [--samples 12] [--out docs/images] [--views front,back]
    python bench/render_closeups.py feet

Needs the pip ``bpy`` module. Heads: front, three-quarter and back, the mouth open
(``expression/jawOpen``) on two of them so teeth and tongue show. Feet: five bodies' shoes.
Small and few renders: Cycles on the CPU at low samples.
"""

from __future__ import annotations

import argparse
import os
import tempfile
from pathlib import Path

import numpy as np

os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="avatar-blender-"))

SETS = {}
SETS["heads"] = [  # (parameters, garments): child, young woman, muscular man, old woman, old man
    ({"gender": 0.3, "age": 0.12}, ("eyebrows", "eyelashes", "hair-bob")),
    ({"gender": 0.0, "age": 0.45, "expression/jawOpen": 0.7}, ("eyebrows-blond", "eyelashes", "hair-long")),  # noqa: E501
    ({"gender": 1.0, "age": 0.5, "muscle": 0.9, "african": 1.0, "asian": 0.0, "caucasian": 0.0}, ("eyebrows-black", "eyelashes", "hair-buzz")),  # noqa: E501
    ({"gender": 0.0, "age": 0.9, "asian": 1.0, "african": 0.0, "caucasian": 0.0, "expression/jawOpen": 0.6}, ("eyebrows", "eyelashes", "hair-bun")),  # noqa: E501
    ({"gender": 1.0, "age": 1.0}, ("eyebrows", "eyelashes")),
]  # fmt: skip
SETS["feet"] = [
    ({"gender": 0.3, "age": 0.12}, ("socks", "shoes", "trousers")),
    ({"gender": 0.0, "age": 0.45}, ("shoes", "jeans")),
    ({"gender": 1.0, "age": 0.5, "muscle": 0.9}, ("socks", "shoes", "shorts")),
    ({"gender": 0.0, "age": 0.9, "weight": 0.9}, ("shoes", "skirt")),
    ({"gender": 1.0, "age": 1.0}, ("socks", "shoes", "trousers")),
]  # fmt: skip
# Per set: where the camera looks (z of the aim point relative to the aligned height, m),
# and the views (name -> direction from subject to camera).
VIEWS = {
    "front": (0.0, -1.0, 0.05), "side": (0.9, -1.0, 0.1), "back": (0.0, 1.0, 0.1),
    "low": (0.7, -1.0, 0.35),
}  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("set", choices=sorted(SETS))
    parser.add_argument("--views", default="front,side,back")
    parser.add_argument("--samples", type=int, default=12)
    parser.add_argument("--out", default="docs/images")
    parser.add_argument("--name", default="closeup")
    parser.add_argument("--texture", type=int, default=1024)
    parser.add_argument("--size", type=int, default=260, help="pixels per head (square)")
    args = parser.parse_args()
    from avatar.blender import render, scene
    from avatar.clothes.library import dress, load_garment, parts
    from avatar.human import Human

    out = Path(args.out)
    chars = []
    chosen = SETS[args.set]
    heads = args.set == "heads"
    for i, (params, names) in enumerate(chosen):
        human = Human(params)
        outfit = dress(human.body, [load_garment(n, texture_size=args.texture) for n in names])
        top = float(human.vertices[:13380, 2].max()) if heads else 0.0
        # Side by side, crowns (or soles) at one height, so one camera frames them all.
        spacing = SPACING if heads else 0.55
        location = ((i - (len(chosen) - 1) / 2) * spacing, 0.0, CROWN - top if heads else 0.0)
        chars.append(scene.Character(f"head{i}", human.parts() + parts(outfit), human.skeleton,
                                     location=location))  # fmt: skip
    size = (args.size * len(chars), args.size)
    for view in args.views.split(","):
        direction = VIEWS[view]
        scene.clear_scene()
        for c in chars:
            scene.build_character(c)
        scene.add_lights()
        if not heads:
            scene.add_floor()
        _aim(direction, spacing * len(chosen), size, CROWN - 0.14 if heads else 0.07)
        path = render.render(out / f"{args.name}_{args.set}_{view}.png", samples=args.samples,
                             resolution=size)  # fmt: skip
        print(path)


SPACING, CROWN = 0.36, 1.8  # metres between heads; where every crown is put


def _aim(direction, width: float, size: tuple[int, int], height: float) -> None:
    """An 85 mm camera looking along -``direction`` at the row of heads, ``width`` across."""
    from avatar.blender.camera import add_camera
    from avatar.camera import CameraModel, look_at

    back = np.asarray(direction, float)
    back /= np.linalg.norm(back)
    distance = width / 2 * 85.0 / 18.0  # half the 36 mm sensor spans width / 2
    centre = np.array([0.0, -0.05, height])
    add_camera(CameraModel(85.0, 36.0, 24.0, "HORIZONTAL", 0.0, 0.0, size, 100, (1.0, 1.0),
                           look_at(centre + back * distance, centre)))  # fmt: skip


if __name__ == "__main__":
    main()
