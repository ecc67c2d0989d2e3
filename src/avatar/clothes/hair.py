"""Hair grown from the skin, and a cap's crown and brim.

A hairstyle is a dense ``base_cap`` over the scalp inside a hairline (so no skin shows
between strands) plus strand cards: ``grow_cards`` roots cards inside the hairline and lays
them along a flow field (radiating from the crown, combed from a parting, drawn back to a
tie) at a lift above the scalp that grows towards the top of the head, which gives the
volume and silhouette of a haircut; ``long_cards`` hangs cards between the guide curves of
MakeHuman's ``helper-hair`` ribbons; ``ponytail`` gathers cards around a falling spine.

Hair textures share one layout (``textures``): v in [0.5, 1] is dense strands (caps),
v in [0, 0.5] strand cards from root (v = 0.5) to tip (v = 0), alpha thinning at the tips.
"""

from __future__ import annotations

import numpy as np

from avatar.body.model import BODY_VERTICES
from avatar.clothes.authoring import (
    AuthoringBody,
    Piece,
    bound,
    cut,
    join,
    orient_outward,
)
from avatar.geometry.shell import boundary_edges
from avatar.mesh import Mesh


def eye_level(body: AuthoringBody) -> tuple[np.ndarray, float]:
    """(head centre (3,), eye height z) of the authoring body."""
    left, right = body.centre("helper-l-eye"), body.centre("helper-r-eye")
    head = body.vertices[:BODY_VERTICES][body.part[:BODY_VERTICES] == "head"]
    centre = np.array([0.0, head[:, 1].mean(), (left[2] + right[2]) / 2])
    return centre, float(centre[2])


def scalp_mask(body: AuthoringBody, front: float, side: float, back: float) -> np.ndarray:
    """(F,) bool skin faces above a hairline: heights above eye level at the front, the
    sides and the back, blended by the direction around the head; ears are left out."""
    centre, eye_z = eye_level(body)
    faces = body.skin_faces
    c = body.vertices[faces].mean(axis=1)
    rel = c - centre
    facing = -rel[:, 1] / np.maximum(np.hypot(rel[:, 0], rel[:, 1]), 1e-6)  # +1 front
    line = (
        eye_z
        + side
        + (front - side) * np.maximum(facing, 0)
        + (back - side) * np.maximum(-facing, 0)
    )
    ear = (np.abs(rel[:, 0]) > 0.068) & (c[:, 2] < eye_z + 0.035)
    head = body.part[faces].tolist()
    is_head = np.array([row.count("head") >= 2 for row in head])
    return is_head & (c[:, 2] > line) & ~ear & (c[:, 2] > eye_z - 0.09)


def cap_uvs(mesh: Mesh, centre: np.ndarray) -> Mesh:
    """UVs of a scalp cap in the dense half of the hair texture (u around, v up), kept off
    the half's edges; faces across the seam behind the head are unwrapped (u tiles)."""
    rel = mesh.vertices[mesh.faces] - centre  # (F, C, 3)
    angle = np.arctan2(rel[..., 0], -rel[..., 1])
    u = (angle / np.pi + 1) * 2.0  # [0, 4]: the texture repeats four times around
    u = np.where(u.max(axis=1, keepdims=True) - u > 2.0, u + 4.0, u)
    v = 0.55 + 0.4 * np.clip((rel[..., 2] + 0.1) / 0.25, 0, 1)
    uv = np.stack([u, v], -1).reshape(-1, 2).astype(np.float32)
    return per_corner(mesh, uv)


def per_corner(mesh: Mesh, uv: np.ndarray) -> Mesh:
    """The mesh with one UV per face corner: uv (F * C, 2) in face-corner order."""
    corners = np.arange(mesh.faces.size, dtype=np.int32).reshape(mesh.faces.shape)
    return Mesh(mesh.vertices, mesh.faces, uv, corners)


def scalp(body: AuthoringBody, ease: float, front=0.05, side=0.03, back=-0.045) -> Piece:
    """A hair or cap shell over the scalp, bound to the skin."""
    faces = body.skin_faces
    mesh = cut(body, faces, scalp_mask(body, front, side, back), ease)
    centre, _ = eye_level(body)
    return bound(body, cap_uvs(mesh, centre), faces)


# A short haircut's hairline, by the direction around the head (degrees from the front):
# height above eye level. Rounded temple corners, sideburns in front of the ears, a line
# curving over each ear and down to the nape. The line falls steadily from the forehead to
# the temple: a corner raised at 45 degrees (a receding temple) showed as a notch where
# hair is drawn back (a ponytail, a bun).
HAIRLINE_DEG = (0, 30, 45, 60, 72, 76, 84, 88, 112, 120, 140, 180)
HAIRLINE_M = (0.07, 0.068, 0.066, 0.05, 0.03, -0.012, -0.012, 0.035, 0.035, -0.02, -0.055, -0.065)


def head_frame(body: AuthoringBody) -> tuple[np.ndarray, float]:
    """(centre of the skull (3,), eye height z): the middle of the head's front-to-back and
    side-to-side extent at eye height (the face's dense vertices do not pull it forward)."""
    _, eye_z = eye_level(body)
    head = body.vertices[:BODY_VERTICES][body.part[:BODY_VERTICES] == "head"]
    y = (head[:, 1].min() + head[:, 1].max()) / 2
    return np.array([0.0, y, eye_z]), eye_z


def around(points: np.ndarray, centre: np.ndarray) -> np.ndarray:
    """(N,) degrees around the vertical axis through ``centre``: 0 front, 180 back."""
    rel = points - centre
    return np.degrees(np.abs(np.arctan2(rel[:, 0], -rel[:, 1])))


def hairline_mask(body: AuthoringBody, lift: float = 0.0) -> np.ndarray:
    """(F,) bool skin faces inside the hairline (``HAIRLINE_*`` raised by ``lift`` m)."""
    centre, eye_z = head_frame(body)
    c = body.vertices[body.skin_faces].mean(axis=1)
    line = eye_z + lift + np.interp(around(c, centre), HAIRLINE_DEG, HAIRLINE_M)
    ear = (np.abs(c[:, 0]) > 0.066) & (c[:, 2] < eye_z + 0.033)
    radial = (c - centre)[:, :2]
    near = np.linalg.norm(radial, axis=1) < 0.11
    # The mouth and throat are skin too: keep only faces that look away from the head's axis.
    normal = body.skin_normals[body.skin_faces].mean(axis=1)[:, :2]
    outside = (np.einsum("fd,fd->f", normal, radial) > 0) | (c[:, 2] > eye_z + 0.06)
    return _no_lone_faces(body.skin_faces, near & outside & (c[:, 2] > line) & ~ear)


def _no_lone_faces(faces: np.ndarray, keep: np.ndarray) -> np.ndarray:
    """(F,) ``keep`` without the kept faces (F, 4) that share no edge with another kept
    one: the hairline's corner at the temple left one face of scalp below it, joined by
    a corner, which hung there as a speck of hair (a buzz cut's most)."""
    chosen = np.flatnonzero(keep)
    quads = faces[chosen]
    edges = np.sort(np.stack([quads, np.roll(quads, -1, axis=1)], -1).reshape(-1, 2), axis=1)
    _, index, counts = np.unique(edges, axis=0, return_inverse=True, return_counts=True)
    shared = (counts[index.reshape(-1)] > 1).reshape(len(chosen), 4).any(axis=1)
    out = keep.copy()
    out[chosen[~shared]] = False
    return out


CAP_RIM_M = 0.0003  # the cap's rim lies this far off the skin ...
CAP_TUCK_M = 0.008  # ... rising to its ease over this much height above the hairline


def base_cap(body: AuthoringBody, ease: float = 0.002, soft: float = 0.0) -> Piece:
    """The scalp inside the hairline as a dense hair surface (what shows between cards),
    ``ease`` m off the skin but tucked down to it at the hairline (``CAP_RIM_M``): a rim
    standing 1.5-2 mm off the forehead cast a dark line along a buzz cut's hairline, the
    edge of a cap.

    soft: m above the hairline over which the cap's v runs down to 0.5 at its rim (0:
    ``cap_uvs`` everywhere), where a buzz cut's texture (``looks.textures.buzz_material``)
    thins its hairs out: a soft hairline, not the edge of a cap."""
    faces = body.skin_faces
    centre, eye_z = head_frame(body)

    def above(points: np.ndarray) -> np.ndarray:
        return points[:, 2] - eye_z - np.interp(around(points, centre), HAIRLINE_DEG, HAIRLINE_M)

    def lift(points: np.ndarray, arm, leg) -> np.ndarray:
        rise = np.clip(above(points) / CAP_TUCK_M, 0, 1)
        return CAP_RIM_M + (ease - CAP_RIM_M) * rise * rise * (3 - 2 * rise)

    mesh = cut(body, faces, hairline_mask(body), lift, relax=8)
    capped = cap_uvs(mesh, centre)
    if soft > 0:  # by the distance to the cap's rim: the hairline and round the ears
        from scipy.spatial import cKDTree

        rim = mesh.vertices[np.unique(boundary_edges(mesh.faces)[0])].astype(np.float64)
        corners = mesh.vertices[mesh.faces].reshape(-1, 3).astype(np.float64)
        rise = np.clip(cKDTree(rim).query(corners)[0] / soft, 0, 1)
        assert capped.uvs is not None  # ``cap_uvs`` gives every corner one
        uv = capped.uvs.copy()
        uv[:, 1] = 0.5 + (uv[:, 1] - 0.5) * np.sqrt(rise)
        capped = per_corner(mesh, uv)
    return bound(body, capped, faces)


CROWN_OFFSET = (0.0, 0.035, 0.1)  # the crown (whorl) from the skull centre at eye height (m)


def flow_crown(crown_offset=CROWN_OFFSET, sweep: float = 0.6, whorl: float = 1.2):
    """A hair flow field combed out from the crown, the front swept towards +x, turning
    round the crown in a whorl (a spiral, as hair grows there): near the crown the
    hair runs round it as much as away from it (``whorl`` times as much), fading to
    straight out over 5-8 cm. (Straight out from one point everywhere, the cards seen
    from above all pointed away from the crown like a sea urchin's spines.)"""

    def flow(points: np.ndarray, centre: np.ndarray, eye_z: float) -> np.ndarray:
        crown = centre + np.asarray(crown_offset)
        d = points - crown
        front = np.clip((centre[1] - points[:, 1]) / 0.08, 0, 1) * np.clip(
            (points[:, 2] - eye_z - 0.04) / 0.04, 0, 1
        )
        round_ = whorl * np.exp(-((np.hypot(d[:, 0], d[:, 1]) / 0.05) ** 2))
        d[:, :2] += round_[:, None] * np.stack([-d[:, 1], d[:, 0]], 1)
        d[:, 0] += sweep * front * np.linalg.norm(d, axis=1)
        return d

    return flow


def flow_parted(front: float = -0.11, crown: float = 0.03):
    """A hair flow field combed away from a centre parting (y from ``front`` to ``crown``
    relative to the skull centre, along the top of the head)."""

    def flow(points: np.ndarray, centre: np.ndarray, eye_z: float) -> np.ndarray:
        y = np.clip(points[:, 1] - centre[1], front, crown) + centre[1]
        part = np.stack([np.zeros(len(points)), y, np.full(len(points), eye_z + 0.2)], 1)
        return points - part

    return flow


def flow_tied(tie_offset=(0.0, 0.07, 0.0)):
    """A hair flow field drawn back to a tie point behind the head."""

    def flow(points: np.ndarray, centre: np.ndarray, eye_z: float) -> np.ndarray:
        return centre + np.asarray(tie_offset) - points

    return flow


def grow_cards(
    body: AuthoringBody,
    flow,
    count: int = 1500,
    length=(0.03, 0.05),
    width: float = 0.008,
    lift=(0.004, 0.014),
    segments: int = 2,
    seed: int = 0,
    root: float = 0.0,
    side_lift: float = 0.0,
    thin: float = 0.0,
) -> Piece:
    """Hair cards rooted inside the hairline, lying along a flow field above the scalp.

    Each card starts a few millimetres above the scalp and rises to its lift as it runs
    ``length`` metres along the flow, so higher cards cover lower ones the way layered hair
    does; ``lift`` (low, high) grows from the hairline (low) to the top of the head (high).
    UVs: a random column strip of the strand half of the hair texture, roots at v = 0.5.

    The defaults are a short haircut (``hair-short``): many narrow cards (8 mm, a few
    dozen hairs each) lying within 1.5 cm of the scalp. Fewer, wider, higher cards (the
    old 380 x 2 cm up to 2.2 cm off the scalp) read as spiky clumps: each card's straight
    edge and tip show against the light and in the silhouette. Two segments per card
    (~9,300 vertices with the base cap, within a game character's 10,000): a 4 cm card
    bends over the skull by half a millimetre between its ends, which four segments
    (15,300 vertices) did not make visible, but the per-frame cost of posing them showed.

    ``root``: m above the skin the cards' roots stand (0: on it, under the base cap); a
    card then never rises below it. A buzz cut's cards lie over the cap all their length:
    rooted on the skin they came up through the cap half-way along, and each card's cut
    through it drew the outline of a scale.

    ``side_lift``: m the cards rise further over the temples and ears (``side_volume``),
    reached half-way along them: long hair's volume at the sides.
    ``thin``: m above the hairline over which the cards thin out (a root kept with the
    probability of its height over it there): a buzz cut's soft hairline.
    """
    rng = np.random.default_rng([seed, count])
    centre, eye_z = head_frame(body)
    roots = _scatter(body, hairline_mask(body, 0.004), count, rng)
    depth = roots[:, 2] - eye_z - np.interp(around(roots, centre), HAIRLINE_DEG, HAIRLINE_M)
    if thin > 0:
        # By the height above the hairline and the distance to the scalp's rim (round
        # the ears, the sideburns): by the height alone, the cards ran at full density
        # up to a crisp line at the sides and temples.
        inside = np.minimum(depth, rim_distance(body, roots))
        kept = rng.uniform(size=count) < np.clip(inside / thin, 0.1, 1)
        roots, depth, count = roots[kept], depth[kept], int(kept.sum())
    top = lift[0] + (lift[1] - lift[0]) * np.clip(depth / 0.06, 0, 1)
    # Hair lies flat at the crown, where it parts round the whorl.
    crown = centre + np.asarray(CROWN_OFFSET)
    top *= 0.5 + 0.5 * np.clip(np.linalg.norm(roots - crown, axis=1) / 0.07, 0, 1)
    top *= rng.uniform(0.55, 1.0, count)
    top = np.maximum(top, root)
    start = max(root, 0.002)
    # Short at the hairline (a fringe would hang over the face), full length further in.
    size = rng.uniform(length[0], length[1], count) * (0.45 + 0.55 * np.clip(depth / 0.04, 0, 1))
    if root > 0:
        roots = _above_skin(body, roots, np.full(len(roots), root))
    rows = [roots]
    point = roots
    for k in range(1, segments + 1):
        step = _tangent(body, point, flow(point, centre, eye_z))
        # Rising evenly along the card (lying down from the root), not steeply at first:
        # a card whose first half rose at 15-25 degrees stood up from the scalp.
        point = point + step * (size / segments)[:, None]
        volume = side_lift * side_volume(point, centre, eye_z) * min(1.0, 2 * k / segments)
        point = _above_skin(body, point, start + (top - start) * (k / segments) + volume)
        rows.append(point)
    path = np.stack(rows, 1)  # (N, K+1, 3)
    normal = body.outward(path.reshape(-1, 3)).reshape(path.shape)
    fringe = _over_the_face(path, centre, eye_z) & (width > 2.5 * FRINGE_STRAND_M)
    if not fringe.any():
        return _card_piece(body, path, normal, width, rng)
    strands, facing = _strands(path[fringe], normal[fringe], width, rng)
    # Spread sideways across the card's plane, strands at its edges would cut into the
    # temples where the head curves in under them.
    strands = _off_skin(body, strands.reshape(-1, 3), 0.003).reshape(strands.shape)
    count = len(strands)
    return join([
        _card_piece(body, path[~fringe], normal[~fringe], width, rng),
        _card_piece(body, strands, facing, np.full(count, FRINGE_STRAND_M), rng,
                    taper=rng.uniform(0.2, 0.45, count)),
    ])  # fmt: skip


def rim_distance(body: AuthoringBody, points: np.ndarray) -> np.ndarray:
    """(N,) m from ``points`` (N, 3) to the nearest point of the scalp's rim (the edge of
    ``hairline_mask``: the hairline, round the ears and down the nape)."""
    from scipy.spatial import cKDTree

    edges, _ = boundary_edges(body.skin_faces[hairline_mask(body)])
    a, b = body.vertices[edges[:, 0]], body.vertices[edges[:, 1]]
    t = np.linspace(0, 1, 5, endpoint=False)[None, :, None]  # points along each edge
    rim = (a[:, None] * (1 - t) + b[:, None] * t).reshape(-1, 3).astype(np.float64)
    return cKDTree(rim).query(np.asarray(points, np.float64))[0]


# Hair falling over the forehead (a fringe, bangs) as strands this wide (m): a card 2.5 cm
# wide hanging over the face reads as a strip of paper, its straight edges and cut tip
# against the skin; strands a few millimetres wide, each ending at its own length and
# tapering to a point, read as hair.
FRINGE_STRAND_M = 0.0045


def _over_the_face(path: np.ndarray, centre: np.ndarray, eye_z: float) -> np.ndarray:
    """(N,) bool cards (paths (N, K, 3)) whose tips hang over the forehead: in front of
    the face, between the temples and below the front hairline's height (``HAIRLINE_M``
    at 0 degrees). (Those at the temples, split and fanned out, reached into a fuller
    cheek than the authoring body's.)"""
    tip = path[:, -1]
    return ((tip[:, 1] < centre[1] - 0.06) & (np.abs(tip[:, 0]) < 0.06)
            & (tip[:, 2] < eye_z + HAIRLINE_M[0] + 0.01))  # fmt: skip


def _strands(path: np.ndarray, normal: np.ndarray, width: float, rng
             ) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """Wide cards (paths (N, K, 3) facing ``normal``) split lengthwise into strands
    ``FRINGE_STRAND_M`` wide side by side across each card's width, each parting a little
    from its neighbours towards its tip, ending at its own length (55-100 % of the card)
    and turned a little about its path. Returns (paths (M, K, 3), normals (M, K, 3))."""
    n, k = path.shape[:2]
    per = max(int(round(width / FRINGE_STRAND_M * 1.3)), 2)  # overlapping: no gaps between
    side = np.cross(normal, np.gradient(path, axis=1))
    side /= np.maximum(np.linalg.norm(side, axis=-1, keepdims=True), 1e-9)
    t = np.linspace(0, 1, k)[None, :, None]
    offset = (np.linspace(-0.5, 0.5, per)[None, :] + rng.normal(0, 0.08, (n, per))) * width
    spread = 1 + rng.uniform(0.0, 0.5, (n, per)) * 1.0  # tips part from their neighbours
    shift = offset[..., None, None] * (1 + (spread[..., None, None] - 1) * t[:, None] ** 2)
    strands = path[:, None] + shift * side[:, None]  # (N, per, K, 3)
    strands = strands.reshape(-1, k, 3)
    facing = np.repeat(normal, per, axis=0)
    m = len(strands)
    strands = _shorten(strands, rng.uniform(0.55, 1.0, m))
    turn = rng.uniform(-0.5, 0.5, m)[:, None, None]
    side = np.repeat(side, per, axis=0)
    return strands, np.cos(turn) * facing + np.sin(turn) * side


SIDE_VOLUME_DEG = (45, 65, 115, 135)  # round the head: from the temples to behind the ears
# m above the eyes: no lift below the first, full from the second to the third (above the
# ears and over the temples), none above the fourth (the crown). Lifted down over the ear
# itself too, a card's vertex bound there came 6.3 mm inside a child's ear.
SIDE_VOLUME_Z = (-0.03, 0.0, 0.035, 0.075)


def side_volume(points: np.ndarray, centre: np.ndarray, eye_z: float) -> np.ndarray:
    """(N,) 0..1 where hair stands out from the head at the sides (points (N, 3)): above
    the ears and over the temples (``SIDE_VOLUME_DEG`` round the head, ``SIDE_VOLUME_Z``
    above the eyes, easing in and out: not down on the shoulders, nor on the crown)."""
    turn = around(points, centre)
    a, b, c, d = SIDE_VOLUME_DEG
    round_ = np.clip((turn - a) / (b - a), 0, 1) * np.clip((d - turn) / (d - c), 0, 1)
    z = points[:, 2] - eye_z
    low, full, fading, high = SIDE_VOLUME_Z
    up = np.clip((z - low) / (full - low), 0, 1) * np.clip((high - z) / (high - fading), 0, 1)
    w = round_ * up
    return w * w * (3 - 2 * w)


def _shorten(path: np.ndarray, fraction: np.ndarray) -> np.ndarray:
    """(N, K, 3) paths resampled evenly (by sample index) over their first ``fraction``
    (N,) of their samples."""
    count, k = path.shape[:2]
    at = np.linspace(0, 1, k)[None, :] * fraction[:, None] * (k - 1)
    lo = np.minimum(np.floor(at).astype(int), k - 2)
    frac = (at - lo)[..., None]
    n = np.arange(count)[:, None]
    return (1 - frac) * path[n, lo] + frac * path[n, lo + 1]


def cards_on(
    body: AuthoringBody,
    keep: np.ndarray,
    flow,
    count: int,
    length=(0.01, 0.02),
    width: float = 0.006,
    lift=(0.0015, 0.004),
    segments: int = 2,
    seed: int = 0,
    density=None,
    reach=None,
    strip: float = 0.12,
    clump: int = 0,
    stand: float = 0.0,
    taper: float = 0.7,
) -> Piece:
    """Short strand cards rooted on the chosen skin faces (``keep``, (F,) bool over
    ``body.skin_faces``), lying along ``flow`` (points (N, 3) -> directions (N, 3)) and
    rising from the skin to a random lift in ``lift`` (m) over their length (beards,
    moustaches). UVs as ``grow_cards``'. The cards are bound to the chosen faces only, so
    a moustache hanging over the lips rides the upper lip, not the jaw below it.

    density: points (N, 3) -> (N,) 0..1, how thickly hair grows there (None: 1). A root
    survives with that probability, and where it is low (the region's soft edges) the
    cards are also shorter and lie flatter, so the hair thins out instead of ending at a
    line. (At most ``count`` cards: roots are drawn three times over, then thinned.)

    reach: roots (N, 3) -> (N,) a factor on the cards' length (None: 1), e.g. locks of
    longer and shorter hair along a moustache's lower edge. strip: the share of the
    texture's width across a card (less: fewer, coarser hairs, as ``_card_piece``).

    clump: cards per clump (0: none). Neighbouring roots are gathered into clumps of
    about that many cards, each of its own length (70-130 %), whose tips are drawn
    together (``CLUMP_PULL``): locks with skin-dark gaps between their tips, as a beard's
    hair grows, instead of one even pile of cards. stand: how much a card's lift follows
    its length (``reach``): 0 none, 1 a card twice as long stands twice as far out.
    taper: a card's width at its tip over its width at the root."""
    rng = np.random.default_rng([seed, count])
    roots = _scatter(body, keep, 3 * count, rng)
    grow = np.ones(len(roots)) if density is None else np.asarray(density(roots), float)
    pick = np.flatnonzero(rng.uniform(size=len(roots)) < grow)[:count]
    roots, grow = roots[pick], grow[pick]
    count = len(roots)
    size = rng.uniform(length[0], length[1], count) * (0.35 + 0.65 * grow)
    factor = np.ones(count) if reach is None else np.asarray(reach(roots), float)
    size = size * factor
    top = rng.uniform(lift[0], lift[1], count) * (0.4 + 0.6 * grow)
    top = top * (1 + stand * (factor - 1))
    group = _clumps(roots, clump, rng) if clump > 0 else None
    if group is not None:
        size = size * rng.uniform(0.7, 1.3, group.max() + 1)[group]
    rows, point = [roots], roots
    for k in range(1, segments + 1):
        step = _tangent(body, point, flow(point))
        point = _above_skin(body, point + step * (size / segments)[:, None],
                            0.0008 + (top - 0.0008) * (k / segments))  # fmt: skip
        rows.append(point)
    path = np.stack(rows, 1)
    if group is not None:
        path = _gather(body, path, group, 0.0008 + (top[:, None] - 0.0008)
                       * np.linspace(0, 1, segments + 1)[None, :])  # fmt: skip
    normal = body.outward(path.reshape(-1, 3)).reshape(path.shape)
    # A clump's cards show neighbouring strips of the texture (hairs of one shade, grey or
    # not together), so each clump reads as a lock against the next.
    u0 = None if group is None else (rng.uniform(0, 1, group.max() + 1)[group]
                                     + rng.uniform(0, 2 * strip, count))  # fmt: skip
    return _card_piece(body, path, normal, width, rng, body.skin_faces[keep], taper=taper,
                       strip=strip, u0=u0)  # fmt: skip


CLUMP_PULL = 0.8  # how far a clumped card's tip moves towards its clump's mean tip


def _clumps(roots: np.ndarray, per: int, rng) -> np.ndarray:
    """(N,) int clump of each root (N, 3): ``len(roots) / per`` random roots are the
    clumps' seeds, and every root joins its nearest seed's clump."""
    from scipy.spatial import cKDTree

    seeds = rng.choice(len(roots), max(len(roots) // per, 1), replace=False)
    return cKDTree(roots[seeds]).query(roots)[1]


def _gather(body: AuthoringBody, path: np.ndarray, group: np.ndarray,
            height: np.ndarray) -> np.ndarray:  # fmt: skip
    """(N, K, 3) card paths whose points past the root are drawn towards their clump's
    mean path (``group`` (N,)), more towards the tips (``CLUMP_PULL`` at the tip), then
    set back ``height`` (N, K) m above the skin."""
    n, k = path.shape[:2]
    total = np.zeros((group.max() + 1, k, 3))
    np.add.at(total, group, path)
    mean = total / np.bincount(group, minlength=len(total))[:, None, None]
    pull = CLUMP_PULL * np.linspace(0, 1, k)[None, :, None]
    out = path + pull * (mean[group] - path)  # roots stay (pull 0), tips converge
    flat = _above_skin(body, out[:, 1:].reshape(-1, 3), height[:, 1:].reshape(-1))
    out[:, 1:] = flat.reshape(n, k - 1, 3)
    return out


def _scatter(body: AuthoringBody, keep: np.ndarray, count: int, rng) -> np.ndarray:
    """(count, 3) random points on the chosen skin faces, uniform by area."""
    quads = body.vertices[body.skin_faces[keep]]
    tris = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
    area = np.linalg.norm(np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0]), axis=1)
    pick = rng.choice(len(tris), count, p=area / area.sum())
    a, b = rng.uniform(size=(2, count))
    flip = a + b > 1
    a[flip], b[flip] = 1 - a[flip], 1 - b[flip]
    t = tris[pick]
    return t[:, 0] + a[:, None] * (t[:, 1] - t[:, 0]) + b[:, None] * (t[:, 2] - t[:, 0])


def _tangent(body: AuthoringBody, points: np.ndarray, direction: np.ndarray) -> np.ndarray:
    """(N, 3) unit directions projected into the skin's tangent plane near each point."""
    n = body.outward(points)
    d = direction - np.einsum("nd,nd->n", direction, n)[:, None] * n
    return d / np.maximum(np.linalg.norm(d, axis=1, keepdims=True), 1e-9)


def _above_skin(body: AuthoringBody, points: np.ndarray, height: np.ndarray) -> np.ndarray:
    """(N, 3) points moved to ``height`` m above the skin along its normal."""
    _, i = body.skin_tree.query(points)
    skin, n = body.vertices[i], body.skin_normals[i].astype(np.float64)
    on = points - np.einsum("nd,nd->n", points - skin, n)[:, None] * n
    return on + np.asarray(height)[:, None] * n


def guides(body: AuthoringBody, samples: int = 16, behind: bool = True,
           bunch: float = 1.0) -> np.ndarray:  # fmt: skip
    """(G, samples, 3) guide curves of long hair from MakeHuman's ``helper-hair`` ribbons
    (which its targets reshape with every body): each ribbon's centre line from the crown
    to the tip, resampled evenly by length. The short fringe ribbons over the face are left
    out, and with ``behind`` those falling in front of the shoulders; the curves are ordered
    by their direction around the head, from the right side round the back to the left
    (neighbours in the order are neighbours on the head)."""
    from avatar.clothes.face import strip_uvs

    faces = body.group_faces("helper-hair")
    centre, eye_z = head_frame(body)
    top = centre + [0, 0, 0.15]
    curves = []
    for ribbon in _components(faces):
        used, local = np.unique(ribbon, return_inverse=True)
        points = body.vertices[used]
        if points[:, 2].min() > eye_z - 0.15:  # a lock over the face, not long hair
            continue
        if behind and points[points[:, 2].argmin(), 1] < centre[1]:  # falls over the chest
            continue
        mesh = Mesh(points.astype(np.float32), local.reshape(ribbon.shape).astype(np.int32))
        row = np.round(strip_uvs(mesh, top)[:, 0] * (len(points) // 2 - 1)).astype(int)
        line = np.stack([points[row == r].mean(0) for r in range(row.max() + 1)])
        curves.append(_resample(line, samples, bunch))
    out = np.stack(curves)
    # Ordered from one side round the back to the other: measured from the front, the
    # angle jumps from +180 to -180 degrees at the back's midline, which put the two
    # curves either side of it at the two ends of the order, never blended (a seam).
    return out[np.argsort(np.arctan2(out[:, -1, 0], out[:, -1, 1] - centre[1]))]


# Long locks start this far above eye level (m), under the hair grown over the head: from
# the crown, where MakeHuman's hair ribbons all begin, 360 locks' roots stacked up into a
# ridge of card edges a few millimetres high, a dark band along the top of the head.
LONG_ROOTS_M = 0.05


def _start_below(path: np.ndarray, height: float) -> np.ndarray:
    """(N, K, 3) paths resampled evenly from where each first comes down to ``height``
    (its root when it starts lower) to its end."""
    flipped = path[:, ::-1] * np.array([1.0, 1.0, -1.0])
    return (_cut_at(flipped, np.full(len(path), -height)) * np.array([1.0, 1.0, -1.0]))[:, ::-1]


def _onto_the_scalp(body: AuthoringBody, curves: np.ndarray, lift: float = 0.004) -> np.ndarray:
    """(G, K, 3) guide curves laid down onto the scalp over the head (at most ``lift`` m
    off it above eye level, freed over the 6 cm below): MakeHuman's hair ribbons stand
    5-18 mm off the crown, and the locks hung from them stood up above the hair grown
    there, a dark ridge of wide cards across the top of the head."""
    _, eye_z = head_frame(body)
    points = curves.reshape(-1, 3).astype(np.float64)
    _, i = body.skin_tree.query(points)
    n = body.skin_normals[i].astype(np.float64)
    height = np.einsum("nd,nd->n", points - body.vertices[i], n)
    free = np.clip((eye_z - points[:, 2]) / 0.06, 0, 1)
    cap = lift + free * np.maximum(height - lift, 0)
    laid = _above_skin(body, points, np.minimum(height, cap))
    return laid.reshape(curves.shape)


def _components(faces: np.ndarray) -> list[np.ndarray]:
    """The faces of each edge-connected piece of a face set."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    used, local = np.unique(faces, return_inverse=True)
    local = local.reshape(faces.shape)
    a, b = local.reshape(-1), np.roll(local, -1, axis=1).reshape(-1)
    graph = coo_matrix((np.ones(len(a)), (a, b)), shape=(len(used), len(used)))
    _, label = connected_components(graph, directed=False)
    piece = label[local[:, 0]]
    return [faces[piece == k] for k in np.unique(piece)]


def _resample(line: np.ndarray, samples: int, bunch: float = 1.0) -> np.ndarray:
    """(samples, 3) points spaced by arc length along a polyline (P, 3): evenly, or with
    ``bunch`` > 1 closer together towards its start (the fraction of the length at
    sample i is (i / (samples - 1)) ** bunch)."""
    along = np.concatenate([[0], np.cumsum(np.linalg.norm(np.diff(line, axis=0), axis=1))])
    t = np.linspace(0, 1, samples) ** bunch * along[-1]
    return np.stack([np.interp(t, along, line[:, k]) for k in range(3)], 1)


def long_cards(
    body: AuthoringBody,
    count: int = 360,
    width: float = 0.024,
    layers=(0.004, 0.024),
    seed: int = 1,
    samples: int = 10,
    side_lift: float = 0.0,
) -> Piece:
    """Long hair: strand cards interpolated between neighbouring guide curves (``guides``),
    stacked at random heights between ``layers`` (m) off the guides, of random length.

    Locks, not a sheet: each card wanders sideways down its length and is turned about
    its own path by a random angle (up to ~25 degrees), so the cards catch the light
    differently and their edges show between one another (300 cards 3 cm wide, all lying
    flat on one surface, read as one flat sheet of painted strands).
    Neighbours are only blended around the back and sides: never across the face.
    UVs: a random column strip of the strand half of the hair texture, roots at v = 0.5.
    ``side_lift``: m the locks stand at least off the head over the temples and ears
    (``side_volume``; the crown keeps them on the scalp).
    """
    rng = np.random.default_rng([seed, count])
    # Samples closer together over the head, where the guides bend over the skull.
    g = _onto_the_scalp(body, guides(body, samples, bunch=1.7))
    pairs = [(i, i + 1) for i in range(len(g) - 1)
             if np.linalg.norm(g[i, -1] - g[i + 1, -1]) < 0.15]  # fmt: skip
    pick = rng.integers(0, len(pairs), count)
    w = rng.uniform(0, 1, count)[:, None, None]
    first, second = np.array(pairs).T
    path = (1 - w) * g[first[pick]] + w * g[second[pick]]  # (N, K, 3)
    k = path.shape[1]
    # Shorter cards end higher up: sample each path to a random fraction of its length.
    path = _shorten(path, rng.uniform(0.75, 1.0, count))
    _, eye_z = head_frame(body)
    path = _start_below(path, eye_z + LONG_ROOTS_M)
    t = np.linspace(0, 1, k)[None, :, None]
    # Lying on the scalp over the head (under the cards grown there), the layers lifting
    # from eye level down over 6 cm: rising from the crown as the square root of their
    # length, the locks' roots stood a centimetre or two off the top of the head, a dark
    # ridge of wide cards across it.
    below = np.clip((eye_z - path[..., 2:]) / 0.06, 0, 1)
    height = rng.uniform(layers[0], layers[1], count)[:, None, None] * below * np.sqrt(t)
    # Over the head each lock at its own height, up to 2 mm apart: laid at one height on
    # the scalp, the locks met there in one surface and shaded one another black.
    height = height + rng.uniform(0, 0.002, count)[:, None, None] * (1 - below)
    # Volume over the temples and ears: lying there on the skull, long hair looked
    # painted on from the side.
    centre, _ = head_frame(body)
    volume = side_lift * side_volume(path.reshape(-1, 3), centre, eye_z).reshape(path.shape[:2])
    vary = np.random.default_rng([seed, count, 11]).uniform(0.7, 1.0, count)  # (own stream)
    height = np.maximum(height, volume[..., None] * vary[:, None, None])
    flat = path.reshape(-1, 3)
    normal = body.outward(flat).reshape(path.shape)
    path = path + height * normal
    along = np.gradient(path, axis=1)
    along /= np.maximum(np.linalg.norm(along, axis=-1, keepdims=True), 1e-9)
    sideways = np.cross(along, normal)
    path = path + rng.normal(0, 0.006, (count, 1, 1)) * t**1.5 * sideways  # wandering locks
    # Turned about their paths where they hang, flat on the scalp over the head (a lock
    # 2.4 cm wide turned 26 degrees there cut into the scalp by an edge and stood up by
    # the other).
    turn = rng.uniform(-0.45, 0.45, count)[:, None, None] * below
    facing = np.cos(turn) * normal + np.sin(turn) * sideways
    # Textured from part way down the strands (lighter than their roots), the inner
    # layers most: starting at the strands' dark roots, and under the layers over them,
    # the hair hanging below the ears rendered darker than short hair of its colour.
    inner = 1 - np.clip((height[:, -1, 0] - layers[0]) / (layers[1] - layers[0]), 0, 1)
    root_v = LONG_ROOT_V - LONG_INNER_V * inner
    return _card_piece(body, path, facing, width, rng, root_v=root_v)


SIDE_LOCKS_DEG = (55, 150)  # long hair's side locks root this far round the head ...
SIDE_LOCKS_Z = (0.0, 0.05)  # ... at these heights above the eyes (under the grown hair)
SIDE_LOCKS_END = (-0.3, -0.19)  # ... and end here (m from the eyes): down the upper back
# Below the jaw (m from the eyes) they turn back to the hair down the back, fully this
# far further down (over the top of the shoulder).
SIDE_LOCKS_TURN_Z = (-0.15, -0.11)
SIDE_LOCKS_GATHER = 0.85  # ... drawn in across the back to this share of their width


def side_locks(body: AuthoringBody, flow, count: int = 160, width: float = 0.024,
               layers=(0.004, 0.016), segments: int = 12, seed: int = 5) -> Piece:  # fmt: skip
    """Long hair over the sides of the head: locks rooted above and around the ears
    (``SIDE_LOCKS_*``), combed along ``flow`` and falling over and behind the ears, then
    straight down at the ears' width (``_fall_clear``), and under the jaw back over the
    shoulders into the hair down the back (``_into_the_back_hair``), each at its own
    height ``layers`` (m) off the skin. MakeHuman's hair ribbons all fall down the back
    (or over the chest): grown from them alone, long hair narrowed under the ears, short
    hair over the ears above long locks down the back (a mullet), and the scalp showed
    between the two from the side. Textured as ``long_cards``' (lighter than the roots)."""
    rng = np.random.default_rng([seed, count])
    centre, eye_z = head_frame(body)
    turn = around(body.vertices[body.skin_faces].mean(axis=1), centre)
    height = body.vertices[body.skin_faces].mean(axis=1)[:, 2] - eye_z
    keep = (hairline_mask(body, 0.004) & (turn > SIDE_LOCKS_DEG[0]) & (turn < SIDE_LOCKS_DEG[1])
            & (height > SIDE_LOCKS_Z[0]) & (height < SIDE_LOCKS_Z[1]))  # fmt: skip
    roots = _scatter(body, keep, count, rng)
    lift = rng.uniform(layers[0], layers[1], count)
    stop = eye_z + rng.uniform(SIDE_LOCKS_END[0], SIDE_LOCKS_END[1], count)
    step = 0.36 / segments
    rows, point = [roots], roots
    for k in range(1, segments + 1):
        along = _tangent(body, point, flow(point, centre, eye_z))
        fall = np.clip(k * step / 0.075, 0, 1)  # combed 7.5 cm, then hanging
        direction = along * (1 - fall) + np.array([0, 0, -1.0]) * fall
        direction /= np.maximum(np.linalg.norm(direction, axis=1, keepdims=True), 1e-9)
        gap = 0.002 + (lift - 0.002) * min(1.0, k / 3)
        point = _off_skin(body, point + step * direction, gap)
        point = _clear_of_the_ears(body, point, gap, centre, (eye_z - 0.09, eye_z + 0.03))
        rows.append(point)
    path = _fall_clear(np.stack(rows, 1), centre, eye_z + 0.03)
    path = _into_the_back_hair(body, _finer(path, 3), lift, eye_z)
    path = _cut_at(path, stop)[:, ::3]
    normal = body.outward(path.reshape(-1, 3)).reshape(path.shape)
    inner = 1 - (lift - layers[0]) / (layers[1] - layers[0])
    return _card_piece(body, path, normal, width, rng, root_v=LONG_ROOT_V - LONG_INNER_V * inner)


def _into_the_back_hair(body: AuthoringBody, path: np.ndarray, lift: np.ndarray,
                        eye_z: float) -> np.ndarray:  # fmt: skip
    """(N, K, 3) side locks' paths whose points below the jaw (``SIDE_LOCKS_TURN_Z``) are
    drawn back to the hair down the back: to the depth of MakeHuman's hair guides
    (``guides``, which the long locks hang from) at their height and across the back, no
    wider than the outermost guide, and ``lift`` (N,) m off the skin. Falling straight
    down at the ears' width, the locks met the slope of the shoulders and slid off it
    every way, fanned out over the shoulders, and from the side they ended there, a
    layer of their own in front of the hair down the back."""
    g = guides(body, 16)  # (G, S, 3) across the back, from one side to the other
    flat = path.reshape(-1, 3)
    z = flat[:, 2]
    # Each guide's x and depth (y) at every point's height (the guides fall downwards).
    gx = np.stack([np.interp(z, c[::-1, 2], c[::-1, 0]) for c in g], 1)  # (P, G)
    gy = np.stack([np.interp(z, c[::-1, 2], c[::-1, 1]) for c in g], 1)
    x = np.clip(flat[:, 0], gx.min(axis=1), gx.max(axis=1))
    order = np.argsort(gx, axis=1)
    gx, gy = np.take_along_axis(gx, order, 1), np.take_along_axis(gy, order, 1)
    depth = np.array([np.interp(xi, a, b) for xi, a, b in zip(x, gx, gy, strict=True)])
    low, high = eye_z + np.array(SIDE_LOCKS_TURN_Z)
    w = np.clip((high - z) / (high - low), 0, 1)
    w = w * w * (3 - 2 * w)
    # Gathered in a little across the back (their own width kept, the shoulders' slope
    # under them pushed them out again).
    target = np.stack([x * SIDE_LOCKS_GATHER, depth, z], 1)
    out = flat + w[:, None] * (target - flat)
    moved = w > 0  # (only those: pushed off the skin again, points beside an ear moved)
    out[moved] = _off_skin(body, out[moved], np.repeat(lift, path.shape[1])[moved])
    return out.reshape(path.shape)


LONG_ROOT_V = 0.4  # long cards' texture starts here at the roots (0.5: the darkest roots)
LONG_INNER_V = 0.1  # ... and this much further towards the tips on the innermost layer


def _card_piece(body: AuthoringBody, path: np.ndarray, normal: np.ndarray, width, rng,
                surface: np.ndarray | None = None, taper=0.7,
                tip_v: float = 0.0, strip: float = 0.12, u0=None,
                root_v=0.5, clear=None) -> Piece:  # fmt: skip
    """Cards along paths (N, K, 3) lying across the normals (N, K, 3), bound to the skin
    (or to ``surface``, (S, 4) base-mesh faces of it), ``width`` m wide (a float or one per
    card, (N,)), narrowing to ``taper`` (a float or (N,)) of their width at the tips,
    their texture running from the roots (v = 0.5) to ``tip_v`` (0: the texture's
    thinned-out strand tips; more: cut ends, as a blunt haircut has) and across a random
    ``strip`` of its width (how many of its hairs a card shows); ``u0`` (N,) the strips'
    left edges (None: random); ``root_v`` (a float or (N,)) where the texture starts at
    the root (0.5: the strands' dark roots; less: lighter, further along the strands);
    ``clear`` (N, K) m the cards' edges are kept off the skin (None: where they fall)."""
    count, k = path.shape[:2]
    side = np.cross(normal, np.gradient(path, axis=1))
    side /= np.maximum(np.linalg.norm(side, axis=-1, keepdims=True), 1e-9)
    width = np.broadcast_to(np.asarray(width, np.float64), (count,))[:, None, None]
    taper = np.broadcast_to(np.asarray(taper, np.float64), (count,))[:, None, None]
    half = (width / 2) * rng.uniform(0.7, 1.2, count)[:, None, None]
    half = half * (1 + (taper - 1) * np.linspace(0, 1, k)[None, :, None])
    verts = np.concatenate([path - half * side, path + half * side], 1)  # (N, 2K, 3)
    if clear is not None:
        gap = np.concatenate([clear, clear], 1).reshape(-1)
        verts = _off_skin(body, verts.reshape(-1, 3), gap).reshape(verts.shape)
    j = np.arange(k - 1)
    quad = np.stack([j, j + 1, k + j + 1, k + j], 1)
    faces = (quad[None] + (2 * k * np.arange(count))[:, None, None]).reshape(-1, 4)
    u0 = (rng.uniform(0, 1, count) if u0 is None else np.asarray(u0, np.float64))[:, None]
    root_v = np.broadcast_to(np.asarray(root_v, np.float64), (count,))[:, None]
    v = root_v - (root_v - tip_v) * np.linspace(0, 1, k)[None, :]
    left = np.stack(np.broadcast_arrays(u0, v), -1)
    uv = np.concatenate([left, left + [strip, 0.0]], 1).reshape(-1, 2).astype(np.float32)
    mesh = orient_outward(body, verts.reshape(-1, 3).astype(np.float32), faces.astype(np.int32))
    mesh = Mesh(mesh.vertices, mesh.faces, uv, mesh.faces.copy())
    return bound(body, mesh, body.skin_faces if surface is None else surface)


def ponytail(body: AuthoringBody, length: float = 0.3, count: int = 240, seed: int = 2) -> Piece:
    """A tied-back tail: strand cards around a spine hanging from the back of the head,
    gathered tight at the tie, fuller below it and tapering to the tips.

    A bundle, not a ribbon: many narrow cards (1.6 cm) fill the tail's whole section
    (each at its own depth, from the core to the surface) and each is turned by its own
    angle about the spine, so from any side some are seen face on and some edge on; their
    paths wander and their tips splay apart. (60 cards 2 cm wide on the tail's surface,
    all facing out, read as one flat ribbon with strands painted on.)"""
    rng = np.random.default_rng([seed, count])
    centre, eye_z = head_frame(body)
    back = body.vertices[:BODY_VERTICES][body.part[:BODY_VERTICES] == "head"][:, 1].max()
    root = np.array([0.0, back + 0.005, eye_z + 0.02])
    k = 13
    t = np.linspace(0, 1, k)
    # The tail falls back and down, then down along the upper back.
    spine = root + np.stack([0 * t, 0.05 * np.sin(t * np.pi / 2) + 0.03 * t, -length * t], 1)
    # Gathered at the tie (2.5 cm across), full below it (7-8 cm), tapering to the tips.
    radius = 0.0125 + 0.037 * np.sin(np.pi * np.clip(t / 0.7, 0, 1) * 0.8) * (1 - 0.55 * t)
    angle = rng.uniform(0, 2 * np.pi, count)[:, None] + rng.normal(0, 0.3, count)[:, None] * t
    reach = np.sqrt(rng.uniform(0.1, 1.0, count))[:, None] * 1.05  # filled, not a shell
    splay = 1 + 0.35 * t[None, :] ** 3 * rng.uniform(0, 1, count)[:, None]  # tips part
    radial = np.stack([np.cos(angle), np.sin(angle) * 0.8, np.zeros_like(angle)], -1)
    path = spine[None] * np.array([1, 1, 0]) + radial * (radius * reach * splay)[..., None]
    wander = rng.normal(0, 0.004, (count, 1, 3)) * np.sin(np.pi * t)[None, :, None]
    path = path + wander * np.array([1, 1, 0])
    path[..., 2] = root[2] - length * t[None, :] * rng.uniform(0.8, 1.05, count)[:, None]
    # Each card turned about the spine by its own angle (the cards' faces point along
    # ``radial`` turned towards the tangent round the tail).
    # (Turned up to 35 degrees, the outer cards mostly face out and catch the light: a
    # tail of cards turned every way up to 57 degrees was seen edge on into its shaded
    # core, darker and narrower than the hair on the head.)
    turn = rng.uniform(-0.6, 0.6, count)[:, None, None]
    around = np.stack([-radial[..., 1], radial[..., 0], np.zeros_like(angle)], -1)
    facing = np.cos(turn) * radial + np.sin(turn) * around
    return _card_piece(body, path, facing, 0.016, rng)


def brim(body: AuthoringBody, cap: Piece, reach: float = 0.07) -> Piece:
    """A cap's visor: the front half of the crown's rim extended forward and slightly down."""
    mesh = cap.mesh
    edges, _ = boundary_edges(mesh.faces)
    centre, _ = eye_level(body)
    rel = mesh.vertices - centre
    facing = -rel[:, 1] / np.maximum(np.hypot(rel[:, 0], rel[:, 1]), 1e-6)
    front = (facing[edges[:, 0]] > 0.2) & (facing[edges[:, 1]] > 0.2)
    edges = edges[front]
    rim = np.unique(edges)
    out = rel[rim] * np.array([1, 1, 0])
    out /= np.linalg.norm(out, axis=1, keepdims=True)
    strength = np.clip((facing[rim] - 0.2) / 0.5, 0, 1) ** 0.7
    tip = mesh.vertices[rim] + (reach * strength)[:, None] * out + [0, 0, -0.012]
    index = {int(v): i for i, v in enumerate(rim)}
    n = len(rim)
    verts = np.concatenate([mesh.vertices[rim], tip]).astype(np.float32)
    faces = np.array([[index[a], index[b], n + index[b], n + index[a]] for a, b in edges], np.int32)
    uv = np.concatenate(
        [
            np.stack([rel[rim, 0] / 0.1, np.zeros(n)], 1),
            np.stack([rel[rim, 0] / 0.1, np.full(n, 0.6)], 1),
        ]
    ).astype(np.float32)
    visor = orient_up(Mesh(verts, faces, uv, faces.copy()))
    return bound(body, visor, body.skin_faces)


def orient_up(mesh: Mesh) -> Mesh:
    """Make a near-horizontal sheet's faces point up (+Z)."""
    v = mesh.vertices[mesh.faces]
    n = np.cross(v[:, 2] - v[:, 0], v[:, 3] - v[:, 1])
    flip = n[:, 2] < 0
    faces = mesh.faces.copy()
    faces[flip] = faces[flip][:, [2, 1, 0, 3]]
    fuv = faces.copy() if mesh.face_uvs is None else mesh.face_uvs.copy()
    fuv[flip] = fuv[flip][:, [2, 1, 0, 3]]
    return Mesh(mesh.vertices, faces, mesh.uvs, fuv)


# ---------------------------------------------------------------------------- hanging hair


def hang_cards(
    body: AuthoringBody,
    flow,
    count: int = 520,
    end: tuple[float, float] = (-0.088, -0.08),
    fringe: float | None = 0.035,
    width: float = 0.022,
    lift=(0.004, 0.02),
    segments: int = 10,
    seed: int = 3,
) -> Piece:
    """Hair that falls: cards rooted inside the hairline, combed along ``flow`` over the
    scalp, then bending down under their weight, never nearer the skin than their lift, cut
    level at ``end`` (low, high) m relative to eye height (a bob's blunt line; each card
    ends at a random height in that range, and its texture is cut there, not thinned
    out). Roots facing the face (within 50 degrees of the
    front) make a ``fringe`` ending that far above the eyes (None: parted off the face).
    Over the sides of the head they fall close over the ears (``_hug_the_sides``).
    """
    rng = np.random.default_rng([seed, count])
    centre, eye_z = head_frame(body)
    roots = _scatter(body, hairline_mask(body, 0.004), count, rng)
    front = around(roots, centre) < 50
    depth = roots[:, 2] - eye_z - np.interp(around(roots, centre), HAIRLINE_DEG, HAIRLINE_M)
    height = lift[0] + (lift[1] - lift[0]) * np.clip(depth / 0.06, 0, 1)
    height *= rng.uniform(0.6, 1.0, count)
    stop = eye_z + rng.uniform(end[0], end[1], count)
    if fringe is not None:
        stop[front] = eye_z + fringe + rng.uniform(-0.004, 0.004, front.sum())
    length = 0.35
    step = length / segments
    rows, point = [roots], roots
    for k in range(1, segments + 1):
        along = _tangent(body, point, flow(point, centre, eye_z))
        fall = np.clip(k / segments * 2.2, 0, 1)  # combed over the crown, then hanging
        direction = along * (1 - fall)[..., None] + np.array([0, 0, -1.0]) * fall
        direction /= np.maximum(np.linalg.norm(direction, axis=1, keepdims=True), 1e-9)
        gap = 0.002 + (height - 0.002) * min(1.0, (k / 3) ** 0.7)
        point = _hug_the_sides(body, point + step * direction, gap, centre, eye_z)
        rows.append(point)
    path = _fall_clear(np.stack(rows, 1), centre, eye_z + 0.03)  # (N, K+1, 3)
    path = _fall_clear(_no_lone_locks(path, centre, eye_z + 0.03), centre, eye_z + 0.03)
    # Drawn in under the ears on a path three times as fine (a straight 3.5 cm segment
    # from above the ear to a point drawn in below it cut in across the ear's level).
    fine = _finer(path, 3)
    fine = _hang_in(body, fine, centre, eye_z - 0.055)
    stop = stop + _layers(path, centre, ~front, np.random.default_rng([seed, count, 7]))
    path = _curl_in(body, _cut_at(fine, stop)[:, ::3], centre)
    normal = _facing_out(body, path, centre, eye_z)
    # A blunt cut: cards to the end, their strands cut there rather than thinning out
    # (tapered, thinned tips a centimetre apart read as frayed ends), narrowing a little
    # as the ends turn in.
    clear = BOB_EDGE_GAP_M * (_side_weight(path.reshape(-1, 3), centre, eye_z) > 0)
    return _card_piece(body, path, normal, width, rng, taper=0.75, tip_v=0.25,
                       clear=clear.reshape(path.shape[:2]))


BOB_SIDE_GAP_M = 0.005  # a bob's hanging cards over the sides of the head: this far off it
# ... and their edges at least this far off the skin there: a card drawn in over the ear
# came within 2 mm of its back by an edge, which lay 2 mm inside a small child's ear.
BOB_EDGE_GAP_M = 0.005
# The head a bob lies over at its sides is wrapped (``_wrapped``) from this far below the
# eyes up: the ears' lobes (under them the hair hangs in, ``_hang_in``).
BOB_WRAP_BELOW_M = 0.06


def _hug_the_sides(body: AuthoringBody, points: np.ndarray, gap: np.ndarray,
                   centre: np.ndarray, eye_z: float) -> np.ndarray:  # fmt: skip
    """(N, 3) hanging cards' points kept ``gap`` (N,) m off the skin, but over the sides of
    the head, above and over the ears, drawn in towards its vertical axis (through
    ``centre``) to ``BOB_SIDE_GAP_M`` outside the head's silhouette seen from that axis
    (``_head_radius``: the ear's rim where they pass over it, so never in between the
    ear and the skull). Keeping their lift there (up to 2 cm off the skull from the top
    of the head, falling straight down from it), a bob's sides flared out at ear level,
    3.5 cm out from the skull and 3 cm from the ears. (Drawn in to 8 mm off the nearest
    skin instead, a card's point came to lie in the fold behind a woman's ear.)"""
    w = _side_weight(points, centre, eye_z)
    target = gap + (np.minimum(gap, BOB_SIDE_GAP_M) - gap) * w
    return _off_skin(body, _onto_the_wrap(body, points, centre, w), target)


def _facing_out(body: AuthoringBody, path: np.ndarray, centre: np.ndarray,
                eye_z: float) -> np.ndarray:  # fmt: skip
    """(N, K, 3) unit normals for a bob's cards along ``path`` (N, K, 3): the skin's, but
    over the sides of the head (``_side_weight``) turned to face straight out from its
    vertical axis (through ``centre``), as the wrapped head they lie on does. Facing the
    nearest skin's normal there (the ear's, which faces forward or back), cards were
    turned edge-on to the head and their edges stood up to 8 mm out of the hair: lumps at
    ear level."""
    flat = path.reshape(-1, 3)
    skin = body.outward(flat)
    radial = np.zeros_like(skin)
    radial[:, :2] = flat[:, :2] - centre[:2]
    radial /= np.maximum(np.linalg.norm(radial, axis=1, keepdims=True), 1e-9)
    w = _side_weight(flat, centre, eye_z)[:, None]
    normal = skin * (1 - w) + radial * w
    normal /= np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), 1e-9)
    return normal.reshape(path.shape)


def _onto_the_wrap(body: AuthoringBody, points: np.ndarray, centre: np.ndarray,
                   weight: np.ndarray) -> np.ndarray:  # fmt: skip
    """(N, 3) points moved by ``weight`` (N,) 0..1 of the way along their radius from the
    head's vertical axis (through ``centre``) to ``BOB_SIDE_GAP_M`` outside the head
    wrapped (``_head_radius`` with ``BOB_WRAP_BELOW_M``)."""
    rel = points[:, :2] - centre[:2]
    radius = np.maximum(np.linalg.norm(rel, axis=1), 1e-9)
    limit = _head_radius(body, centre, points, hull_below=BOB_WRAP_BELOW_M) + BOB_SIDE_GAP_M
    moved = radius + (limit - radius) * weight
    out = points.astype(np.float64).copy()
    out[:, :2] = centre[:2] + rel * (moved / radius)[:, None]
    return out


def _clear_of_the_ears(body: AuthoringBody, points: np.ndarray, gap: np.ndarray,
                       centre: np.ndarray, heights: tuple[float, float]) -> np.ndarray:  # fmt: skip
    """(N, 3) points between the ``heights`` (low, high) moved out from the head's vertical axis
    (through ``centre``) to at least ``gap`` (N,) m outside the head's silhouette seen
    from it (``_head_radius``, the ears' rims included): kept off the nearest skin only,
    a long lock's point lay in the fold behind the ear, 1 cm off the skull, which was 8 mm
    inside a small child's ear."""
    rel = points[:, :2] - centre[:2]
    radius = np.maximum(np.linalg.norm(rel, axis=1), 1e-9)
    # (Not down by the shoulders, whose outline would push the locks out over them.)
    at = (points[:, 2] > heights[0]) & (points[:, 2] < heights[1])
    need = np.where(at, _head_radius(body, centre, points) + gap, 0.0)
    out = points.copy()
    out[:, :2] = centre[:2] + rel * (np.maximum(radius, need) / radius)[:, None]
    return out


def _head_radius(body: AuthoringBody, centre: np.ndarray, points: np.ndarray,
                 step_deg: float = 3.0, step_z: float = 0.004,
                 reach_deg: float = 12.0,
                 hull_below: float | None = None) -> np.ndarray:  # fmt: skip
    """(N,) m from the vertical axis through ``centre`` to the outermost skin of the head
    (ears included) about the direction and at the height of each point (N, 3): the most
    of the skin vertices' in a grid of ``step_deg`` by ``step_z`` cells round the axis,
    widened by ``reach_deg`` round it (a card's half width: a card drawn in by its middle
    in front of an ear cut through the ear by its edge) and a cell up and down, read
    bilinearly. ``hull_below``: m below ``centre`` from which up the head is wrapped
    (``_wrapped``: what hair drawn taut over it lies on; None: the skin itself)."""
    from scipy.ndimage import map_coordinates, maximum_filter

    skin = body.vertices[:BODY_VERTICES]
    skin = skin[skin[:, 2] > centre[2] - 0.2]
    rel = skin - centre
    grid_a = ((np.degrees(np.arctan2(rel[:, 0], -rel[:, 1])) + 180) / step_deg).astype(int)
    grid_z = ((rel[:, 2] + 0.2) / step_z).astype(int)
    shape = (int(360 / step_deg) + 1, int(0.45 / step_z) + 1)
    keep = (grid_z >= 0) & (grid_z < shape[1])
    table = np.zeros(shape)
    np.maximum.at(table, (grid_a[keep], grid_z[keep]), np.hypot(rel[keep, 0], rel[keep, 1]))
    # Round the head, not from its top to the shoulders (wrapped, its top row was theirs).
    table = maximum_filter(table, size=(2 * int(reach_deg / step_deg) + 1, 3),
                           mode=("wrap", "constant"))  # fmt: skip
    if hull_below is not None:
        low = int((0.2 - hull_below) / step_z)
        table[:, low:] = _wrapped(table[:, low:], step_deg, step_z)
    q = points - centre
    at = np.stack([(np.degrees(np.arctan2(q[:, 0], -q[:, 1])) + 180) / step_deg - 0.5,
                   (q[:, 2] + 0.2) / step_z - 0.5])  # fmt: skip
    return map_coordinates(table, at, order=1, mode="nearest")


def _wrapped(table: np.ndarray, step_deg: float, step_z: float) -> np.ndarray:
    """(A, Z) radii (m) of the head round its vertical axis (``A`` directions ``step_deg``
    apart from the back, ``Z`` heights ``step_z`` apart, up; 0 where no skin is) wrapped
    as hair drawn over it wraps it: each height's outline round the axis by its convex
    hull, then each direction's profile up the head by its own (no hollow between the
    skull over the ear and the ear's rim, nor behind the ear). Hair hugging the skin's
    outline instead stood out over each ear in a round lump, an ear-muff, with a step
    above it and a groove behind it. Below each direction's widest point the radius stays
    (hair falls straight past it)."""
    angle = np.radians((np.arange(table.shape[0]) + 0.5) * step_deg - 180)
    across = np.stack([np.sin(angle), -np.cos(angle)], 1)  # (A, 2) unit directions
    out = table.copy()
    for z in range(table.shape[1]):  # round the axis, from it
        out[:, z] = _hull_reach(out[:, z, None] * across, across, np.zeros(2), out[:, z])
    height = np.arange(table.shape[1]) * step_z
    up = np.array([0.0, 1.0])
    for a in range(table.shape[0]):  # up the head, out from the axis
        on_axis = np.stack([height, np.zeros_like(height)], 1)
        out[a] = _hull_reach(np.stack([height, out[a]], 1), up, on_axis, out[a])
    # Straight down past the widest point (hair falls past the ears, not in under them).
    return np.maximum.accumulate(out[:, ::-1], axis=1)[:, ::-1]


def _hull_reach(points: np.ndarray, direction: np.ndarray, start: np.ndarray,
                radius: np.ndarray) -> np.ndarray:  # fmt: skip
    """(N,) how far the convex hull of 2-D ``points`` (N, 2) with ``start`` ((2,) or (N,
    2), inside it) reaches along ``direction`` ((N, 2) or (2,), unit) from each start:
    ``radius`` (N,) (the points' own distances) where the points with a radius are too
    few or in a line to make a hull. Over the hull's edges facing that way, the least
    distance to the edge's line; never less than ``radius``, nor more than the farthest
    point reaches."""
    from scipy.spatial import ConvexHull, QhullError

    on = radius > 0
    corners = np.vstack([points[on], np.reshape(start, (-1, 2))])
    try:
        hull = ConvexHull(corners)
    except (QhullError, ValueError):  # flat or empty: nothing to wrap
        return radius
    normal, offset = hull.equations[:, :2], hull.equations[:, 2]
    facing = np.broadcast_to(direction @ normal.T, (len(radius), len(offset)))
    room = -(offset + np.broadcast_to(start, (len(radius), 2)) @ normal.T)
    reach = np.where(facing > 1e-6, room / np.maximum(facing, 1e-6), np.inf).min(axis=1)
    return np.clip(reach, radius, radius.max())


def _side_weight(points: np.ndarray, centre: np.ndarray, eye_z: float) -> np.ndarray:
    """(N,) 0..1 over the sides of the head (65-115 degrees round it, easing out to 35 and
    145) below 3 cm above the eyes, easing out to 9 cm (the crown keeps its volume). (Eased
    over 3 cm up and 20 degrees round, cards coming down from the crown's full lift over
    the temples turned in by 68 degrees, a kink.)"""
    turn = around(points, centre)
    round_ = np.clip((turn - 35) / 30, 0, 1) * np.clip((145 - turn) / 30, 0, 1)
    low = np.clip((eye_z + 0.09 - points[:, 2]) / 0.06, 0, 1)
    w = round_ * low
    return w * w * (3 - 2 * w)


def _fall_clear(path: np.ndarray, centre: np.ndarray, below: float) -> np.ndarray:
    """(N, K, 3) hanging paths that, below the height ``below``, never come back in
    towards the head's vertical axis (through ``centre``) once out: hair falls straight
    past the widest point under it (an ear, the back of the skull) instead of following
    the skin back in. (Kept off the skin point by point, cards pushed out over the ears
    dipped back in under them by up to a centimetre: loops sticking out at ear level.)"""
    rel = (path - centre)[..., :2]
    radius = np.linalg.norm(rel, axis=-1)
    hanging = path[..., 2] < below
    widest = np.maximum.accumulate(np.where(hanging, radius, 0.0), axis=1)
    scale = np.where(hanging, widest / np.maximum(radius, 1e-9), 1.0)
    out = path.copy()
    out[..., :2] = centre[:2] + rel * scale[..., None]
    return out


def _finer(path: np.ndarray, times: int) -> np.ndarray:
    """(N, (K - 1) * times + 1, 3) the paths (N, K, 3) with ``times - 1`` points put evenly
    between each pair of their points (the same polylines)."""
    t = np.linspace(0, path.shape[1] - 1, (path.shape[1] - 1) * times + 1)
    j = np.minimum(t.astype(int), path.shape[1] - 2)
    f = (t - j)[None, :, None]
    return path[:, j] * (1 - f) + path[:, j + 1] * f


HANG_GAP_M = 0.012  # hanging hair below the ears: at most this far off the neck and jaw
HANG_PULL_M = 0.045  # ... reached over this drop below the ears


def _hang_in(body: AuthoringBody, path: np.ndarray, centre: np.ndarray,
             below: float) -> np.ndarray:  # fmt: skip
    """(N, K, 3) hanging paths drawn in towards the head's vertical axis (through
    ``centre``) below the height ``below`` (under the ears), behind the cheeks, until they
    hang at most ``HANG_GAP_M`` off the skin, reached gradually over ``HANG_PULL_M`` of
    drop: hair falls past the ears and then in against the neck and jaw under its weight.
    (Falling straight down from the ears' width, a bob's side locks hung 3.5 cm off the
    neck and stood out from it seen from behind.) Kept 3 mm off the skin."""
    out = path.reshape(-1, 3).copy()
    drop = np.clip((below - out[:, 2]) / HANG_PULL_M, 0, 1)
    side = np.clip((around(out, centre) - 50) / 30, 0, 1)  # not over the cheeks
    weight = (drop * drop * (3 - 2 * drop)) * side
    moved = weight > 0
    for _ in range(3):  # the skin is not straight in: step in, measure again
        gap, _ = body.skin_tree.query(out)
        shift = np.maximum(gap - HANG_GAP_M, 0) * weight
        rel = out[:, :2] - centre[:2]
        radius = np.maximum(np.linalg.norm(rel, axis=1), 1e-9)
        out[:, :2] = centre[:2] + rel * (np.maximum(radius - shift, 0) / radius)[:, None]
        out[moved] = _off_skin(body, out[moved], 0.003)
    return out.reshape(path.shape)


def _no_lone_locks(path: np.ndarray, centre: np.ndarray, below: float,
                   lean: float = 0.5, slack: float = 0.008) -> np.ndarray:  # fmt: skip
    """(N, K, 3) hanging paths pushed out from the head's vertical axis (through
    ``centre``), below the height ``below``, so that none stands out from the hair around
    it: each point at least as far out as every neighbour within 3 cm (over the head's
    surface: arc round it at 10 cm, height), less ``lean`` times their distance and
    ``slack`` m. The cards that pass over an ear stood 2-3.5 cm out from those just in
    front of and behind it (a lone lock, a loop seen from the front); now the hair
    around the ear is pushed out with them, one smooth curtain."""
    from scipy.spatial import cKDTree

    flat = path.reshape(-1, 3)
    rel = flat[:, :2] - centre[:2]
    radius = np.linalg.norm(rel, axis=1)
    where = np.stack([np.arctan2(rel[:, 0], -rel[:, 1]) * 0.1, flat[:, 2]], 1)
    hanging = np.flatnonzero(flat[:, 2] < below)
    pairs = cKDTree(where[hanging]).query_pairs(0.03, output_type="ndarray")
    a, b = hanging[pairs[:, 0]], hanging[pairs[:, 1]]
    apart = np.linalg.norm(where[a] - where[b], axis=1)
    need = radius.copy()
    np.maximum.at(need, a, radius[b] - lean * apart - slack)
    np.maximum.at(need, b, radius[a] - lean * apart - slack)
    out = flat.copy()
    out[:, :2] = centre[:2] + rel * (need / np.maximum(radius, 1e-9))[:, None]
    return out.reshape(path.shape)


def _layers(path: np.ndarray, centre: np.ndarray, free: np.ndarray, rng) -> np.ndarray:
    """(N,) m by which hanging cards (paths (N, K, 3)) end above their cut: a third of the
    ``free`` ones hanging behind the neck end 0.8-2.5 cm higher (the cut's outer layers,
    so the ends vary in length instead of one box edge). Not by the face: resampled
    shorter, a card's points cut across the temple's curve, into a face fuller than the
    authoring body's."""
    behind = free & (path[:, -1, 1] > centre[1] + 0.02)
    return np.where(behind & (rng.uniform(size=len(path)) < 0.35),
                    rng.uniform(0.008, 0.025, len(path)), 0.0)  # fmt: skip


def _curl_in(body: AuthoringBody, path: np.ndarray, centre: np.ndarray,
             reach: float = 0.035, depth: float = 0.012) -> np.ndarray:  # fmt: skip
    """(N, K, 3) hanging paths whose last ``reach`` m turn in towards the head's vertical
    axis (through ``centre``, the skull's centre at eye height) by up to ``depth`` m at
    the tips (a bob's ends curl under; hanging straight down they ended in a box edge),
    kept 2 mm off the skin."""
    seg = np.linalg.norm(np.diff(path, axis=1), axis=2)
    arc = np.concatenate([np.zeros((len(path), 1)), np.cumsum(seg, axis=1)], 1)
    s = np.clip((arc - (arc[:, -1:] - reach)) / reach, 0, 1)  # 0 above, 1 at the tip
    # Only the ends at the cut, below the cheekbones (``centre`` is at eye height): short
    # cards ending by the temples turned in towards the face and kinked.
    s = s * (path[:, -1:, 2] < centre[2] - 0.05)
    inward = (centre - path) * np.array([1.0, 1.0, 0.0])
    inward /= np.maximum(np.linalg.norm(inward, axis=-1, keepdims=True), 1e-9)
    # No further in than the room left to the skin over the card's curled part (curled
    # into the nape and pushed back out, ends folded back on themselves).
    room, _ = body.skin_tree.query(path.reshape(-1, 3))
    room = np.where(s > 0, room.reshape(s.shape), np.inf).min(axis=1, keepdims=True)
    shift = np.minimum(depth, np.maximum(room - 0.006, 0)) * s**2
    curled = path + shift[..., None] * inward
    moved = shift > 0  # (the others are where ``hang_cards`` put them, off the skin)
    curled[moved] = _off_skin(body, curled[moved], 0.002)
    return curled


def _off_skin(body: AuthoringBody, points: np.ndarray, gap) -> np.ndarray:
    """(N, 3) points moved out along the nearest skin vertices' normals until each is at
    least ``gap`` m ((N,) or a float) outside them; points farther out stay where they are."""
    gap = np.broadcast_to(np.asarray(gap, np.float64), (len(points),))
    _, i = body.skin_tree.query(points, k=6)
    out = points.astype(np.float64).copy()
    for k in range(i.shape[1]):
        skin, n = body.vertices[i[:, k]], body.skin_normals[i[:, k]].astype(np.float64)
        d = np.einsum("nd,nd->n", out - skin, n)
        out += np.clip(gap - d, 0, None)[:, None] * n
    return out


def _cut_at(path: np.ndarray, stop: np.ndarray) -> np.ndarray:
    """(N, K, 3) paths resampled over their length down to where each first reaches the
    height ``stop`` (N,) (the whole path when it never does)."""
    n, k = path.shape[:2]
    seg = np.linalg.norm(np.diff(path, axis=1), axis=2)
    arc = np.concatenate([np.zeros((n, 1)), np.cumsum(seg, axis=1)], 1)  # (N, K)
    below = path[..., 2] <= stop[:, None]
    first = np.where(below.any(axis=1), below.argmax(axis=1), k - 1)
    j = np.maximum(first, 1)
    rows = np.arange(n)
    z0, z1 = path[rows, j - 1, 2], path[rows, j, 2]
    frac = np.where(below.any(axis=1), np.clip((z0 - stop) / np.maximum(z0 - z1, 1e-9), 0, 1), 1)
    total = arc[rows, j - 1] + frac * (arc[rows, j] - arc[rows, j - 1])
    t = np.linspace(0, 1, k)[None, :] * total[:, None]
    out = np.empty_like(path)
    for c in range(3):
        out[..., c] = np.stack([np.interp(t[r], arc[r], path[r, :, c]) for r in range(n)])
    return out


def bun(body: AuthoringBody, radius: float = 0.032, count: int = 90, seed: int = 4) -> Piece:
    """A bun: strand cards wound round a ball pinned high on the back of the head (as
    hair wound into a knot), every card outside the scalp."""
    rng = np.random.default_rng([seed, count])
    centre, eye_z = head_frame(body)
    skull = body.vertices[:BODY_VERTICES][body.part[:BODY_VERTICES] == "head"]
    anchor = np.array([0.0, skull[:, 1].max() - 0.02, eye_z + 0.075])
    _, i = body.skin_tree.query(anchor)
    normal = body.skin_normals[i].astype(np.float64)
    ball = body.vertices[i] + normal * (radius * 0.85)
    k = 12
    # Each card winds half way round the ball on a random great circle.
    axis = rng.normal(size=(count, 3))
    axis /= np.linalg.norm(axis, axis=1, keepdims=True)
    a = np.cross(axis, rng.normal(size=(count, 3)))
    a /= np.linalg.norm(a, axis=1, keepdims=True)
    b = np.cross(axis, a)
    t = rng.uniform(0, 2 * np.pi, count)[:, None] + np.linspace(0, np.pi * 1.1, k)[None, :]
    r = radius * rng.uniform(0.85, 1.05, count)[:, None, None]
    path = ball + r * (np.cos(t)[..., None] * a[:, None] + np.sin(t)[..., None] * b[:, None])
    flat = _off_skin(body, path.reshape(-1, 3), 0.004).reshape(path.shape)
    outward = flat - ball
    outward /= np.linalg.norm(outward, axis=-1, keepdims=True)
    return _card_piece(body, flat, outward, 0.018, rng)
