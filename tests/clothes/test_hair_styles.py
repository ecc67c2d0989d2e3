"""Issue 14's hair styles up close: a ponytail is a bundle of strands (not one flat
ribbon), a bob's ends are cut blunt (not frayed), and every built-in hair style keeps to
a game character's vertex budget."""

from __future__ import annotations

import numpy as np
import pytest

from avatar.clothes import builtin, hair
from avatar.clothes.library import authoring_body, load_garment


@pytest.fixture(scope="module")
def body():
    return authoring_body()


def test_ponytail_is_a_bundle_of_cards_facing_every_way(body):
    """Cards fill the tail's section (not only its surface) and face every way round it:
    from behind, some are seen face on and some edge on, as strands of a bundle."""
    mesh = hair.ponytail(body).mesh
    cards = mesh.vertices.reshape(-1, 2, 13, 3).astype(np.float64)  # side, along, xyz
    assert len(cards) >= 120
    middle = cards[:, :, 6].mean(axis=1)  # (N, 3) each card's centre half way down
    spine = np.median(middle, axis=0)
    reach = np.hypot(*(middle - spine)[:, :2].T)
    assert np.percentile(reach, 20) < 0.65 * np.percentile(reach, 90)  # a core, not a shell
    across = cards[:, 1, 6] - cards[:, 0, 6]  # each card's width direction half way down
    across /= np.linalg.norm(across, axis=1, keepdims=True)
    out = (middle - spine) * [1, 1, 0]
    out /= np.maximum(np.linalg.norm(out, axis=1, keepdims=True), 1e-9)
    # A card on a ribbon-like shell lies across the radius (|cos| ~ 0); a bundle's cards
    # turn every way.
    cos = np.abs(np.einsum("nd,nd->n", across, out))
    assert np.percentile(cos, 75) > 0.4


def test_bob_ends_are_cut_blunt(body):
    """The hanging cards' ends show the strands cut (the texture's alpha at their tips is
    well covered), over a level line, not thinned-out tips spread over a few centimetres."""
    piece = hair.hang_cards(body, hair.flow_parted())
    mesh = piece.mesh
    alpha = load_garment("hair-bob", texture_size=256).material.base_color_texture[..., 3]
    uv = mesh.uvs[mesh.face_uvs].reshape(-1, 2)
    tips = uv[np.isclose(uv[:, 1], uv[:, 1].min())]
    rows = np.clip(((1 - tips[:, 1]) * 255).astype(int), 0, 255)
    cols = np.clip((np.mod(tips[:, 0], 1) * 255).astype(int), 0, 255)
    assert (alpha[rows, cols] > 127).mean() > 0.5  # was ~0: faded tips
    centre, eye_z = hair.head_frame(body)
    v = mesh.vertices
    low = v[(np.abs(v[:, 0]) > 0.06) & (v[:, 2] < eye_z - 0.06)]
    assert np.ptp(np.percentile(low[:, 2], [1, 10])) < 0.01  # one level line


def test_every_hair_style_keeps_to_a_vertex_budget(body):
    counts = {s.name: len(s.make(body).mesh.vertices) for s in builtin.SPECS
              if s.category == "hair"}  # fmt: skip
    assert counts["hair-short"] <= 10_000
    assert max(counts.values()) <= 16_000, counts


def test_long_hair_is_locks_not_one_sheet(body):
    """Long hair's cards are turned about their paths, each its own way (their faces not
    all lying on one surface), and wander sideways as locks do."""
    mesh = hair.long_cards(body).mesh
    cards = mesh.vertices.reshape(-1, 2, 10, 3).astype(np.float64)
    middle = cards[:, :, 6].mean(axis=1)
    across = cards[:, 1, 6] - cards[:, 0, 6]
    across /= np.linalg.norm(across, axis=1, keepdims=True)
    outward = body.outward(middle)
    tilt = np.abs(np.einsum("nd,nd->n", across, outward))  # 0: lying flat on the surface
    assert np.percentile(tilt, 75) > 0.2


def test_long_hair_has_no_seam_down_the_back(body):
    """Cards are blended between every pair of neighbouring guide curves, the two either
    side of the back's midline too: no gap between the left and right cards there (it
    was 7.7 mm wide at the tips, a dark line down the back)."""
    centre, _ = hair.head_frame(body)
    lines = hair.long_cards(body).mesh.vertices.reshape(-1, 2, 10, 3).mean(axis=1)
    points = lines.reshape(-1, 3).astype(np.float64)
    low = (points[:, 2] > 1.08) & (points[:, 2] < 1.25) & (points[:, 1] > centre[1])
    x = np.sort(points[low & (np.abs(points[:, 0]) < 0.06), 0])
    assert len(x) > 200 and np.diff(x).max() < 0.004


def test_long_hair_bangs_are_narrow_strands(body):
    """What hangs over the forehead is many strands a few millimetres wide, each tapering
    to a point and thinned out by the texture's tips, not 2.5 cm paper strips."""
    mesh = builtin.BY_NAME["hair-long"].make(body).mesh
    centre, eye_z = hair.head_frame(body)
    v = mesh.vertices.astype(np.float64)
    f = mesh.faces
    c = v[f].mean(axis=1)
    over = ((c[:, 1] < centre[1] - 0.06) & (c[:, 2] > eye_z + 0.01) & (c[:, 2] < eye_z + 0.06)
            & (np.abs(c[:, 0]) < 0.05))  # fmt: skip
    # A face's width: the shorter of its two sides (the strands run down over 1-2 cm).
    width = np.minimum(np.linalg.norm(v[f[:, 0]] - v[f[:, 1]], axis=1),
                       np.linalg.norm(v[f[:, 1]] - v[f[:, 2]], axis=1))  # fmt: skip
    assert over.sum() > 100  # was 30 faces of 17 wide cards
    assert np.percentile(width[over], 90) < 0.006  # was 2 cm
    # Their tips end on the texture's thinned-out strand tips (v near 0).
    uv = mesh.uvs[mesh.face_uvs[over]].reshape(-1, 2)
    assert np.percentile(uv[:, 1], 5) < 0.05


def test_short_hair_turns_round_a_crown_whorl_and_lies_down(body):
    """Seen from above, cards near the crown run round it (a whorl) rather than straight
    out from it (a sea urchin: 13 degrees off straight out on average), and on top of the
    head they leave the scalp at a shallow angle (a median 14 degrees over their first
    half before)."""
    centre, eye_z = hair.head_frame(body)
    cards = hair.grow_cards(body, hair.flow_crown()).mesh.vertices
    lines = cards.reshape(-1, 2, 3, 3).astype(np.float64).mean(axis=1)
    root, middle, tip = lines[:, 0], lines[:, 1], lines[:, 2]
    crown = centre + np.asarray(hair.CROWN_OFFSET)
    seen = (tip - root)[:, :2]
    out = (root - crown)[:, :2]
    near = np.hypot(*out.T) < 0.05
    cos = np.abs(np.einsum("nd,nd->n", seen, out)) / (
        np.linalg.norm(seen, axis=1) * np.maximum(np.linalg.norm(out, axis=1), 1e-9)
    )
    assert near.sum() > 100
    assert np.degrees(np.arccos(np.clip(cos[near], 0, 1))).mean() > 30
    first = middle - root
    first /= np.linalg.norm(first, axis=1, keepdims=True)
    rise = np.degrees(np.arcsin(np.einsum("nd,nd->n", first, body.outward(root))))
    assert np.median(rise[root[:, 2] > eye_z + 0.08]) < 12


def test_ponytail_is_a_full_bundle(body):
    """Below the tie the tail is some 6 cm across (it was under 5: a narrow dark rope)."""
    lines = hair.ponytail(body).mesh.vertices.reshape(-1, 2, 13, 3).mean(axis=1)
    row = lines[:, 5].astype(np.float64)  # 40 % down the tail
    assert np.ptp(np.percentile(row[:, 0], [5, 95])) > 0.054
    assert np.ptp(np.percentile(row[:, 1], [5, 95])) > 0.04


def test_bob_ends_turn_in_and_vary_in_length(body):
    """The bob's ends curl in towards the neck over their last few centimetres and end at
    layered lengths (they hung straight to one level: a box edge)."""
    centre, _ = hair.head_frame(body)
    lines = hair.hang_cards(body, hair.flow_parted()).mesh.vertices.reshape(-1, 2, 11, 3)
    lines = lines.mean(axis=1).astype(np.float64)
    back = lines[:, -1, 1] > centre[1] - 0.02

    def from_axis(p):
        return np.hypot(p[..., 0] - centre[0], p[..., 1] - centre[1])

    assert np.median(from_axis(lines[back, -1]) - from_axis(lines[back, -3])) < -0.006
    assert lines[back, -1, 2].std() > 0.006  # was 2.3 mm
    # Turned, not folded: no card bends back on itself (ends curled into the nape and
    # pushed back out folded by up to 165 degrees).
    step = np.diff(lines, axis=1)
    step /= np.maximum(np.linalg.norm(step, axis=2, keepdims=True), 1e-12)
    bend = np.degrees(np.arccos(np.clip(np.einsum("nkd,nkd->nk", step[:, 1:], step[:, :-1]),
                                        -1, 1)))  # fmt: skip
    assert bend.max() < 60


def test_bob_falls_clear_of_the_ears(body):
    """At ear level a bob's cards fall straight past the ears: once out from the head's
    vertical axis, a card does not come back in by more than 3 mm before its curled end
    (pushed out over the ear and back in under it, 37 % of the cards dipped by up to
    11 mm: loops sticking out at ear level)."""
    centre, eye_z = hair.head_frame(body)
    lines = hair.hang_cards(body, hair.flow_parted()).mesh.vertices.reshape(-1, 2, 11, 3)
    lines = lines.mean(axis=1).astype(np.float64)
    radius = np.hypot(lines[..., 0] - centre[0], lines[..., 1] - centre[1])
    ears = (lines[..., 2] > eye_z - 0.05) & (lines[..., 2] < eye_z + 0.03)
    widest = np.maximum.accumulate(np.where(ears, radius, -np.inf), axis=1)
    dip = np.where(ears, widest - radius, 0.0).max(axis=1)
    assert (dip > 0.003).mean() < 0.06, (dip > 0.003).mean()
    assert dip.max() < 0.0075, dip.max()


def test_bob_has_no_lone_locks_over_the_ears(body):
    """At ear level no card of the bob stands far out from the hair around it (within
    1.2 cm over the head's surface): the cards passing over an ear stood up to 3.6 cm
    out from those just in front of and behind it, a loop seen from the front."""
    from scipy.spatial import cKDTree

    centre, eye_z = hair.head_frame(body)
    lines = hair.hang_cards(body, hair.flow_parted()).mesh.vertices.reshape(-1, 2, 11, 3)
    points = lines.mean(axis=1).astype(np.float64).reshape(-1, 3)
    card = np.repeat(np.arange(len(lines)), 11)
    rel = points[:, :2] - centre[:2]
    radius = np.linalg.norm(rel, axis=1)
    where = np.stack([np.arctan2(rel[:, 0], -rel[:, 1]) * 0.1, points[:, 2]], 1)
    ears = np.flatnonzero((points[:, 2] > eye_z - 0.05) & (points[:, 2] < eye_z + 0.03)
                          & (np.abs(points[:, 0]) > 0.05))  # fmt: skip
    tree = cKDTree(where)
    out = np.zeros(len(lines))
    for i, near in zip(ears, tree.query_ball_point(where[ears], 0.012), strict=True):
        others = [j for j in near if card[j] != card[i]]
        if len(others) > 5:
            out[card[i]] = max(out[card[i]], radius[i] - np.median(radius[others]))
    assert len(ears) > 500
    assert np.percentile(out, 99) < 0.015 and out.max() < 0.02, (np.percentile(out, 99), out.max())


def test_bob_side_locks_hang_in_against_the_neck(body):
    """Seen from behind, a bob's locks at the sides (behind the cheeks, 70-130 degrees
    round the head) hang in against the jaw and neck at the level of their ends: their
    points there lie within 1.5 cm of the skin in the median (they fell straight down
    from the ears' width, 3.5 cm off the neck: a gap under locks standing out)."""
    centre, eye_z = hair.head_frame(body)
    lines = hair.hang_cards(body, hair.flow_parted()).mesh.vertices.reshape(-1, 2, 11, 3)
    points = lines.mean(axis=1).astype(np.float64).reshape(-1, 3)
    turn = hair.around(points, centre)
    low = (turn > 70) & (turn < 130) & (points[:, 2] < eye_z - 0.07)
    gap, _ = body.skin_tree.query(points[low])
    assert low.sum() > 150
    assert np.median(gap) < 0.015, np.median(gap)  # was 0.035


def test_long_hair_lies_on_the_scalp_over_the_head(body):
    """Over the head the long locks lie on the scalp, under the hair grown there (they
    hung from MakeHuman's hair ribbons, which stand off the crown, and lifted at once:
    10 mm off it in the median, up to 28, a dark ridge of wide cards across the top)."""
    from avatar.geometry import collision

    _, eye_z = hair.head_frame(body)
    surface = collision.skin_surface(body.base.faces[body.base.face_groups["body"]])
    v = hair.long_cards(body).mesh.vertices
    top = v[v[:, 2] > eye_z + 0.02]
    height = collision.query(body.vertices[:13380], surface, top).distance
    assert len(top) > 500
    assert np.median(height) < 0.006 and np.percentile(height, 90) < 0.012


def test_long_hair_has_volume_over_the_ears(body):
    """From the side, long hair stands off the head over the temples and ears (60-120
    degrees round it, up to 3 cm above the eyes): a centimetre off the skin in the median
    (4.9 mm: it lay on the skull there like paint), while the crown keeps it on the scalp
    (``test_long_hair_lies_on_the_scalp_over_the_head``)."""
    from avatar.geometry import collision

    centre, eye_z = hair.head_frame(body)
    surface = collision.skin_surface(body.base.faces[body.base.face_groups["body"]])
    v = load_garment("hair-long", texture_size=64).mesh.vertices.astype(np.float64)
    turn = hair.around(v, centre)
    side = (turn > 60) & (turn < 120) & (v[:, 2] > eye_z) & (v[:, 2] < eye_z + 0.03)
    height = collision.query(body.vertices[:13380], surface, v[side]).distance
    assert side.sum() > 100
    assert np.median(height) > 0.01, np.median(height)
    assert np.percentile(height, 90) < 0.025  # volume, not a helmet


def test_long_hair_roots_do_not_stack_up_at_the_crown(body):
    """The long locks' roots spread round the back of the head under the hair grown over
    it, not all at the crown where MakeHuman's hair ribbons begin: 298 of the 360 locks
    started within a centimetre of one another there, a stack of card edges that rendered
    as a dark band along the top of long hair."""
    from scipy.spatial import cKDTree

    _, eye_z = hair.head_frame(body)
    cards = hair.long_cards(body).mesh.vertices.reshape(-1, 2, 10, 3).mean(axis=1)
    roots = cards[:, 0].astype(np.float64)
    crowded = max(len(near) for near in cKDTree(roots).query_ball_point(roots, 0.01))
    assert crowded < 0.3 * len(roots), crowded
    assert roots[:, 2].max() < eye_z + 0.07  # under the grown hair (it covers the crown)


@pytest.mark.parametrize("name", ["hair-bob", "hair-long", "hair-ponytail"])
def test_hair_worn_alone_stays_outside_fuller_faces(name):
    """Each style worn on its own (fitted alone, not under the others) keeps every vertex
    outside a girl's, a young woman's and a heavy woman's skin (a bob cut into the temples
    of three of them by 3-6 mm when its cards there were layered shorter)."""
    from avatar.clothes import library
    from avatar.geometry import collision
    from avatar.human import Human

    for params in ({"gender": 0.0, "age": 0.35}, {"gender": 0.3, "age": 0.12},
                   {"gender": 0.0, "age": 0.6, "weight": 0.9}):  # fmt: skip
        human = Human(params).dressed(name)
        faces = human.model.base.faces[human.model.base.face_groups["body"]]
        part = library.parts(human.outfit)[0]
        _, depth = collision.penetration(human.vertices[:13380], faces, part.mesh.vertices)
        assert depth.max() <= 0.001, f"{name} on {params}: {depth.max() * 1000:.2f} mm inside"


def test_long_hair_is_textured_lighter_than_the_roots_inner_layers_most(body):
    """Long locks start part way down the strand texture (lighter than its dark roots at
    v = 0.5), the innermost layers furthest: textured from the roots and shaded by the
    layers over them, long hair below the ears rendered darker than short hair."""
    from avatar.clothes import hair

    piece = hair.long_cards(body)
    k = 10  # samples a lock
    uv = piece.mesh.uvs.reshape(-1, 2 * k, 2)
    root_v, tip_v = uv[:, 0, 1], uv[:, k - 1, 1]
    assert np.all(root_v <= 0.41) and np.all(tip_v < 0.01)
    assert np.percentile(root_v, 10) < 0.33 < 0.37 < np.percentile(root_v, 90)
    # Inner locks (nearer the guides, which lie on the skin) start lighter.
    verts = piece.mesh.vertices.reshape(-1, 2 * k, 3).astype(np.float64)
    tip = verts[:, k - 1]
    gap, _ = body.skin_tree.query(tip)
    assert np.corrcoef(gap, root_v)[0, 1] > 0.3


def test_buzz_cut_thins_out_at_the_sides_as_at_the_forehead(body):
    """A buzz cut's cards thin out towards the scalp's rim round the ears and at the
    sideburns as at the forehead: within 4 mm of the rim, under a third as many cards as
    in a band as wide 15-19 mm in (0.46 at the sides, thinned only by the height above
    the hairline: a crisp side hairline)."""
    centre, _ = hair.head_frame(body)
    piece = hair.grow_cards(body, hair.flow_crown(sweep=0.0), builtin.BUZZ_CARDS,
                            (0.005, 0.009), builtin.BUZZ_WIDTH, (0.0024, 0.003), 1,
                            root=builtin.BUZZ_ROOT, thin=builtin.BUZZ_HAIRLINE_M)  # fmt: skip
    cards = piece.mesh.vertices.reshape(-1, 4, 3).astype(np.float64)
    roots = (cards[:, 0] + cards[:, 2]) / 2
    from_rim = _from_rim(body, roots)
    turn = hair.around(roots, centre)
    for where in ((turn > 60) & (turn < 120), turn < 40):
        near = (where & (from_rim < 0.004)).sum()
        inside = (where & (from_rim > 0.015) & (from_rim < 0.019)).sum()
        assert inside > 15 and near < inside / 3, (near, inside)


def _from_rim(body, points) -> np.ndarray:
    """(N,) m from points to the nearest point on the edge of the scalp (``hairline_mask``)."""
    from scipy.spatial import cKDTree

    from avatar.geometry.shell import boundary_edges

    edges, _ = boundary_edges(body.skin_faces[hair.hairline_mask(body)])
    t = np.linspace(0, 1, 5, endpoint=False)[None, :, None]
    a, b = body.vertices[edges[:, 0]][:, None], body.vertices[edges[:, 1]][:, None]
    return cKDTree((a * (1 - t) + b * t).reshape(-1, 3)).query(points)[0]


def _worn_round_the_head(params, name):
    """(hair vertices (N, 3), their (angle round the head in degrees, 0 in front; height
    above the eyes (m); m from the head's vertical axis) (N, 3), the skin's of the head
    (S, 3)) for a style worn alone by the body of ``params``."""
    from avatar.clothes import library
    from avatar.human import Human

    human = Human(params).dressed(name)
    base = human.model.base
    v = human.vertices.astype(np.float64)
    eye_z = np.mean([v[np.unique(base.faces[base.face_groups[g]])][:, 2].mean()
                     for g in ("helper-l-eye", "helper-r-eye")])  # fmt: skip
    skin = v[:13380][v[:13380, 2] > eye_z - 0.15]
    axis = np.array([0.0, (skin[:, 1].min() + skin[:, 1].max()) / 2])
    worn = library.parts(human.outfit)[0].mesh.vertices.astype(np.float64)

    def round_(p):
        rel = p[:, :2] - axis
        return np.stack([np.degrees(np.arctan2(rel[:, 0], -rel[:, 1])), p[:, 2] - eye_z,
                         np.linalg.norm(rel, axis=1)], 1)  # fmt: skip

    return worn, round_(worn), round_(skin)


@pytest.mark.parametrize("params", [{"gender": 1.0}, {"gender": 0.0, "age": 0.45},
                                    {"gender": 0.3, "age": 0.12}, {"age": 0.1}])  # fmt: skip
def test_bob_falls_close_over_the_ears(params):
    """Over the ears (60-120 degrees round the head, from 3 cm below the eyes to 3 cm
    above them) a bob's outer surface lies within 1.8 cm of the head's silhouette seen
    from its vertical axis (the ear's rim where it passes over it), on a man, a woman and
    two small children: its sides flared out there, 2.5-3.3 cm out (the 95th percentile)
    on all four. And not a vertex inside the ears or the head."""
    from scipy.spatial import cKDTree

    worn, hair_at, skin_at = _worn_round_the_head(params, "hair-bob")
    side = ((np.abs(hair_at[:, 0]) > 60) & (np.abs(hair_at[:, 0]) < 120)
            & (np.abs(hair_at[:, 1]) < 0.03))  # fmt: skip
    # The head's silhouette there: its outermost skin within 1.2 cm round it and up or down.
    arc = 0.0014  # m of arc a degree round a head some 8 cm across
    tree = cKDTree(np.stack([skin_at[:, 0] * arc, skin_at[:, 1]], 1))
    near = tree.query_ball_point(np.stack([hair_at[side, 0] * arc, hair_at[side, 1]], 1), 0.012)
    silhouette = np.array([skin_at[n, 2].max() for n in near])
    standoff = hair_at[side, 2] - silhouette
    assert side.sum() > 1000
    assert np.percentile(standoff, 95) < 0.018, np.percentile(standoff, 95)  # was 0.025-0.033

    from avatar.geometry import collision
    from avatar.human import Human

    human = Human(params)
    faces = human.model.base.faces[human.model.base.face_groups["body"]]
    _, depth = collision.penetration(human.vertices[:13380], faces, worn)
    assert depth.max() <= 0.001, depth.max()


@pytest.mark.parametrize("params", [{"gender": 0.0, "age": 0.45}, {"gender": 0.0, "age": 0.25},
                                    {"gender": 1.0}])  # fmt: skip
def test_long_hair_falls_at_full_width_past_the_ears(params):
    """Seen from the front or behind, long hair falls past the ears at their width: 6 cm
    below the eyes (the jaw) it is at least 92 % as wide as over the ears (84-89 %: it
    narrowed under the ears, its long locks hanging from guides at the back only) and
    wider than the head with its ears by 1.8 cm (0.4-1 cm), and 10 cm below the eyes (the
    chin) still 90 % as wide."""
    worn, at, skin_at = _worn_round_the_head(params, "hair-long")

    def half_width(points, lo, hi):
        band = points[(points[:, 1] > lo) & (points[:, 1] < hi)]
        return np.percentile(np.abs(band[:, 0]), 98)

    x = np.c_[worn[:, 0], at[:, 1]]  # (across, height above the eyes)
    ears = half_width(x, -0.03, 0.0)
    head = half_width(np.c_[skin_at[:, 2] * np.sin(np.radians(skin_at[:, 0])),
                            skin_at[:, 1]], -0.03, 0.0)  # fmt: skip
    jaw, chin = half_width(x, -0.065, -0.055), half_width(x, -0.105, -0.095)
    assert jaw > 0.92 * ears, jaw / ears
    assert 2 * (jaw - head) > 0.018, 2 * (jaw - head)
    assert chin > 0.9 * ears, chin / ears


def _first_hit(origins, direction, triangles) -> np.ndarray:
    """(N,) distance along ``direction`` from each origin (N, 3) to the first of the
    triangles (T, 3, 3) it meets (inf: none): Moller and Trumbore's test."""
    a = triangles[:, 0]
    e1, e2 = triangles[:, 1] - a, triangles[:, 2] - a
    p = np.cross(direction, e2)
    det = np.einsum("td,td->t", p, e1)
    inv = 1 / np.where(np.abs(det) < 1e-14, 1e-14, det)
    out = np.full(len(origins), np.inf)
    for s in range(0, len(origins), 128):
        t0 = origins[s:s + 128, None] - a[None]
        u = np.einsum("ntd,td->nt", t0, p) * inv
        q = np.cross(t0, e1[None])
        v = (q @ direction) * inv
        t = np.einsum("td,ntd->nt", e2, q) * inv
        hit = (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 0)
        out[s:s + 128] = np.where(hit, t, np.inf).min(axis=1)
    return out


def test_long_hair_covers_the_head_round_the_ears_from_the_side():
    """Seen straight from the side, from in front of the ear back to the back of the
    head and from 6 cm above the eyes down to 10 cm below them, 99 % of the lines of sight
    that meet the head meet the hair first (87 %: the neck and jaw showed under the ears,
    between short hair over the ears and long locks down the back)."""
    from avatar.human import Human

    human = Human({"gender": 0.0, "age": 0.45}).dressed("hair-long")
    worn, at, skin_at = _worn_round_the_head({"gender": 0.0, "age": 0.45}, "hair-long")
    eye_z = float(np.median(worn[:, 2] - at[:, 1]))
    v = human.vertices.astype(np.float64)
    base = human.model.base

    def triangles(points, quads, keep):
        tri = np.concatenate([points[quads[:, [0, 1, 2]]], points[quads[:, [0, 2, 3]]]])
        return tri[keep(tri.mean(axis=1))]

    skin = triangles(v, base.faces[base.face_groups["body"]],
                     lambda c: (c[:, 0] > 0) & (c[:, 2] > eye_z - 0.2))  # fmt: skip
    from avatar.clothes import library

    mesh = library.parts(human.outfit)[0].mesh
    hair_ = triangles(mesh.vertices.astype(np.float64), mesh.faces, lambda c: c[:, 0] > 0)
    head = v[:13380][v[:13380, 2] > eye_z - 0.15]
    middle = (head[:, 1].min() + head[:, 1].max()) / 2
    y, z = np.meshgrid(np.linspace(middle - 0.02, middle + 0.09, 40),
                       np.linspace(eye_z - 0.1, eye_z + 0.06, 50))  # fmt: skip
    origins = np.stack([np.full(y.size, 0.4), y.ravel(), z.ravel()], 1)
    look = np.array([-1.0, 0.0, 0.0])
    to_skin, to_hair = _first_hit(origins, look, skin), _first_hit(origins, look, hair_)
    seen = np.isfinite(to_skin)
    assert seen.sum() > 1000
    assert (to_hair[seen] < to_skin[seen]).mean() > 0.99, (to_hair[seen] < to_skin[seen]).mean()
