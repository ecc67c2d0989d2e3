"""Render face close-ups (docs/images/faces_*.png) to check skin, mouth, brows and hair by eye.

    python bench/render_faces.py [--samples 12] [--out docs/images] [--name faces]

Needs the pip ``bpy`` module. Each head is shown front and three-quarter, the mouth open
(``expression/jawOpen``) on every other head so teeth and tongue show. Small and few
renders: Cycles on the CPU at low samples.
"""

from __future__ import annotations

import argparse
import os
import tempfile
from pathlib import Path

import numpy as np

os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="avatar-blender-"))

HEADS = [  # (parameters, garments): child, young woman, muscular man, old woman, old man (bald)
    ({"gender": 0.3, "age": 0.12}, ("eyebrows", "eyelashes", "hair-short")),
    ({"gender": 0.0, "age": 0.45, "expression/jawOpen": 0.7}, ("eyebrows-blond", "eyelashes", "hair-long")),  # noqa: E501
    ({"gender": 1.0, "age": 0.5, "muscle": 0.9, "african": 1.0, "asian": 0.0, "caucasian": 0.0}, ("eyebrows-black", "eyelashes")),  # noqa: E501
    ({"gender": 0.0, "age": 0.9, "asian": 1.0, "african": 0.0, "caucasian": 0.0, "expression/jawOpen": 0.6}, ("eyebrows", "eyelashes", "hair-ponytail")),  # noqa: E501
    ({"gender": 1.0, "age": 1.0}, ("eyebrows", "eyelashes")),
]  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--samples", type=int, default=12)
    parser.add_argument("--out", default="docs/images")
    parser.add_argument("--name", default="faces")
    parser.add_argument("--texture", type=int, default=1024)
    parser.add_argument("--size", type=int, default=260, help="pixels per head (square)")
    args = parser.parse_args()
    from avatar.blender import render, scene
    from avatar.clothes.library import dress, load_garment, parts
    from avatar.human import Human

    out = Path(args.out)
    chars = []
    for i, (params, names) in enumerate(HEADS):
        human = Human(params)
        outfit = dress(human.body, [load_garment(n, texture_size=args.texture) for n in names])
        top = float(human.vertices[:13380, 2].max())
        # Heads side by side, their crowns at one height, so one camera frames them all.
        location = ((i - (len(HEADS) - 1) / 2) * SPACING, 0.0, CROWN - top)
        chars.append(scene.Character(f"head{i}", human.parts() + parts(outfit), human.skeleton,
                                     location=location))  # fmt: skip
    size = (args.size * len(chars), args.size)
    for view, direction in (("front", (0.0, -1.0, 0.05)), ("side", (0.9, -1.0, 0.1))):
        scene.clear_scene()
        for c in chars:
            scene.build_character(c)
        scene.add_lights()
        _aim(direction, SPACING * len(HEADS), size)
        path = render.render(out / f"{args.name}_{view}.png", samples=args.samples,
                             resolution=size)  # fmt: skip
        print(path)


SPACING, CROWN = 0.36, 1.8  # metres between heads; where every crown is put


def _aim(direction, width: float, size: tuple[int, int]) -> None:
    """An 85 mm camera looking along -``direction`` at the row of heads, ``width`` across."""
    from avatar.blender.camera import add_camera
    from avatar.camera import CameraModel, look_at

    back = np.asarray(direction, float)
    back /= np.linalg.norm(back)
    distance = width / 2 * 85.0 / 18.0  # half the 36 mm sensor spans width / 2
    centre = np.array([0.0, -0.05, CROWN - 0.14])
    add_camera(CameraModel(85.0, 36.0, 24.0, "HORIZONTAL", 0.0, 0.0, size, 100, (1.0, 1.0),
                           look_at(centre + back * distance, centre)))  # fmt: skip


if __name__ == "__main__":
    main()
