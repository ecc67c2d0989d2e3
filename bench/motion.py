"""Motion benchmark: BVH parse time and retarget frames/s vs Blender and the 2020 add-on.

    .venv/bin/python bench/motion.py [CLIP.bvh] [--table]

Anchors, all measured in this run except the last:
- Blender's own importer, ``bpy.ops.import_anim.bvh`` (bpy from the venv), same file: parse
  and load times against its import time, and retarget times too ("x N vs Blender import":
  retargeting the clip onto an Avatar rig takes 1/N of the time Blender takes to import it
  onto the clip's own skeleton);
- the 2020 AVATAR add-on: 7 ms per frame retargeting onto its body (its paper's figure).
``--table`` also prints the per-clip quality table for docs/benchmarks.md.
"""

from __future__ import annotations

import os
import platform
import sys
import tempfile
import time
from datetime import date
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
FIXTURES = ROOT / ".." / "shared" / "fixtures" / "bvh"
CLIP = FIXTURES / "cmu_motionbuilder" / "01_01_forward_jumps.bvh"
ADDON_2020_MS_PER_FRAME = 7.0


def best(fn, repeat: int = 5) -> float:
    """Best wall time of ``repeat`` runs (seconds): the least disturbed on a shared box."""
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return min(times)


def blender_import_seconds(clip: Path) -> float | None:
    """Wall time of ``bpy.ops.import_anim.bvh`` on ``clip`` (None without bpy)."""
    os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp())
    try:
        import bpy
    except ImportError:
        return None

    def run():
        bpy.ops.wm.read_factory_settings(use_empty=True)
        bpy.ops.import_anim.bvh(filepath=str(clip))

    return best(run, repeat=2)


def main(argv: list[str]) -> None:
    from avatar.human import Human
    from avatar.io import bvh
    from avatar.motion.retarget import retarget

    clip = Path(next((a for a in argv if not a.startswith("--")), CLIP))
    target = Human().skeleton
    parse = best(lambda: bvh.read(clip))
    convert = best(lambda: bvh.load(clip))
    source, anim = bvh.load(clip)
    frames = anim.frames
    full = best(lambda: retarget(source, anim, target), repeat=7)
    lean = best(lambda: retarget(source, anim, target, fix_feet=False, measure=False), repeat=7)
    blender = blender_import_seconds(clip)
    print(f"# Motion benchmark, {date.today()}, {platform.processor() or platform.machine()}, "
          f"{os.cpu_count()} cores, Python {platform.python_version()}")  # fmt: skip
    print(f"clip {clip.name}: {frames} frames, {len(source.names)} joints -> "
          f"{len(target.names)}-bone default rig")  # fmt: skip
    print(f"parse (text -> arrays)        {parse * 1e3:8.1f} ms")
    print(f"load (parse + convert)        {convert * 1e3:8.1f} ms")
    if blender is not None:
        print(f"Blender import_anim.bvh       {blender * 1e3:8.1f} ms   "
              f"parse x{blender / parse:.1f} faster, load x{blender / convert:.1f}")  # fmt: skip
    for label, sec in (("retarget + feet + metrics", full), ("retarget only", lean)):
        fps = frames / sec
        vs_blender = f", x{blender / sec:.0f} vs Blender import" if blender is not None else ""
        print(f"{label:29s} {sec * 1e3:8.1f} ms = {fps:9.0f} frames/s   "
              f"x{ADDON_2020_MS_PER_FRAME / 1e3 * fps:.0f} vs 2020 add-on{vs_blender}")  # fmt: skip
    if "--table" in argv:
        quality_table(target)


def quality_table(target) -> None:
    """Markdown table: per clip median/p95 direction error, skating, penetration."""
    from avatar.io import bvh
    from avatar.motion.retarget import retarget

    print("\n| clip | convention | frames | median deg | p95 deg | skating cm/contact frame "
          "| contact frames | penetration cm |")  # fmt: skip
    print("| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: |")
    for clip in sorted(FIXTURES.glob("*/*.bvh")):
        if "face" in clip.name:
            continue
        source, anim = bvh.load(clip)
        _, rep = retarget(source, anim, target)
        q = rep.quality
        print(f"| {clip.parent.name}/{clip.name} | {rep.source_convention} | {rep.frames} | "
              f"{q.direction_median:.2f} | {q.direction_p95:.2f} | {q.skating_cm:.2f} | "
              f"{q.contact_frames} | {q.penetration_cm:.1f} |")  # fmt: skip


if __name__ == "__main__":
    main(sys.argv[1:])
