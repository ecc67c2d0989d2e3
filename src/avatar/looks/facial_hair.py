"""Facial hair materials: strand cards of beards and moustaches, and stubble; and how
brows and facial hair follow the wearer (hair colour, greying with age).

Beards and moustaches use the hair layout of ``textures`` (strand cards, roots at
v = 0.5); stubble is an atlas of short hairs cut a day or three ago over the whole beard
area (``clothes.face.stubble``'s UVs: u the arc round the face, v the height from the
mouth, both in metres over ``STUBBLE_SPAN_M``), its density fading to nothing over a
centimetre at the beard's edges (``beard_edge``).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from avatar.looks import fabrics, textures
from avatar.material import Material

# Where a full beard grows, by the direction around the head (degrees from the front): its
# upper edge above the mouth (m). From the moustache under the nose it drops to the corner
# of the mouth, then the cheek line climbs diagonally across the cheek to the sideburns in
# front of the ears (seen from the front, a line from the mouth's corner to the ear, not a
# level cut across the face). ``clothes.face`` cuts the beard's pieces along this line.
CHEEK_DEG = (0, 10, 18, 24, 32, 45, 58, 70, 80, 88)
CHEEK_M = (0.017, 0.014, 0.006, 0.004, 0.012, 0.024, 0.036, 0.05, 0.062, 0.066)
EDGE_M = 0.01  # the beard thins out over this band at its edges (density 1 -> 0)
WOBBLE_M = 0.004  # how far the edge wanders off the line (irregular, as hair grows)
# ... but on the cheeks (between the CHEEK_FADE_DEG pairs, blending from EDGE_M at the
# corner of the mouth and the sideburns) over CHEEK_FADE_M up the face, some 1.6 cm
# across the slanted line on the skin: over EDGE_M its 10-90 % fall-off measured 4.4 mm
# on the skin, and the cheek line read as drawn with a pen. The fade grows down into
# the beard; its bare end rises only CHEEK_RAISE_M (no hair on the cheekbones).
CHEEK_FADE_M = 0.036
CHEEK_FADE_DEG = (18, 32, 72, 86)
CHEEK_RAISE_M = 0.002
ARC_RADIUS_M = 0.075  # stubble u: arc length round the face at about this radius

# The stubble atlas: u over [-SPAN_U, SPAN_U] m of arc, v over [V_LOW, V_HIGH] m from the
# mouth (a canonical adult's: ``clothes.face.stubble`` maps the throat's edge to STUBBLE_
# THROAT_M). One tile of stubs repeats every STUBBLE_TILE_M across it.
STUBBLE_SPAN_U = 0.135
STUBBLE_V = (-0.13, 0.08)
STUBBLE_THROAT_M = -0.074  # the beard's lower edge (2 cm under the chin), default adult
STUBBLE_TILE_M = 0.03
STUBBLE_INSET_M = 0.005  # stubble fades out this far inside the beard's cheek line
# The lips' hole in the atlas: half width, half height and middle (v, m from the mouth).
STUBBLE_LIPS_M = (0.028, 0.0165, -0.0155)
STUBBLE_BACK_M = 0.01  # u's angle is measured about the skull centre moved this far forward

# Greying (MakeHuman age: 0.5 = 25 years, 1 = 90): grey strands appear from GREY_FROM and
# make up GREY_MOST of the hair at age 1.
GREY_FROM, GREY_MOST = 0.6, 0.9
GREY_RGB = np.array([0.62, 0.61, 0.58], np.float32)  # linear: white-grey hair
GREY_LIGHTS = (0.35, 2.3)  # grey strands lighter than the median: shade ** 0.35, at most 2.3


def _soft(x: np.ndarray) -> np.ndarray:
    """A smooth step from 0 (x <= -0.5) to 1 (x >= 0.5), x in units of the edge's width."""
    t = np.clip(x + 0.5, 0, 1)
    return t * t * (3 - 2 * t)


def cheek_wobble(turn_deg: np.ndarray) -> np.ndarray:
    """(N,) m the beard's edges wander off their lines at ``turn_deg`` round the head."""
    angle = np.radians(turn_deg)
    return WOBBLE_M * (0.6 * np.sin(7.0 * angle + 1.3) + 0.4 * np.sin(17.0 * angle + 0.4))


def cheek_fade(turn_deg: np.ndarray, rel_z: np.ndarray) -> np.ndarray:
    """(N,) density of a full beard under its upper (cheek) line, 0..1: turn_deg, degrees
    round the head from the front (absolute); rel_z, m above the mouth. It thins out over
    ``EDGE_M`` up the face by the mouth and the sideburns, over ``CHEEK_FADE_M`` on the
    cheeks (``CHEEK_FADE_DEG``), bare from ``EDGE_M / 2`` (plus ``CHEEK_RAISE_M`` on the
    cheeks) above the wandering line."""
    top = np.interp(turn_deg, CHEEK_DEG, CHEEK_M) + cheek_wobble(turn_deg)
    wide = np.interp(turn_deg, CHEEK_FADE_DEG, (0.0, 1.0, 1.0, 0.0))
    width = EDGE_M + wide * (CHEEK_FADE_M - EDGE_M)
    bare = top + EDGE_M / 2 + wide * CHEEK_RAISE_M
    return _soft((bare - width / 2 - rel_z) / width)


def beard_edge(turn_deg: np.ndarray, rel_z: np.ndarray) -> np.ndarray:
    """(N,) density of a full beard from its upper (cheek) line (``cheek_fade``) and its
    back edge in front of the ears, 0..1: turn_deg, degrees round the head from the front
    (absolute); rel_z, m above the mouth. (The throat's edge depends on the chin:
    ``clothes.face.facial_hair_density``.)"""
    back = np.radians(88 - turn_deg) * 0.08
    return cheek_fade(turn_deg, rel_z) * _soft(back / (0.6 * EDGE_M))


def grey_share(age: float) -> float:
    """Share of grey strands at MakeHuman ``age`` (0 below ``GREY_FROM``, salt and pepper
    in the sixties, ``GREY_MOST`` at 1)."""
    t = np.clip((age - GREY_FROM) / (1 - GREY_FROM), 0, 1)
    return float(GREY_MOST * t**0.8)


# A beard's undercoat (``clothes.face.beard_undercoat``) runs over the dense rows of the
# hair layout (v in [0.5, 1]): its hairs cover none of the skin at v = UNDERCOAT_V[0] and
# all of it from UNDERCOAT_V[1] up.
UNDERCOAT_V = (0.52, 0.9)
UNDERCOAT_SHADE = 0.8  # sRGB factor on the undercoat (some 0.6 as light, linear)
UNDERCOAT_ROUGHNESS = 0.55  # the hair fabric's mean
UNDERCOAT_CLIMB = 0.09  # where it is full, v climbs this much up the face (from 0.9)


def undercoat_v(density: np.ndarray) -> np.ndarray:
    """(N,) the undercoat's v for a beard's density (0..1) there (``UNDERCOAT_V``)."""
    low, high = UNDERCOAT_V
    return low + (high - low) * np.clip(np.asarray(density, np.float64), 0, 1)


def beard_material(spec, size: int = 1024) -> Material:
    """A beard's or moustache's cut-out strand material in the spec's hair colour (the
    scalp hair's, ``textures.hair_material``).

    Strand cards (v in [0, 0.5]) thinned into single hairs (``card_cover``), about as
    light from root to tip (``_even_cards``): a card of scalp strands would read as a
    solid block on the face, and scalp hair's roots-dark, tips-light shading drew each
    clump of a short beard as a scale with a light rim over the next one's dark roots.
    The dense rows (v in [0.5, 1]) are the undercoat under a beard's cards: short hairs
    along v, covering more of the skin the higher v is (``UNDERCOAT_V``)."""
    m = textures.hair_material(spec, size)
    colour = np.array(m.base_color_texture, copy=True)
    colour[..., :3] = _lifted(colour[..., :3], fabrics.rgb(spec.colour))
    rng = np.random.default_rng([size, 17])
    hair = max(size // 340, 1)  # texels per hair across (a card's ~0.12 mm at 1024 px)
    half = size // 2
    cards = slice(size - half, size)  # rows of the strand-card half (v in [0, 0.5])
    colour[cards, :, :3] = _even_cards(colour[cards, :, :3])
    colour[cards, :, 3] = np.round(colour[cards, :, 3] * card_cover(half, size, hair, rng))
    colour[: size - half, :, 3] = undercoat_alpha(size - half, size, hair, rng)
    # The undercoat is the hair deep in the beard, in the shade of the clumps over it:
    # as light as the cards, the gaps between clumps did not show and the beard read as
    # one even mat. Its hairs in their own shades (``undercoat_shade``): the hair
    # layout's dense rows keep one lock's shade down a whole column, which the undercoat
    # stretches down the whole face: fine parallel stripes, corduroy.
    rgb = fabrics.rgb(spec.colour)[None, None, :] * undercoat_shade(size - half, size, rng)
    under = _lifted(fabrics.srgb(rgb), fabrics.rgb(spec.colour)).astype(np.float32)
    colour[: size - half, :, :3] = np.round(under * UNDERCOAT_SHADE).astype(np.uint8)
    # No normal map, and the undercoat's roughness even: the hair fabric's grooves run
    # the texture's whole height, and on the undercoat, mapped up the face with v
    # stretched some tenfold (``clothes.face.beard_undercoat``), they drew long vertical
    # streaks down a grey beard; on the cards alone (they lie at all angles on the
    # face, a few hairs to a card) they drew dark blotches a centimetre across. A
    # beard's hairs show in its colour and alpha.
    rough = np.array(m.roughness_texture, copy=True)
    rough[: size - half] = int(round(255 * UNDERCOAT_ROUGHNESS))
    extras = {**m.extras, "translucency": BEARD_TRANSLUCENCY, "sheen": BEARD_SHEEN,
              "facial": True}  # fmt: skip
    return replace(m, base_color_texture=colour, normal_texture=None,
                   roughness_texture=rough, extras=extras)  # fmt: skip


# Facial hair is lighter than scalp hair of the same colour: coarser hairs lying in one
# or two layers on the skin, lit through and between, where scalp hair is a deep pile in
# its own shade. A dark brown beard in the scalp's albedo (linear luminance 0.03, its
# undercoat 0.014) rendered as a black mask. The lift by the hair's linear luminance:
# FACIAL_LIFT[1] for dark hair up to FACIAL_LIFT_LUM[0], fading to 1 (fair hair, grey).
FACIAL_LIFT = (1.0, 1.7)
# ... but a grey beard's grey strands a little darker than the scalp's: unshaded by the
# hair fabric's relief (``beard_material`` has no normal map), at the scalp's grey an old
# man's beard rendered white, a mat of cotton wool.
FACIAL_GREY = 0.75
FACIAL_LIFT_LUM = (0.04, 0.3)


def facial_lift(rgb: np.ndarray) -> float:
    """Brightness factor of facial hair over scalp hair of linear colour ``rgb`` (3,)."""
    lum = float(np.asarray(rgb, np.float32) @ np.array([0.2126, 0.7152, 0.0722], np.float32))
    return float(np.interp(lum, FACIAL_LIFT_LUM, FACIAL_LIFT[::-1]))


def _lifted(srgb_u8: np.ndarray, rgb: np.ndarray) -> np.ndarray:
    """(..., 3) uint8 sRGB texels of facial hair of colour ``rgb`` lifted (``facial_lift``)."""
    return fabrics.srgb(np.clip(_linear(srgb_u8) * facial_lift(rgb), 0, 1))


def card_cover(rows: int, size: int, hair: int, rng) -> np.ndarray:
    """(rows, size) float32 coverage (0..1) of a beard's strand-card rows (row 0 the
    roots): single hairs ``hair`` texels wide, about one hair column in three kept and never
    two side by side (kept neighbours merged into flat ribbons a few hairs wide, read as
    flakes), each ending at its own length (55..100 % of the card) and tapering to one
    texel over its last third (a fine tip instead of a blunt cut)."""
    cols = size // hair + 1
    pick = rng.uniform(size=cols) < 0.5
    for i in range(1, cols):  # no two neighbours: a hair, then at least one gap
        pick[i] &= not pick[i - 1]
    kept = np.repeat(pick, hair)[:size].astype(np.float32)
    length = np.repeat(rng.uniform(0.55, 1.0, cols), hair)[:size]
    middle = np.tile(np.arange(hair) == hair // 2, cols)[:size]  # a hair's central texel
    t = (np.arange(rows) + 0.5) / rows  # roots (0) to tips (1) down the card half
    ends = np.where(middle, length, length * 0.67)  # a hair's sides stop short of its tip
    tip = np.clip((ends[None, :] - t[:, None]) / 0.06, 0, 1)
    return (kept[None, :] * tip).astype(np.float32)


def _even_cards(rgb: np.ndarray) -> np.ndarray:
    """(rows, W, 3) uint8 sRGB of a hair texture's strand-card rows with the scalp
    layout's lightening from root to tip (``textures.strand_shade``) evened out to a
    tenth: each strand keeps its own shade."""
    rows = rgb.shape[0]
    t = (np.arange(rows) + 0.5) / rows
    along = 0.6 + 0.65 * t**0.8  # ``textures.strand_shade``'s card rows
    even = (0.95 + 0.1 * t) / along
    lin = _linear(rgb) * even[:, None, None]
    return fabrics.srgb(np.clip(lin, 0, 1))


# Light a beard's cards pass through (the renderer's hint, ``blender.materials``): they lie
# on the skin, one layer over the undercoat, so little; at scalp hair's 0.6 a grey beard's
# clumps lit from behind by the key light glowed white, flakes of cotton wool. (A share of
# the light the hair does not reflect, as scalp hair's 0.6.)
BEARD_TRANSLUCENCY = 0.1
# The fibre rim (Principled sheen) on a beard's cards: at scalp hair's 0.25 a clump lying
# at a grazing angle to the camera (under the lip, on the chin) lit up as a whole, a grey
# flake on a dark beard.
BEARD_SHEEN = 0.05


def undercoat_alpha(rows: int, size: int, hair: int, rng) -> np.ndarray:
    """(rows, size) uint8 alpha of the undercoat rows (row 0: v = 1): hairs ``hair``
    texels wide and some 30 rows long, in random order of appearance, so that a row at v
    shows the share ``(v - UNDERCOAT_V[0]) / (UNDERCOAT_V[1] - UNDERCOAT_V[0])`` of them
    (a beard thinning out hair by hair at its edge, not fading as a whole)."""
    cols = size // hair + 1
    # Each hair's rank (0..1) among its neighbours, varying along its length (v).
    knots = rng.uniform(size=(rows // 30 + 2, cols))
    at = np.linspace(0, rows // 30 + 1, rows)
    rank = np.stack([np.interp(at, np.arange(len(knots)), knots[:, c]) for c in range(cols)], 1)
    rank = np.repeat(rank, hair, axis=1)[:, :size]
    v = 1 - (np.arange(rows) + 0.5) / size  # row 0 at the top (v = 1), down to 0.5
    low, high = UNDERCOAT_V
    share = np.clip((v - low) / (high - low), 0, 1)[:, None]
    return np.where(rank < share * 1.02, 255, 0).astype(np.uint8)


# The undercoat's shading (``undercoat_shade``): hairs of UNDERCOAT_HAIR_ROWS (of the
# texture's height; ~1 cm up the face where the beard is full) times 0.5..1.5, each of its
# own shade (UNDERCOAT_HAIR_SPREAD), in locks UNDERCOAT_LOCKS across the texture's width
# and one hair's length tall, staggered lock to lock, shaded UNDERCOAT_LOCK_SPREAD.
UNDERCOAT_HAIR_ROWS = 1 / 96
UNDERCOAT_HAIR_SPREAD = 0.25
UNDERCOAT_LOCKS = 32
UNDERCOAT_LOCK_SPREAD = 0.2


def undercoat_shade(rows: int, size: int, rng) -> np.ndarray:
    """(rows, size, 1) float32 brightness of a beard's undercoat rows (row 0: v = 1),
    about 0.72 (the hair layout's dense rows): short hairs of random lengths down each
    column, each of its own shade, in locks that change shade along the hair's length as
    well as across it. (Locks one shade down the whole column, as the scalp's dense rows
    have them, ran as parallel stripes down the beard.)"""
    seg = max(size * UNDERCOAT_HAIR_ROWS, 1.0)
    # Hair ends down each column at random spacing: 0.5..1.5 of a hair's length.
    count = int(rows / (0.5 * seg)) + 2
    ends = np.cumsum(rng.uniform(0.5, 1.5, (count, size)) * seg, axis=0)
    ends -= rng.uniform(0, seg, size)[None, :]
    hair = np.empty((rows, size), np.int64)
    for c in range(size):
        hair[:, c] = np.searchsorted(ends[:, c], np.arange(rows), side="right")
    hair = hair * size + np.arange(size)[None, :]
    own = rng.uniform(1 - UNDERCOAT_HAIR_SPREAD, 1 + UNDERCOAT_HAIR_SPREAD, hair.max() + 1)
    # Locks: a coarse random grid, smooth in both directions, each lock column's knots
    # at their own rows (no lock boundaries lining up across the beard).
    knots = rng.uniform(1 - UNDERCOAT_LOCK_SPREAD, 1 + UNDERCOAT_LOCK_SPREAD,
                        (int(rows / seg) + 3, UNDERCOAT_LOCKS))  # fmt: skip
    phase = rng.uniform(0, 1, UNDERCOAT_LOCKS)
    at = np.arange(rows)[:, None] / seg + phase[None, :]
    along = np.stack([np.interp(at[:, j], np.arange(len(knots)), knots[:, j])
                      for j in range(UNDERCOAT_LOCKS)], 1)  # fmt: skip
    lock_u = np.arange(UNDERCOAT_LOCKS) * size / UNDERCOAT_LOCKS
    locks = np.stack([np.interp(np.arange(size), lock_u, row, period=size) for row in along])
    return (0.72 * locks * own[hair])[..., None].astype(np.float32)


def stubble_alpha(size: int, seed: int = 0) -> np.ndarray:
    """(S, S) uint8 alpha of a tileable stubble tile (wraps in u and v): a faint shadow of
    hair under the skin and some two thousand short stubs, each a fraction of a millimetre
    thick and one to two long, pointing down the face (the texture's -v) with scatter."""
    rng = np.random.default_rng([seed, size, 13])
    pad = int(0.06 * size) + 2
    canvas = np.zeros((size + pad, size), np.float32)  # stubs running off the bottom
    count = 2000
    start = rng.uniform([0, 0], [size, size], (count, 2))
    angle = np.radians(90 + rng.normal(0, 25, count))  # image rows run down
    length = size * rng.uniform(0.02, 0.045, count)
    for p, a, n in zip(start, angle, length, strict=True):
        points = np.array([p, p + n * np.array([np.cos(a), np.sin(a)])], np.float32)
        width = np.array([0.0045, 0.003], np.float32) * size
        textures.stroke(canvas, points, np.maximum(width, 0.8), rng.uniform(0.7, 1.0), wrap=True)
    tile = canvas[:size].copy()
    tile[:pad] = np.maximum(tile[:pad], canvas[size:])  # ... wrap round to the top rows
    return np.round(np.clip(0.04 + 0.96 * tile, 0, 1) * 255).astype(np.uint8)


def stubble_density(shape: tuple[int, int]) -> np.ndarray:
    """(H, W) float32 density of stubble over the atlas (row 0 the top, v = 1): 1 inside
    the beard area, 0 outside, falling off over ``EDGE_M`` just inside the beard's cheek
    line (``STUBBLE_INSET_M`` below it), in front of the ears (u's angle measured about
    the point where ``clothes.face`` cuts the beard off at the back: 0 at 90 degrees),
    under the chin (``STUBBLE_THROAT_M``) and round the lips (``STUBBLE_LIPS_M``)."""
    h, w = shape
    u = (np.arange(w) + 0.5) / w
    v = 1 - (np.arange(h) + 0.5) / h
    arc = (2 * u - 1) * STUBBLE_SPAN_U
    rel_z = STUBBLE_V[0] + v * (STUBBLE_V[1] - STUBBLE_V[0])
    turn = np.degrees(np.abs(arc) / ARC_RADIUS_M)
    t, z = np.meshgrid(turn, rel_z)
    angle = np.radians(t)
    wobble = WOBBLE_M * (0.6 * np.sin(7.0 * angle + 1.3) + 0.4 * np.sin(17.0 * angle + 0.4))
    top = np.interp(t, CHEEK_DEG, CHEEK_M) + wobble - STUBBLE_INSET_M
    back = np.radians(90 - t) * ARC_RADIUS_M  # m of arc in front of the cut
    # Round the lips (the stubble piece's hole): thinning to nothing at the lips' edge,
    # full within a few millimetres, as fine hair does at the vermilion border.
    half_u, half_v, middle_v = STUBBLE_LIPS_M
    lips = np.hypot(np.meshgrid(arc, rel_z)[0] / half_u, (z - middle_v) / half_v)
    d = (
        _soft((top - z) / EDGE_M)
        * _soft((back - 0.5 * EDGE_M) / EDGE_M)
        * _soft((z - STUBBLE_THROAT_M) / EDGE_M)
        * _soft((lips - 1.1) / 0.25)
    )
    return d.astype(np.float32)


def stubble_atlas(size: int) -> np.ndarray:
    """(H, W) uint8 alpha of the stubble atlas: the tile (``stubble_alpha``, one repeat
    per ``STUBBLE_TILE_M``) repeated over the beard area, times ``stubble_density``.
    size: texels of one tile before it is averaged down 4:1 (1024: ~8.5 px per mm)."""
    tile = stubble_alpha(size).astype(np.float32)
    k = 4 if size >= 64 else 1
    tile = tile.reshape(size // k, k, size // k, k).mean(axis=(1, 3))
    per_m = tile.shape[0] / STUBBLE_TILE_M
    w = int(round(2 * STUBBLE_SPAN_U * per_m))
    h = int(round((STUBBLE_V[1] - STUBBLE_V[0]) * per_m))
    reps = (h // tile.shape[0] + 1, w // tile.shape[1] + 1)
    alpha = np.tile(tile, reps)[:h, :w] * stubble_density((h, w))
    return np.round(alpha).astype(np.uint8)


def stubble_material(spec, size: int = 1024) -> Material:
    """Stubble in the spec's hair colour: short dark stubs blended (glTF ``BLEND``) over
    the skin, thinning out at the beard's edges (``stubble_atlas``)."""
    alpha = stubble_atlas(size)
    rgb = fabrics.rgb(spec.colour).astype(np.float32) * 0.7
    colour = np.concatenate([np.broadcast_to(fabrics.srgb(rgb), alpha.shape + (3,)),
                             alpha[..., None]], -1)  # fmt: skip
    return Material(
        name=spec.name,
        base_color_texture=np.ascontiguousarray(colour),
        roughness=0.6,
        alpha_mode="BLEND",
        double_sided=False,
        extras={"fabric": "stubble", "colour": spec.colour},
    )


def for_wearer(material: Material, kind: str, age: float, colour=None) -> Material:
    """``material`` of a brow or facial-hair built-in recoloured for its wearer.

    kind: "brows" (``textures.hair_material``'s brow shade of ``colour``), "cards" (beard,
    moustache, scalp hair: strand cards) or "stubble". age: MakeHuman's age (0..1):
    grey strands mix in from ``GREY_FROM`` (``grey_share``), and a child's brows are
    fainter and lighter.
    colour: the wearer's hair colour (a name or linear RGB), or None to keep the
    material's own. Returns a new Material (the texture's alpha is kept, but for a
    child's brows)."""
    tex = material.base_color_texture
    assert tex is not None and tex.shape[2] == 4, "a hair material with alpha"
    size = tex.shape[:2]
    if colour is not None:
        rgb = fabrics.rgb(colour).astype(np.float32)
        if kind == "brows":
            rgb = rgb * textures.brow_shade(rgb)
        elif material.extras.get("facial"):  # a beard, a moustache
            rgb = rgb * facial_lift(rgb)
        elif kind == "stubble":
            rgb = rgb * 0.7
        lin = rgb[None, None, :] * _strand_shade(tex, kind)[..., None]
    else:
        lin = _linear(tex[..., :3])
    share = grey_share(age)
    if share > 0:
        rng = np.random.default_rng([size[0], size[1], 31])
        if kind == "cards":  # whole strands grey: salt and pepper
            grey = np.array(np.broadcast_to(rng.uniform(size=size[1])[None, :] < share, size))
            # The dense half (caps, a beard's undercoat) hair by hair: whole columns grey
            # ran as streaks up a cap and down a beard.
            hairs = textures.dense_hairs(size[0] // 2, size[1], rng)
            grey[: size[0] // 2] = rng.uniform(size=hairs.max() + 1)[hairs] < share
        else:
            grey = rng.uniform(size=size) < share
        white = GREY_RGB * (0.55 if kind == "brows" else 1.0)  # brows: coarser, a darker grey
        if material.extras.get("facial"):
            white = white * FACIAL_GREY
        # Grey strands keep the card's strand shading (a flat grey reads as paint), its
        # lights compressed (``GREY_LIGHTS``): a beard's cards, 2.4 times as light as its
        # undercoat, went to pure white, cotton wool.
        shade = _strand_shade(tex, kind)
        light = np.minimum(shade, GREY_LIGHTS[1]) ** GREY_LIGHTS[0]
        white = white[None, None, :] * np.where(shade > 1, light, shade)[..., None]
        lin = np.where(grey[..., None], white, lin)
    alpha = tex[..., 3]
    if kind == "brows" and age < 0.3:  # a child's brows: fine, fair, faint
        young = float(np.clip((0.3 - age) / 0.3, 0, 1))
        lin = lin * (1 - 0.35 * young) + 0.35 * young * np.clip(lin * 2.2, 0, 1)
        alpha = np.round(alpha * (1 - 0.35 * young)).astype(np.uint8)
    out = np.concatenate([fabrics.srgb(lin), alpha[..., None]], -1)
    return replace(material, base_color_texture=np.ascontiguousarray(out))


def _strand_shade(tex: np.ndarray, kind: str) -> np.ndarray:
    """(H, W) float32 the strand shading of a strand-card texture (each texel's luminance
    over the median shown one), so a recolouring keeps its strands; ones for other kinds."""
    if kind != "cards":
        return np.ones(tex.shape[:2], np.float32)
    own = _linear(tex[..., :3]).mean(-1)
    shown = own[tex[..., 3] > 127]
    return own / max(float(np.median(shown)) if shown.size else 1.0, 1e-4)


def _linear(srgb_u8: np.ndarray) -> np.ndarray:
    """(..., 3) float32 linear values of sRGB bytes."""
    s = srgb_u8.astype(np.float32) / 255
    return np.where(s <= 0.04045, s / 12.92, ((s + 0.055) / 1.055) ** 2.4).astype(np.float32)
