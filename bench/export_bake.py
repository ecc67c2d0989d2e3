"""Exporting a dressed, animated human: baked garment corrections against plain skinning.

    .venv/bin/python bench/export_bake.py [--seconds 10] [--fps 30] [--wear tshirt,jeans,...]

One dressed body (the default human, game_engine rig), the built-in walk. In the same run:
the plain skinned GLB (``resolve_garments=False``) and the baked one (one morph target per
corrected frame per garment, ``avatar.clothes.bake``): export time, the bake's time per
frame (``Outfit.frame(exact=True)`` alone as the anchor), file sizes, how many frames got a
target and how many garment vertices a target moves on average. Prints a table for
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


def _frame_anchor(human, walk, frames: int) -> float:
    """Seconds per ``Outfit.frame(exact=True)`` call (body skinning included), median."""
    from avatar.rig import kinematics, skinning

    world = kinematics.forward(human.skeleton, walk.rotations[:frames], walk.translations[:frames])
    matrices = kinematics.skinning_matrices(human.skeleton, world)
    times = []
    for t in range(frames):
        start = time.perf_counter()
        body = skinning.linear_blend(human.vertices, human.weights, matrices[t])
        human.outfit.frame(body, matrices[t], exact=True)
        times.append(time.perf_counter() - start)
    return float(np.median(times))


def _targets(path: Path) -> tuple[int, int, float]:
    """(garment parts with targets, targets, mean vertices moved per target) of a file."""
    import pygltflib

    gltf = pygltflib.GLTF2().load(str(path))
    counts = [
        (gltf.accessors[t["POSITION"]].sparse.count if gltf.accessors[t["POSITION"]].sparse
         else gltf.accessors[t["POSITION"]].count)
        for m in gltf.meshes for t in (m.primitives[0].targets or [])
    ]  # fmt: skip
    parts = sum(1 for m in gltf.meshes if m.primitives[0].targets)
    return parts, len(counts), float(np.mean(counts)) if counts else 0.0


def main(argv: list[str]) -> None:
    import avatar

    seconds, fps = float(_arg(argv, "--seconds", "10")), float(_arg(argv, "--fps", "30"))
    wear = _arg(argv, "--wear", WEAR).split(",")
    human = avatar.Human({}, rig="game_engine").dressed(*wear)
    walk = human.walk(seconds=seconds, fps=fps)
    start = time.perf_counter()
    human.outfit  # noqa: B018 -- dress once, outside both timings
    dress = time.perf_counter() - start
    anchor = _frame_anchor(human, walk, min(20, walk.frames))
    with tempfile.TemporaryDirectory() as tmp:
        rows = {}
        for label, resolve in (("plain", False), ("baked", True)):
            path = Path(tmp) / f"{label}.glb"
            start = time.perf_counter()
            avatar.save(human, path, walk, resolve_garments=resolve)
            rows[label] = (time.perf_counter() - start, path.stat().st_size, _targets(path))
    (plain_s, plain_b, _), (baked_s, baked_b, counts) = rows["plain"], rows["baked"]
    parts, targets, moved = counts
    per_frame = (baked_s - plain_s) / walk.frames
    print(f"{walk.frames} frames ({seconds:g} s at {fps:g} fps), garments: {', '.join(wear)}; "
          f"dressing {dress:.2f} s")  # fmt: skip
    print("| measure | plain skinned | baked | ratio |")
    print("| --- | ---: | ---: | ---: |")
    print(f"| export time | {plain_s:.1f} s | {baked_s:.1f} s | {baked_s / plain_s:.1f}x |")
    exact = f"`Outfit.frame(exact=True)` ({anchor * 1e3:.0f} ms)"
    print(f"| bake per frame (export difference / frames) | | {per_frame * 1e3:.0f} ms | "
          f"{per_frame / anchor:.2f}x {exact} |")  # fmt: skip
    print(f"| GLB size | {plain_b / 1e6:.2f} MB | {baked_b / 1e6:.2f} MB | "
          f"{baked_b / plain_b:.2f}x |")  # fmt: skip
    print(f"| morph targets | 0 | {targets} on {parts} garments | "
          f"{targets / max(parts, 1) / walk.frames:.0%} of frames |")  # fmt: skip
    print(f"| vertices moved per target (mean) | | {moved:.0f} | "
          f"{(baked_b - plain_b) / max(targets, 1) / 1e3:.1f} kB/target |")  # fmt: skip


if __name__ == "__main__":
    main(sys.argv[1:])
