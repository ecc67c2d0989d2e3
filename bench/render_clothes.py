"""Render dressed bodies front and back (docs/images/clothes_*.png) to check garments by eye.

    python bench/render_clothes.py [--samples 16] [--out docs/images]

Needs the pip ``bpy`` module. Rest pose, or with ``--walk`` mid-stride in the built-in walk
(docs/images/clothes_walk_*.png): the body skinned and the garments as ``Outfit.frame``
resolves them for that frame (exact), rendered as still meshes.
"""

from __future__ import annotations

import argparse
import os
import tempfile
from pathlib import Path

import numpy as np

os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="avatar-blender-"))

BODIES = [  # child, teen, woman, man, heavy, muscular, elderly woman and man: all 30 items
    ({"gender": 0.5, "age": 0.12}, ("eyebrows", "eyelashes", "hair-bob", "tshirt", "sweatpants", "sneakers")),  # noqa: E501
    ({"gender": 0.0, "age": 0.3, "weight": 0.35}, ("eyebrows-black", "eyelashes", "hair-ponytail", "swimsuit")),  # noqa: E501
    ({"gender": 0.0, "age": 0.5, "weight": 0.5}, ("eyebrows-blond", "eyelashes", "hair-long", "dress", "shoes-black")),  # noqa: E501
    ({"gender": 1.0, "age": 0.5}, ("eyebrows", "eyelashes", "hair-short", "longsleeve", "jacket", "jeans", "boots")),  # noqa: E501
    ({"gender": 0.0, "age": 0.6, "weight": 1.0}, ("eyebrows", "eyelashes", "hair-short", "tanktop", "skirt", "socks", "shoes")),  # noqa: E501
    ({"gender": 1.0, "age": 0.3, "muscle": 1.0}, ("eyebrows-black", "eyelashes", "hair-buzz", "hoodie", "shorts", "sneakers")),  # noqa: E501
    ({"gender": 0.0, "age": 0.95, "weight": 0.6}, ("eyebrows", "eyelashes", "hair-bun", "tshirt", "cardigan", "leggings", "shoes-black")),  # noqa: E501
    ({"gender": 1.0, "age": 1.0, "weight": 0.6}, ("eyebrows", "eyelashes", "cap", "tshirt", "trousers", "socks", "shoes")),  # noqa: E501
]  # fmt: skip


class Posed:
    """A dressed Human frozen in one frame: still meshes at their posed places."""

    def __init__(self, human, matrices, exact: bool = True):
        from avatar.part import MeshPart
        from avatar.rig import skinning

        self.human, self.skeleton = human, human.skeleton
        outfit = human.outfit
        body = skinning.linear_blend(human.vertices, human.weights, matrices)
        garments = outfit.frame(body, matrices, exact=exact)
        # Walk in place: the frame keeps the body where the rest pose stood.
        shift = np.zeros(3, np.float32)
        shift[:2] = (body[:13380] - human.vertices[:13380]).mean(axis=0)[:2]
        rest = human.parts()  # body parts, then the outfit's garments
        count = len(rest) - len(garments)
        self._parts = [
            MeshPart(p.name, p.mesh.with_vertices(body[human.part_vertices(p.name)] - shift),
                     p.material)
            for p in rest[:count]
        ] + [
            MeshPart(p.name, p.mesh.with_vertices(v - shift), p.material)
            for p, v in zip(rest[count:], garments, strict=True)
        ]  # fmt: skip

    def parts(self):
        return self._parts


class Dressed:
    """A dressed Human at rest: its parts (body, then garments, exact)."""

    def __init__(self, human):
        self.human, self.skeleton = human, human.skeleton
        self._parts = human.parts()

    def parts(self):
        return self._parts


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--samples", type=int, default=16)
    parser.add_argument("--out", default="docs/images")
    parser.add_argument("--walk", action="store_true", help="mid-stride in the built-in walk")
    parser.add_argument("--name", default="clothes", help="file stem: NAME[_walk]_front.png")
    parser.add_argument("--views", default="front,back")
    args = parser.parse_args()
    from avatar.blender import render, scene
    from avatar.human import Human

    chars = []
    for i, (params, names) in enumerate(BODIES):
        human = Human(params).dressed(*names)  # raised onto its shoes' soles
        shown = Dressed(human)
        if args.walk:
            shown = Posed(human, _mid_stride(human))
        chars.append(scene.Character(f"dressed{i}", shown.parts(), shown.skeleton))
    out = Path(args.out)
    stem = f"{args.name}_walk" if args.walk else args.name
    directions = {"front": (0.25, -1.0, 0.12), "back": (-0.25, 1.0, 0.12)}
    for view in args.views.split(","):
        direction = directions[view]
        size = (280 * len(chars), 620)
        render.stage_characters(chars, size, spacing=0.7, direction=direction)
        render.render(out / f"{stem}_{view}.png", samples=args.samples, resolution=size)
        print(out / f"{stem}_{view}.png")


def _mid_stride(human) -> np.ndarray:
    """(J, 4, 4) skinning matrices a quarter into the built-in walk: legs apart, arms swung."""
    from avatar.rig import kinematics

    walk = human.walk(seconds=1.0, fps=24)
    world = kinematics.forward(human.skeleton, walk.rotations[6:7], walk.translations[6:7])
    return kinematics.skinning_matrices(human.skeleton, world)[0]


if __name__ == "__main__":
    main()
