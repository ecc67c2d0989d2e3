"""Floor contact of the skinned body after retargeting every fixture clip.

    .venv/bin/python bench/motion_floor.py [--frames N]

Per clip (onto the default Avatar body and rig): the lowest skin vertex per frame against
the floor z = 0 (``avatar.motion.floor``), on at most N evenly spaced frames (default 3000),
as retargeted (the retargeter alone, no mesh) and after ``floor.settle`` (vertical shifts,
frame by frame, putting planted feet on the floor), and the time one measurement took.
Prints a table for docs/benchmarks.md.
Also retargets each clip with its joints renamed ``j0..jN`` (bone map by topology) and
reports the largest change of a body segment's direction against the name-based result.
"""

from __future__ import annotations

import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
FIXTURES = ROOT / ".." / "shared" / "fixtures" / "bvh"


def _segments(target, animation, segs):
    from avatar.rig.kinematics import forward

    heads = forward(target, animation.rotations, animation.translations)[..., :3, 3]
    return heads[:, segs[:, 1]] - heads[:, segs[:, 0]]


def main(argv: list[str]) -> None:
    from avatar.human import Human
    from avatar.io import bvh
    from avatar.motion import bonemap, floor, geometry
    from avatar.motion.retarget import retarget

    most = int(argv[argv.index("--frames") + 1]) if "--frames" in argv else 3000
    human = Human()
    target = human.skeleton
    tmap = bonemap.detect(target)
    segs = np.array([(tmap.bones[r], tmap.bones[n]) for r, n in bonemap.NEXT.items()
                     if r in bonemap.CORE and n in bonemap.CORE])  # fmt: skip
    print("| clip | frames | skinned | as retargeted: penetration cm (frames) | hover cm median "
          "/ max | contact frames | settle shift cm | settled: penetration cm | hover cm median "
          "/ max | measure s | renamed: max deg |")  # fmt: skip
    print("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    for clip in sorted(FIXTURES.glob("*/*.bvh")):
        if "face" in clip.name:
            continue
        source, anim = bvh.load(clip)
        out, _ = retarget(source, anim, target)
        before = floor.measure_body(human.body, out, most)
        settled, shift = floor.settle_body(human.body, out, most)
        t = time.perf_counter()
        rep = floor.measure_body(human.body, settled, most)
        seconds = time.perf_counter() - t
        names = tuple(f"j{j}" for j in range(len(source.names)))
        anon = replace(source, names=names)
        a, _ = retarget(source, anim, target, match_names=False, measure=False)
        b, _ = retarget(anon, replace(anim, bone_names=names), target, match_names=False,
                        measure=False)  # fmt: skip
        err = geometry.angle(_segments(target, a, segs), _segments(target, b, segs)).max()
        print(
            f"| {clip.parent.name}/{clip.name} | {rep.total_frames} | {rep.frames} | "
            f"{before.penetration_cm:.1f} ({before.penetrating * 100:.1f}%) | "
            f"{before.hover_cm:.1f} / {before.hover_max_cm:.1f} | {before.contact_frames} | "
            f"{np.median(shift) * 100:+.1f} ({shift.min() * 100:+.1f}..{shift.max() * 100:+.1f}) | "
            f"{rep.penetration_cm:.1f} | {rep.hover_cm:.1f} / {rep.hover_max_cm:.1f} | "
            f"{seconds:.2f} | {err:.3f} |"
        )


if __name__ == "__main__":
    main(sys.argv[1:])
