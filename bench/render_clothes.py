"""Render dressed bodies front and back (docs/images/clothes_*.png) to check garments by eye.

    python bench/render_clothes.py [--samples 16] [--out docs/images]

Needs the pip ``bpy`` module. Rest pose, plus one mid-motion frame when a clip is given.
"""

from __future__ import annotations

import argparse
import os
import tempfile
from pathlib import Path

os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="avatar-blender-"))

BODIES = [
    ({"gender": 0.0, "age": 0.5, "weight": 0.5}, ("eyebrows-blond", "eyelashes", "hair-long", "tshirt", "jeans", "shoes")),  # noqa: E501
    ({"gender": 1.0, "age": 0.6, "weight": 0.9, "muscle": 0.3}, ("eyebrows", "eyelashes", "hair-short", "longsleeve", "trousers", "socks", "shoes")),  # noqa: E501
    ({"gender": 0.0, "age": 0.3, "weight": 0.2}, ("eyebrows-black", "eyelashes", "hair-ponytail", "dress", "shoes")),  # noqa: E501
    ({"gender": 1.0, "age": 0.9, "weight": 0.6}, ("eyebrows", "eyelashes", "cap", "jacket", "tshirt", "shorts", "socks", "shoes")),  # noqa: E501
    ({"gender": 0.0, "age": 0.45, "weight": 0.7}, ("eyebrows", "eyelashes", "hair-short", "tanktop", "skirt", "shoes")),  # noqa: E501
    ({"gender": 1.0, "age": 0.25, "muscle": 1.0}, ("eyebrows", "eyelashes", "hair-short", "hoodie", "leggings", "shoes")),  # noqa: E501
    ({"gender": 0.0, "age": 0.5, "weight": 0.4}, ("eyebrows-blond", "eyelashes", "hair-long", "swimsuit")),  # noqa: E501
]  # fmt: skip


class Dressed:
    """A Human with garments, shaped like what ``scene.character_from_human`` reads."""

    def __init__(self, human, outfit):
        from avatar.clothes.library import parts

        self.human, self.skeleton = human, human.skeleton
        self._parts = human.parts() + parts(outfit)

    def parts(self):
        return self._parts


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--samples", type=int, default=16)
    parser.add_argument("--out", default="docs/images")
    parser.add_argument("--texture", type=int, default=512)
    args = parser.parse_args()
    from avatar.blender import render, scene
    from avatar.clothes.library import dress, load_garment
    from avatar.human import Human

    chars = []
    for i, (params, names) in enumerate(BODIES):
        human = Human(params)
        outfit = dress(human, [load_garment(n, texture_size=args.texture) for n in names])
        chars.append(scene.character_from_human(Dressed(human, outfit), name=f"dressed{i}"))
    out = Path(args.out)
    for view, direction in (("front", (0.25, -1.0, 0.12)), ("back", (-0.25, 1.0, 0.12))):
        size = (300 * len(chars), 620)
        render.stage_characters(chars, size, spacing=0.7, direction=direction)
        render.render(out / f"clothes_{view}.png", samples=args.samples, resolution=size)
        print(out / f"clothes_{view}.png")


if __name__ == "__main__":
    main()
