"""Blender exports of a dressed, animated human: baked garment shape keys against plain skinning.

    .venv/bin/python bench/export_blender_bake.py [--seconds 1] [--fps 30] [--wear tshirt,jeans]

One dressed body (the default human, game_engine rig), the built-in walk, exported through
Blender (pip ``bpy``) to .blend, .fbx and .usdc, once plain (``resolve_garments=False``)
and once baked (one shape key per corrected frame per garment, keyed by a CONSTANT action on
the Key datablock). Prints per-format export times and sizes, then the baked run split into
its steps: the garment bake (numpy, ``avatar.clothes.bake``), building the scene (shape keys
and their action included) and the writer, so the Blender-side overhead of the keys shows.
"""

from __future__ import annotations

import os
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="avatar-bpy-"))

WEAR = "tshirt,jeans"
FORMATS = (".blend", ".fbx", ".usdc")


def _arg(argv: list[str], name: str, default: str) -> str:
    return argv[argv.index(name) + 1] if name in argv else default


def _steps(human, walk) -> dict[str, float]:
    """Seconds of the baked export's steps (to .blend) and the shape key count."""
    from avatar import export as files
    from avatar.blender import export, scene

    start = time.perf_counter()
    character = files.character(human, walk)
    baked = time.perf_counter()
    scene.clear_scene()
    built = scene.build_character(character)
    staged = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp:
        export.export(Path(tmp) / "steps.blend", [built.root, *built.parts])
    written = time.perf_counter()
    keys = sum(len(o.data.shape_keys.key_blocks) - 1 for o in built.parts if o.data.shape_keys)
    return {"bake": baked - start, "build": staged - baked, "write": written - staged,
            "keys": keys}  # fmt: skip


def _plain_build(human, walk) -> float:
    from avatar import export
    from avatar.blender import scene

    character = export.character(human, walk, resolve_garments=False)
    scene.clear_scene()
    start = time.perf_counter()
    scene.build_character(character)
    return time.perf_counter() - start


def main(argv: list[str]) -> None:
    import avatar

    seconds, fps = float(_arg(argv, "--seconds", "1")), float(_arg(argv, "--fps", "30"))
    human = avatar.Human(rig="game_engine").dressed(*_arg(argv, "--wear", WEAR).split(","))
    walk = human.walk(seconds=seconds, fps=fps)
    print(f"{walk.frames} frames, garments {[g.name for g in human.outfit]}")  # fit once, untimed
    print("| format | plain s | baked s | plain MB | baked MB |")
    print("|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        for suffix in FORMATS:
            row = []
            for resolve in (False, True):
                path = Path(tmp) / f"{'baked' if resolve else 'plain'}{suffix}"
                start = time.perf_counter()
                avatar.save(human, path, walk, resolve_garments=resolve)
                row.append((time.perf_counter() - start, path.stat().st_size / 1e6))
            print(f"| {suffix} | {row[0][0]:.2f} | {row[1][0]:.2f} "
                  f"| {row[0][1]:.1f} | {row[1][1]:.1f} |")  # fmt: skip
    steps = _steps(human, walk)
    plain = _plain_build(human, walk)
    print(f"baked .blend steps: bake {steps['bake']:.2f} s "
          f"({steps['bake'] / walk.frames * 1e3:.0f} ms a frame), build {steps['build']:.2f} s "
          f"(plain build {plain:.2f} s), write {steps['write']:.2f} s; "
          f"{steps['keys']} frame shape keys")  # fmt: skip


if __name__ == "__main__":
    main(sys.argv[1:])
