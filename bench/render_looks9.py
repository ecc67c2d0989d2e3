"""Render the ninth look pass's shoe close-ups (docs/images/looks9_shoes_*.png): a man in
shoes, a woman in boots, a child in sneakers, one body a picture, framed closer than
``render_shoe_last``'s sets, with ``render_closeups``' cameras.

    python bench/render_looks9.py s9-shoes --views profile,front --size 360 --samples 12
    python bench/render_looks9.py s9-boots --views side --walk
    python bench/render_looks9.py s9-shoes --views toe --at 0.2,-0.12,0.16  # one shoe
    python bench/render_looks9.py sheet BEFORE_DIR AFTER_DIR OUT.png s9-shoes_profile ...

``sheet`` puts renders side by side (a row per folder: before over after).
Needs the pip ``bpy`` module (Cycles on the CPU).
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import render_closeups as closeups  # noqa: E402
import render_shoe_last as shoe_last  # noqa: E402

SETS = {f"s9-{names[-1]}": [(body, names)] for body, names in shoe_last.SETS["s8"]}
FRAMING = {name: (0.56, 0.55, 0.05) for name in SETS}  # one pair, 56 cm across
VIEWS = {**shoe_last.VIEWS, "toe": (0.35, -1.0, 0.35)}  # from in front, a little above


def sheet(rows: list[str], out: str, stems: list[str]) -> None:
    """Renders ``stems`` from each folder in ``rows`` side by side, a row per folder (two:
    labelled before and after), saved with a 256-colour palette (docs pictures < 400 KB)."""
    import numpy as np
    from PIL import Image, ImageDraw

    grid = [np.concatenate([np.asarray(Image.open(Path(r) / f"closeup_{s}.png").convert("RGB"))
                            for s in stems], 1) for r in rows]  # fmt: skip
    image = Image.fromarray(np.concatenate(grid, 0))
    if len(rows) == 2:
        draw = ImageDraw.Draw(image)
        for k, label in enumerate(("before", "after")):
            y = k * grid[0].shape[0]
            draw.rectangle((0, y, 60, y + 14), fill=(0, 0, 0))
            draw.text((4, y + 1), label, fill=(255, 255, 255))
    image.quantize(256, method=Image.Quantize.MEDIANCUT).save(out, optimize=True)


def _aimed_at(x: float, y: float, width: float, z: float | None = None):
    """``render_closeups``' camera aimed at (x, y, z: the set's aim height if None),
    ``width`` m across (one shoe close)."""
    import numpy as np

    from avatar.blender.camera import add_camera
    from avatar.camera import CameraModel, look_at

    def aim(direction, _width: float, size: tuple[int, int], height: float) -> None:
        back = np.asarray(direction, float) / np.linalg.norm(direction)
        centre = np.array([x, y, height if z is None else z])
        distance = width / 2 * 85.0 / 18.0
        add_camera(CameraModel(85.0, 36.0, 24.0, "HORIZONTAL", 0.0, 0.0, size, 100, (1.0, 1.0),
                               look_at(centre + back * distance, centre)))  # fmt: skip

    return aim


def main() -> None:
    if sys.argv[1] == "sheet":
        sheet(sys.argv[2:4], sys.argv[4], sys.argv[5:])
        return
    if "--at" in sys.argv:  # --at x,y,width[,z]: one shoe, close (the left one: x ~ 0.2)
        i = sys.argv.index("--at")
        closeups._aim = _aimed_at(*(float(a) for a in sys.argv[i + 1].split(",")))
        del sys.argv[i : i + 2]
    closeups.SETS.update(SETS)
    closeups.FRAMING.update(FRAMING)
    closeups.VIEWS.update(VIEWS)
    closeups.main()


if __name__ == "__main__":
    main()
