"""Facial hair materials: strand cards of beards and moustaches, and tiled stubble.

Beards and moustaches use the hair layout of ``textures`` (strand cards, roots at
v = 0.5); stubble is a tileable texture of short hairs cut a day or three ago, drawn
on a layer lifted just off the skin (``clothes.face.stubble``, one repeat per 3 cm).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from avatar.looks import fabrics, textures
from avatar.material import Material


def beard_material(spec, size: int = 1024) -> Material:
    """A beard's or moustache's cut-out strand material in the spec's hair colour (the
    scalp hair's, ``textures.hair_material``) with its card strands thinned: beard hair is
    sparse, so only about two hair-wide columns in five are kept and skin shows between
    them (a card of scalp strands would read as a solid block on the face)."""
    m = textures.hair_material(spec, size)
    colour = np.array(m.base_color_texture, copy=True)
    rng = np.random.default_rng([size, 17])
    hair = max(size // 340, 1)  # texels per hair across (a card's ~0.1 mm at 1024 px)
    kept = np.repeat(rng.uniform(size=size // hair + 1) < 0.4, hair)[:size]
    cards = slice(size - size // 2, size)  # rows of the strand-card half (v in [0, 0.5])
    colour[cards, :, 3] = colour[cards, :, 3] * kept[None, :]
    return replace(m, base_color_texture=colour)


def stubble_alpha(size: int, seed: int = 0) -> np.ndarray:
    """(S, S) uint8 tileable alpha of stubble: a faint shadow of hair under the skin and
    some sixteen hundred short stubs, each a fraction of a millimetre thick and one to two
    long, pointing down the face (the texture's -v) with some scatter."""
    rng = np.random.default_rng([seed, size, 13])
    canvas = np.zeros((size, size), np.float32)
    count = 1600
    start = rng.uniform([0, 0.03 * size], [size, 0.95 * size], (count, 2))
    angle = np.radians(90 + rng.normal(0, 25, count))  # image rows run down
    length = size * rng.uniform(0.02, 0.045, count)
    for p, a, n in zip(start, angle, length, strict=True):
        points = np.array([p, p + n * np.array([np.cos(a), np.sin(a)])], np.float32)
        width = np.array([0.0045, 0.003], np.float32) * size
        textures.stroke(canvas, points, np.maximum(width, 0.8), rng.uniform(0.6, 0.9), wrap=True)
    return np.round(np.clip(0.1 + 0.8 * canvas, 0, 1) * 255).astype(np.uint8)


def stubble_material(spec, size: int = 1024) -> Material:
    """Stubble in the spec's hair colour: blended (glTF ``BLEND``) over the skin, so the
    stubs and the shadow between them darken it without hard edges."""
    alpha = stubble_alpha(size)
    rgb = fabrics.rgb(spec.colour).astype(np.float32) * 0.8
    colour = np.concatenate([np.broadcast_to(fabrics.srgb(rgb), (size, size, 3)),
                             alpha[..., None]], -1)  # fmt: skip
    return Material(
        name=spec.name,
        base_color_texture=np.ascontiguousarray(colour),
        roughness=0.6,
        alpha_mode="BLEND",
        double_sided=False,
        extras={"fabric": "stubble", "colour": spec.colour},
    )
