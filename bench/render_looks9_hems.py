"""Render the close-ups of issue 14's ninth garment pass (docs/images/looks9_*.png): skirt and
dress hems mid-stride, the dress's sides from the front, and the hoodie and jacket under the
arm, on a man and a woman.

    python bench/render_looks9_hems.py hems --views front,back --walk --frame 6 --samples 12
    python bench/render_looks9_hems.py side --views front --walk --samples 12
    python bench/render_looks9_hems.py underarm --samples 12 --size 300 [--out DIR --name N]

``hems`` and ``side`` use ``render_closeups``' row cameras. ``underarm`` renders each body on
its own, at rest (A-pose) and with its arms out (``t-pose``), with a 35 mm camera in front of
the wearer's left side, below the shoulder, looking up into the armpit: the row camera of
``render_looks8`` (``--views under``) stood 4 m off and under the floor, and showed only the
floor. The tiles are put together in one PNG ``<out>/<name>_underarm.png``.

Needs the pip ``bpy`` module (Cycles on the CPU).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import render_closeups as closeups  # noqa: E402
import render_looks7 as looks7  # noqa: E402
import render_looks8 as looks8  # noqa: E402

SETS = {
    "hems": looks7.SETS["hems"],
    "side": [  # the sheet's woman in the dress, and a heavier woman: the dress's sides
        ({"gender": 0.0, "age": 0.5, "weight": 0.5}, ("hair-long", "dress", "shoes-black")),
        ({"gender": 0.0, "age": 0.6, "weight": 1.0}, ("dress", "shoes")),
    ],
    "underarm": looks8.SETS["armpit"] + looks8.SETS["opening"],
}  # fmt: skip
FRAMING = {"hems": looks7.FRAMING["hems"], "side": (0.7, 1.3, 0.8)}

# The underarm camera per pose: from the wearer's front left and below the shoulder (a
# direction from the armpit) and m away, aimed UNDER_DROP m below the shoulder joint. At
# rest the arm hangs 45 degrees out: the camera looks into the gap from the front, above
# the hand; with the arms out it looks up into the armpit from below.
UNDER_VIEWS = {"rest": ((0.35, -0.9, -0.25), 0.55), "t-pose": ((0.25, -0.55, -0.8), 0.7)}
UNDER_DROP = 0.08
POSES = ("rest", "t-pose")


def main() -> None:
    if len(sys.argv) > 1 and sys.argv[1] == "underarm":
        underarm(sys.argv[2:])
        return
    if "--frame" in sys.argv:  # a walk frame other than render_closeups' quarter stride
        at = sys.argv.index("--frame")
        frame = int(sys.argv[at + 1])
        del sys.argv[at:at + 2]
        closeups._mid_stride = lambda human, outfit, parts: looks7._walk_frame(
            human, outfit, parts, frame)  # fmt: skip
    closeups.SETS.update(SETS)
    closeups.FRAMING.update(FRAMING)
    closeups.main()


def underarm(argv: list[str]) -> None:
    """Each body of the ``underarm`` set in each of ``POSES``, one render each, tiled: a row
    per pose, a column per body."""
    import argparse

    from PIL import Image

    parser = argparse.ArgumentParser()
    parser.add_argument("--samples", type=int, default=12)
    parser.add_argument("--size", type=int, default=300)
    parser.add_argument("--out", default="docs/images")
    parser.add_argument("--name", default="looks9")
    args = parser.parse_args(argv)
    out = Path(args.out)
    tiles = []
    for pose in POSES:
        row = []
        for i, (params, names) in enumerate(SETS["underarm"]):
            path = out / f"{args.name}_underarm_{pose}_{i}.png"
            row.append(_render_underarm(params, names, pose, path, args.samples, args.size))
        tiles.append(row)
    sheet = Image.new("RGB", (args.size * len(tiles[0]), args.size * len(tiles)), "white")
    for r, row in enumerate(tiles):
        for c, path in enumerate(row):
            sheet.paste(Image.open(path).convert("RGB"), (c * args.size, r * args.size))
    final = out / f"{args.name}_underarm.png"
    sheet.save(final)
    print(final)


def _render_underarm(params: dict, names: tuple, pose: str, path: Path, samples: int,
                     size: int) -> Path:  # fmt: skip
    from avatar.blender import render, scene
    from avatar.blender.camera import add_camera
    from avatar.camera import CameraModel, look_at
    from avatar.human import Human

    human = Human(params).dressed(*names)
    animation = human.pose(pose)
    parts, world = _posed(human, animation)
    shoulder = world[human.skeleton.names.index("upperarm01.L"), :3, 3]
    target = shoulder - np.array([0.0, 0.0, UNDER_DROP])
    view, distance = UNDER_VIEWS[pose]
    eye = target + np.asarray(view, float) / np.linalg.norm(view) * distance
    scene.clear_scene()
    scene.build_character(scene.Character("under", parts, human.skeleton))
    scene.add_lights()
    add_camera(CameraModel(35.0, 36.0, 36.0, "HORIZONTAL", 0.0, 0.0, (size, size), 100,
                           (1.0, 1.0), look_at(eye, target)))  # fmt: skip
    return render.render(path, samples=samples, resolution=(size, size))


def _posed(human, animation):
    """The human's parts posed in the first frame of ``animation``, garments resolved for
    it (exact, as exports have them), and the frame's (J, 4, 4) world matrices."""
    from avatar.part import MeshPart
    from avatar.rig import kinematics, skinning

    world = kinematics.forward(human.skeleton, animation.rotations[:1],
                               animation.translations[:1])  # fmt: skip
    matrices = kinematics.skinning_matrices(human.skeleton, world)[0]
    body = skinning.linear_blend(human.vertices, human.weights, matrices)
    garments = human.outfit.frame(body, matrices, exact=True)
    rest_parts = human.parts()
    count = len(rest_parts) - len(garments)
    out = [MeshPart(p.name, p.mesh.with_vertices(body[human.part_vertices(p.name)]), p.material)
           for p in rest_parts[:count]]  # fmt: skip
    out += [MeshPart(p.name, p.mesh.with_vertices(v), p.material)
            for p, v in zip(rest_parts[count:], garments, strict=True)]  # fmt: skip
    return out, world[0]


if __name__ == "__main__":
    main()
