"""A contact sheet of dataset samples: per row RGB with COCO keypoints (green visible, orange
occluded) and boxes, body parts, instances (one hue per person, shades per garment), depth
and camera-frame normals. For looking at labels, in docs and in reviews."""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from avatar.dataset import store
from avatar.dataset.people import COCO_SKELETON, PARTS
from avatar.io import exr


def _palette(n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    out = rng.integers(40, 255, (n, 3)).astype(np.uint8)
    out[0] = 0
    return out


def sheet(out: Path, ids: Sequence[int], path: Path, cell: int = 192) -> Path:
    """Write a PNG contact sheet of samples ``ids`` of dataset folder ``out``."""
    from PIL import Image, ImageDraw

    rows = []
    parts_colours = _palette(len(PARTS) + 1, 3)
    for i in ids:
        folder = store.sample_dir(out, i)
        meta = json.loads((folder / "meta.json").read_text())
        rgb = Image.open(folder / "rgb.png").convert("RGB")
        scale = cell / max(rgb.size)
        draw_rgb = rgb.resize((round(rgb.width * scale), round(rgb.height * scale)))
        d = ImageDraw.Draw(draw_rgb)
        for person in meta["people"]:
            kps = np.array(person["coco_keypoints"], dtype=float)
            for a, b in COCO_SKELETON:
                if kps[a - 1, 2] > 0 and kps[b - 1, 2] > 0:
                    d.line([tuple(kps[a - 1, :2] * scale), tuple(kps[b - 1, :2] * scale)],
                           fill=(80, 180, 255), width=1)  # fmt: skip
            for x, y, v in kps:
                if v > 0:
                    colour = (60, 230, 60) if v == 2 else (255, 150, 0)
                    d.ellipse([x * scale - 2, y * scale - 2, x * scale + 2, y * scale + 2],
                              fill=colour)  # fmt: skip
            if person["bbox"]:
                x, y, w, h = (c * scale for c in person["bbox"])
                d.rectangle([x, y, x + w, y + h], outline=(255, 255, 0))
        parts = np.array(Image.open(folder / "parts.png"))
        inst = np.array(Image.open(folder / "instances.png")).astype(np.int64)
        hue = _palette(1000, 5)[np.clip(inst, 0, 999)]
        depth = exr.read(folder / "depth.exr")["Z"]
        finite = np.isfinite(depth)
        shade = np.zeros(depth.shape, np.uint8)
        if finite.any():
            lo, hi = np.percentile(depth[finite], [1, 99])
            shade[finite] = (255 * (1 - np.clip((depth[finite] - lo) / max(hi - lo, 1e-6),
                                                0, 1)) * 0.85 + 38).astype(np.uint8)  # fmt: skip
        normals = exr.read(folder / "normals.exr")
        n = np.stack([normals["X"], -normals["Y"], -normals["Z"]], axis=-1)  # OpenGL-style view
        n_img = ((n * 0.5 + 0.5) * 255 * (np.abs(n).sum(-1, keepdims=True) > 0)).astype(np.uint8)
        panels = [draw_rgb] + [
            Image.fromarray(a).resize(draw_rgb.size, Image.Resampling.NEAREST)
            for a in (parts_colours[parts], hue.astype(np.uint8), shade, n_img)
        ]
        row = Image.new("RGB", (sum(p.width for p in panels), draw_rgb.height))
        x = 0
        for p in panels:
            row.paste(p.convert("RGB"), (x, 0))
            x += p.width
        rows.append(row)
    sheet_img = Image.new("RGB", (max(r.width for r in rows), sum(r.height for r in rows)))
    y = 0
    for r in rows:
        sheet_img.paste(r, (0, y))
        y += r.height
    path.parent.mkdir(parents=True, exist_ok=True)
    sheet_img.save(path)
    return path


def conventions(out: Path, index: int, path: Path, scale: int = 3) -> Path:
    """A sample's RGB with its conventions drawn on it: the pixel axes u (right) and v
    (down) from pixel (0, 0), the principal point, the world axes X, Y, Z (red, green,
    blue, 0.5 m) at the origin projected through K and world_to_camera, and each person's
    3D joints projected (dots)."""
    from PIL import Image, ImageDraw

    from avatar.camera import project

    folder = store.sample_dir(out, index)
    meta = json.loads((folder / "meta.json").read_text())
    K, w2c = np.array(meta["K"]), np.array(meta["world_to_camera"])
    rgb = Image.open(folder / "rgb.png").convert("RGB")
    image = rgb.resize((rgb.width * scale, rgb.height * scale), Image.Resampling.LANCZOS)
    d = ImageDraw.Draw(image)

    def at(u: float, v: float) -> tuple[float, float]:  # OpenCV pixel -> drawn position
        return ((u + 0.5) * scale, (v + 0.5) * scale)

    d.line([at(0, 0), at(40, 0)], fill=(255, 255, 255), width=2)
    d.line([at(0, 0), at(0, 40)], fill=(255, 255, 255), width=2)
    d.text(at(42, -4), "u (x)", fill=(255, 255, 255))
    d.text(at(2, 42), "v (y)", fill=(255, 255, 255))
    d.text(at(3, 3), "(0, 0): centre of the top-left pixel", fill=(255, 255, 255))
    cx, cy = K[0, 2], K[1, 2]
    d.ellipse([*at(cx - 1.5, cy - 1.5), *at(cx + 1.5, cy + 1.5)], outline=(255, 255, 0))
    d.text(at(cx + 3, cy + 2), "(cx, cy)", fill=(255, 255, 0))
    axes = project(np.array([[0, 0, 0], [0.5, 0, 0], [0, 0.5, 0], [0, 0, 0.5]]), K, w2c)
    for end, colour, name in zip(axes[1:], [(255, 60, 60), (60, 255, 60), (80, 140, 255)],
                                 "XYZ", strict=True):  # fmt: skip
        d.line([at(*axes[0][:2]), at(*end[:2])], fill=colour, width=3)
        d.text(at(end[0] + 2, end[1]), f"world {name}", fill=colour)
    for person in meta["people"]:
        for u, v, z in person["joints_2d"]:
            if z > 0:
                d.point(at(u, v), fill=(255, 0, 255))
    path.parent.mkdir(parents=True, exist_ok=True)
    image.save(path)
    return path
