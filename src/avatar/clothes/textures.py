"""Alpha-cut textures for hair, eyebrows and eyelashes (numpy, deterministic).

Hair layout (see ``hair``): image rows 0..S/2 (v 1..0.5) are dense strands for scalp caps;
rows S/2..S (v 0.5..0) are cards from the roots to the tips, each strand ending at its own
random length so the tips thin out.
"""

from __future__ import annotations

import numpy as np

from avatar.clothes import fabrics
from avatar.material import Material


def strand_alpha(size: int, seed: int = 0) -> np.ndarray:
    """(S, S) uint8 alpha: opaque upper half, strand ends in the lower half."""
    rng = np.random.default_rng([seed, size])
    cols = np.arange(size)
    # Strand lengths vary smoothly across u (locks) plus per-column jitter.
    locks = np.interp(cols, np.linspace(0, size, 17), rng.uniform(0.45, 1.0, 17))
    length = np.clip(locks + rng.normal(0, 0.12, size), 0.15, 1.0)
    t = (np.arange(size // 2) + 0.5) / (size // 2)  # 0 at the roots, 1 at the tips
    card = (t[:, None] < length[None, :]).astype(np.float32)
    card *= (rng.uniform(size=size) < 0.85)[None, :]  # some columns empty: see-through gaps
    alpha = np.concatenate([np.ones((size - size // 2, size), np.float32), card])
    return np.round(alpha * 255).astype(np.uint8)


def brow_alpha(size: int, seed: int = 0) -> np.ndarray:
    """(S, S) uint8 alpha of one eyebrow: a tapered band of slanted short strokes."""
    rng = np.random.default_rng([seed, size, 7])
    v, u = np.mgrid[0:size, 0:size] / size
    v = 1 - v  # row 0 is the top
    # Thick at the inner end (u = 0), thin at the outer end, arching slightly.
    half = 0.28 * (1 - 0.65 * u) * (u > 0.02) * (u < 0.98)
    band = np.abs(v - 0.5 - 0.08 * np.sin(np.pi * u)) < half
    strokes = np.sin(2 * np.pi * (55 * u + 14 * v) + rng.uniform(0, 6)) > 0.1
    return np.round(band * strokes * 230).astype(np.uint8)


def lash_alpha(size: int) -> np.ndarray:
    """(S, S) uint8 alpha of fine lash strands (every other thin stripe)."""
    u = np.arange(size) / size
    stripes = (np.sin(2 * np.pi * 90 * u) > 0.2).astype(np.float32)
    return np.round(np.tile(stripes, (size, 1)) * 255).astype(np.uint8)


def hair_material(spec, size: int = 1024) -> Material:
    """The Material of a hair or face built-in (hair fabric, its colour, alpha cut-out)."""
    if spec.name == "eyebrows":
        alpha = brow_alpha(size)
    elif spec.name == "eyelashes":
        alpha = lash_alpha(size)
    else:
        alpha = strand_alpha(size)
    m = fabrics.material("hair", spec.colour, size, name=spec.name, alpha=alpha)
    return m
