"""Maps of a tailored garment: fabric, seams, stitching, pockets and folds painted into one
texture laid out as the garment's panels (numpy only).

A tailored garment (jeans, trousers, a skirt) has its own UV layout: each cloth panel is a
chart, in metres times ``scale`` (UV units per metre). The garment builder says what to
draw as ``Mark`` records in that UV space; ``material`` paints them over the fabric's weave
(``fabrics``), at the same size in every map:

- seam: two panels sewn together: a groove with the cloth puckered up either side;
- stitch: a row of thread stitches (dashes standing proud, in the thread colour);
- edge: the edge of a layer of cloth (a pocket's opening): a step down and its shadow;
- patch: a closed outline (a back pocket): the cloth inside raised by a layer;
- fold: a soft ridge (wrinkles behind the knee, whiskers, stacking at the hem);
- crease: a sharp pressed ridge (trousers);
- rivet / button: a small metal dome;
- wash: a soft patch where the dye is worn lighter (denim at the knees and seat).

Heights are in millimetres; the normal map is their gradient, so a seam is as deep on a
child's jeans as on a man's (the layout's ``scale`` keeps pixels per millimetre).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from avatar.looks import fabrics
from avatar.material import Material

KINDS = ("seam", "stitch", "edge", "patch", "fold", "crease", "rivet", "button", "wash")


@dataclass(frozen=True)
class Mark:
    """One thing drawn on a tailored garment.

    kind: one of ``KINDS``. points: (P, 2) UV polyline (closed for a patch, one point for
    a rivet, button or wash), or (M, 2, 2) separate segments (seams along panel edges).
    width: metres across (stitch: the thread; fold: the ridge;
    wash: the radius). strength: relative height (fold, crease) or lightening (wash);
    negative folds are valleys.
    """

    kind: str
    points: np.ndarray
    width: float = 0.002
    strength: float = 1.0

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ValueError(f"unknown mark kind {self.kind!r}; expected one of {KINDS}")


@dataclass(frozen=True)
class Layout:
    """What a tailored material is painted from: UV units per metre and the marks."""

    scale: float
    marks: tuple[Mark, ...] = ()
    thread: str | tuple[float, float, float] = "cream"  # stitching colour (name or linear RGB)
    metal: tuple[float, float, float] = (0.55, 0.36, 0.18)  # rivets and buttons (copper)
    extras: dict = field(default_factory=dict)


def _segment_distance(px: np.ndarray, a: np.ndarray, b: np.ndarray):
    """(distance, t along a->b in [0, 1]) of pixel centres px (..., 2) to a segment."""
    d = b - a
    t = np.clip(((px - a) @ d) / max(float(d @ d), 1e-12), 0, 1)
    return np.linalg.norm(px - (a + t[..., None] * d), axis=-1), t


class Canvas:
    """Distance fields of polylines on an (S, S) image, segment by segment (each in its own
    small window, so long seams cost what their pixels cost)."""

    def __init__(self, size: int):
        self.size = size

    def to_pixels(self, uv: np.ndarray) -> np.ndarray:
        uv = np.atleast_2d(np.asarray(uv, np.float64))
        return np.stack([uv[:, 0] * self.size, (1 - uv[:, 1]) * self.size], -1)

    def distance(self, points: np.ndarray, reach: float, closed: bool = False):
        """(distance px, arc length px at the nearest point, window) of a UV polyline over
        the window (row slice, column slice) of the image it reaches (``reach`` px round
        it); np.inf where no segment is within ``reach``."""
        points = np.asarray(points, np.float64)
        if points.ndim == 3:  # (M, 2, 2) separate segments
            segments = self.to_pixels(points.reshape(-1, 2)).reshape(-1, 2, 2)
        else:
            p = self.to_pixels(points)
            if closed:
                p = np.concatenate([p, p[:1]])
            if len(p) == 1:
                p = np.concatenate([p, p + 1e-3])
            segments = np.stack([p[:-1], p[1:]], 1)
        flat = segments.reshape(-1, 2)
        lo = np.clip(np.floor(flat.min(0) - reach).astype(int), 0, self.size)
        hi = np.clip(np.ceil(flat.max(0) + reach).astype(int) + 1, 0, self.size)
        window = (slice(lo[1], hi[1]), slice(lo[0], hi[0]))
        dist = np.full((hi[1] - lo[1], hi[0] - lo[0]), np.inf, np.float32)
        arc = np.zeros(dist.shape, np.float32)
        start = 0.0
        for a, b in segments:
            s0 = np.floor(np.minimum(a, b) - reach).astype(int)
            s1 = np.ceil(np.maximum(a, b) + reach).astype(int) + 1
            x0, y0 = max(s0[0], lo[0]), max(s0[1], lo[1])
            x1, y1 = min(s1[0], hi[0]), min(s1[1], hi[1])
            length = float(np.linalg.norm(b - a))
            if x1 > x0 and y1 > y0:
                ys, xs = np.mgrid[y0:y1, x0:x1]
                px = np.stack([xs, ys], -1).astype(np.float64) + 0.5
                d, t = _segment_distance(px, a, b)
                sub = (slice(y0 - lo[1], y1 - lo[1]), slice(x0 - lo[0], x1 - lo[0]))
                closer = d < dist[sub]
                dist[sub][closer] = d[closer]
                arc[sub][closer] = (start + t * length)[closer]
            start += length
        return dist, arc, window

    def inside(self, points: np.ndarray) -> np.ndarray:
        """(S, S) bool: pixels inside a closed UV polygon (even-odd rule)."""
        p = self.to_pixels(points)
        lo = np.clip(np.floor(p.min(0)).astype(int), 0, self.size)
        hi = np.clip(np.ceil(p.max(0)).astype(int) + 1, 0, self.size)
        out = np.zeros((self.size, self.size), bool)
        ys, xs = np.mgrid[lo[1] : hi[1], lo[0] : hi[0]] + 0.5
        hit = np.zeros(xs.shape, bool)
        for a, b in zip(p, np.roll(p, -1, axis=0), strict=True):
            crosses = (a[1] > ys) != (b[1] > ys)
            x_at = a[0] + (ys - a[1]) * (b[0] - a[0]) / np.where(b[1] == a[1], 1e-12, b[1] - a[1])
            hit ^= crosses & (xs < x_at)
        out[lo[1] : hi[1], lo[0] : hi[0]] = hit
        return out


def _colour(value) -> np.ndarray:
    return fabrics.rgb(value)  # a name, "#rrggbb" or linear RGB


def weave(fabric: fabrics.Fabric, size: int, px_per_metre: float) -> np.ndarray:
    """(S, S) float32 the fabric's tileable weave (in [-1, 1]) at its real scale, threads
    coarsened to at least 4 px each so they do not alias at this texel density."""
    tile = max(16, int(round(fabrics.TILE_METRES * px_per_metre)))
    threads = min(fabric.threads, max(4, tile // 4))
    h = fabrics.height_field(replace(fabric, threads=threads), tile)
    reps = size // tile + 2
    return np.tile(h, (reps, reps))[:size, :size]


def material(name: str, fabric_name: str, colour, layout: Layout, size: int = 2048) -> Material:
    """A tailored garment's Material: colour, normal and roughness maps (S, S) of the fabric
    with ``layout``'s marks painted on (see the module docstring)."""
    fabric = fabrics.FABRICS[fabric_name]
    canvas = Canvas(size)
    px_mm = layout.scale * size / 1000  # pixels per millimetre of cloth
    base = weave(fabric, size, layout.scale * size)
    height = (fabric.relief * base).astype(np.float32)  # mm: the weave's relief
    shade = (1.0 + fabric.contrast * base).astype(np.float32)
    # Warp slubs streak the cloth along its length (the panels' v runs down the leg).
    slub_tile = fabrics.streaks(256, np.random.default_rng([size, 11]), 40)
    slubs = np.tile(slub_tile, (size // 256 + 1, size // 256 + 1))[:size, :size]
    thread = np.zeros((size, size), np.float32)  # stitch coverage
    metal = np.zeros((size, size), np.float32)
    wash = np.zeros((size, size), np.float32)
    for mark in layout.marks:
        width_px = max(mark.width * 1000 * px_mm, 1.0)
        reach = {"seam": 4 * px_mm, "stitch": 2 * width_px, "edge": 5 * px_mm,
                 "patch": 3 * px_mm, "fold": 3 * width_px, "crease": 3 * width_px,
                 "rivet": width_px, "button": width_px, "wash": 2.5 * width_px}[mark.kind]
        d_win, arc_win, w = canvas.distance(mark.points, reach, closed=mark.kind == "patch")
        # Only the pixels the mark reaches (a seam mark spans the texture, thinly).
        near = np.isfinite(d_win) if mark.kind != "patch" else np.ones(d_win.shape, bool)
        if mark.kind == "patch":
            near &= canvas.inside(mark.points)[w] | np.isfinite(d_win)
        d, arc = d_win[near], arc_win[near]
        h, sh = height[w], shade[w]  # views: writing into them paints the maps
        if mark.kind == "seam":
            x = d / px_mm  # mm
            h[near] += -0.45 * np.exp(-((x / 0.6) ** 2)) + 0.25 * np.exp(-(((x - 1.8) / 1.2) ** 2))
            sh[near] *= 1 - 0.25 * np.exp(-((x / 0.8) ** 2))
        elif mark.kind == "stitch":
            period = 3.2 * px_mm  # a stitch every 3.2 mm
            core = np.clip(1 - d / (width_px / 2 + 0.5), 0, 1) * ((arc % period) < 0.72 * period)
            h[near] += 0.35 * core
            thread[w][near] = np.maximum(thread[w][near], core)
        elif mark.kind == "edge":
            x = d / px_mm
            h[near] += 0.3 * np.exp(-((x / 1.2) ** 2))
            sh[near] *= 1 - 0.35 * np.exp(-((x / 0.7) ** 2))
        elif mark.kind == "patch":
            inside = canvas.inside(mark.points)[w][near]
            x = np.minimum(d / px_mm, 3)
            h[near] += np.where(inside, 0.35 * np.clip(x / 1.5, 0, 1), 0)
            sh[near] *= 1 - 0.3 * np.exp(-((x / 0.6) ** 2))
        elif mark.kind in ("fold", "crease"):
            x = d / width_px
            profile = np.exp(-(x**2)) if mark.kind == "fold" else np.exp(-np.abs(x) * 2.5)
            ridge = mark.strength * profile
            h[near] += (0.9 if mark.kind == "fold" else 0.5) * mark.width * 1000 * ridge
            sh[near] *= 1 + 0.12 * ridge
        elif mark.kind in ("rivet", "button"):
            r = np.clip(d / (width_px / 2), 0, None)
            h[near] += 0.8 * mark.width * 1000 * np.sqrt(np.clip(1 - r**2, 0, 1))
            metal[w][near] = np.maximum(metal[w][near], (r < 1).astype(np.float32))
        else:  # wash
            fade = mark.strength * np.exp(-((d / width_px) ** 2))
            wash[w][near] = np.maximum(wash[w][near], fade)
    # Worn dye: lighter where washed, and more so on the weave's raised threads (denim).
    grain = np.kron(fabrics._noise(size // 8, np.random.default_rng([size, 7]), 1, 8),
                    np.ones((8, 8), np.float32))  # blotches, cheap at 2K  # fmt: skip
    wash = np.clip(wash * (0.8 + 0.4 * grain), 0, 1)
    rgb = fabrics.yarn_colour(fabric, _colour(colour), base, slubs) * (
        shade / (1.0 + fabric.contrast * base))[..., None]  # marks' shading  # fmt: skip
    # Worn dye fades towards the undyed yarn, most on the weave's raised threads.
    worn = np.asarray(fabric.weft if fabric.weft is not None else (0.25, 0.3, 0.41), np.float32)
    faded = rgb + wash[..., None] * (0.9 * worn * np.array([0.62, 0.78, 1.15]) - rgb) * (
        0.7 + 0.3 * base[..., None])  # fmt: skip
    thread_rgb = _colour(layout.thread).astype(np.float32)
    rgb = faded * (1 - thread[..., None]) + thread_rgb * (0.85 + 0.15 * base[..., None]) * thread[
        ..., None]  # fmt: skip
    rgb = rgb * (1 - metal[..., None]) + np.asarray(layout.metal) * metal[..., None] * (
        0.6 + 0.4 * np.clip(height, 0, 1)[..., None])  # fmt: skip
    # mm of relief -> the normal map's slope: one pixel is 1 / px_mm mm.
    normal = fabrics.normal_map(height.astype(np.float32), px_mm * 1.0)
    rough = np.clip(fabric.roughness + fabric.rough_weave * base - 0.5 * metal + 0.05 * thread
                    + 0.05 * wash, 0.15, 1)  # fmt: skip
    return Material(
        name=name,
        base_color_texture=fabrics.srgb(rgb),
        normal_texture=normal,
        roughness=1.0,
        roughness_texture=np.round(rough * 255).astype(np.uint8),
        extras={"fabric": fabric_name, "colour": colour if isinstance(colour, str) else "custom",
                "tailored": True, "uv_per_metre": layout.scale, **layout.extras},  # fmt: skip
    )


__all__ = ["KINDS", "Canvas", "Layout", "Mark", "material", "weave"]
