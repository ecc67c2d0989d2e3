"""Procedural fabrics: tileable colour, normal and roughness maps (numpy only).

Each fabric is a height field built from periodic pieces (weave rows and columns, knit loops,
grain noise from random Fourier phases), so every map tiles seamlessly; the normal map is the
height field's periodic gradient and colour and roughness follow the same structure. One tile
covers ``TILE_METRES`` of cloth; garment UVs are in tiles, so texel density is the same on
every garment (2048 px per 20 cm is ~0.1 mm per pixel).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from avatar.material import Material

TILE_METRES = 0.2
# The finest period (m) a knit's or plain weave's relief keeps at full strength. Cycles
# samples textures without mipmaps, so a finer one aliases at render distance (a pixel
# spans 1-1.5 mm of cloth on a full figure): 1-3 mm knit rows and 1 mm cotton threads
# with 45-58 degrees of RMS normal tilt beat into moire (zig-zag bands on a cardigan,
# shimmer on a T-shirt). Finer relief fades to FINE_FLOOR of its strength: still there
# in a close-up, no longer loud enough to beat. Twills (denim, wool) keep theirs: their
# diagonal is their look, and tailored garments coarsen threads to the texel density.
FINEST, FINE_FLOOR = 0.0035, 0.08


@dataclass(frozen=True)
class Fabric:
    """A fabric's look: height-field recipe, roughness and sheen."""

    name: str
    weave: str  # "plain", "twill", "knit", "grain", "strands"
    threads: int  # thread count (or knit loops) across one tile
    depth: float  # normal strength
    roughness: float
    contrast: float  # colour variation driven by the height field
    # Yarn-dyed twill (denim): the colour is the warp's; the undyed weft (linear RGB) shows
    # in the twill's valleys, up to ``weft_share`` of a texel, and the warp's ring-spun
    # slubs streak the cloth along its length by +-``slub``.
    weft: tuple[float, float, float] | None = None
    weft_share: float = 0.0
    slub: float = 0.0
    relief: float = 0.12  # mm: the weave's height on a tailored garment's normal map
    rough_weave: float = 0.06  # roughness change over the weave (fibre ridges vs valleys)


FABRICS = {
    "cotton": Fabric("cotton", "plain", 180, 1.2, 0.85, 0.12),
    "denim": Fabric("denim", "twill", 120, 2.0, 0.8, 0.2, weft=(0.42, 0.4, 0.34),
                    weft_share=0.3, slub=0.18, relief=0.3, rough_weave=0.16),
    # A knit's loops are in its relief (normal map); its colour varies only faintly with
    # them, or the fine V-loops shimmer (moire) at a distance and their direction shows.
    "knit": Fabric("knit", "knit", 36, 1.8, 0.9, 0.06),
    "jersey": Fabric("jersey", "knit", 90, 1.2, 0.8, 0.1),
    # Garment leather: a soft satin-to-matte grain (roughness ~0.55-0.7, gently varied),
    # shallow, so it reads as leather rather than crinkled wet plastic with glittery specks.
    "leather": Fabric("leather", "grain", 40, 0.35, 0.62, 0.05, rough_weave=0.09),
    "canvas": Fabric("canvas", "plain", 70, 1.8, 0.9, 0.2),
    # Stretch knit (leggings, swimsuits): a soft satin sheen, not a gloss; at 0.35 black
    # leggings read as latex, with mirror-like streaks down the shins.
    "lycra": Fabric("lycra", "knit", 160, 0.6, 0.55, 0.06),
    "wool": Fabric("wool", "twill", 60, 2.2, 0.95, 0.25),
    "hair": Fabric("hair", "strands", 220, 2.5, 0.5, 0.6),
    "rubber": Fabric("rubber", "grain", 90, 0.8, 0.75, 0.05),
    "calf": Fabric("calf", "grain", 220, 0.25, 0.35, 0.04),  # smooth shoe leather
    # A leather sole's edge, inked and burnished: smooth, semi-matt (rubber's grain and
    # roughness read as grey plastic on a dress shoe).
    "sole": Fabric("sole", "grain", 160, 0.2, 0.5, 0.03, rough_weave=0.05),
    "cord": Fabric("cord", "twill", 40, 2.5, 0.9, 0.3),
    "linen": Fabric("linen", "plain", 110, 1.6, 0.9, 0.22),  # coarse, slubby plain weave
}

COLOURS = {
    "white": (0.85, 0.85, 0.83), "black": (0.03, 0.03, 0.035), "grey": (0.35, 0.36, 0.38),
    # Indigo: a denim's warp as worn (mid-dark, before the weft shows through); light
    # indigo a light wash, dark indigo a rinse.
    "navy": (0.03, 0.06, 0.18), "indigo": (0.014, 0.024, 0.085), "red": (0.55, 0.05, 0.05),
    "green": (0.08, 0.25, 0.1), "olive": (0.2, 0.22, 0.08), "khaki": (0.45, 0.38, 0.22),
    "brown": (0.18, 0.09, 0.04), "beige": (0.62, 0.52, 0.4), "sky": (0.3, 0.5, 0.75),
    "yellow": (0.8, 0.6, 0.08), "pink": (0.75, 0.35, 0.45), "teal": (0.04, 0.3, 0.32),
    "dark brown hair": (0.05, 0.025, 0.012), "blond hair": (0.45, 0.32, 0.15),
    "black hair": (0.025, 0.02, 0.018), "tan": (0.33, 0.17, 0.07), "cream": (0.75, 0.72, 0.64),
    "charcoal": (0.06, 0.06, 0.065), "burgundy": (0.22, 0.02, 0.04),
    "auburn hair": (0.14, 0.045, 0.018), "grey hair": (0.36, 0.35, 0.34),
    "dark brown": (0.07, 0.035, 0.018), "light indigo": (0.16, 0.25, 0.45),
    "dark indigo": (0.007, 0.011, 0.04), "light grey": (0.6, 0.61, 0.62),
    "sole brown": (0.03, 0.016, 0.009), "sole black": (0.012, 0.011, 0.011),
}  # fmt: skip


def rgb(colour) -> np.ndarray:
    """(3,) linear RGB of a colour: a name in COLOURS, an sRGB hex text ``"#rrggbb"`` (a
    custom colour as a colour picker gives it) or three linear floats in [0, 1]."""
    if isinstance(colour, str):
        if colour.startswith("#"):
            code = colour[1:]
            srgb_bytes = np.array([int(code[i : i + 2], 16) for i in (0, 2, 4)]) / 255.0
            return np.where(srgb_bytes <= 0.04045, srgb_bytes / 12.92,
                            ((srgb_bytes + 0.055) / 1.055) ** 2.4)  # fmt: skip
        return np.asarray(COLOURS[colour], np.float64)
    return np.asarray(colour, np.float64)


def _grid(size: int) -> tuple[np.ndarray, np.ndarray]:
    t = np.arange(size, dtype=np.float32) * (2 * np.pi / size)
    u, v = np.meshgrid(t, t, indexing="xy")
    return u, v


def _noise(size: int, rng: np.random.Generator, low: int, high: int) -> np.ndarray:
    """Periodic band-limited noise in [-1, 1] from random Fourier phases (frequencies low..high)."""
    spectrum = np.zeros((size, size), np.complex64)
    f = np.fft.fftfreq(size) * size
    fx, fy = np.meshgrid(f, f)
    r = np.hypot(fx, fy)
    band = (r >= low) & (r <= high)
    phases = rng.uniform(0, 2 * np.pi, band.sum())
    spectrum[band] = np.exp(1j * phases) / np.sqrt(np.maximum(r[band], 1))
    field = np.fft.ifft2(spectrum).real.astype(np.float32)
    return field / max(float(np.abs(field).max()), 1e-6)


def height_field(fabric: Fabric, size: int, seed: int = 0) -> np.ndarray:
    """(size, size) float32 tileable height in about [-1, 1]."""
    rng = np.random.default_rng([seed, size, fabric.threads])
    u, v = _grid(size)
    n = fabric.threads
    grain = _noise(size, rng, 4, 40)
    if fabric.weave == "plain":
        warp = np.abs(np.sin(n * u / 2)) * (0.5 + 0.5 * np.sign(np.sin(n * v / 2)))
        weft = np.abs(np.sin(n * v / 2)) * (0.5 - 0.5 * np.sign(np.sin(n * v / 2)))
        h = warp + weft + 0.3 * grain
    elif fabric.weave == "twill":
        diagonal = np.sin(n * (u + v) / 2) ** 2
        h = 0.6 * diagonal + 0.4 * np.abs(np.sin(n * u)) + 0.4 * grain
    elif fabric.weave == "knit":
        # Rows of V-shaped loops: ridges bent by a zig-zag across each column, as many
        # rows as columns per tile (a stitch about as tall as wide; rows twice as dense
        # fell under FINEST and beat into moire).
        zig = np.abs(((n * u / np.pi) % 2) - 1)
        h = np.sin(n * v / 2 + 2.0 * zig) ** 2 + 0.25 * grain
    elif fabric.weave == "strands":
        wander = _noise(size, rng, 1, 6)
        h = np.sin(n * u + 6 * wander) * 0.5 + 0.5 + 0.3 * _noise(size, rng, 30, 120)
    else:  # leather grain: cells from high-frequency noise, wrinkles from low
        h = np.abs(_noise(size, rng, n // 2, n)) + 0.5 * _noise(size, rng, 2, 8)
    h = h - h.mean()
    h = h / max(float(np.abs(h).max()), 1e-6)
    if fabric.weave in ("knit", "plain"):
        h = band_limited(h, TILE_METRES / FINEST)
    return h.astype(np.float32)


def band_limited(height: np.ndarray, cycles: float) -> np.ndarray:
    """(S, S) a periodic height field with what is finer than ``cycles`` per tile faded
    (a smooth roll-off over a sixth of that, down to FINE_FLOOR): a pre-filter, as a
    mipmap would, for a renderer that has none."""
    size = height.shape[0]
    f = np.fft.fftfreq(size) * size
    r = np.hypot(*np.meshgrid(f, f))
    fade = np.exp(-((np.clip(r - cycles, 0, None) / (0.15 * cycles)) ** 2))
    gain = FINE_FLOOR + (1 - FINE_FLOOR) * fade
    return np.fft.ifft2(np.fft.fft2(height) * gain).real


def normal_map(height: np.ndarray, depth: float) -> np.ndarray:
    """(H, W, 3) uint8 tangent-space normals (+Y up, OpenGL) of a periodic height field."""
    dx = (np.roll(height, -1, 1) - np.roll(height, 1, 1)) * 0.5
    dy = (np.roll(height, 1, 0) - np.roll(height, -1, 0)) * 0.5  # row 0 is the top (v = 1)
    n = np.stack([-dx * depth, -dy * depth, np.ones_like(height)], -1)
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    return np.round((n * 0.5 + 0.5) * 255).astype(np.uint8)


def _srgb_exact(linear: np.ndarray) -> np.ndarray:
    s = np.where(linear <= 0.0031308, 12.92 * linear, 1.055 * linear ** (1 / 2.4) - 0.055)
    return np.round(s * 255).astype(np.uint8)


# Linear [0, 1] in 2^16 steps -> sRGB byte: a table lookup instead of a power per texel
# (a 2K texture has 12 million channels). Steps of 1.5e-5 change no byte.
_SRGB_TABLE = _srgb_exact(np.linspace(0, 1, 65536))


def srgb(linear: np.ndarray) -> np.ndarray:
    """uint8 sRGB of linear values (clipped to [0, 1])."""
    index = np.clip(np.asarray(linear, np.float32), 0, 1) * np.float32(65535)
    return _SRGB_TABLE[(index + np.float32(0.5)).astype(np.int32)]


@lru_cache(maxsize=32)
def maps(fabric_name: str, size: int = 1024, seed: int = 0):
    """(height (S, S) float32, normal (S, S, 3) uint8, roughness (S, S) uint8), cached."""
    fabric = FABRICS[fabric_name]
    h = height_field(fabric, size, seed)
    rough = np.clip(fabric.roughness + max(0.08, fabric.rough_weave) * h, 0, 1)
    return h, normal_map(h, fabric.depth * size / 256), np.round(rough * 255).astype(np.uint8)


def streaks(size: int, rng: np.random.Generator, length: int) -> np.ndarray:
    """(size, size) float32 tileable streaks in about [-1, 1] running down the columns
    (along v: a warp's length): noise averaged over ``length`` rows (wrapped)."""
    n = _noise(size, rng, 8, max(9, size // 6))
    total = np.cumsum(np.concatenate([n, n[:length]]), axis=0)
    out = (total[length:] - total[:-length]) / length
    return (out / max(float(np.abs(out).max()), 1e-6)).astype(np.float32)


def yarn_colour(fabric: Fabric, colour: np.ndarray, height: np.ndarray,
                slubs: np.ndarray | None = None) -> np.ndarray:  # fmt: skip
    """(H, W, 3) float32 linear colour of a fabric in ``colour`` (3,) over its weave's
    ``height`` (H, W): shaded by the height field; for a yarn-dyed twill (``weft``) the
    warp's colour streaked by ``slubs`` (H, W) with the light weft in the valleys."""
    shade = 1.0 + fabric.contrast * height
    out = colour[None, None, :].astype(np.float32) * shade[..., None]
    if fabric.weft is None:
        return out
    if slubs is not None:
        out = out * (1.0 + fabric.slub * slubs)[..., None]
    weft = fabric.weft_share * np.clip((0.15 - height) / 0.9, 0, 1)
    return out * (1 - weft[..., None]) + np.asarray(fabric.weft, np.float32) * weft[..., None]


def colour_map(fabric_name: str, colour, size: int = 1024, seed: int = 0) -> np.ndarray:
    """(S, S, 3) uint8 sRGB colour texture of a fabric in a linear RGB colour (or a name)."""
    fabric = FABRICS[fabric_name]
    h, _, _ = maps(fabric_name, size, seed)
    slubs = streaks(size, np.random.default_rng([seed, size, 11]), max(4, size // 8))
    return srgb(yarn_colour(fabric, rgb(colour), h, slubs if fabric.slub else None))


def material(
    fabric_name: str,
    colour="grey",
    size: int = 1024,
    seed: int = 0,
    name: str | None = None,
    alpha: np.ndarray | None = None,
) -> Material:
    """A Material of a fabric in a colour; ``alpha`` (S, S) uint8 makes a cut-out (hair)."""
    _, normal, rough = maps(fabric_name, size, seed)
    colour_tex = colour_map(fabric_name, colour, size, seed)
    mode = "OPAQUE"
    if alpha is not None:
        colour_tex = np.concatenate([colour_tex, alpha[..., None]], -1)
        mode = "MASK"
    label = colour if isinstance(colour, str) else "custom"
    return Material(
        name=name or f"{fabric_name} {label}",
        base_color_texture=colour_tex,
        normal_texture=normal,
        roughness=1.0,
        roughness_texture=rough,
        alpha_mode=mode,
        double_sided=alpha is not None,
        extras={"fabric": fabric_name, "colour": label, "tile_metres": TILE_METRES},
    )


def atlas(
    name: str,
    rows: list[tuple[float, float, str, object]],
    size: int = 1024,
    stitches: tuple[float, ...] = (),
) -> Material:
    """One Material whose texture is cut in horizontal bands, each its own fabric and colour:
    ``rows`` of (v0, v1, fabric, colour) with v in [0, 1] (v up). For garments made of
    several materials (a shoe's leather, sole rubber and laces) that must stay one part.
    stitches: v heights where a dashed seam of thread a few shades lighter than the
    leather (tan on brown, grey on black) is drawn across the texture.
    """
    colour = np.zeros((size, size, 3), np.uint8)
    normal = np.zeros((size, size, 3), np.uint8)
    rough = np.zeros((size, size), np.uint8)
    for v0, v1, fabric, tint in rows:
        r0, r1 = int(round((1 - v1) * size)), int(round((1 - v0) * size))
        _, n, r = maps(fabric, size)
        colour[r0:r1] = colour_map(fabric, tint, size)[r0:r1]
        normal[r0:r1], rough[r0:r1] = n[r0:r1], r[r0:r1]
    for v in stitches:  # dashes 6 px long, 2 px thick, a thread's height in the normal map
        row = int(round((1 - v) * size))
        dash = (np.arange(size) // 6) % 2 == 0
        # A thread in the leather's own hue (near-white dashes read as laces from afar).
        colour[row : row + 2, dash] = np.clip(np.asarray(colour[row : row + 2, dash], np.float32)
                                              * 1.5 + 25, 0, 255).astype(np.uint8)  # fmt: skip
        normal[row, dash] = (128, 170, 230)
        normal[row + 1, dash] = (128, 86, 230)
    return Material(
        name=name,
        base_color_texture=colour,
        normal_texture=normal,
        roughness=1.0,
        roughness_texture=rough,
        extras={"fabric": "atlas", "rows": [[v0, v1, f] for v0, v1, f, _ in rows]},
    )
