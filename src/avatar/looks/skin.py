"""Procedural skin and eye materials (MakeHuman ships no skin colour texture).

Skin: a texture in the base mesh's UV space. The tone is a mix, in linear RGB, of three
reference albedos weighted by the ethnicity macros, shifted a little by age and gender.
MakeHuman's greyscale region masks (``textures/mpfb_*.jpg``: lips, aureolae, nails, ears,
eyelids, ...) tint their regions; low-contrast value noise at several scales adds mottling
and pores. A roughness map makes lips, nails and the mouth glossier than skin.

Eyes: an iris, pupil and sclera texture laid out for the base mesh's eyeballs
(``helper-l-eye``/``helper-r-eye``), whose UVs ``eye_uvs`` stretches to the full image.

Reference colours (sRGB, picked against photographic skin albedo charts; mixing them in
linear light is how reflectances of mixed populations average):

    caucasian  (224, 182, 162)    asian  (214, 170, 130)    african  (104, 68, 50)
"""

from __future__ import annotations

import functools
import hashlib
import logging
from pathlib import Path

import numpy as np

from avatar.body import assets
from avatar.io import images
from avatar.looks import wrinkles
from avatar.material import Material

log = logging.getLogger(__name__)

REFERENCE_SRGB = {
    "caucasian": (224, 182, 162),
    "asian": (214, 170, 130),
    "african": (104, 68, 50),
}

# Region -> (mask file in mpfb2/textures, linear RGB multiplier of the skin tone, roughness).
REGIONS = {
    "face": ("mpfb_face.jpg", (1.0, 0.95, 0.93), 0.5),
    "ears": ("mpfb_ears.jpg", (1.0, 0.86, 0.83), 0.5),
    "eyelids": ("mpfb_eyelids.jpg", (0.86, 0.76, 0.76), 0.45),
    "lips": ("mpfb_lips.jpg", (0.88, 0.62, 0.62), 0.38),
    "aureolae": ("mpfb_aureolae.jpg", (0.62, 0.45, 0.42), 0.45),
    "crotch": ("mpfb_crotch.jpg", (0.86, 0.78, 0.76), 0.55),
    "genitals": ("mpfb_genitals.jpg", (0.74, 0.58, 0.56), 0.45),
    "fingernails": ("mpfb_fingernails.jpg", None, 0.25),
    "toenails": ("mpfb_toenails.jpg", None, 0.25),
    "inside-mouth": ("mpfb_inside-mouth.jpg", None, 0.2),
}
NAIL_SRGB = (236, 205, 198)
MOUTH_SRGB = (198, 110, 114)  # wet mucosa: pinker and lighter than lips (seen in shadow)
# Islands of other helper geometry that share the body's UV space (u0, v0, u1, v1),
# measured on base.obj: teeth and tongue get their own colours so they are not skin.
TEETH_UV = (0.675, 0.87, 0.742, 0.90)
TONGUE_UV = (0.62, 0.925, 0.652, 0.988)
TEETH_SRGB, TONGUE_SRGB = (232, 224, 204), (208, 118, 122)

# The eyeballs' UV boxes in base.obj (u0, v0, u1, v1); the right eye's layout is the left's
# mirrored in u. Inside a box, the front pole sits at CORNEA_CENTRE (normalised, left eye).
EYE_UV_BOXES = {
    "l": (0.760085, 0.931566, 0.785432, 0.956999),
    "r": (0.787978, 0.931566, 0.813324, 0.956999),
}
CORNEA_CENTRE = (0.24031, 0.74604)
# Normalised UV distance from the front pole -> angle from the eye's axis (degrees), from
# the rings of the eyeball mesh (measured on base.obj).
EYE_RINGS = ((0.0, 0.0), (0.025, 11.25), (0.05, 22.5), (0.104, 45.0), (0.172, 67.5),
             (0.30, 90.0))  # fmt: skip
IRIS_SRGB = {
    "brown": (92, 54, 30),
    "dark_brown": (52, 32, 20),
    "hazel": (128, 96, 48),
    "green": (82, 112, 66),
    "blue": (78, 118, 160),
    "grey": (118, 128, 136),
}


# ---------------------------------------------------------------------------- colour


def srgb_to_linear(c: np.ndarray) -> np.ndarray:
    """sRGB values in [0, 1] -> linear light (IEC 61966-2-1)."""
    c = np.asarray(c, dtype=np.float32)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def linear_to_srgb(c: np.ndarray) -> np.ndarray:
    """Linear light in [0, 1] -> sRGB values in [0, 1]."""
    c = np.clip(np.asarray(c, dtype=np.float32), 0.0, 1.0)
    return np.where(c <= 0.0031308, c * 12.92, 1.055 * c ** (1 / 2.4) - 0.055)


def _linear(srgb8) -> np.ndarray:
    return srgb_to_linear(np.asarray(srgb8, dtype=np.float32) / 255.0)


def _to_uint8(linear: np.ndarray) -> np.ndarray:
    return np.rint(linear_to_srgb(linear) * 255.0).astype(np.uint8)


def skin_tone(
    african: float = 1 / 3,
    asian: float = 1 / 3,
    caucasian: float = 1 / 3,
    age: float = 0.5,
    gender: float = 0.5,
) -> np.ndarray:
    """(3,) float32 linear RGB skin albedo for MakeHuman macro values.

    Ethnicity weights are normalised to sum 1 (all zero means equal thirds), as MakeHuman
    does. age in [0, 1] (0 = 1 year, 0.5 = 25, 1 = 90): children are lighter and pinker,
    old skin a little paler and yellower. gender in [0, 1] (1 = male): men slightly
    darker and redder.
    """
    w = np.clip(np.array([african, asian, caucasian], dtype=np.float32), 0, None)
    w = w / w.sum() if w.sum() > 0 else np.full(3, 1 / 3, np.float32)
    refs = np.stack([_linear(REFERENCE_SRGB[k]) for k in ("african", "asian", "caucasian")])
    tone = w @ refs
    young = np.clip((0.5 - age) / 0.5, 0, 1)  # 1 for babies, 0 from 25 years on
    old = np.clip((age - 0.5) / 0.5, 0, 1)
    tone = tone * (1 + 0.08 * young) * np.array([1.0, 1 - 0.03 * young, 1 - 0.02 * young])
    tone = tone * np.array([1 - 0.04 * old, 1 - 0.04 * old, 1 - 0.10 * old])
    g = np.clip(gender, 0, 1) - 0.5
    tone = tone * (1 - 0.06 * g) * np.array([1.0 + 0.03 * g, 1.0, 1.0 - 0.02 * g])
    return np.clip(tone, 0, 1).astype(np.float32)


# ---------------------------------------------------------------------------- noise


def value_noise(rng: np.random.Generator, size: int, cells: int) -> np.ndarray:
    """(size, size) float32 smooth noise in [-1, 1] with ``cells`` features across the image.

    Random values on a (cells + 1)^2 lattice, smoothstep-interpolated (vectorised).
    """
    lattice = rng.uniform(-1.0, 1.0, (cells + 1, cells + 1)).astype(np.float32)
    x = np.linspace(0.0, cells, size, endpoint=False, dtype=np.float32)
    i = np.minimum(x.astype(np.int32), cells - 1)
    f = (x - i).astype(np.float32)
    f = f * f * (3 - 2 * f)
    rows = lattice[i] * (1 - f)[:, None] + lattice[i + 1] * f[:, None]  # (size, cells + 1)
    return rows[:, i] * (1 - f)[None, :] + rows[:, i + 1] * f[None, :]


def fractal_noise(rng: np.random.Generator, size: int, cells: tuple[int, ...]) -> np.ndarray:
    """(size, size) sum of value noise octaves with 1/sqrt(cells) amplitudes, roughly [-1, 1]."""
    amps = [1 / np.sqrt(c) for c in cells]
    total = sum(a * value_noise(rng, size, c) for a, c in zip(amps, cells, strict=True))
    return (total / sum(amps)).astype(np.float32)


# ---------------------------------------------------------------------------- masks


def region_masks(size: int, data_dir: Path | None = None) -> dict[str, np.ndarray]:
    """Region name -> (size, size) float32 mask in [0, 1] (image rows top = v 1).

    Decoding MakeHuman's 2048^2 JPEGs takes seconds, so resized masks are cached on disk
    (under ``assets.cache_root()``, keyed by the mask files and size) and in memory.
    """
    root = data_dir or assets.find_data_dir()
    files = {name: root / "textures" / spec[0] for name, spec in REGIONS.items()}
    present = {n: p for n, p in files.items() if p.is_file()}
    if len(present) < len(files):
        log.warning("skin masks missing: %s", ", ".join(sorted(set(files) - set(present))))
    key = hashlib.sha256(f"v2 {size}".encode())
    for name, path in sorted(present.items()):
        stat = path.stat()
        key.update(f"{name}:{path}:{stat.st_size}:{stat.st_mtime_ns}".encode())
    return _cached_masks(key.hexdigest()[:20], tuple(sorted(present.items())), size)


@functools.lru_cache(maxsize=4)
def _cached_masks(key: str, files: tuple[tuple[str, Path], ...], size: int):
    cache = assets.cache_root() / "skin" / f"masks-{key}.npz"
    if cache.is_file():
        try:
            with np.load(cache) as data:
                return {name: data[name].astype(np.float32) / 255.0 for name in data.files}
        except (OSError, ValueError, KeyError):
            log.warning("ignoring unreadable skin mask cache %s", cache)
    masks8 = {name: _resize(images.read(path), size) for name, path in files}
    for m in masks8.values():
        m[m < 4] = 0  # JPEG ringing leaves faint noise everywhere; it is not a region
    try:
        cache.parent.mkdir(parents=True, exist_ok=True)
        tmp = cache.with_suffix(".tmp.npz")
        np.savez_compressed(tmp, **masks8)
        tmp.replace(cache)  # atomic: parallel workers never read a half-written cache
    except OSError as exc:
        log.warning("cannot cache skin masks in %s: %s", cache, exc)
    return {name: m.astype(np.float32) / 255.0 for name, m in masks8.items()}


def _resize(image: np.ndarray, size: int) -> np.ndarray:
    """(H, W) uint8 -> (size, size) uint8: box filter for integer factors, else bilinear."""
    h, w = image.shape[:2]
    if h % size == 0 and w % size == 0:
        fy, fx = h // size, w // size
        return np.rint(image.reshape(size, fy, size, fx).mean(axis=(1, 3))).astype(np.uint8)
    ys = (np.arange(size) + 0.5) * h / size - 0.5
    xs = (np.arange(size) + 0.5) * w / size - 0.5
    y0 = np.clip(np.floor(ys).astype(int), 0, h - 2)
    x0 = np.clip(np.floor(xs).astype(int), 0, w - 2)
    fy, fx = np.clip(ys - y0, 0, 1)[:, None], np.clip(xs - x0, 0, 1)[None, :]
    img = image.astype(np.float32)
    top = img[y0][:, x0] * (1 - fx) + img[y0][:, x0 + 1] * fx
    bottom = img[y0 + 1][:, x0] * (1 - fx) + img[y0 + 1][:, x0 + 1] * fx
    return np.rint(top * (1 - fy) + bottom * fy).astype(np.uint8)


def _uv_box_mask(size: int, box: tuple[float, float, float, float]) -> np.ndarray:
    """(size, size) bool: pixels whose UV lies in (u0, v0, u1, v1)."""
    u = (np.arange(size) + 0.5) / size
    v = 1.0 - (np.arange(size) + 0.5) / size
    return ((v >= box[1]) & (v <= box[3]))[:, None] & ((u >= box[0]) & (u <= box[2]))[None, :]


# ---------------------------------------------------------------------------- skin


def skin_material(
    african: float = 1 / 3,
    asian: float = 1 / 3,
    caucasian: float = 1 / 3,
    age: float = 0.5,
    gender: float = 0.5,
    *,
    size: int = 1024,
    seed: int = 0,
    data_dir: Path | None = None,
) -> Material:
    """A skin Material for the base mesh's UVs: colour (size, size, 3) and roughness maps.

    Parameters are MakeHuman macro values (see ``skin_tone``); ``seed`` picks the noise.
    Results are cached by parameters (rounded to 1e-3), so a dataset reusing a skin pays
    once. The arrays are read-only.
    """
    key = tuple(round(float(x), 3) for x in (african, asian, caucasian, age, gender))
    return _skin_material(key, int(size), int(seed), str(data_dir) if data_dir else None)


@functools.lru_cache(maxsize=16)
def _skin_material(key: tuple, size: int, seed: int, data_dir: str | None) -> Material:
    african, asian, caucasian, age, gender = key
    tone = skin_tone(african, asian, caucasian, age, gender)
    masks = region_masks(size, Path(data_dir) if data_dir else None)
    rng = np.random.default_rng([seed, size])
    colour, rough = _base_skin(tone, size, rng, age)
    _paint_regions(colour, rough, tone, masks)
    _paint_mouth_parts(colour, rough)
    height = _relief(colour, rough, size, rng, age)
    image = np.ascontiguousarray(_to_uint8(colour))
    rough8 = np.rint(np.clip(rough, 0, 1) * 255).astype(np.uint8)
    normal = wrinkles.normal_map(height, wrinkles.FACE_MM_PER_PIXEL_1024 * 1024 / size)
    for array in (image, rough8, normal):
        array.flags.writeable = False  # shared by every caller of the cache
    return Material(
        name="skin",
        base_color=(1.0, 1.0, 1.0, 1.0),
        base_color_texture=image,
        normal_texture=normal,
        roughness=1.0,
        roughness_texture=rough8,
        extras={"subsurface": 0.2, "subsurface_radius": [0.012, 0.005, 0.003]},
    )


def _base_skin(tone: np.ndarray, size: int, rng: np.random.Generator, age: float):
    """(size, size, 3) linear colour and (size, size) roughness of plain skin with noise.

    Skin varies mostly in redness (blood under it), little in lightness: broad blotches
    that darken read as dirt (on a bald scalp most), so the mottling shifts hue with only
    a faint change of lightness, and the grain is fine.
    """
    old = float(np.clip((age - 0.5) / 0.5, 0, 1))
    mottle = fractal_noise(rng, size, (6, 14, 40))  # blotches, a few cm across
    blush = fractal_noise(rng, size, (10, 24, 60))  # redness drift
    pores = fractal_noise(rng, size, (size // 8, size // 3))  # fine grain, a pixel or two
    spots = np.clip(value_noise(rng, size, 90) - 0.6, 0, None) * old  # age spots
    light = 1 + (0.012 + 0.015 * old) * mottle + 0.035 * pores - 0.35 * spots
    red = 0.03 * blush + 0.012 * mottle
    hue = np.stack([1 + red, 1 - 0.6 * red, 1 - 0.8 * red], axis=-1)
    spot_hue = np.array([1.0, 0.96, 0.88], np.float32)  # age spots are brown, not grey
    colour = tone[None, None, :] * light[..., None] * hue
    colour *= 1 + (spot_hue - 1) * np.clip(spots * 4, 0, 1)[..., None]
    rough = 0.56 + 0.1 * old + 0.06 * pores + 0.02 * mottle  # skin, not oil: little gloss
    return colour.astype(np.float32), rough.astype(np.float32)


def _relief(colour, rough, size: int, rng: np.random.Generator, age: float) -> np.ndarray:
    """(size, size) skin height in millimetres: fine pores everywhere and, with age,
    wrinkles (``looks.wrinkles``); their valleys get a little darker and drier in place."""
    pores = fractal_noise(rng, size, (size // 6, size // 2))
    amount = wrinkles.age_amount(age)
    height = 0.025 * (1 + 0.5 * amount) * pores
    if amount > 0:
        depth = wrinkles.wrinkle_depth(wrinkles.uv_positions(size)) * np.float32(amount)
        height -= depth
        colour *= (1 - 0.35 * np.clip(depth, 0, 0.5))[..., None]  # a shadow deep in a crease
        rough += 0.25 * np.clip(depth, 0, 0.5)
    return height.astype(np.float32)


def _paint_regions(colour, rough, tone, masks: dict[str, np.ndarray]) -> None:
    """Blend each masked region's tint and roughness offset in place (in its bounding box)."""
    nail, mouth = _linear(NAIL_SRGB), _linear(MOUTH_SRGB)
    for name, (_, tint, region_rough) in REGIONS.items():
        if name not in masks or not masks[name].any():
            continue
        box = _bounding_box(masks[name])
        m = masks[name][box][..., None]
        c = colour[box]
        if tint is not None:
            target = c * np.asarray(tint, np.float32)
        elif name == "inside-mouth":
            target = mouth
        else:  # nails: pale, taking a little of the skin's colour through them
            target = 0.75 * nail + 0.25 * tone
        colour[box] = c + (target - c) * m
        # Relative to plain skin (0.56), so age's drier skin shows in every region.
        rough[box] += (np.float32(region_rough) - np.float32(0.56)) * m[..., 0]


def _bounding_box(mask: np.ndarray) -> tuple[slice, slice]:
    """Row and column slices enclosing the non-zero pixels of a (H, W) mask."""
    rows = np.flatnonzero(mask.any(axis=1))
    cols = np.flatnonzero(mask.any(axis=0))
    return slice(rows[0], rows[-1] + 1), slice(cols[0], cols[-1] + 1)


def _paint_mouth_parts(colour, rough) -> None:
    """Teeth and tongue islands share the body's UV space: give them their own colours."""
    size = colour.shape[0]
    for box, srgb, r in ((TEETH_UV, TEETH_SRGB, 0.15), (TONGUE_UV, TONGUE_SRGB, 0.3)):
        inside = _uv_box_mask(size, box)
        colour[inside] = _linear(srgb)
        rough[inside] = r


# ---------------------------------------------------------------------------- mouth

MOUTH_PARTS = ("teeth", "tongue")
GUM_SRGB = (204, 104, 110)  # healthy gums: coral pink, wet
# Tooth widths (mm) from the midline back: incisors, canine, premolars, molars; the
# teeth texture spreads them over each half of the arch.
TOOTH_MM = (8.5, 6.5, 7.5, 7.0, 6.5, 10.0, 9.0)
ARCH_MM, STRIP_MM = 110.0, 22.0  # the teeth strip's length along the arch and across it


def mouth_material(part: str, age: float = 0.5) -> Material:
    """The material of a mouth part of the base mesh ("teeth" or "tongue").

    Teeth: glossy enamel, ivory that yellows a little with ``age`` (0..1, MakeHuman's age
    macro), translucent at the edges (a little subsurface), with gums: the teeth texture
    (``teeth_texture``, for the teeth part's UVs ``clothes.face.teeth_uvs``) draws pink
    gums with a scalloped line over each tooth and the gaps between teeth; ``base_color``
    is the enamel's tint. Tongue: wet, pink-red, with subsurface scattering like the lips,
    a plain colour (seen in shadow inside the mouth).
    """
    if part not in MOUTH_PARTS:
        raise ValueError(f"mouth part must be one of {MOUTH_PARTS}, got {part!r}")
    old = float(np.clip((age - 0.5) / 0.5, 0, 1))
    if part == "teeth":
        srgb = np.array(TEETH_SRGB, np.float32) * (1.0, 1.0 - 0.03 * old, 1.0 - 0.12 * old)
        r, g, b = (float(c) for c in srgb_to_linear(srgb / 255.0))
        return Material(
            name="teeth",
            base_color=(r, g, b, 1.0),
            roughness=0.2,
            base_color_texture=teeth_texture(),
            extras={"subsurface": 0.1, "subsurface_radius": [0.004, 0.003, 0.002]},
        )
    r, g, b = (float(c) for c in srgb_to_linear(np.array(TONGUE_SRGB, np.float32) / 255.0))
    return Material(
        name="tongue",
        base_color=(r, g, b, 1.0),
        roughness=0.3,
        extras={"subsurface": 0.2, "subsurface_radius": [0.01, 0.004, 0.0025]},
    )


@functools.lru_cache(maxsize=2)
def teeth_texture(width: int = 512, height: int = 256) -> np.ndarray:
    """(height, width, 3) uint8 sRGB teeth and gums, relative to the enamel's tint (the
    material's ``base_color`` multiplies it: enamel is white here, gums are pink divided by
    the tint). Layout (``clothes.face.teeth_uvs``): u along the arch, v from the gum side
    (1) over the outer face down to the biting edge (v = 1/3) and up the inner face (0).

    Gums cover a band along both long sides, scalloped: about 3 mm over each tooth's
    middle, dipping 6 mm between teeth (the papillae); the gaps between teeth darken, and
    the biting edge is a little grey-blue (thin enamel)."""
    u = (np.arange(width, dtype=np.float32) + 0.5) / width
    v = 1.0 - (np.arange(height, dtype=np.float32) + 0.5) / height
    # Position within a tooth along the arch (0..1) and distance to its nearest gap (mm).
    bounds = np.cumsum((0.0,) + TOOTH_MM) / sum(TOOTH_MM) * 0.5  # half arch, from the middle
    side = np.abs(u - 0.5)
    k = np.clip(np.searchsorted(bounds, side) - 1, 0, len(TOOTH_MM) - 1)
    within = np.clip((side - bounds[k]) / (bounds[k + 1] - bounds[k]), 0, 1)
    gap_mm = np.minimum(within, 1 - within) * np.asarray(TOOTH_MM)[k]
    scallop = 3.0 + 2.5 * (1 - np.sin(np.pi * within)) ** 1.5  # gum depth (mm) along u
    outer_mm = (1.0 - v)[:, None] * STRIP_MM  # depth from the gum side
    inner_mm = v[:, None] * STRIP_MM  # from the inner side
    px = STRIP_MM / height  # one pixel in mm, for anti-aliased edges
    gum = np.maximum(np.clip((scallop[None, :] - outer_mm) / px + 0.5, 0, 1),
                     np.clip((0.8 * scallop[None, :] - inner_mm) / px + 0.5, 0, 1))  # fmt: skip
    gap = np.exp(-((gap_mm / 0.45) ** 2))[None, :] * np.ones_like(outer_mm)
    edge = np.exp(-(((v - 1 / 3) * STRIP_MM / 1.5) ** 2))[:, None]  # biting edge
    enamel = np.ones((height, width, 3), np.float32)
    enamel *= (1 - 0.55 * gap)[..., None]
    enamel *= 1 + (np.array([0.85, 0.9, 0.98], np.float32) - 1) * edge[..., None]
    tint = srgb_to_linear(np.array(TEETH_SRGB, np.float32) / 255.0)
    pink = np.clip(_linear(GUM_SRGB) / tint, 0, 1)
    margin = 1 + 0.15 * np.exp(-(((gum - 0.5) * 2) ** 2))  # a lighter rim at the gum line
    colour = enamel * (1 - gum[..., None]) + (pink * margin[..., None]) * gum[..., None]
    image = _to_uint8(np.clip(colour, 0, 1))
    image.flags.writeable = False
    return image


# ---------------------------------------------------------------------------- eyes


def eye_uvs(uvs: np.ndarray, side: str) -> np.ndarray:
    """(U, 2) base-mesh UVs of eyeball ``side`` ("l" or "r") -> (U, 2) UVs for eye_material.

    Stretches the eye's small UV box over the whole texture; the right eye is mirrored so
    both eyes share one texture.
    """
    u0, v0, u1, v1 = EYE_UV_BOXES[side]
    out = (np.asarray(uvs, np.float64) - (u0, v0)) / (u1 - u0, v1 - v0)
    if side == "r":
        out[:, 0] = 1.0 - out[:, 0]
    if out.size and (out.min() < -0.01 or out.max() > 1.01):
        raise ValueError(f"UVs are not the base mesh's {side} eyeball UVs")
    return out.astype(np.float32)


def eye_material(
    iris: str | tuple[int, int, int] = "brown",
    *,
    size: int = 1024,
    seed: int = 0,
    pupil: float = 7.0,
) -> Material:
    """An eyeball Material: sclera, iris and pupil laid out for ``eye_uvs``.

    iris: a name from IRIS_SRGB or an sRGB triple. pupil: pupil radius in degrees of the
    eyeball (about 5 in bright light, 9 in the dark). Cached by parameters.
    """
    rgb = tuple(IRIS_SRGB[iris]) if isinstance(iris, str) else tuple(int(c) for c in iris)
    return _eye_material(rgb, int(size), int(seed), round(float(pupil), 2))


@functools.lru_cache(maxsize=8)
def _eye_material(rgb: tuple, size: int, seed: int, pupil: float) -> Material:
    rng = np.random.default_rng([seed, size, 7])
    theta, phi = _eye_angles(size)
    colour = _sclera(theta, phi, rng)
    iris_colour, iris_alpha = _iris(theta, phi, _linear(rgb), pupil, rng)
    colour = colour * (1 - iris_alpha[..., None]) + iris_colour * iris_alpha[..., None]
    image = np.ascontiguousarray(_to_uint8(colour))
    image.flags.writeable = False
    return Material(
        name="eye",
        base_color_texture=image,
        roughness=0.08,  # wet cornea
        extras={"subsurface": 0.05},
    )


def _eye_angles(size: int) -> tuple[np.ndarray, np.ndarray]:
    """(size, size) angle from the eye's axis and azimuth (degrees, radians) per pixel."""
    u = (np.arange(size, dtype=np.float32) + 0.5) / size
    v = 1.0 - (np.arange(size, dtype=np.float32) + 0.5) / size
    du = u[None, :] - CORNEA_CENTRE[0]
    dv = v[:, None] - CORNEA_CENTRE[1]
    r = np.hypot(du, dv)
    rings = np.array(EYE_RINGS, dtype=np.float32)
    theta = np.interp(r, rings[:, 0], rings[:, 1], right=120.0)
    return theta.astype(np.float32), np.arctan2(dv, du).astype(np.float32)


def _periodic_noise(rng: np.random.Generator, phi: np.ndarray, periods: int) -> np.ndarray:
    """Smooth noise in [-1, 1] over the azimuth, ``periods`` features around the circle."""
    table = rng.uniform(-1, 1, periods).astype(np.float32)
    x = (phi / (2 * np.pi) % 1.0) * periods
    i = x.astype(np.int32) % periods
    f = x - np.floor(x)
    f = f * f * (3 - 2 * f)
    return table[i] * (1 - f) + table[(i + 1) % periods] * f


def _iris(theta, phi, base: np.ndarray, pupil: float, rng) -> tuple[np.ndarray, np.ndarray]:
    """Iris colour (linear, with fibres, collarette, limbal ring, pupil) and its coverage."""
    limbus = 28.0  # iris edge: limbus radius 5.9 mm on a 12 mm eyeball
    t = np.clip((theta - pupil) / (limbus - pupil), 0, 1)  # 0 at the pupil, 1 at the edge
    fibres = 0.6 * _periodic_noise(rng, phi, 180) + 0.4 * _periodic_noise(rng, phi, 57)
    wobble = 0.04 * _periodic_noise(rng, phi, 23)
    collarette = np.exp(-(((t - 0.32 - wobble) / 0.07) ** 2))
    light = 1.0 + 0.35 * fibres * (0.4 + t) + 0.45 * collarette
    light *= 1.0 - 0.55 * np.clip((t - 0.8) / 0.2, 0, 1) ** 2  # dark limbal ring
    inner = np.clip((t - 0.0) / 0.15, 0, 1)  # darker ruff near the pupil
    colour = base[None, None, :] * (light * (0.6 + 0.4 * inner))[..., None]
    warm = np.array([1.25, 1.05, 0.7], np.float32)  # amber centre, as in most irises
    colour = colour * (1 + (warm - 1) * (np.clip(0.45 - t, 0, 1) / 0.45)[..., None])
    pupil_mask = np.clip((pupil + 0.6 - theta) / 1.2, 0, 1)[..., None]
    colour = colour * (1 - pupil_mask) + np.float32(0.004) * pupil_mask
    alpha = np.clip((limbus + 1.2 - theta) / 2.4, 0, 1)  # soft limbus
    return colour.astype(np.float32), alpha.astype(np.float32)


def _sclera(theta, phi, rng) -> np.ndarray:
    """Off-white sclera, pinker and veined away from the cornea, with a faint limbal shadow."""
    white = _linear((236, 230, 222))
    pink = _linear((222, 170, 160))
    # Thin vessels: only the peaks of fine azimuthal noise, fading in towards the cornea.
    veins = np.clip(_periodic_noise(rng, phi, 150) + 0.3 * _periodic_noise(rng, phi, 37), 0, 1)
    redness = np.clip((theta - 45.0) / 60.0, 0, 1) * (0.15 + 0.5 * veins**8)
    colour = white * (1 - redness[..., None]) + pink * redness[..., None]
    shade = 1.0 - 0.12 * np.exp(-(((theta - 30.0) / 4.0) ** 2))
    return (colour * shade[..., None]).astype(np.float32)
