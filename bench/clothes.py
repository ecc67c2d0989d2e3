"""Clothes benchmark: fit + penetration-resolve speed, and the worst penetration over bodies.

    .venv/bin/python bench/clothes.py [--bodies 200] [--frames 300]

1. Shape change: dress a new body in four garments (T-shirt, jeans, shoes, short hair);
   goal < 5 ms per garment. Anchor: the body's own shape evaluation in the same run.
2. Posed frames: a 300-frame walk, body skinned + garments skinned and resolved per frame;
   goal > 60 frames/s. Anchor: skinning the body alone.
3. Penetration: random bodies (all ages, both sexes, extreme weights) x every built-in
   garment (as four layered outfits), in rest pose and over the walk (every 10th frame) and,
   when the test fixtures are present, CMU's forward jumps. Reports the deepest garment
   vertex inside the body (goal: <= 1 mm).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

import avatar
from avatar.clothes import collision, library
from avatar.rig import kinematics, skinning

OUTFITS = [("tshirt", "jeans", "socks", "shoes", "cap"),
           ("longsleeve", "hoodie", "trousers", "hair-long"),
           ("tanktop", "jacket", "shorts", "leggings", "hair-ponytail"),
           ("swimsuit", "skirt", "dress", "hair-short")]  # fmt: skip
FOUR = ("tshirt", "jeans", "shoes", "hair-short")
JUMP = Path(__file__).resolve().parents[2] / "shared/fixtures/bvh/cmu_motionbuilder"


def timed(fn, repeat: int) -> float:
    fn()
    start = time.perf_counter()
    for _ in range(repeat):
        fn()
    return (time.perf_counter() - start) / repeat


def shape_change(model) -> None:
    garments = [library.load_garment(n) for n in FOUR]
    library.dress(avatar.Human({}, model=model), garments)  # warm-up: anchors, weights
    bodies = []
    for w in np.linspace(0.1, 0.9, 20):  # a new body each call, realised outside the timing
        human = avatar.Human({"weight": w, "gender": 0.3}, model=model)
        human.vertices, human.weights, human.skeleton  # noqa: B018
        bodies.append(human)
    times = []
    for human in bodies:
        start = time.perf_counter()
        library.dress(human, garments)
        times.append(time.perf_counter() - start)
    fit = float(np.median(times))
    weights = iter(np.linspace(0.1, 0.9, 1000))  # a new body each call (no memo)
    body = timed(lambda: model.shape({"weight": next(weights), "gender": 0.3}), 20)
    print(f"shape change: {fit * 1e3:.1f} ms for 4 garments = {fit / 4 * 1e3:.2f} ms/garment "
          f"(goal < 5; median of 20 new bodies); body shape alone {body * 1e3:.2f} ms, "
          f"ratio {fit / 4 / body:.1f}x")  # fmt: skip


def posed_frames(model, frames: int) -> None:
    human = avatar.Human({"gender": 0.6}, model=model).dressed(*FOUR)
    outfit = human.outfit
    walk = avatar.walk(human.skeleton, seconds=frames / 30, fps=30)
    mats = kinematics.skinning_matrices(
        human.skeleton, kinematics.forward(human.skeleton, walk.rotations, walk.translations)
    )
    start = time.perf_counter()
    for t in range(frames):
        body = skinning.linear_blend(human.vertices, human.weights, mats[t])
        outfit.frame(body, mats[t])
    dressed = (time.perf_counter() - start) / frames
    alone = timed(lambda: skinning.linear_blend(human.vertices, human.weights, mats[0]), 20)
    print(f"posed frames: {1 / dressed:.0f} frames/s with 4 garments (goal > 60); body "
          f"skinning alone {1 / alone:.0f} frames/s, ratio {dressed / alone:.1f}x")  # fmt: skip


def worst_penetration(model, bodies: int) -> None:
    rng = np.random.default_rng(2020)
    faces = model.base.faces[model.base.face_groups["body"]]
    worst = {"rest": 0.0, "walk": 0.0, "jump": 0.0}
    jump = avatar.load_bvh(JUMP / "01_01_forward_jumps.bvh") if JUMP.is_dir() else None
    for i in range(bodies):
        params = {"gender": rng.uniform(), "age": rng.uniform(0.0, 1.0),
                  "weight": rng.choice([0.0, 1.0, rng.uniform()]), "muscle": rng.uniform(),
                  "height": rng.uniform()}  # fmt: skip
        for names in OUTFITS:
            human = avatar.Human(params, model=model).dressed(*names)
            outfit = human.outfit
            for part in library.parts(outfit):
                d = collision.penetration(human.vertices[:13380], faces, part.mesh.vertices)[1]
                worst["rest"] = max(worst["rest"], float(d.max()))
            clips = {"walk": avatar.walk(human.skeleton, seconds=1.0, fps=10)}
            if jump is not None and i % 10 == 0:
                clips["jump"] = avatar.retarget(*jump, human.skeleton, frames=slice(0, 2700, 90),
                                                measure=False)[0]  # fmt: skip
            for name, clip in clips.items():
                worst[name] = max(worst[name], _motion_worst(human, outfit, clip, faces))
        if (i + 1) % 10 == 0:
            print(f"  {i + 1} bodies: worst depth (mm) " +
                  ", ".join(f"{k} {v * 1e3:.2f}" for k, v in worst.items()), flush=True)  # fmt: skip
    print(f"penetration over {bodies} bodies x {sum(map(len, OUTFITS))} garments: " +
          ", ".join(f"{k} {v * 1e3:.2f} mm" for k, v in worst.items()) + " (goal <= 1 mm)")  # fmt: skip


def _motion_worst(human, outfit, clip, faces) -> float:
    mats = kinematics.skinning_matrices(
        human.skeleton, kinematics.forward(human.skeleton, clip.rotations, clip.translations)
    )
    worst = 0.0
    for t in range(clip.frames):
        body = skinning.linear_blend(human.vertices, human.weights, mats[t])
        for verts in outfit.frame(body, mats[t]):
            worst = max(worst, float(collision.penetration(body[:13380], faces, verts)[1].max()))
    return worst


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--bodies", type=int, default=200)
    parser.add_argument("--frames", type=int, default=300)
    args = parser.parse_args()
    model = avatar.BodyModel.load()
    shape_change(model)
    posed_frames(model, args.frames)
    worst_penetration(model, args.bodies)


if __name__ == "__main__":
    main()
