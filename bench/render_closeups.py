"""Render close-ups of heads or feet (docs/images/closeup_*.png) to check skin, mouth,
brows, hair, beards and shoes by eye.

    python bench/render_closeups.py heads [--samples 12] [--out docs/images] [--views front,back]
    python bench/render_closeups.py feet
    python bench/render_closeups.py legs [--walk] [--views front,back,side]   # bottoms
    python bench/render_closeups.py tops [--walk]                             # cap, hood, dress

Needs the pip ``bpy`` module. Heads: front, three-quarter and back, the mouth open
(``expression/jawOpen``) on three of them so teeth and tongue show, a beard and a
moustache. Feet: five bodies' shoes.
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
    ({"gender": 1.0, "age": 1.0}, ("eyebrows", "eyelashes", "beard-short")),
    ({"gender": 1.0, "age": 0.6, "expression/jawOpen": 0.8}, ("eyebrows", "eyelashes", "hair-short", "moustache")),  # noqa: E501
]  # fmt: skip
SETS["feet"] = [
    ({"gender": 0.3, "age": 0.12}, ("socks", "shoes", "trousers")),
    ({"gender": 0.0, "age": 0.45}, ("shoes", "jeans")),
    ({"gender": 1.0, "age": 0.5, "muscle": 0.9}, ("socks", "shoes", "shorts")),
    ({"gender": 0.0, "age": 0.9, "weight": 0.9}, ("shoes", "skirt")),
    ({"gender": 1.0, "age": 1.0}, ("socks", "shoes", "trousers")),
]  # fmt: skip
SETS["legs"] = [  # jeans, trousers, skirt, dress on four bodies, waist to floor
    ({"gender": 0.0, "age": 0.45}, ("jeans", "sneakers")),
    ({"gender": 1.0, "age": 0.5, "weight": 0.7}, ("jeans", "boots")),
    ({"gender": 1.0, "age": 0.9}, ("trousers", "shoes-black")),
    ({"gender": 0.0, "age": 0.6, "weight": 0.9}, ("tanktop", "skirt", "shoes")),
    ({"gender": 0.0, "age": 0.3}, ("dress", "shoes-black")),
]  # fmt: skip
SETS["tops"] = [  # cap and hood from the shoulders up
    ({"gender": 1.0, "age": 0.5}, ("eyebrows", "eyelashes", "hair-short", "tshirt", "cap")),
    ({"gender": 1.0, "age": 0.3, "muscle": 0.8}, ("eyebrows", "eyelashes", "hair-buzz", "hoodie")),
    ({"gender": 0.0, "age": 0.12}, ("eyebrows", "eyelashes", "hair-bob", "hoodie", "cap")),
    ({"gender": 0.0, "age": 0.4}, ("eyebrows", "eyelashes", "hair-long", "dress")),
]  # fmt: skip
SETS["hair"] = [  # issue 14's hair and facial-hair checks: ages, long and tied hair, a cap
    ({"gender": 1.0, "age": 0.45}, ("eyebrows", "eyelashes", "hair-short", "stubble")),
    ({"gender": 1.0, "age": 0.95}, ("eyebrows", "eyelashes", "hair-short", "moustache")),
    ({"gender": 0.0, "age": 0.95}, ("eyebrows", "eyelashes", "hair-bob")),
    ({"gender": 0.0, "age": 0.45}, ("eyebrows", "eyelashes", "hair-long")),
    ({"gender": 0.0, "age": 0.35}, ("eyebrows", "eyelashes", "hair-ponytail")),
    ({"gender": 0.0, "age": 0.3}, ("eyebrows", "eyelashes", "hair-bob")),
    ({"gender": 1.0, "age": 0.5}, ("eyebrows", "eyelashes", "hair-short", "cap")),
]  # fmt: skip
SETS["looks5"] = [  # issue 14's hair after the fifth look pass: every style, child to elderly
    ({"gender": 0.3, "age": 0.12}, ("eyebrows", "eyelashes", "hair-bob")),
    ({"gender": 0.0, "age": 0.45}, ("eyebrows", "eyelashes", "hair-long")),
    ({"gender": 0.0, "age": 0.35}, ("eyebrows", "eyelashes", "hair-ponytail")),
    ({"gender": 1.0, "age": 0.25}, ("eyebrows", "eyelashes", "hair-short")),
    ({"gender": 1.0, "age": 0.5}, ("eyebrows", "eyelashes", "hair-short")),
    ({"gender": 0.0, "age": 0.95}, ("eyebrows", "eyelashes", "hair-bun")),
    ({"gender": 1.0, "age": 0.95}, ("eyebrows", "eyelashes", "hair-buzz")),
]  # fmt: skip
SETS["facial"] = [  # moustache, short beard and stubble, young and old, framed on the mouth
    ({"gender": 1.0, "age": 0.5}, ("eyebrows", "eyelashes", "hair-short", "moustache")),
    ({"gender": 1.0, "age": 0.95}, ("eyebrows", "eyelashes", "hair-short", "moustache")),
    ({"gender": 1.0, "age": 0.45}, ("eyebrows", "eyelashes", "hair-short", "beard-short")),
    ({"gender": 1.0, "age": 1.0, "weight": 0.8}, ("eyebrows", "eyelashes", "beard-short")),
    ({"gender": 1.0, "age": 0.4}, ("eyebrows", "eyelashes", "hair-buzz", "stubble")),
    ({"gender": 1.0, "age": 0.7, "african": 1.0, "asian": 0.0, "caucasian": 0.0}, ("eyebrows", "eyelashes", "hair-short", "stubble")),  # noqa: E501
]  # fmt: skip
SETS["jacket"] = [  # issue 14's sixth pass: the jacket's construction, man, woman, child
    ({"gender": 1.0, "age": 0.5}, ("jacket", "tshirt", "jeans")),
    ({"gender": 0.0, "age": 0.45}, ("jacket", "longsleeve", "trousers")),
    ({"gender": 1.0, "age": 0.9, "weight": 0.8}, ("jacket", "tshirt", "trousers")),
]  # fmt: skip
SETS["shoes6"] = [  # issue 14's sixth pass: shoes, sneakers and boots side by side
    ({"gender": 1.0, "age": 0.5}, ("socks", "shoes", "jeans")),
    ({"gender": 0.0, "age": 0.45}, ("socks", "sneakers", "jeans")),
    ({"gender": 0.3, "age": 0.12}, ("socks", "sneakers", "shorts")),
    ({"gender": 1.0, "age": 0.5, "weight": 0.7}, ("socks", "boots", "jeans")),
]  # fmt: skip
HEAD_SETS = ("heads", "hair", "looks5", "facial")
CROWN_AIM = 1.8 - 0.32  # tops: crowns put at 1.8 m (as heads), the camera on the shoulders
# set -> (metres between bodies, frame height / width per body, aim height (m))
FRAMING = {"legs": (0.6, 2.2, 0.62), "tops": (0.55, 1.25, CROWN_AIM),
           "facial": (0.22, 1.0, 1.8 - 0.2), "jacket": (0.75, 1.2, 1.2),
           "shoes6": (0.42, 0.5, 0.07)}  # fmt: skip
# Per set: where the camera looks (z of the aim point relative to the aligned height, m),
# and the views (name -> direction from subject to camera).
VIEWS = {
    "front": (0.0, -1.0, 0.05), "side": (0.9, -1.0, 0.1), "back": (0.0, 1.0, 0.1),
    "low": (0.7, -1.0, 0.35), "top": (0.0, 0.75, 1.0),
}  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("set", choices=sorted(SETS))
    parser.add_argument("--views", default="front,side,back")
    parser.add_argument("--samples", type=int, default=12)
    parser.add_argument("--out", default="docs/images")
    parser.add_argument("--name", default="closeup")
    parser.add_argument("--size", type=int, default=260, help="pixels per head (square)")
    parser.add_argument("--walk", action="store_true", help="mid-stride in the built-in walk")
    args = parser.parse_args()
    from avatar.blender import render, scene
    from avatar.human import Human

    out = Path(args.out)
    chars = []
    chosen = SETS[args.set]
    heads = args.set in HEAD_SETS
    spacing, tall, aim = FRAMING.get(args.set, (SPACING if heads else 0.55, 1.0, None))
    for i, (params, names) in enumerate(chosen):
        human = Human(params).dressed(*names)  # stands on its shoes' soles
        outfit = human.outfit  # exact, as exports have it; its parts come last in parts()
        crowns = heads or args.set == "tops"
        top = float(human.vertices[:13380, 2].max()) if crowns else 0.0
        # Side by side, crowns (or soles) at one height, so one camera frames them all.
        location = ((i - (len(chosen) - 1) / 2) * spacing, 0.0, CROWN - top if crowns else 0.0)
        shown = human.parts()
        if args.walk:
            shown = _mid_stride(human, outfit, shown)
        chars.append(scene.Character(f"head{i}", shown, human.skeleton, location=location))
    size = (args.size * len(chars), int(args.size * tall))
    for view in args.views.split(","):
        direction = VIEWS[view]
        scene.clear_scene()
        for c in chars:
            scene.build_character(c)
        scene.add_lights()
        if not heads:
            scene.add_floor()
        height = aim if aim is not None else (CROWN - 0.14 if heads else 0.07)
        _aim(direction, spacing * len(chosen), size, height)
        stem = f"{args.name}_{args.set}{'_walk' if args.walk else ''}_{view}"
        path = render.render(out / f"{stem}.png", samples=args.samples,
                             resolution=size)  # fmt: skip
        print(path)


def _mid_stride(human, outfit, rest_parts):
    """The parts posed a quarter into the built-in walk (legs apart), garments resolved for
    the frame (exact) and shaded as ``library.garment_part`` shades them, walking in place."""
    from avatar.clothes.library import garment_normals
    from avatar.part import MeshPart
    from avatar.rig import kinematics, skinning

    walk = human.walk(seconds=1.0, fps=24)
    world = kinematics.forward(human.skeleton, walk.rotations[6:7], walk.translations[6:7])
    matrices = kinematics.skinning_matrices(human.skeleton, world)[0]
    body = skinning.linear_blend(human.vertices, human.weights, matrices)
    garments = outfit.frame(body, matrices, exact=True)
    shift = np.zeros(3, np.float32)
    shift[:2] = (body[:13380] - human.vertices[:13380]).mean(axis=0)[:2]
    count = len(rest_parts) - len(garments)
    out = [MeshPart(p.name, p.mesh.with_vertices(body[human.part_vertices(p.name)] - shift),
                    p.material) for p in rest_parts[:count]]  # fmt: skip
    return out + [MeshPart(p.name, p.mesh.with_vertices(v - shift), p.material,
                           normals=garment_normals(g, v))
                  for p, g, v in zip(rest_parts[count:], outfit.garments, garments,
                                     strict=True)]  # fmt: skip


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
