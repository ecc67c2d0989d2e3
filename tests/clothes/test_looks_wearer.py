"""Issue 14's looks: brows and facial hair follow the wearer (hair colour, greying with
age), stubble fades out at the beard's edges without banding, the knit's colour does not
shimmer and the jacket's leather is satin, not glittery wet plastic."""

import numpy as np
import pytest

from avatar.clothes import builtin, face, library
from avatar.clothes.library import load_garment
from avatar.looks import fabrics, facial_hair, textures

LUMA = np.array([0.2126, 0.7152, 0.0722], np.float32)


def _shown_luma(material, level=127) -> float:
    """Mean linear luminance of the texels a hair material shows (alpha above level)."""
    tex = material.base_color_texture
    lin = facial_hair._linear(tex[..., :3]) @ LUMA
    return float(lin[tex[..., 3] > level].mean())


def _worn(names, age, options=None):
    loaded = [load_garment(n, texture_size=128) for n in names]
    worn = library.wearer_looks(loaded, list(names), options or {}, age)
    return {g.name: g.material for g in worn}


@pytest.mark.parametrize("item", ["beard-short", "moustache", "stubble"])
def test_facial_hair_greys_with_age(item):
    """A 90-year-old's beard is mostly grey; a 30-year-old's keeps the hair's colour."""
    young = _worn(["hair-short", item], 0.3)[item]
    old = _worn(["hair-short", item], 0.95)[item]
    level = 127 if item != "stubble" else 60
    assert _shown_luma(old, level) > 4 * _shown_luma(young, level)
    assert facial_hair.grey_share(0.5) == 0 and 0.1 < facial_hair.grey_share(0.7) < 0.5
    assert facial_hair.grey_share(1.0) > 0.8


def test_facial_hair_and_brows_follow_the_hair_worn():
    """A blond scalp: beard and brows blond too (lighter than with dark hair), but the
    named brow colours keep theirs."""
    names = ["hair-short", "beard-short", "eyebrows", "eyebrows-black"]
    dark = _worn(names, 0.4)
    blond = _worn(names, 0.4, {"hair-short": {"colour": "blond hair"}})
    assert _shown_luma(blond["beard-short"]) > 3 * _shown_luma(dark["beard-short"])
    assert _shown_luma(blond["eyebrows"]) > 3 * _shown_luma(dark["eyebrows"])
    black = _shown_luma(dark["eyebrows-black"])
    assert _shown_luma(blond["eyebrows-black"]) == pytest.approx(black)


def test_brows_are_the_hairs_colour_not_pencil_black_and_grey_with_age():
    dark = load_garment("eyebrows", texture_size=128).material
    hair = float(fabrics.rgb("dark brown hair") @ LUMA)
    assert _shown_luma(dark) > 0.75 * hair  # was half the hair's: near-black pencil lines
    child, adult, elder = (_worn(["eyebrows"], a)["eyebrows"] for a in (0.05, 0.4, 0.95))
    assert _shown_luma(elder) > 3 * _shown_luma(adult)
    assert _shown_luma(child, 60) > 1.2 * _shown_luma(adult, 60)  # fairer
    assert child.base_color_texture[..., 3].mean() < 0.8 * adult.base_color_texture[..., 3].mean()


def test_blond_brows_still_read_against_fair_skin():
    blond = load_garment("eyebrows-blond", texture_size=128).material
    fair_skin = 0.45  # linear luminance of a fair skin's base colour, about
    assert _shown_luma(blond) < 0.5 * fair_skin
    assert (blond.base_color_texture[..., 3] > 127).mean() > 0.05


def test_brow_edges_are_soft():
    """Many brow texels are partly covered (hairs thinning out), not all-or-nothing."""
    alpha = textures.brow_alpha(512) / 255
    covered = alpha > 0.02
    partial = (alpha > 0.1) & (alpha < 0.75)
    assert partial.sum() > 0.3 * covered.sum()


def test_moustache_tips_are_ragged():
    """Each kept strand of a beard card ends at its own length over a taper: the tips'
    rows spread, and partly covered texels break the outline."""
    tex = load_garment("moustache", texture_size=256).material.base_color_texture
    cards = tex[128:, :, 3].astype(np.float32) / 255  # the strand-card half
    strands = cards[:8].max(axis=0) > 0.5
    last = np.array([np.nonzero(cards[:, c] > 0.5)[0].max() for c in np.nonzero(strands)[0]])
    assert last.std() > 0.08 * cards.shape[0]
    assert ((cards > 0.05) & (cards < 0.6)).sum() > 0.15 * (cards > 0.05).sum()


def test_stubble_fades_out_over_a_centimetre_at_its_edges():
    """The atlas's density falls from full to nothing over ~1 cm at the cheek line, and
    the stubble piece's own boundary (but round the lips) lies where the density is
    (nearly) nothing: no hard top edge across the cheeks, none behind the jaw."""
    shape = (760, 920)
    density = facial_hair.stubble_density(shape)
    v = facial_hair.STUBBLE_V[0] + (1 - (np.arange(shape[0]) + 0.5) / shape[0]) * (
        facial_hair.STUBBLE_V[1] - facial_hair.STUBBLE_V[0])
    for col in (shape[1] // 2, int(shape[1] * 0.8)):  # the front; a cheek
        prof = density[:, col]
        top = v[prof > 0.95].max() - v[(prof < 0.05) & (v > v[prof > 0.95].max())].min()
        assert abs(top) > 0.007
    piece = face.stubble(library.authoring_body())
    mesh = piece.mesh
    from avatar.geometry.shell import boundary_edges

    edges, _ = boundary_edges(mesh.faces)
    rim = np.unique(edges)
    _, mouth, *_ = face.mouth_frame(library.authoring_body())
    rim = rim[np.linalg.norm(mesh.vertices[rim] - mouth, axis=1) > 0.045]  # not the lips' rim
    corner_uv = np.zeros((len(mesh.vertices), 2), np.float32)
    corner_uv[mesh.faces.ravel()] = mesh.uvs[mesh.face_uvs.ravel()]
    uv = corner_uv[rim]
    rows = np.clip(((1 - uv[:, 1]) * shape[0]).astype(int), 0, shape[0] - 1)
    cols = np.clip((uv[:, 0] * shape[1]).astype(int), 0, shape[1] - 1)
    assert np.median(density[rows, cols]) < 0.15
    assert np.percentile(density[rows, cols], 90) < 0.5


def test_stubble_has_no_banding_and_no_film():
    """The stub tile wraps in v as well as u (no empty rows every repeat: horizontal bands
    across the chin) and is mostly clear skin between dark stubs, not a tinted film."""
    alpha = facial_hair.stubble_alpha(512).astype(np.float32) / 255
    rows = alpha.mean(axis=1)
    assert rows.min() > 0.6 * np.median(rows)
    spectrum = np.abs(np.fft.rfft(rows - rows.mean()))
    assert spectrum.max() < 0.05 * rows.mean() * len(rows)
    assert (alpha < 0.08).mean() > 0.4  # bare skin between the stubs
    atlas = facial_hair.stubble_atlas(256).astype(np.float32)
    inside = atlas[: atlas.shape[0] * 3 // 4, atlas.shape[1] * 2 // 5 : atlas.shape[1] * 3 // 5]
    band = inside.mean(axis=1)
    band = band[band > 0.8 * band.max()]  # rows fully inside the beard
    assert band.min() > 0.6 * np.median(band)


def _high_frequency(gray: np.ndarray) -> float:
    """RMS difference of neighbouring texels (both directions), gray in [0, 1]."""
    across = (gray - np.roll(gray, 1, 0)) ** 2 + (gray - np.roll(gray, 1, 1)) ** 2
    return float(np.sqrt(across.mean()))


@pytest.mark.parametrize("name", ["hoodie", "cardigan"])
def test_knit_colour_has_little_fine_contrast(name):
    """The knit's loops are in its normal map; its colour map's fine contrast stays low (it
    shimmered at sheet size and showed the loops' direction flipping at a UV seam)."""
    m = load_garment(name, texture_size=512).material
    gray = m.base_color_texture[..., :3].astype(np.float32).mean(-1) / 255
    assert _high_frequency(gray) < 0.01
    normal = m.normal_texture[..., :2].astype(np.float32).mean(-1) / 255
    assert _high_frequency(normal) > 0.05  # the loops still in the relief


def test_jacket_leather_is_satin_not_glittery_plastic():
    m = load_garment("jacket", texture_size=512).material
    nz = m.normal_texture[..., 2].astype(np.float32) / 127.5 - 1
    assert np.degrees(np.arccos(np.percentile(nz, 5))) < 12  # no crinkle
    normal = m.normal_texture[..., :2].astype(np.float32).mean(-1) / 255
    # No glitter in the leather itself: the median 64 px block (the jacket's seams, zip
    # teeth and topstitching are sharp on purpose, and sparse).
    blocks = normal[: normal.shape[0] // 64 * 64, : normal.shape[1] // 64 * 64]
    blocks = blocks.reshape(normal.shape[0] // 64, 64, -1, 64).swapaxes(1, 2).reshape(-1, 64, 64)
    assert np.median([_high_frequency(b) for b in blocks]) < 0.015
    rough = m.roughness_texture.astype(np.float32) / 255 * m.roughness
    low, high = np.percentile(rough, [1, 99])
    assert 0.5 <= low and high <= 0.75 and high - low > 0.03  # satin to matte, gently varied


def test_facial_hair_specs_default_to_following_the_hair():
    for name in library.FOLLOWS_HAIR:
        assert name in builtin.BY_NAME


@pytest.mark.parametrize("style", ["hair-short", "hair-bob"])
def test_scalp_hair_greys_with_age_as_the_brows_do(style):
    """An old wearer's built-in hair is salt and pepper to grey on the brows' age curve; a
    young one's keeps its colour; a colour the user picked is kept at any age."""
    young = _worn([style, "eyebrows"], 0.4)
    sixties = _worn([style, "eyebrows"], 0.75)
    old = _worn([style, "eyebrows"], 0.95)
    own = load_garment(style, texture_size=128).material
    assert young[style] is own  # untouched below the greying age
    lumas = [_shown_luma(m[style]) for m in (young, sixties, old)]
    assert lumas[0] < lumas[1] < lumas[2] and lumas[2] > 4 * lumas[0]
    # Grey strands, not a grey wash: shown texels are either the hair's colour or grey.
    tex = old[style].base_color_texture
    lin = facial_hair._linear(tex[..., :3])
    shown = tex[..., 3] > 127
    chroma = (lin.max(-1) - lin.min(-1))[shown] / np.maximum(lin.max(-1)[shown], 1e-4)
    assert (chroma < 0.12).mean() > 0.6 and (chroma > 0.3).mean() > 0.03
    brows = [_shown_luma(m["eyebrows"]) for m in (young, old)]
    assert brows[1] > 3 * brows[0]  # the brows grey alongside
    picked = {"colour": "auburn hair"}
    dyed = load_garment(style, texture_size=128, options=picked)
    kept = library.wearer_looks([dyed], [style], {style: picked}, 0.95)[0]
    assert kept.material is dyed.material
