"""Render the README's pictures: `.venv/bin/python docs/pictures.py [bodies]`.

Writes docs/images/bodies.png (a row of bodies across the parameter space).
"""

from __future__ import annotations

import os
import sys
import tempfile
from pathlib import Path

os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="avatar-blender-"))

from avatar import export  # noqa: E402
from avatar.blender import render  # noqa: E402
from avatar.body.model import BodyModel  # noqa: E402
from avatar.human import Human  # noqa: E402

IMAGES = Path(__file__).parent / "images"
BODIES = {
    "child": {"age": 0.12, "gender": 0.4, "caucasian": 1.0},
    "old man": {"age": 1.0, "gender": 1.0, "weight": 0.65, "african": 1.0},
    "muscular woman": {"gender": 0.0, "muscle": 1.0, "weight": 0.55, "asian": 1.0},
    "default": {},
    "heavy, belly +2.5": {"gender": 0.7, "weight": 1.0, "pca/belly": 2.5},
    "thin, tall": {"gender": 0.2, "weight": 0.0, "height": 0.9, "pca/limbs_fat": -2},
    "hips fat +3": {"gender": 0.0, "pca/hips_fat": 3.0, "pca/breast": 2.0},
}


def bodies() -> Path:
    model = BodyModel.load()
    chars = [export.character(Human(p, model=model), name=n) for n, p in BODIES.items()]
    return render.render_grid(chars, IMAGES / "bodies.png", spacing=0.9,
                              resolution=(1800, 700), samples=48)  # fmt: skip


def _strip(human, animation, path: Path, every: int) -> Path:
    character = export.character(human, animation)
    return render.render_strip(character, path, every=every, panel=(240, 400), samples=24)


def motion() -> list[Path]:
    """docs/images/walk.png (built-in walk) and jump.png (CMU 01_01, from the test fixtures)."""
    import avatar

    model = BodyModel.load()
    walker = Human({"gender": 0.8, "age": 0.35}, model=model).dressed(
        "tshirt", "jeans", "shoes", "hair-short", "eyebrows")  # fmt: skip
    out = [_strip(walker, walker.walk(seconds=1.0, fps=24), IMAGES / "walk.png", 4)]
    clip = Path(__file__).resolve().parents[2] / "shared/fixtures/bvh/cmu_motionbuilder"
    if (clip / "01_01_forward_jumps.bvh").is_file():
        jumper = Human({"gender": 0.1, "muscle": 0.7}, model=model).dressed(
            "tanktop", "leggings", "shoes", "hair-ponytail", "eyebrows")  # fmt: skip
        skeleton, anim = avatar.load_bvh(clip / "01_01_forward_jumps.bvh")
        # Retargeting onto the Human (not just its skeleton) stands the clip on its soles.
        jump, _ = jumper.retarget(skeleton, anim, frames=slice(120, 360), fps=24)
        out.append(_strip(jumper, jump, IMAGES / "jump.png", 8))
    return out


if __name__ == "__main__":
    for name in sys.argv[1:] or ["bodies", "motion"]:
        print(globals()[name]())
