"""Exporting a dressed, animated human: compact baked garment corrections against plain skinning.

    .venv/bin/python bench/export_bake.py [--seconds 10] [--fps 30] [--wear tshirt,jeans,...]
    .venv/bin/python bench/export_bake.py --clip CLIP.bvh   # e.g. CMU 01_01 (2,752 frames)
    .venv/bin/python bench/export_bake.py --clip CLIP.bvh --frames 1000:1500   # an excerpt
    ... --keep DIR   # keep both GLBs in DIR (to inspect a frame that goes inside)

One dressed body (the default human, game_engine rig), the built-in walk or a BVH clip
retargeted onto it. In the same run: the plain skinned GLB (``resolve_garments=False``) and
the baked one (a few correction shapes per garment and segment of the clip driven by
per-frame weights, ``avatar.clothes.bake``): export time, the bake's time per frame
(``Outfit.frame(exact=True)`` alone as the anchor), file sizes, correction shapes per
garment, and the worst garment penetration played back from each file (morphs blended with
the keyed weights, then the file's skin and animation: what a viewer shows), naming each
baked frame more than 1 mm inside (garment, vertex, depth). Prints a table for
docs/benchmarks.md.
"""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

import numpy as np

WEAR = "tshirt,jeans,shoes,hair-short"


def _arg(argv: list[str], name: str, default: str) -> str:
    return argv[argv.index(name) + 1] if name in argv else default


def _excerpt(clip, frames: str):
    """(the clip's frames ``start:stop[:step]``, a label for them); all without ``frames``."""
    from dataclasses import replace

    if not frames:
        return clip, ""
    rows = slice(*(int(x) if x else None for x in frames.split(":")))
    excerpt = replace(clip, rotations=clip.rotations[rows], translations=clip.translations[rows])
    return excerpt, f" frames {frames}"


def _frame_anchor(human, clip, frames: int) -> float:
    """Seconds per ``Outfit.frame(exact=True)`` call (body skinning included), median."""
    from avatar.rig import kinematics, skinning

    world = kinematics.forward(human.skeleton, clip.rotations[:frames], clip.translations[:frames])
    matrices = kinematics.skinning_matrices(human.skeleton, world)
    times = []
    for t in range(frames):
        start = time.perf_counter()
        body = skinning.linear_blend(human.vertices, human.weights, matrices[t])
        human.outfit.frame(body, matrices[t], exact=True)
        times.append(time.perf_counter() - start)
    return float(np.median(times))


def _played_penetration(path: Path, faces: np.ndarray) -> tuple[float, list[str]]:
    """(worst depth (m) of a garment vertex inside the body over every frame, one line per
    frame with any vertex more than 1 mm inside), played back from the file alone."""
    from avatar.geometry import collision
    from avatar.human import BODY_PART_GROUPS
    from avatar.io import gltf
    from avatar.rig import kinematics, skinning

    file = gltf.read(path)
    name, clip = next(iter(file.animations.items()))
    keyed = file.morph_weights.get(name, {})
    world = kinematics.forward(file.skeleton, clip.rotations, clip.translations)
    parts = {p.name: p for p in file.parts}
    garments = [p for n, p in parts.items() if n not in BODY_PART_GROUPS and "_LOD" not in n]
    worst, bad = 0.0, []
    for t in range(clip.frames):
        matrices = kinematics.skinning_matrices(file.skeleton, world[t : t + 1])[0]
        skin = skinning.SkinWeights(*parts["body"].skin)
        body = skinning.linear_blend(parts["body"].mesh.vertices, skin, matrices)
        frame_worst, where = 0.0, ""
        for g in garments:
            rest = g.mesh.vertices.astype(np.float64)
            for k, delta in enumerate(g.morphs.values()):
                if g.name in keyed and keyed[g.name][t, k]:
                    rest = rest + keyed[g.name][t, k] * delta
            posed = skinning.linear_blend(rest, skinning.SkinWeights(*g.skin), matrices)
            depth = collision.penetration(body, faces, posed)[1]
            if depth.max() > frame_worst:
                frame_worst, where = float(depth.max()), f"{g.name} vertex {depth.argmax()}"
        worst = max(worst, frame_worst)
        if frame_worst > 1e-3:
            bad.append(f"frame {t}: {where} {frame_worst * 1e3:.1f} mm inside")
    return worst, bad


def main(argv: list[str]) -> None:
    import avatar
    from avatar.clothes import bake
    from avatar.human import BODY_PART_GROUPS

    seconds, fps = float(_arg(argv, "--seconds", "10")), float(_arg(argv, "--fps", "30"))
    wear = _arg(argv, "--wear", WEAR).split(",")
    human = avatar.Human({}, rig="game_engine").dressed(*wear)
    if "--clip" in argv:
        source = Path(_arg(argv, "--clip", ""))
        clip, _ = human.retarget(*avatar.load_bvh(source))
        clip, excerpt = _excerpt(clip, _arg(argv, "--frames", ""))
        label = f"{source.stem}{excerpt}: {clip.frames} frames at {clip.fps:g} fps"
    else:
        clip = human.walk(seconds=seconds, fps=fps)
        label = f"walk: {clip.frames} frames ({seconds:g} s at {fps:g} fps)"
    start = time.perf_counter()
    human.outfit  # noqa: B018 -- dress once, outside both timings
    dress = time.perf_counter() - start
    anchor = _frame_anchor(human, clip, min(20, clip.frames))
    faces = human.model.base.faces[human.model.base.face_groups["body"]]
    keep = _arg(argv, "--keep", "")
    with tempfile.TemporaryDirectory() as scratch:
        tmp = keep or scratch
        Path(tmp).mkdir(parents=True, exist_ok=True)
        rows = {}
        for name, resolve in (("plain", False), ("baked", True)):
            path = Path(tmp) / f"{name}.glb"
            start = time.perf_counter()
            avatar.save(human, path, clip, resolve_garments=resolve)
            seconds_taken = time.perf_counter() - start
            shapes = {p.name: len(p.morphs) for p in avatar.load(path).parts
                      if p.name not in BODY_PART_GROUPS}  # fmt: skip
            rows[name] = (seconds_taken, path.stat().st_size, shapes,
                          _played_penetration(path, faces))  # fmt: skip
    (plain_s, plain_b, _, plain_in), (baked_s, baked_b, shapes, baked_in) = rows.values()
    per_frame = (baked_s - plain_s) / clip.frames
    print(f"{label}; garments: {', '.join(wear)}; dressing {dress:.2f} s")
    print("| measure | plain skinned | baked | ratio |")
    print("| --- | ---: | ---: | ---: |")
    print(f"| export time | {plain_s:.1f} s | {baked_s:.1f} s | {baked_s / plain_s:.1f}x |")
    exact = f"`Outfit.frame(exact=True)` ({anchor * 1e3:.0f} ms)"
    print(f"| bake per frame (export difference / frames) | | {per_frame * 1e3:.0f} ms | "
          f"{per_frame / anchor:.2f}x {exact} |")  # fmt: skip
    print(f"| GLB size | {plain_b / 1e6:.2f} MB | {baked_b / 1e6:.2f} MB | "
          f"{baked_b / plain_b:.2f}x |")  # fmt: skip
    segments = len(bake.segments(clip.frames))
    print(f"| correction shapes (incl. offsets; {segments} segments) | 0 | "
          f"{', '.join(f'{k} {v}' for k, v in shapes.items())} | |")  # fmt: skip
    print(f"| worst garment depth inside the body, played back | {plain_in[0] * 1e3:.1f} mm | "
          f"{baked_in[0] * 1e3:.1f} mm | |")  # fmt: skip
    print(f"| frames with a garment vertex > 1 mm inside | {len(plain_in[1])} | "
          f"{len(baked_in[1])} | of {clip.frames} |")  # fmt: skip
    for line in baked_in[1][:20]:
        print(f"baked {line}")


if __name__ == "__main__":
    main(sys.argv[1:])
