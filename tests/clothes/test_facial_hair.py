"""Facial hair: a short beard and a moustache (strand cards) and stubble (a tiled layer on
the skin), grown from the base mesh's face so they fit every body, stay outside the skin
with the mouth open and ride the jaw."""

from __future__ import annotations

import numpy as np
import pytest

from avatar.clothes import face, library
from avatar.clothes.library import authoring_body, load_garment
from avatar.geometry import collision
from avatar.human import Human
from avatar.looks import facial_hair

ITEMS = ("beard-short", "moustache", "stubble")


def test_facial_hair_is_in_the_library():
    entries = {e.name: e for e in library.list_garments()}
    for name in ITEMS:
        assert entries[name].category == "beard"
        assert library.mhm_kind(entries[name]) == "clothes"  # MakeHuman has no beard slot
    assert {e.name for e in library.list_garments("facial hair")} == set(ITEMS)
    beard = load_garment("beard-short", texture_size=64)
    stubble = load_garment("stubble", texture_size=64)
    assert beard.material.alpha_mode == "MASK" and beard.material.base_color_texture.shape[2] == 4
    assert stubble.material.alpha_mode == "BLEND" and not stubble.collide


def test_beard_leaves_lips_and_forehead_bare():
    body = authoring_body()
    lips = face._region(body, "lips", 0.25)
    _, mouth, eye_z, chin_z = face.mouth_frame(body)
    for part in ("beard", "moustache"):
        mask = face.facial_hair_mask(body, part)
        assert mask.sum() > 100 and not (mask & lips).any()
        c = body.vertices[body.skin_faces[mask]].mean(axis=1)
        assert c[:, 2].max() < eye_z
    beard = body.vertices[body.skin_faces[face.facial_hair_mask(body, "beard")]].mean(axis=1)
    assert beard[:, 2].min() < chin_z  # under the chin
    assert np.abs(beard[:, 0]).max() > 0.06  # out to the jaw's angle and sideburns


@pytest.mark.parametrize("params", [
    {"gender": 1.0},
    {"gender": 1.0, "expression/jawOpen": 1.0},
    {"gender": 1.0, "weight": 1.0, "age": 1.0, "expression/jawOpen": 0.8},
    {"gender": 0.8, "age": 0.3, "muscle": 1.0, "expression/mouthSmileLeft": 1.0,
     "expression/mouthSmileRight": 1.0},
])  # fmt: skip
def test_facial_hair_stays_outside_the_skin(params):
    human = Human(params).dressed(*ITEMS)
    faces = human.model.base.faces[human.model.base.face_groups["body"]]
    for part in library.parts(human.outfit):
        _, depth = collision.penetration(human.vertices[:13380], faces, part.mesh.vertices)
        assert depth.max() <= 0.001, f"{part.name}: {depth.max() * 1000:.2f} mm inside"


def test_beard_follows_the_jaw():
    shut = Human({"gender": 1.0}).dressed("beard-short", "moustache")
    open_ = Human({"gender": 1.0, "expression/jawOpen": 1.0}).dressed("beard-short", "moustache")
    mouth = shut.vertices[shut.model.base.groups["helper-upper-teeth"]].mean(axis=0)
    drops = {}
    for g_shut, g_open in zip(shut.outfit.garments, open_.outfit.garments, strict=True):
        before, after = g_shut.mesh.vertices, g_open.mesh.vertices
        drops[g_shut.name] = drop = before[:, 2] - after[:, 2]
        if g_shut.name == "beard-short":
            chin = (before[:, 2] < mouth[2] - 0.035) & (before[:, 1] < mouth[1])
            assert chin.sum() > 100 and np.median(drop[chin]) > 0.01  # the chin's hair drops
            # ... carried by the jaw bone when the rig moves it.
            jaw = shut.skeleton.names.index("jaw")
            w = g_shut.weights
            on_jaw = (w.weights * (w.indices == jaw)).sum(axis=1)
            assert np.median(on_jaw[chin]) > 0.5
            chin_drop = np.median(drop[chin])
    # The moustache rides the upper lip (which jawOpen lowers a little), not the jaw.
    assert np.median(drops["moustache"]) < 0.6 * chin_drop
    assert np.percentile(drops["moustache"], 95) < 0.9 * chin_drop


def test_stubble_texture_tiles_and_is_see_through():
    from avatar.looks import facial_hair

    alpha = facial_hair.stubble_alpha(256)
    assert 0.2 < alpha.mean() / 255 < 0.6  # skin shows between the stubs
    assert alpha.min() > 0  # a faint shadow everywhere: no bald spots in the tile
    # Columns wrap: the first and last columns are as alike as neighbouring columns are.
    seam = np.abs(alpha[:, 0].astype(int) - alpha[:, -1]).mean()
    inner = np.abs(alpha[:, 100].astype(int) - alpha[:, 101]).mean()
    assert seam < 2 * inner + 5


def test_beard_cards_are_sparser_than_scalp_hair():
    """Beard cards show skin between their hairs (a scalp card's strands would read as a
    solid block on the face)."""
    beard = load_garment("beard-short", texture_size=256).material.base_color_texture
    scalp = load_garment("hair-short", texture_size=256).material.base_color_texture
    half = slice(128, 256)  # the strand cards' rows
    beard_cover = (beard[half, :, 3] > 127).mean()
    assert beard_cover < 0.5 * (scalp[half, :, 3] > 127).mean() and beard_cover > 0.05


def _roots(piece) -> tuple[np.ndarray, np.ndarray]:
    """(N, 3) root and (N,) length (m) of each strand card of a facial hair piece (cards of
    2 x K vertices: one long side, then the other, root first; K - 1 quads a card)."""
    count, quads = len(piece.mesh.vertices), len(piece.mesh.faces)
    k = count // (count - 2 * quads)  # count = 2K cards, quads = (K - 1) cards
    v = piece.mesh.vertices.reshape(-1, 2, k, 3).astype(np.float64)
    mid = v.mean(axis=1)  # (N, 3, 3) the card's centre line
    return mid[:, 0], np.linalg.norm(np.diff(mid, axis=1), axis=2).sum(axis=1)


@pytest.fixture(scope="module")
def frame():
    body = authoring_body()
    return body, face.mouth_frame(body)


def test_beard_edge_follows_the_cheek_line_not_a_level_cut(frame):
    """Seen from the front a beard's upper edge runs from the corner of the mouth up
    across the cheek to the sideburns; it wanders (no ruler line) and it is not sharp:
    hair thins out over its last centimetre (sparser and shorter cards)."""
    body, (centre, mouth, eye_z, _) = frame
    roots, length = _roots(face.beard_cards(body))
    turn = face.around(roots, centre)
    rel_z = roots[:, 2] - mouth[2]

    def top(lo, hi):  # the edge: the highest roots at these directions around the head
        return np.percentile(rel_z[(turn >= lo) & (turn < hi)], 97)

    corner, cheek, sideburn = top(17, 25), top(50, 60), top(76, 86)
    assert top(0, 8) > corner + 0.006  # the moustache stands above the mouth's corner
    assert cheek > corner + 0.015 and sideburn > cheek + 0.015  # rising to the ear
    # An irregular line: the edge's height against a smooth fit over 30..80 degrees.
    bins = np.arange(30, 80, 2.5)
    edge = np.array([top(a, a + 2.5) for a in bins])
    wander = edge - np.polyval(np.polyfit(bins, edge, 2), bins)
    assert 0.0015 < wander.std() < 0.006


def _cheek_fall_off(body, centre, mouth, eye_z, lo=35, hi=70) -> float:
    """The beard's 10-90 % fall-off across its cheek line, m on the skin: the median
    distance from points of density 0.9 to the nearest of density 0.1, over skin points
    ``lo``..``hi`` degrees round the face, between the mouth and the eyes."""
    from scipy.spatial import cKDTree

    from avatar.clothes.hair import _scatter

    c = body.vertices[body.skin_faces].mean(axis=1).astype(np.float64)
    turn = face.around(c, centre)
    cheek = (turn > lo - 5) & (turn < hi + 5) & (c[:, 1] < centre[1] - 0.01)
    cheek &= (c[:, 2] > mouth[2] - 0.01) & (c[:, 2] < eye_z + 0.01)
    p = _scatter(body, cheek, 200_000, np.random.default_rng(0))
    p = p[(face.around(p, centre) > lo) & (face.around(p, centre) < hi)]
    d = face.facial_hair_density(body, "beard", p)
    full, bare = p[np.abs(d - 0.9) < 0.02], p[np.abs(d - 0.1) < 0.02]
    return float(np.median(cKDTree(bare).query(full)[0]))


def test_beard_thins_out_over_two_centimetres_on_the_cheeks(frame):
    """Hair density falls from full to none across the cheek line over some 1.5-2 cm of
    skin (10 to 90 %: it was 4.4 mm, a line drawn with a pen), without hair climbing
    onto the cheekbones (bare from 8 mm above the drawn line), and the cards there are
    fewer per area and shorter."""
    body, (centre, mouth, eye_z, _) = frame
    width = _cheek_fall_off(body, centre, mouth, eye_z)
    assert 0.014 < width < 0.022, width
    c = body.vertices[body.skin_faces].mean(axis=1).astype(np.float64)
    density = face.facial_hair_density(body, "beard", c)
    turn = face.around(c, centre)
    line = np.interp(turn, face.CHEEK_DEG, face.CHEEK_M) + facial_hair.cheek_wobble(turn)
    above = (c[:, 2] - mouth[2] > line + 0.008) & (c[:, 1] < centre[1] - 0.01)
    assert above.sum() > 200 and density[above].max() < 0.02
    roots, length = _roots(face.beard_cards(body))
    grow = face.facial_hair_density(body, "beard", roots)
    quads = body.vertices[body.skin_faces].astype(np.float64)
    area = 0.5 * np.linalg.norm(np.cross(quads[:, 2] - quads[:, 0], quads[:, 3] - quads[:, 1]),
                                axis=1)  # fmt: skip
    keep = face.facial_hair_mask(body, "beard")
    rim_faces, full_faces = keep & (density > 0.05) & (density < 0.5), keep & (density > 0.95)
    rim, full = (grow > 0.05) & (grow < 0.5), grow > 0.95
    per_area = rim.sum() / area[rim_faces].sum(), full.sum() / area[full_faces].sum()
    assert per_area[0] < 0.6 * per_area[1]
    assert np.median(length[rim]) < 0.75 * np.median(length[full])


def test_moustache_tapers_to_the_corners_of_the_mouth(frame):
    """Full under the nose, narrowing to points at the corners of the mouth: not a block."""
    body, (_, mouth, *_) = frame
    roots, length = _roots(face.moustache(body))
    across = np.abs(roots[:, 0]) / face.MOUSTACHE_HALF_M
    rel_z = roots[:, 2] - mouth[2]

    def height(lo, hi):
        z = rel_z[(across >= lo) & (across < hi)]
        return np.percentile(z, 95) - np.percentile(z, 5)

    middle, outer = height(0.0, 0.2), height(0.8, 0.95)
    assert middle > 0.01 and outer < 0.55 * middle
    # ... and its ends hang down towards the corners of the mouth.
    assert np.median(rel_z[across > 0.75]) < np.median(rel_z[across < 0.3]) - 0.006
    assert np.abs(roots[:, 0]).max() < 1.15 * face.MOUSTACHE_HALF_M


def _stubble_uv_metres(body):
    """The stubble piece's faces (F, 4, 3) and their corners' UVs in atlas metres."""
    from avatar.looks import facial_hair as fh

    mesh = face.stubble(body).mesh
    points = mesh.vertices[mesh.faces].astype(np.float64)
    uv = mesh.uvs[mesh.face_uvs].astype(np.float64)
    return mesh, points, uv * [2 * fh.STUBBLE_SPAN_U, fh.STUBBLE_V[1] - fh.STUBBLE_V[0]]


def test_stubble_is_not_stretched_under_the_chin(frame):
    """Down the skin under the chin (faces looking down) the atlas runs at most of a metre
    per metre, as on the face: v was the height, which barely changes where the skin runs
    back level, so the stubs were drawn as streaks (a fifth of the rate in places)."""
    body, (centre, mouth, eye_z, chin_z) = frame
    _, points, uv = _stubble_uv_metres(body)
    e1, e2 = points[:, 1] - points[:, 0], points[:, 3] - points[:, 0]
    normal = np.cross(e1, e2)
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    a = e1 / np.linalg.norm(e1, axis=1, keepdims=True)
    b = np.cross(normal, a)
    local = np.stack([np.stack([e @ a_, e @ b_]) for e, a_, b_ in zip(
        np.concatenate([e1, e2]), np.concatenate([a, a]), np.concatenate([b, b]),
        strict=True)]).reshape(2, -1, 2).transpose(1, 0, 2)  # fmt: skip
    d_uv = np.stack([uv[:, 1] - uv[:, 0], uv[:, 3] - uv[:, 0]], 1)
    jacobian = np.linalg.solve(local, d_uv)  # (F, 2, 2): surface metres -> atlas metres
    grad_v = np.linalg.norm(jacobian[:, :, 1], axis=1)
    c = points.mean(axis=1)
    normal *= np.sign(np.einsum("fd,fd->", normal, c - centre))  # outward
    # Under the chin: the nose's underside also looks down, but grows no stubble.
    under = (normal[:, 2] < -0.6) & (c[:, 2] < mouth[2])
    face_ = (c[:, 2] > mouth[2]) & (c[:, 2] < eye_z)
    assert under.sum() > 50
    assert 0.7 < np.median(grad_v[under]) < 1.3 and np.percentile(grad_v[under], 10) > 0.35
    assert 0.8 < np.median(grad_v[face_]) < 1.2


def test_stubble_thins_out_to_the_lips(frame):
    """The stubble's edge round the lips falls on (nearly) no density, not a hard line,
    and a centimetre above the lip it is full again."""
    from avatar.geometry.shell import boundary_edges
    from avatar.looks import facial_hair as fh

    body, (_, mouth, *_) = frame
    mesh = face.stubble(body).mesh
    rim = np.unique(boundary_edges(mesh.faces)[0])
    rim = rim[np.linalg.norm(mesh.vertices[rim] - mouth, axis=1) < 0.045]  # the lips' rim
    uv = np.zeros((len(mesh.vertices), 2), np.float32)
    uv[mesh.faces.ravel()] = mesh.uvs[mesh.face_uvs.ravel()]
    shape = (760, 920)
    density = fh.stubble_density(shape)
    rows = np.clip(((1 - uv[rim, 1]) * shape[0]).astype(int), 0, shape[0] - 1)
    cols = np.clip((uv[rim, 0] * shape[1]).astype(int), 0, shape[1] - 1)
    assert len(rim) > 30 and np.median(density[rows, cols]) < 0.1
    above = (0.012 - fh.STUBBLE_V[0]) / (fh.STUBBLE_V[1] - fh.STUBBLE_V[0])  # 12 mm up
    assert density[int((1 - above) * shape[0]), shape[1] // 2] > 0.9


def test_moustache_thins_out_under_the_nose(frame):
    """The moustache's top under the nose is not a line: in its middle, the top 2 mm of
    roots are far sparser than the full hair below (they were as dense: a felt block)."""
    body, (_, mouth, *_) = frame
    roots, _ = _roots(face.moustache(body))
    middle = np.abs(roots[:, 0]) < 0.4 * face.MOUSTACHE_HALF_M
    depth = np.percentile(roots[middle, 2], 98) - roots[middle, 2]
    top = ((depth >= 0) & (depth < 0.002)).sum()
    full = ((depth >= 0.004) & (depth < 0.008)).sum() / 2
    assert top < 0.6 * full


def test_short_beard_is_light():
    """The short beard stays under 10,000 vertices (it was 21,600, the heaviest item)."""
    mesh = load_garment("beard-short", texture_size=64).mesh
    assert len(mesh.vertices) < 10_000


def test_stubble_is_not_squeezed_across_the_throat(frame):
    """On the throat the atlas runs at a metre per metre both ways, as on the cheeks: u
    was an arc round the skull's axis (2 cm behind the throat) and v ran in from the
    jaw's sides, which squeezed the stubs 2.4 times across the throat and stretched them
    down it."""
    body, (centre, mouth, eye_z, chin_z) = frame
    _, points, uv = _stubble_uv_metres(body)
    stretch = _atlas_stretch(points, uv)  # (F, 2) largest and smallest
    c = points.mean(axis=1)
    throat = c[:, 2] < chin_z - 0.005
    cheek = (c[:, 2] > mouth[2] - 0.02) & (np.abs(c[:, 0]) > 0.04) & (c[:, 2] < eye_z)
    assert throat.sum() > 10 and cheek.sum() > 50
    for region in (throat, cheek):
        big, small = np.median(stretch[region], axis=0)
        assert big < 1.2 and small > 0.8, (big, small)  # the throat's was 2.43 and 0.69


def _atlas_stretch(points: np.ndarray, uv: np.ndarray) -> np.ndarray:
    """(F, 2) singular values (largest, smallest) of each quad's map from the skin to the
    atlas (metres per metre): 1 and 1 where the stubs keep their size and shape."""
    e1, e2 = points[:, 1] - points[:, 0], points[:, 3] - points[:, 0]
    a = e1 / np.linalg.norm(e1, axis=1, keepdims=True)
    normal = np.cross(e1, e2)
    b = np.cross(normal / np.linalg.norm(normal, axis=1, keepdims=True), a)
    local = np.stack([np.stack([np.einsum("nd,nd->n", e, a), np.einsum("nd,nd->n", e, b)], 1)
                      for e in (e1, e2)], 2)  # fmt: skip
    d_uv = np.stack([uv[:, 1] - uv[:, 0], uv[:, 3] - uv[:, 0]], 2)
    return np.linalg.svd(d_uv @ np.linalg.inv(local), compute_uv=False)


def test_moustache_lower_edge_breaks_up_over_the_lip(frame):
    """Along the lip the moustache's lowest tips wander by millimetres (locks of their own
    length), not one line: 0.66 mm from a smooth curve before, which rendered as a
    straight lower edge on the mouth's line."""
    body, (centre, mouth, eye_z, _) = frame
    cards = face.moustache(body).mesh.vertices.reshape(-1, 2, 3, 3).astype(np.float64)
    tips = cards[:, :, -1].reshape(-1, 3)
    bins = np.arange(-0.024, 0.024, 0.002)
    edge = np.array([np.percentile(tips[(tips[:, 0] >= a) & (tips[:, 0] < a + 0.002), 2], 3)
                     for a in bins])  # fmt: skip
    wander = edge - np.polyval(np.polyfit(bins, edge, 4), bins)
    assert wander.std() > 0.0012


def test_facial_hair_cards_show_few_coarse_hairs():
    """A moustache card spans few of the texture's hairs (coarse strands that show their
    direction), not a scalp card's forty hair-thin ones (a felt at any distance)."""
    mesh = load_garment("moustache", texture_size=64).mesh
    uv = mesh.uvs[mesh.face_uvs]  # (F, 4, 2)
    across = np.ptp(uv[..., 0], axis=1)
    assert np.median(across) < 0.07


def _opaque_hits(body, piece, alpha: np.ndarray, cutoff: float, points: np.ndarray) -> np.ndarray:
    """(N,) bool: whether a ray from each skin point (N, 3) straight out along the skin's
    normal meets an opaque texel (``alpha`` (H, W) uint8 at or above ``cutoff``) of the
    piece's faces within a centimetre (Moller-Trumbore over the nearby triangles)."""
    from scipy.spatial import cKDTree

    mesh = piece.mesh
    quads, uvq = mesh.vertices[mesh.faces].astype(np.float64), mesh.uvs[mesh.face_uvs]
    tris = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
    uvs = np.concatenate([uvq[:, [0, 1, 2]], uvq[:, [0, 2, 3]]]).astype(np.float64)
    near = cKDTree(tris.mean(axis=1)).query_ball_point(points, r=0.012)
    ray = np.repeat(np.arange(len(points)), [len(n) for n in near])
    tri = np.concatenate([np.asarray(n, int) for n in near])
    normal = body.outward(points)
    origin, direction = points[ray] - 0.0002 * normal[ray], normal[ray]
    a, b, c = tris[tri, 0], tris[tri, 1] - tris[tri, 0], tris[tri, 2] - tris[tri, 0]
    p = np.cross(direction, c)
    det = np.einsum("nd,nd->n", b, p)
    ok = np.abs(det) > 1e-14
    inv = np.where(ok, 1 / np.where(ok, det, 1), 0)
    s = origin - a
    u = np.einsum("nd,nd->n", s, p) * inv
    q = np.cross(s, b)
    v = np.einsum("nd,nd->n", direction, q) * inv
    t = np.einsum("nd,nd->n", c, q) * inv
    hit = ok & (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 0) & (t < 0.01)
    uv = ((1 - u - v)[:, None] * uvs[tri, 0] + u[:, None] * uvs[tri, 1]
          + v[:, None] * uvs[tri, 2])  # fmt: skip
    h, w = alpha.shape
    col = np.floor(np.mod(uv[:, 0], 1.0) * w).astype(int) % w
    row = np.clip(np.floor((1 - uv[:, 1]) * h).astype(int), 0, h - 1)
    opaque = hit & (alpha[row, col] >= cutoff * 255)
    return np.bincount(ray[opaque], minlength=len(points)) > 0


def test_short_beard_covers_the_skin_where_it_grows_fully(frame):
    """Seen straight on, the skin under a short beard is covered by hair wherever the
    beard grows fully (density over 0.9): cards alone (2,400 of them, two in five of
    their hairs kept) covered ~70 % and the rest rendered as skin blotches, a grey beard
    on pale skin most. Its soft edge still shows skin between the hairs."""
    from avatar.clothes.hair import _scatter

    body, _ = frame
    material = load_garment("beard-short", texture_size=1024).material
    alpha = material.base_color_texture[..., 3]
    rng = np.random.default_rng(0)
    points = _scatter(body, face.facial_hair_mask(body, "beard"), 6000, rng)
    density = face.facial_hair_density(body, "beard", points)
    covered = _opaque_hits(body, face.beard(body), alpha, material.alpha_cutoff, points)
    full, edge = density > 0.9, (density > 0.05) & (density < 0.3)
    assert full.sum() > 1000 and edge.sum() > 100
    assert covered[full].mean() > 0.97, covered[full].mean()
    assert covered[edge].mean() < 0.8, covered[edge].mean()


def _card_ends(piece) -> tuple[np.ndarray, np.ndarray]:
    """(N, 3) roots and (N, 3) tips of a facial hair piece's one-segment cards."""
    mid = piece.mesh.vertices.reshape(-1, 2, 2, 3).astype(np.float64).mean(axis=1)
    return mid[:, 0], mid[:, 1]


def test_short_beard_is_longer_at_the_chin_than_on_the_cheeks(frame):
    """A short beard grows longest at the front of the chin and shortest on the cheeks
    (one length everywhere read as a felt mat): chin cards at least 1.6 times as long."""
    body, (centre, mouth, _, chin_z) = frame
    roots, tips = _card_ends(face.beard_cards(body))
    length = np.linalg.norm(tips - roots, axis=1)
    turn = face.around(roots, centre)
    full = face.facial_hair_density(body, "beard", roots) > 0.9
    chin = (turn < 20) & (roots[:, 2] < mouth[2] - 0.02) & (roots[:, 2] > chin_z)
    cheek = (turn > 50) & (turn < 80) & full
    assert chin.sum() > 50 and cheek.sum() > 100
    assert np.median(length[chin]) > 1.6 * np.median(length[cheek])


def test_short_beard_grows_in_clumps(frame):
    """Neighbouring cards' tips are drawn together into clumps (gaps between them):
    tips lie closer to their nearest neighbours than the roots do (were 1.1 times as
    far apart, spread as evenly as the roots)."""
    from scipy.spatial import cKDTree

    body, _ = frame
    roots, tips = _card_ends(face.beard_cards(body))

    def spacing(points):
        return cKDTree(points).query(points, k=2)[0][:, 1].mean()

    assert spacing(tips) < 0.75 * spacing(roots)


def test_short_beard_edges_break_up_into_single_hairs(frame):
    """Over the beard's soft edges (cheek line, neck line) stray hairs: cards a hair or
    two wide standing off the skin, where the beard thins out (density under 0.7)."""
    body, _ = frame
    strays = face.beard_strays(body)
    roots, tips = _card_ends(strays)
    v = strays.mesh.vertices.reshape(-1, 2, 2, 3).astype(np.float64)
    width = np.linalg.norm(v[:, 1, 0] - v[:, 0, 0], axis=1)
    grow = face.facial_hair_density(body, "beard", roots)
    assert len(roots) > 150 and np.median(width) < 0.002
    assert np.mean(grow < 0.7) > 0.95
    assert len(load_garment("beard-short", texture_size=64).mesh.vertices) > len(
        face.beard_undercoat(body).mesh.vertices) + len(face.beard_cards(body, 1950).mesh.vertices)


def test_beard_undercoat_is_in_the_shade_of_its_clumps():
    """The undercoat (the hair deep in the beard, seen between clumps) is darker than the
    cards over it: as light, the beard read as one even mat."""
    texture = load_garment("beard-short", texture_size=256).material.base_color_texture
    shown, light = texture[..., 3] > 127, texture[..., :3].mean(-1)
    under, cards = light[:128][shown[:128]].mean(), light[128:][shown[128:]].mean()
    assert under < 0.75 * cards


def test_grey_beard_greys_hair_by_hair_not_in_streaks():
    """An old man's beard greys hair by hair in the undercoat (the dense rows): whole
    texture columns grey drew vertical streaks down the beard and up a grey cap."""
    from avatar.looks import facial_hair

    material = load_garment("beard-short", texture_size=256).material
    tex = facial_hair.for_wearer(material, "cards", 0.9, "dark brown hair").base_color_texture
    grey = tex[:128, :, :3].astype(float).mean(-1) > 100
    mixed = ~(grey.all(axis=0) | (~grey).all(axis=0))  # columns partly grey, partly not
    assert 0.2 < grey.mean() < 0.95 and mixed.mean() > 0.5


def test_short_beard_clumps_taper_to_points(frame):
    """A beard card narrows to under half its root's width at its tip, and is some 3 mm
    wide: 4.4 mm cards ending at 70 % of it laid blunt, rounded clump ends over the next
    clump's roots, read as scales."""
    body, _ = frame
    v = face.beard_cards(body).mesh.vertices.reshape(-1, 2, 2, 3).astype(np.float64)
    root = np.linalg.norm(v[:, 1, 0] - v[:, 0, 0], axis=1)
    tip = np.linalg.norm(v[:, 1, 1] - v[:, 0, 1], axis=1)
    assert np.median(tip / root) < 0.45, np.median(tip / root)  # was 0.7
    assert np.median(root) < 0.0036, np.median(root)  # was 4.2 mm


def test_beard_cards_draw_single_fine_hairs():
    """Across a beard card's rows the opaque texels come in single hairs (runs of at
    most a hair's 3 texels at 1024 px: kept neighbours merged into ribbons up to 14 texels
    wide, flakes), as light at the tips as at the roots within a third (scalp hair's
    lightening, 1.77 times, drew each clump as a scale with a light rim)."""
    material = load_garment("beard-short", texture_size=1024).material
    texture = material.base_color_texture
    cards = texture[512:]
    runs = []
    for row in cards[8:-8:16, :, 3] > 127:
        edges = np.diff(np.r_[0, row.astype(int), 0])
        runs.append(np.flatnonzero(edges == -1) - np.flatnonzero(edges == 1))
    runs = np.concatenate(runs)
    assert len(runs) > 1000 and runs.max() <= 3, runs.max()
    lum = _linear(cards[..., :3]) @ np.array([0.2126, 0.7152, 0.0722])
    shown = cards[..., 3] > 127
    root, tip = (np.median(lum[rows][shown[rows]]) for rows in (slice(8, 90), slice(380, 480)))
    assert tip < 1.3 * root, tip / root


def test_dark_beard_shows_its_colour():
    """A black-haired man's beard has the albedo of real dark hair (linear luminance at
    least 0.015 in its undercoat and cards: 0.0095 in the undercoat, near black), a dark
    brown beard stays brown (red over blue), and an old man's grey beard has grey, not
    white, hairs (none over 0.9: a fifth of its card texels were 1.0, cotton wool)."""
    from avatar.looks import facial_hair

    material = load_garment("beard-short", texture_size=256).material
    weights = np.array([0.2126, 0.7152, 0.0722])

    def shown(colour, age=0.45):
        tex = facial_hair.for_wearer(material, "cards", age, colour).base_color_texture
        lin = _linear(tex[..., :3])
        return [lin[rows][tex[rows, :, 3] > 127] for rows in (slice(0, 128), slice(128, 256))]

    for texels in shown("black hair"):
        assert np.median(texels @ weights) > 0.015, np.median(texels @ weights)
    for texels in shown("dark brown hair"):
        red, _, blue = np.median(texels, axis=0)
        assert red > 2.5 * blue and 0.02 < np.median(texels @ weights) < 0.1
    grey = np.concatenate(shown("dark brown hair", age=1.0)) @ weights
    assert grey.max() < 0.9, (grey > 0.9).mean()


def _linear(srgb_u8: np.ndarray) -> np.ndarray:
    s = srgb_u8.astype(np.float64) / 255
    return np.where(s <= 0.04045, s / 12.92, ((s + 0.055) / 1.055) ** 2.4)


def test_beard_cards_have_little_sheen():
    """A beard asks the renderer for little fibre rim (Principled sheen): at scalp hair's
    0.25 (no hint), clumps lying at a grazing angle under the lip and on the chin lit up
    whole, grey flakes on a dark beard."""
    extras = load_garment("beard-short", texture_size=64).material.extras
    assert float(extras.get("sheen", 0.25)) <= 0.1


def test_dark_brown_beard_is_lighter_than_its_hair_colour():
    """A dark brown beard's undercoat (most of what shows of a full beard) is lighter
    than the scalp hair's colour (linear luminance at least 1.3 times it: 0.95 times,
    0.028, rendered as a black mask), and so is a black one; a grey hair's beard is not
    lifted (within 5 %)."""
    from avatar.looks import fabrics, facial_hair

    material = load_garment("beard-short", texture_size=256).material
    weights = np.array([0.2126, 0.7152, 0.0722])

    def undercoat(tex):
        shown = tex[:128, :, 3] > 127
        return float((_linear(tex[:128, :, :3])[shown] @ weights).mean())

    for colour in ("dark brown hair", "black hair"):
        hair = float(fabrics.rgb(colour) @ weights)
        tex = facial_hair.for_wearer(material, "cards", 0.45, colour).base_color_texture
        assert undercoat(tex) > 1.3 * hair, undercoat(tex) / hair
    grey = facial_hair.for_wearer(material, "cards", 0.45, "grey hair").base_color_texture
    scalp = facial_hair.for_wearer(load_garment("hair-short", texture_size=256).material,
                                   "cards", 0.45, "grey hair").base_color_texture  # fmt: skip
    assert undercoat(grey) < 1.05 * undercoat(scalp) / facial_hair.UNDERCOAT_SHADE**2.2


def test_beard_relief_has_no_streaks():
    """A beard's normal map, if it has one, has no grooves running down whole texture
    columns in its undercoat rows (the spread of the column means of its x component
    under 2 of 255: 40, the hair fabric's grooves, drew long vertical streaks down a grey
    beard, the undercoat's v being stretched up the face), nor its roughness."""
    material = load_garment("beard-short", texture_size=256).material
    if material.normal_texture is not None:
        normal = material.normal_texture[:128, :, 0].astype(np.float64)
        assert normal.mean(axis=0).std() < 2.0, normal.mean(axis=0).std()
    rough = material.roughness_texture[:128].astype(np.float64)
    assert rough.mean(axis=0).std() < 2.0, rough.mean(axis=0).std()


def test_grey_beard_is_a_little_darker_than_grey_scalp_hair():
    """An old man's grey beard strands are darker than the same texture greyed as scalp
    hair (at most 0.8 times the median of its light texels): without the hair fabric's
    relief shading them, at the scalp's grey a beard rendered white as cotton wool."""
    from dataclasses import replace

    from avatar.looks import facial_hair

    material = load_garment("beard-short", texture_size=256).material
    scalp_like = replace(material, extras={k: v for k, v in material.extras.items()
                                           if k != "facial"})  # fmt: skip
    weights = np.array([0.2126, 0.7152, 0.0722])

    def light(m):
        tex = facial_hair.for_wearer(m, "cards", 1.0, "dark brown hair").base_color_texture
        lum = _linear(tex[..., :3])[tex[..., 3] > 127] @ weights
        return np.median(lum[lum > 0.2])

    assert light(material) < 0.8 * light(scalp_like), light(material) / light(scalp_like)


def test_beard_undercoat_has_no_corduroy():
    """Down the fully covered undercoat rows (stretched down the whole face) no shade runs
    a whole texture column: the column means' spectrum at 0.6-5 mm on the face (8-64
    cycles across the 4 cm texture width) is within a few times its fine-noise floor
    (128-512 cycles). The scalp layout's locks, one shade a column, put 35 times the
    floor there at 512 px: fine parallel stripes, corduroy."""
    size = 512
    tex = load_garment("beard-short", texture_size=size).material.base_color_texture
    v = 1 - (np.arange(size // 2) + 0.5) / size
    full = tex[: size // 2][v > facial_hair.UNDERCOAT_V[1]]  # the fully covered rows
    full = _linear(full[..., :3]) @ [0.2126, 0.7152, 0.0722]
    profile = full.mean(axis=0)
    power = np.abs(np.fft.rfft(profile - profile.mean())) ** 2
    n = len(power)
    ratio = power[n // 64 : n // 8].mean() / power[n // 4 :].mean()
    assert ratio < 6, ratio


def test_beard_undercoat_hairs_are_not_parallel(frame):
    """The undercoat's hairs (along its texture's v, across its u) lean this way and that
    over the face, a quarter of it by more than 6 degrees from straight down (u the arc
    round the face alone: under a degree, every hair parallel, corduroy)."""
    body, (centre, *_) = frame
    mesh = face.beard_undercoat(body).mesh
    tri = mesh.vertices[mesh.faces[:, :3]].astype(np.float64)
    u = mesh.uvs[mesh.face_uvs[:, :3], 0].astype(np.float64)
    e1, e2 = tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]
    normal = np.cross(e1, e2)
    # u's gradient in each triangle's plane; the hairs run across it.
    du = np.stack([u[:, 1] - u[:, 0], u[:, 2] - u[:, 0], np.zeros(len(u))], 1)
    grad = np.linalg.solve(np.stack([e1, e2, normal], 1), du[..., None])[..., 0]
    hair = np.cross(normal, grad)
    hair /= np.linalg.norm(hair, axis=1, keepdims=True)
    rel = tri.mean(axis=1) - centre
    round_ = np.stack([-rel[:, 1], rel[:, 0], np.zeros(len(rel))], 1)
    round_ /= np.linalg.norm(round_, axis=1, keepdims=True)
    lean = np.degrees(np.arcsin(np.clip(np.abs(np.einsum("fd,fd->f", hair, round_)), 0, 1)))
    assert np.percentile(lean, 75) > 6, np.percentile(lean, 75)


@pytest.mark.parametrize("params", [
    {"gender": 0.52, "age": 0.52, "weight": 0.72, "muscle": 0.45, "height": 0.85},
    {"gender": 1.0, "age": 0.9, "weight": 0.3},
])  # fmt: skip
def test_skin_drawn_items_ride_the_skin_when_the_head_bends(params):
    """Stubble, brows and lashes lie on the skin with no push-out, so frames must skin them
    as the skin is skinned. Cut to 4 bones a vertex (the colliding garments' frame weights),
    the stubble sank 2.0-2.7 mm into the mouth's corners with the neck bent in CMU's jumps,
    and vanished there. Here: the head bowed 45 degrees over the three neck bones and
    turned 30 degrees; every item stays as deep as at rest (+0.3 mm)."""
    from avatar.rig import kinematics, quaternion, skinning

    human = Human(params).dressed("stubble", "eyebrows", "eyelashes")
    faces = human.model.base.faces[human.model.base.face_groups["body"]]
    rest = [
        collision.penetration(human.vertices[:13380], faces, g.mesh.vertices)[1].max()
        for g in human.outfit.garments
    ]
    walk = human.walk(seconds=1.0, fps=24)
    rot, trans = walk.rotations[:1].copy(), walk.translations[:1]
    names = list(human.skeleton.names)
    bow = quaternion.from_euler(np.radians([15.0, 0.0, 10.0]))
    for bone in ("neck01", "neck02", "neck03"):
        j = names.index(bone)
        rot[0, j] = quaternion.multiply(rot[0, j], bow)
    mats = kinematics.skinning_matrices(
        human.skeleton, kinematics.forward(human.skeleton, rot, trans)
    )[0]
    posed = skinning.linear_blend(human.vertices, human.weights, mats)
    frame = human.outfit.frame(posed, mats)
    for g, verts, before in zip(human.outfit.garments, frame, rest, strict=True):
        _, depth = collision.penetration(posed[:13380], faces, verts)
        assert depth.max() <= max(before, 0.0) + 3e-4, (
            f"{g.name}: {depth.max() * 1e3:.2f} mm inside (rest {before * 1e3:.2f} mm)"
        )
