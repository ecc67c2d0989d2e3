"""Clothes benchmark: fit + penetration-resolve speed, and the worst penetration over bodies.

    .venv/bin/python bench/clothes.py [--bodies 200] [--frames 300]

1. Shape change: dress a new body in four garments (T-shirt, jeans, shoes, short hair);
   goal < 5 ms per garment. Anchor: the body's own shape evaluation in the same run.
2. Posed frames: a 300-frame walk, body skinned + garments skinned and resolved per frame;
   goal > 60 frames/s. Anchor: skinning the body alone. Then every 10th frame with
   ``exact=True`` (what exports bake), against the real-time path.
3. Penetration: random bodies (all ages, both sexes, extreme weights) x every built-in
   item (garments, hair, facial hair, brows, lashes; as seven layered outfits) and, when
   the test fixtures are present, the MakeHuman fixture garments, in rest pose, over the
   walk and (every 10th body, when the fixtures are present) CMU's forward jumps, every
   ``--step``-th (``--jump-step``-th) frame at 30 fps; ``--shard K/N`` runs every Nth body
   from K, so N processes share the work. Reports the deepest garment vertex inside the
   body (goal: <= 1 mm), confirmed by the winding number, split into free and pinched
   (where skinning pushed one body part into another; see ``Worst``).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

import avatar
from avatar.clothes import library
from avatar.geometry import collision
from avatar.rig import kinematics, skinning

OUTFITS = [("tshirt", "jeans", "socks", "shoes", "cap"),
           ("longsleeve", "hoodie", "trousers", "hair-long"),
           ("tanktop", "jacket", "shorts", "leggings", "hair-ponytail"),
           ("swimsuit", "skirt", "dress", "hair-short"),
           ("tshirt", "cardigan", "sweatpants", "sneakers", "hair-bob", "beard-short"),
           ("longsleeve", "jeans", "socks", "boots", "hair-bun", "moustache"),
           ("tanktop", "trousers", "shoes-black", "hair-buzz", "stubble", "eyebrows-black",
            "eyelashes")]  # fmt: skip
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
    library.dress(avatar.Human({}, model=model).body, garments)  # warm-up: anchors, weights
    bodies = []
    for w in np.linspace(0.1, 0.9, 20):  # a new body each call, realised outside the timing
        human = avatar.Human({"weight": w, "gender": 0.3}, model=model)
        human.vertices, human.weights, human.skeleton  # noqa: B018
        bodies.append(human)
    times = []
    for human in bodies:
        start = time.perf_counter()
        library.dress(human.body, garments)
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
    walk = human.walk(seconds=frames / 30, fps=30)
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
    start = time.perf_counter()
    for t in range(0, frames, 10):  # exact: every vertex tested by winding number
        body = skinning.linear_blend(human.vertices, human.weights, mats[t])
        outfit.frame(body, mats[t], exact=True)
    exact = (time.perf_counter() - start) / len(range(0, frames, 10))
    print(f"posed frames, exact=True: {exact * 1e3:.0f} ms a frame, ratio {exact / dressed:.1f}x "
          f"the real-time path")  # fmt: skip


MH_CLOTHES = JUMP.parents[1] / "makehuman"
PINCH_REACH = 0.03  # m: skin inside the body this close to a garment vertex pinches it


def mh_outfits() -> list[tuple[str, ...]]:
    """The MakeHuman fixture garments as outfits (paths), when the fixtures are present."""
    found = sorted(str(p) for p in MH_CLOTHES.glob("*/*/*.mhclo"))
    suits = [p for p in found if "suit" in p]
    rest = [p for p in found if "suit" not in p and "eyebrow" not in p and "eyelash" not in p]
    return [(suit, *rest[i % len(rest) : i % len(rest) + 1]) for i, suit in enumerate(suits)]


class Worst:
    """Deepest garment vertex inside the body, per case, split by where the body is whole.

    free: the skin around the vertex is not inside another body part.
    pinched: skinning pushed one body part into another within ``PINCH_REACH`` of the
        vertex (a thigh into the belly in a crouch): there the body has no outside between
        the parts, so a garment caught between them is inside one of them.
    """

    def __init__(self):
        self.depth: dict[str, float] = {}
        self.where: dict[str, str] = {}

    def add(self, case: str, depth: float, where: str) -> None:
        if depth > self.depth.get(case, -1.0):
            self.depth[case], self.where[case] = depth, where

    def line(self) -> str:
        return ", ".join(
            f"{k} {v * 1e3:.2f} mm ({self.where[k]})" for k, v in sorted(self.depth.items())
        )


def check_frame(worst: Worst, case: str, body, surface, faces, outfit, verts_list, label) -> None:
    """Measure one frame: the winding number (right even where the body passes into itself)
    finds the garment vertices inside the body, the exact distance to all its triangles
    says how deep, and the skin around them tells free from pinched."""
    x = body[:13380]
    normals = surface.normals(x)
    for g, verts in zip(outfit.garments, verts_list, strict=True):
        worst.add(case + " free", 0.0, "-")
        inside = np.flatnonzero(collision.winding_number(verts, x, surface.triangles) > 0)
        if len(inside) == 0:
            continue
        depth = np.zeros(len(verts), np.float32)
        depth[inside] = collision.surface_distance(verts[inside], x, surface.triangles)
        # Skin within reach of the vertex (its depth plus PINCH_REACH) that lies inside
        # the body itself: one part pushed into another there.
        reach = depth[inside] + PINCH_REACH
        near = cKDTree(x).query_ball_point(verts[inside], reach)
        skin = np.unique(np.concatenate([np.asarray(n, np.int64) for n in near]))
        lifted = x[skin] + 5e-4 * normals[skin]
        overlap = skin[collision.winding_number(lifted, x, surface.triangles) > 0]
        pinched = np.zeros(len(inside), bool)
        if len(overlap):
            gap = cKDTree(x[overlap]).query(verts[inside])[0]
            pinched = gap < reach
        for kind, mask in (("free", ~pinched), ("pinched", pinched)):
            if mask.any():
                worst.add(f"{case} {kind}", float(depth[inside][mask].max()), f"{g.name}, {label}")


def random_body(rng) -> dict[str, float]:
    return {"gender": rng.uniform(), "age": rng.uniform(0.0, 1.0),
            "weight": rng.choice([0.0, 1.0, rng.uniform()]), "muscle": rng.uniform(),
            "height": rng.uniform()}  # fmt: skip


def worst_penetration(model, bodies: int, jump_every: int, step: int, exact: bool,
                      jump_step: int, shard: tuple[int, int] = (0, 1)) -> None:  # fmt: skip
    rng = np.random.default_rng(2020)
    every = [random_body(rng) for _ in range(bodies)]  # the same bodies however sharded
    surface = collision.skin_surface(model.base.faces)
    faces = model.base.faces[model.base.face_groups["body"]]
    jump = avatar.load_bvh(JUMP / "01_01_forward_jumps.bvh") if JUMP.is_dir() else None
    outfits = [("built-in", names) for names in OUTFITS] + [("MakeHuman", o) for o in mh_outfits()]
    worst = Worst()
    start = time.perf_counter()
    for i in range(shard[0], bodies, shard[1]):
        params = every[i]
        label = ", ".join(f"{k} {v:.2f}" for k, v in params.items())
        body = avatar.Human(params, model=model)
        clips = {"walk": body.walk(seconds=1.2, fps=30 / step)}
        if jump is not None and jump_every and i % jump_every == 0:
            clips["jump"] = body.retarget(*jump, measure=False,
                                            frames=slice(0, 2752, 3 * jump_step))[0]  # fmt: skip
        mats = {
            name: kinematics.skinning_matrices(
                body.skeleton,
                kinematics.forward(body.skeleton, clip.rotations, clip.translations),
            )
            for name, clip in clips.items()
        }
        for kind, names in outfits:
            human = body.dressed(*names)
            outfit = human.outfit
            rest = [g.mesh.vertices for g in outfit.garments]
            check_frame(worst, f"{kind} rest", human.vertices, surface, faces, outfit, rest, label)
            for name, m in mats.items():
                for t in range(len(m)):
                    posed = skinning.linear_blend(human.vertices, human.weights, m[t])
                    frame = outfit.frame(posed, m[t], exact=exact)
                    where = f"{label}, frame {t}"
                    check_frame(
                        worst, f"{kind} {name}", posed, surface, faces, outfit, frame, where
                    )
        if (i + 1) % 5 < shard[1] or i + shard[1] >= bodies or jump_every == 1:
            print(
                f"  {i + 1} bodies, {time.perf_counter() - start:.0f} s: {worst.line()}", flush=True
            )
    print(f"penetration over {bodies} bodies (goal <= 1 mm, free):")
    for case in sorted(worst.depth):
        print(f"  {case:28s} {worst.depth[case] * 1e3:7.2f} mm  ({worst.where[case]})")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--bodies", type=int, default=200)
    parser.add_argument("--frames", type=int, default=300)
    parser.add_argument(
        "--jump-every", type=int, default=10, help="jump on every Nth body (0: never)"
    )
    parser.add_argument("--step", type=int, default=3, help="check every Nth frame (30 fps)")
    parser.add_argument("--jump-step", type=int, default=36, help="same, for the jumps")
    parser.add_argument("--shard", default="0/1", help="K/N: bodies K, K+N, ... (parallel runs)")
    parser.add_argument("--only-penetration", action="store_true")
    parser.add_argument(
        "--fast", action="store_true", help="measure the real-time path, not frame(exact=True)"
    )
    args = parser.parse_args()
    model = avatar.BodyModel.load()
    if not args.only_penetration:
        shape_change(model)
        posed_frames(model, args.frames)
    shard = tuple(int(k) for k in args.shard.split("/"))
    worst_penetration(model, args.bodies, args.jump_every, args.step, not args.fast,
                      args.jump_step, (shard[0], shard[1]))  # fmt: skip


if __name__ == "__main__":
    main()
