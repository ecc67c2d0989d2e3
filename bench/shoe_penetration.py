"""Worst footwear vertex inside the body (winding number, exact depth) at rest and through
the built-in walk, for the built-in shoes, black shoes, sneakers and boots on a few bodies,
and how far the soles stand from the floor at rest (goal: <= 1 mm inside, soles on it).

    python bench/shoe_penetration.py [--bodies 6] [--step 3]
"""

from __future__ import annotations

import argparse
import sys

import numpy as np

import avatar
from avatar.geometry import collision
from avatar.rig import kinematics, skinning

FOOTWEAR = ("shoes", "shoes-black", "sneakers", "boots")


def depth(verts: np.ndarray, body: np.ndarray, surface) -> float:
    """m: the deepest of ``verts`` (N, 3) inside the skin ``body`` (13380, 3)."""
    inside = np.flatnonzero(collision.winding_number(verts, body, surface.triangles) > 0)
    if len(inside) == 0:
        return 0.0
    return float(collision.surface_distance(verts[inside], body, surface.triangles).max())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--bodies", type=int, default=6)
    parser.add_argument("--step", type=int, default=3, help="every Nth frame of the walk")
    args = parser.parse_args()
    model = avatar.BodyModel.load()
    surface = collision.skin_surface(model.base.faces)
    rng = np.random.default_rng(14)
    bodies = [{"gender": 1.0, "age": 0.5}, {"gender": 0.0, "age": 0.45},
              {"gender": 0.3, "age": 0.12}, {"gender": 1.0, "age": 0.9, "weight": 0.9}]
    bodies += [{"gender": rng.uniform(), "age": rng.uniform(0.1, 1), "weight": rng.uniform(),
                "muscle": rng.uniform(), "height": rng.uniform()}
               for _ in range(max(0, args.bodies - 4))]  # fmt: skip
    worst = {}
    for params in bodies[: args.bodies]:
        for name in FOOTWEAR:
            human = avatar.Human(params, model=model).dressed(name)
            verts = human.outfit.garments[0].mesh.vertices
            rest = depth(verts, human.vertices[:13380], surface)
            floor = float(verts[:, 2].min())
            walk = human.walk(seconds=1.2, fps=30 / args.step)
            mats = kinematics.skinning_matrices(human.skeleton, kinematics.forward(
                human.skeleton, walk.rotations, walk.translations))  # fmt: skip
            moving = 0.0
            for m in mats:
                posed = skinning.linear_blend(human.vertices, human.weights, m)
                frame = human.outfit.frame(posed, m, exact=True)[0]
                moving = max(moving, depth(frame, posed[:13380], surface))
            worst[name] = max(worst.get(name, (0, 0, 0)), (rest, moving, abs(floor)))
            sys.stdout.write(f"{name:12s} {params}: rest {rest * 1e3:5.2f} mm, walk "
                             f"{moving * 1e3:5.2f} mm, lowest sole z {floor * 1e3:+6.2f} mm\n")
    for name, (rest, moving, floor) in worst.items():
        sys.stdout.write(f"worst {name:12s} rest {rest * 1e3:5.2f} mm  walk {moving * 1e3:5.2f} mm"
                         f"  |sole z| {floor * 1e3:5.2f} mm\n")


if __name__ == "__main__":
    main()
