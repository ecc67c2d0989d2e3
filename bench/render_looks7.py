"""Render the close-ups of issue 14's seventh garment pass (docs/images/looks7_*.png): flared
hems mid-stride (the dress on three bodies, the skirt), the cardigan's back hem on the
elderly woman and the hoodie's hood from behind, with ``render_closeups``' cameras.

    python bench/render_looks7.py hems --views front,back --walk --samples 16
    python bench/render_looks7.py seat --views back [--walk]
    python bench/render_looks7.py hood --views back,side
    python bench/render_looks7.py hem4 --views back --walk --frame 4   # another walk frame

Needs the pip ``bpy`` module (Cycles on the CPU).
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import render_closeups as closeups  # noqa: E402

SETS = {
    "hems": [  # the dress on three bodies and the skirt on a woman
        ({"gender": 0.0, "age": 0.3}, ("dress", "shoes-black")),
        ({"gender": 0.3, "age": 0.15}, ("dress", "sneakers")),
        ({"gender": 0.0, "age": 0.6, "weight": 1.0}, ("dress", "shoes")),
        ({"gender": 0.0, "age": 0.45}, ("tshirt", "skirt", "shoes-black")),
    ],
    "hem4": [  # the calf of the back leg sweeping into the dress's hem early in the stride
        ({"gender": 0.3, "age": 0.15}, ("dress", "sneakers")),
        ({"gender": 0.0, "age": 0.3}, ("dress", "shoes-black")),
    ],
    "seat": [  # the cardigan's back hem over leggings on the elderly woman
        ({"gender": 0.0, "age": 0.95, "weight": 0.6}, ("tshirt", "cardigan", "leggings")),
        ({"gender": 0.0, "age": 0.9, "weight": 0.7}, ("tshirt", "cardigan", "leggings")),
    ],
    "hood": [  # the hoodie's hood lying on the back
        ({"gender": 1.0, "age": 0.3, "muscle": 0.8}, ("hair-buzz", "hoodie", "jeans")),
        ({"gender": 0.0, "age": 0.4}, ("hair-bob", "hoodie", "jeans")),
    ],
}  # fmt: skip
FRAMING = {"hem4": (0.6, 0.6, 0.36), "hems": (0.6, 1.0, 0.55), "seat": (0.7, 0.5, 0.78),
           "hood": (0.7, 0.45, 1.12)}  # fmt: skip


def main() -> None:
    if "--frame" in sys.argv:  # a walk frame other than render_closeups' quarter stride
        at = sys.argv.index("--frame")
        frame = int(sys.argv[at + 1])
        del sys.argv[at:at + 2]
        closeups._mid_stride = lambda human, outfit, parts: _walk_frame(human, outfit, parts,
                                                                       frame)  # fmt: skip
    closeups.SETS.update(SETS)
    closeups.FRAMING.update(FRAMING)
    closeups.main()


def _walk_frame(human, outfit, rest_parts, frame: int):
    """``render_closeups._mid_stride`` at ``frame`` of the built-in walk (24 fps)."""
    import numpy as np

    from avatar.part import MeshPart
    from avatar.rig import kinematics, skinning

    walk = human.walk(seconds=1.0, fps=24)
    world = kinematics.forward(human.skeleton, walk.rotations[frame:frame + 1],
                               walk.translations[frame:frame + 1])  # fmt: skip
    matrices = kinematics.skinning_matrices(human.skeleton, world)[0]
    body = skinning.linear_blend(human.vertices, human.weights, matrices)
    garments = outfit.frame(body, matrices, exact=True)
    shift = np.zeros(3, np.float32)
    shift[:2] = (body[:13380] - human.vertices[:13380]).mean(axis=0)[:2]
    count = len(rest_parts) - len(garments)
    out = [MeshPart(p.name, p.mesh.with_vertices(body[human.part_vertices(p.name)] - shift),
                    p.material) for p in rest_parts[:count]]  # fmt: skip
    return out + [MeshPart(p.name, p.mesh.with_vertices(v - shift), p.material)
                  for p, v in zip(rest_parts[count:], garments, strict=True)]  # fmt: skip


if __name__ == "__main__":
    main()
