"""Render the close-ups of issue 14's tenth pass (docs/images/looks10_armhole_*.png): the
jacket's armhole seam and its topstitching, a man in jacket, T-shirt and jeans, at rest and
mid-stride, seen from behind and from the side of his left shoulder.

    python bench/render_looks10_armhole.py --samples 12 --size 320 --name after [--out DIR]

Each pose is one render (35 mm, SIDE_DISTANCE m from a point SIDE_DROP m below the left
shoulder joint); the tiles are put side by side in ``<out>/looks10_armhole_<name>.png``.
Run it on the code before and after a change for a before/after pair of the same framing.
Needs the pip ``bpy`` module.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import render_looks9_hems as looks9  # noqa: E402

MAN = ({"gender": 1.0, "age": 0.5}, ("jacket", "tshirt", "jeans"))
# (label, animation, frame, camera): at rest and mid-stride (frame 6 of a 24-frame walk)
# from behind the left shoulder ("back"), at rest from the wearer's left ("side").
POSES = (("rest", "rest", 0, "back"), ("walk", "walk", 6, "back"), ("side", "rest", 0, "side"))
VIEWS = {"back": (0.55, 1.0, 0.15), "side": (1.0, 0.15, 0.05)}  # +y is behind the wearer
SIDE_DISTANCE, SIDE_DROP = 0.42, 0.09


def main() -> None:
    from PIL import Image

    parser = argparse.ArgumentParser()
    parser.add_argument("--samples", type=int, default=12)
    parser.add_argument("--size", type=int, default=320)
    parser.add_argument("--out", default="docs/images")
    parser.add_argument("--name", default="after")
    args = parser.parse_args()
    out = Path(args.out)
    tiles = [_render(label, kind, frame, camera, out / f"looks10_armhole_{args.name}_{label}.png",
                     args.samples, args.size)
             for label, kind, frame, camera in POSES]  # fmt: skip
    sheet = Image.new("RGB", (args.size * len(tiles), args.size), "white")
    for c, path in enumerate(tiles):
        sheet.paste(Image.open(path).convert("RGB"), (c * args.size, 0))
        path.unlink()
    final = out / f"looks10_armhole_{args.name}.png"
    sheet.save(final)
    print(final)


def _render(label: str, kind: str, frame: int, camera: str, path: Path, samples: int,
            size: int) -> Path:  # fmt: skip
    from avatar.blender import render, scene
    from avatar.blender.camera import add_camera
    from avatar.camera import CameraModel, look_at
    from avatar.human import Human

    params, names = MAN
    human = Human(params).dressed(*names)
    animation = human.walk(seconds=1.0, fps=24) if kind == "walk" else human.pose(kind)
    one = _Frame(animation.rotations[frame:frame + 1], animation.translations[frame:frame + 1])
    parts, world = looks9._posed(human, one)
    shoulder = world[human.skeleton.names.index("upperarm01.L"), :3, 3]
    target = shoulder - np.array([0.0, 0.0, SIDE_DROP])
    view = np.asarray(VIEWS[camera], float)
    eye = target + view / np.linalg.norm(view) * SIDE_DISTANCE
    scene.clear_scene()
    scene.build_character(scene.Character(label, parts, human.skeleton))
    scene.add_lights()
    add_camera(CameraModel(35.0, 36.0, 36.0, "HORIZONTAL", 0.0, 0.0, (size, size), 100,
                           (1.0, 1.0), look_at(eye, target)))  # fmt: skip
    return render.render(path, samples=samples, resolution=(size, size))


class _Frame:
    """One frame of an animation: what ``render_looks9_hems._posed`` reads."""

    def __init__(self, rotations: np.ndarray, translations: np.ndarray):
        self.rotations, self.translations = rotations, translations


if __name__ == "__main__":
    main()
