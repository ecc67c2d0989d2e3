"""Alpha-cut textures for hair, eyebrows and eyelashes (numpy, deterministic).

Every texture is painted from individual strands: tapered strokes splatted with
anti-aliased edges into an (S, S) coverage image, so alpha has opaque cores, soft edges and
see-through gaps, and a colour map follows the same strands (dark roots, lighter tips).

Layouts (UV v up, image row 0 at the top, ``material`` module convention):

- hair: v in [0.5, 1] dense strands running along v for scalp shells (u around the head),
  v in [0, 0.5] card strands from the roots (v = 0.5) to thinning tips (v = 0);
- eyebrow: u from the inner end (0) to the tail (1) of one brow, v up across it;
- eyelash: u along the lid, v from the lid margin (0) to the lash tips (1).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from avatar.looks import fabrics
from avatar.material import Material


def stroke(
    canvas: np.ndarray,
    points: np.ndarray,
    width: np.ndarray,
    value: float = 1.0,
    wrap: bool = False,
) -> None:
    """Splat one tapered strand into ``canvas`` (H, W) float32, in place (max-composited).

    points: (P, 2) polyline in pixels (x = column, y = row); width: (P,) full width in
    pixels at each point. Edges are anti-aliased over one pixel; with ``wrap`` columns
    wrap around (tileable u), else what falls outside is dropped.
    """
    h, w = canvas.shape
    pad = float(width.max()) / 2 + 1.5
    lo = np.floor(points.min(0) - pad).astype(int)
    hi = np.ceil(points.max(0) + pad).astype(int)
    y0, y1 = max(lo[1], 0), min(hi[1], h)
    if y1 <= y0:
        return
    ys, xs = np.mgrid[y0:y1, lo[0] : hi[0]]
    pix = np.stack([xs, ys], -1).astype(np.float32) + 0.5  # (h, w, 2) pixel centres
    best = np.full(xs.shape, np.inf, np.float32)
    for a, b, wa, wb in zip(points[:-1], points[1:], width[:-1], width[1:], strict=True):
        d = b - a
        t = np.clip(((pix - a) @ d) / max(float(d @ d), 1e-9), 0, 1)
        dist = np.linalg.norm(pix - (a + t[..., None] * d), axis=-1) - (wa + t * (wb - wa)) / 2
        best = np.minimum(best, dist)
    cover = np.clip(0.5 - best, 0, 1) * value
    cols = xs[0] % w if wrap else xs[0]
    inside = (cols >= 0) & (cols < w)
    cols, cover = cols[inside], cover[:, inside]
    rows = slice(y0, y1)
    canvas[rows, cols] = np.maximum(canvas[rows, cols], cover)


def _curve(start, direction, length, bend, samples: int = 5) -> np.ndarray:
    """(samples, 2) points of a gently bending strand (bend: radians over its length)."""
    t = np.linspace(0, 1, samples)
    angle = np.arctan2(direction[1], direction[0]) + bend * t
    step = length / (samples - 1)
    xy = np.stack([np.cos(angle), np.sin(angle)], -1) * step
    xy[0] = 0
    return np.asarray(start, np.float32) + np.cumsum(xy, 0).astype(np.float32)


def lash_alpha(size: int, seed: int = 0) -> np.ndarray:
    """(S, S) uint8 alpha of eyelashes (layout in the module docstring): upper lashes over
    v in [0.5, 1], lower ones (shorter, sparser) over [0, 0.5]; each half has a dense lash
    line at its root and thin strands tapering to the tips, fanning out towards the corners.
    A pixel spans about twice as much lid along u as across it along v; strands are drawn
    steep so that they stand up from the lid after that stretch."""
    rng = np.random.default_rng([seed, size, 11])
    half = size // 2
    canvas = np.zeros((size, size), np.float32)
    for root_row, count, reach, density in (
        (half - 1.0, 300, 1.0, 1.0),
        (size - 1.0, 140, 0.55, 0.75),
    ):
        for i in range(count):
            u = (i + rng.uniform(0.1, 0.9)) / count
            middle = np.sin(np.pi * u)
            if rng.uniform() > density * (0.35 + 0.65 * middle**0.5):
                continue
            length = half * reach * rng.uniform(0.6, 0.98) * (0.55 + 0.45 * middle)
            fan = 0.45 * (u - 0.5) + rng.normal(0, 0.03)  # radians off straight up
            direction = (np.sin(fan), -np.cos(fan))  # up the image (towards the tips)
            points = _curve((u * size, root_row), direction, length, 0.15 * np.sign(fan))
            width = np.linspace(0.012, 0.0025, len(points)) * size
            stroke(canvas, points, np.maximum(width, 0.7), rng.uniform(0.9, 1.0))
        line = np.linspace(1, 0, max(size // 25, 2)) ** 1.2  # the lash line at the lid margin
        rows = int(root_row) - np.arange(len(line))
        canvas[rows] = np.maximum(canvas[rows], line[:, None])
    return np.round(np.clip(canvas, 0, 1) * 255).astype(np.uint8)


def brow_shape(u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(centre line, half thickness) of an eyebrow in texture v at positions u (0 inner end,
    1 tail): a tall rounded head, the arch peaking at two thirds, a thin descending tail."""
    centre = (
        0.42
        + 0.18 * np.sin(np.pi / 2 * np.clip(u / 0.65, 0, 1))
        - 0.45 * np.clip(u - 0.65, 0, 1) ** 1.3
    )
    half = 0.2 * (1 - 0.68 * u) * np.sqrt(np.clip(u / 0.05, 0, 1))
    return centre, half * np.clip((1 - u) / 0.1, 0, 1) ** 0.6


def brow_alpha(size: int, seed: int = 0) -> np.ndarray:
    """(S, S) uint8 alpha of one eyebrow: some three thousand short slanted hairs, upright
    at the head and sweeping outward along the body; lower hairs grow up and out, upper
    ones out and down, and the edges thin out instead of ending in a hard line."""
    rng = np.random.default_rng([seed, size, 7])
    canvas = np.zeros((size, size), np.float32)
    u = rng.uniform(0.0, 1.0, 3200) ** 0.85
    centre, half = brow_shape(u)
    across = rng.uniform(-1.2, 1.2, len(u))  # -1 lower edge, +1 upper edge
    v = centre + half * across
    # Hairs thin out over the outer third of the brow's width: a soft edge, not a line.
    opacity = rng.uniform(0.75, 1.0, len(u)) * np.clip((1.3 - np.abs(across)) / 0.75, 0, 1)
    keep = (half > 0.01) & (opacity > 0.05)
    for ui, vi, ai, oi in zip(u[keep], v[keep], across[keep], opacity[keep], strict=True):
        # Degrees from the +u axis: ~75 at the head, ~20 along the body, ~5 at the tail,
        # steeper below the centre line and flatter (down) above it.
        head = np.clip(ui / 0.25, 0, 1)
        angle = 75 - 55 * head - 60 * np.clip(ui - 0.6, 0, 0.4) - 18 * head * ai
        angle = np.radians(angle + rng.normal(0, 7))
        direction = (np.cos(angle), -np.sin(angle))  # image rows run down
        length = size * rng.uniform(0.06, 0.1) * (1 - 0.35 * ui)
        start = ((0.03 + 0.85 * ui) * size, (1 - vi) * size)  # room for the tail's hairs
        points = _curve(start, direction, length, rng.normal(-0.2, 0.1), samples=4)
        width = np.linspace(0.0075, 0.002, len(points)) * size * (1 - 0.3 * ui)
        stroke(canvas, points, np.maximum(width, 0.6), oi)
    return np.round(np.clip(canvas, 0, 1) * 255).astype(np.uint8)


def strand_alpha(size: int, seed: int = 0) -> np.ndarray:
    """(S, S) uint8 alpha of the hair layout (module docstring): dense short hairs over
    the upper half (``SCALP_SHOWS`` of them missing), strands of varying length thinning
    to the tips over the lower half."""
    rng = np.random.default_rng([seed, size])
    half = size // 2
    cols = np.arange(size)
    # Strand lengths vary smoothly across u (locks) plus per-column jitter.
    locks = np.interp(cols, np.linspace(0, size, 17), rng.uniform(0.5, 1.0, 17))
    length = np.clip(locks + rng.normal(0, 0.1, size), 0.2, 1.0)
    t = (np.arange(half) + 0.5) / half  # 0 at the roots, 1 at the tips
    fade = np.clip((length[None, :] - t[:, None]) / 0.08, 0, 1)
    strands = 0.55 + 0.45 * np.sin(2 * np.pi * cols * 97 / size + rng.uniform(0, 6, size)) ** 2
    card = fade * strands[None, :] * (rng.uniform(size=size) < 0.9)[None, :]
    # The dense half (scalp caps) with a few of its short hairs missing (``SCALP_SHOWS``):
    # seen through the gaps between a buzz cut's cards, an opaque cap read as a textured
    # helmet; now the scalp shows faintly through, as under real close-cropped hair.
    gaps = np.random.default_rng([seed, size, 5])
    hairs = dense_hairs(size - half, size, gaps)
    dense = (gaps.uniform(size=hairs.max() + 1) >= SCALP_SHOWS)[hairs].astype(np.float32)
    return np.round(np.concatenate([dense, card]) * 255).astype(np.uint8)


SCALP_SHOWS = 0.18  # share of the dense half's short hairs left out (scalp between them)


def strand_shade(size: int, seed: int = 0) -> np.ndarray:
    """(S, S) float32 brightness of the hair layout: strand-to-strand variation along u,
    dark roots lightening to the tips on the cards, the scalp half as dark as the roots."""
    rng = np.random.default_rng([seed, size, 3])
    cols = np.arange(size)
    locks = np.interp(cols, np.linspace(0, size, 33), rng.uniform(0.8, 1.2, 33), period=size)
    strand = locks * rng.uniform(0.82, 1.18, size)
    half = size // 2
    t = (np.arange(size - half) + 0.5) / (size - half)  # 0 at the roots, 1 at the tips
    along = np.concatenate([np.full(half, 0.72), 0.6 + 0.65 * t**0.8])
    shade = along[:, None] * strand[None, :]
    # The dense half in short hairs (``dense_hairs``), each of its own shade: one shade a
    # column from v = 0.5 to 1 drew streaks the height of a scalp cap (a buzz cut's most).
    hairs = dense_hairs(half, size, rng)
    shade[:half] = 0.72 * locks[None, :] * rng.uniform(0.75, 1.25, hairs.max() + 1)[hairs]
    return shade.astype(np.float32)


DENSE_HAIR_ROWS = 1 / 96  # of the texture's height: a hair's length in the dense half


def dense_hairs(rows: int, size: int, rng) -> np.ndarray:
    """Indices ((rows, size) int) numbering short hairs down a (rows, size) block of a
    ``size`` texture's dense half: each column cut into lengths of ``DENSE_HAIR_ROWS``,
    staggered column to column (hair ends do not line up into rows). Index an array of
    one value per hair with it (``values[index]``, values of ``index.max() + 1``)."""
    seg = max(int(round(size * DENSE_HAIR_ROWS)), 1)
    offset = rng.integers(0, seg, size)
    along = (np.arange(rows)[:, None] + offset[None, :]) // seg
    return along * size + np.arange(size)[None, :]


def brow_shade(rgb: np.ndarray) -> float:
    """Brightness factor of brow hair over scalp hair of linear colour ``rgb`` (3,): dark
    hair's brows about as dark as the hair, fair hair's a few shades deeper so they read
    against fair skin."""
    lum = float(np.asarray(rgb, np.float32) @ np.array([0.2126, 0.7152, 0.0722], np.float32))
    return float(np.interp(lum, [0.03, 0.3], [0.9, 0.55]))


def hair_material(spec, size: int = 1024) -> Material:
    """The Material of a hair or face built-in: strand colour, normal and roughness maps
    of the ``hair`` fabric in the spec's colour, and the strand alpha of its kind.

    Lashes and brows are thinner than a pixel at most distances: they blend (glTF ``BLEND``)
    rather than cut out, so they read as soft fringes instead of dotted cards. Hair cards
    cut out (``MASK``), which real-time engines draw without sorting.
    """
    if spec.name.startswith("eyebrows"):
        alpha, mode, shade = brow_alpha(size), "BLEND", np.ones((size, size), np.float32)
    elif spec.name == "eyelashes":
        alpha, mode, shade = lash_alpha(size), "BLEND", np.ones((size, size), np.float32)
    else:
        alpha, mode, shade = strand_alpha(size), "MASK", strand_shade(size)
    m = fabrics.material("hair", spec.colour, size, name=spec.name, alpha=alpha)
    rgb = fabrics.rgb(spec.colour)[None, None, :] * shade[..., None]
    if spec.name.startswith("eyebrows"):
        # Brow hairs are about the hair's colour: dark hair's brows as dark, blond brows a
        # few shades deeper so they read against fair skin (not the near-black of a pencil).
        rgb = rgb * brow_shade(fabrics.rgb(spec.colour))
    colour = np.concatenate([fabrics.srgb(rgb), alpha[..., None]], -1)
    # Hair is a fibre, not a mirror: a weaker specular keeps dark hair from glaring white.
    extras = {**m.extras, "specular": 0.3}
    return replace(m, base_color_texture=colour, alpha_mode=mode, extras=extras)


# A buzz cut's scalp layer (the dense half of its texture, ``buzz_material``): stubble,
# not a cap. A share BUZZ_COVER of its short hairs is kept (the scalp shows between them
# up close), thinning out to BUZZ_EDGE_COVER at v = 0.5, where ``clothes.hair.base_cap``
# maps the hairline (a soft hairline, hair by hair, instead of an edge), over BUZZ_EDGE_V.
BUZZ_COVER = 0.6
BUZZ_EDGE_COVER = 0.08
BUZZ_EDGE_V = 0.1
BUZZ_CARD_KEEP = 0.7  # share of a buzz card's strand columns kept (scalp between them)
BUZZ_BUMP = 1.5  # the normal map's depth of a stubble hair (``fabrics.normal_map``)


def buzz_material(spec, size: int = 1024) -> Material:
    """A buzz cut's Material: ``hair_material`` with its dense half made stubble (short
    hairs, ``BUZZ_COVER`` of them, fewer towards the hairline's v = 0.5, each raised in
    the normal map as a short bump of its own height, so light catches hairs rather than
    one combed surface) and its cards thinned (``BUZZ_CARD_KEEP``)."""
    m = hair_material(spec, size)
    colour = np.array(m.base_color_texture, copy=True)
    normal = np.array(m.normal_texture, copy=True)
    half = size // 2
    rng = np.random.default_rng([size, 41])
    seg = max(int(round(size * DENSE_HAIR_ROWS)), 1)  # as ``dense_hairs``
    rows = np.arange(half)[:, None] + rng.integers(0, seg, size)[None, :]
    hairs = (rows // seg) * size + np.arange(size)[None, :]
    v = 1 - (np.arange(half) + 0.5) / size  # row 0 at v = 1, down to 0.5
    edge = np.clip((v - 0.5) / BUZZ_EDGE_V, 0, 1)
    share = BUZZ_EDGE_COVER + (BUZZ_COVER - BUZZ_EDGE_COVER) * edge * edge * (3 - 2 * edge)
    rank = rng.uniform(size=hairs.max() + 1)[hairs]
    kept = rank < share[:, None]
    colour[:half, :, 3] = np.where(kept, 255, 0).astype(np.uint8)
    # Each hair a bump (its own height, rounded along its length) on the scalp.
    along = rows % seg
    bump = np.sin(np.pi * (along + 0.5) / seg) * rng.uniform(0.5, 1.0, hairs.max() + 1)[hairs]
    height = np.where(kept, bump, 0.0).astype(np.float32)
    normal[:half] = fabrics.normal_map(height, BUZZ_BUMP)
    keep = (rng.uniform(size=size) < BUZZ_CARD_KEEP)[None, :]
    colour[half:, :, 3] = np.where(keep, colour[half:, :, 3], 0).astype(np.uint8)
    return replace(m, base_color_texture=colour, normal_texture=normal)
