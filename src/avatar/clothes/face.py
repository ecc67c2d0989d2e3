"""Face pieces: eyebrows painted on patches of the brow skin, eyelashes on the base mesh's
lash helper strips (textures in ``textures``: ``brow_alpha``, ``lash_alpha``), facial hair
(a short beard as strand cards over a dense undercoat, a moustache as strand cards, stubble
as a tiled layer on the skin), and
the UVs of the teeth over their teeth-and-gums texture."""

from __future__ import annotations

import functools

import numpy as np

from avatar.body.model import BODY_VERTICES
from avatar.clothes.authoring import AuthoringBody, Piece, bound, cut, join, single_references
from avatar.clothes.hair import around, cards_on, head_frame, per_corner
from avatar.geometry.shell import boundary_edges
from avatar.looks.facial_hair import (  # noqa: F401
    CHEEK_DEG,
    CHEEK_M,
    EDGE_M,
    WOBBLE_M,
    beard_edge,
    cheek_wobble,
)
from avatar.mesh import Mesh, vertex_normals


def eyebrows(body: AuthoringBody, inner=0.019, outer=0.03, low=0.006, height=0.022) -> Piece:
    """Two brow patches on the skin above the eyes, each with UVs spanning the eyebrow
    texture: u from ``inner`` metres inside the eye centre (0) to ``outer`` outside it (1),
    v from ``low`` above the eye centre over ``height`` metres. The texture's alpha draws
    the brow's shape and hairs; the patch is only where they may be."""
    faces = body.skin_faces
    pieces = []
    for group in ("helper-l-eye", "helper-r-eye"):
        eye = body.centre(group)
        side = np.sign(eye[0])

        def uv(p, eye=eye, side=side):
            u = (side * (p[..., 0] - eye[0]) + inner) / (inner + outer)
            return np.stack([u, (p[..., 2] - eye[2] - low) / height], -1)

        corners = uv(body.vertices[faces])  # (F, 4, 2)
        inside = ((corners > 0) & (corners < 1)).all(axis=(1, 2))
        keep = inside & (body.vertices[faces][:, :, 1].mean(1) < eye[1])
        mesh = cut(body, faces, keep, 0.0006)
        mesh = per_corner(mesh, uv(mesh.vertices[mesh.faces]).reshape(-1, 2).astype(np.float32))
        pieces.append(bound(body, mesh, faces))
    return join(pieces)


def eyelashes(body: AuthoringBody, groups: tuple[str, ...]) -> Piece:
    """The base mesh's eyelash helper strips (single-vertex references, as MakeHuman binds
    its eyelash proxies), with strip UVs: u along the lid, v from the lid margin (0) to the
    lash tips, so the lash texture's strands run from root to tip (upper lids over v in
    [0.5, 1], lower lids over [0, 0.5])."""
    pieces = []
    for group in groups:
        piece = single_references(body, group)
        eye = body.centre(group.replace("eyelashes-1", "eye").replace("eyelashes-2", "eye"))
        uv = strip_uvs(piece.mesh, eye)
        uv[:, 1] = 0.5 * uv[:, 1] + (0.5 if group.endswith("-2") else 0.0)  # -2: upper lid
        mesh = Mesh(piece.mesh.vertices, piece.mesh.faces, uv, piece.mesh.faces.copy())
        pieces.append(Piece(mesh, piece.binding))
    return join(pieces)


def strip_uvs(mesh: Mesh, eye: np.ndarray) -> np.ndarray:
    """(V, 2) float32 UVs of a quad-grid strip: v is the hop distance from the long boundary
    side nearest ``eye`` (the root side), u the hop distance from the short side nearest it,
    both scaled to [0, 1]."""
    edges, _ = boundary_edges(mesh.faces)
    following = dict(zip(edges[:, 0].tolist(), edges[:, 1].tolist(), strict=True))
    loop = [int(edges[0, 0])]
    while following[loop[-1]] != loop[0]:
        loop.append(following[loop[-1]])
    uses = np.bincount(mesh.faces.ravel(), minlength=len(mesh.vertices))
    corners = [i for i, v in enumerate(loop) if uses[v] == 1]
    loop = loop[corners[0] :] + loop[: corners[0]]  # start at a corner
    corners = [c - corners[0] for c in corners] + [len(loop)]
    sides = [loop[a : b + 1] if b < len(loop) else loop[a:] + loop[:1]
             for a, b in zip(corners[:-1], corners[1:], strict=True)]  # fmt: skip
    long_sides = sorted(sides, key=len)[2:]
    root = min(long_sides, key=lambda s: np.linalg.norm(mesh.vertices[s] - eye, axis=1).mean())
    short = min(sorted(sides, key=len)[:2],
                key=lambda s: np.linalg.norm(mesh.vertices[s] - eye, axis=1).mean())  # fmt: skip
    v = _hops(mesh.faces, len(mesh.vertices), root)
    u = _hops(mesh.faces, len(mesh.vertices), short)
    return np.stack([u / u.max(), v / v.max()], 1).astype(np.float32)


def _hops(faces: np.ndarray, count: int, sources: list[int]) -> np.ndarray:
    """(V,) number of edge hops from the nearest source vertex (inf where unreachable)."""
    a = faces.reshape(-1)
    b = np.roll(faces, -1, axis=1).reshape(-1)
    dist = np.full(count, np.inf)
    dist[sources] = 0
    while True:
        new = dist.copy()
        np.minimum.at(new, b, dist[a] + 1)
        np.minimum.at(new, a, dist[b] + 1)
        if np.array_equal(new, dist):
            return dist
        dist = new


def teeth(mesh: Mesh, upper: np.ndarray, model=None) -> Mesh:
    """The teeth part as it renders: UVs over the teeth texture (``teeth_uvs``) and the
    front teeth seated in a natural bite (``seat_teeth``). mesh, upper: as ``teeth_uvs``.
    ``model``: the BodyModel the mesh is a part of, whose base mesh then gives the arch
    positions (``model_bite``), so that every path that writes teeth (a Human's parts, the
    Blender extension's live updates) seats them identically."""
    mesh = teeth_uvs(mesh, upper)
    weights = model_bite(model) if model is not None else bite(mesh, upper)
    return mesh.with_vertices(seat(mesh.vertices, *weights))


# The front of the arch (incisors, canines) is moved, fading out over the premolars: u is
# the arch position of ``teeth_uvs`` (0.5 = between the central incisors).
SEAT_FULL, SEAT_NONE = 0.09, 0.24  # |u - 0.5| up to which the full shift applies / none
OVERBITE = 0.22  # of the upper row's height: the incisors reach this far below the lower's
OVERJET_M = (0.0015, 0.0012)  # upper front forward, lower front back (m)


def seat_teeth(mesh: Mesh, upper: np.ndarray) -> Mesh:
    """The teeth with the front of the arch in a natural bite: MakeHuman's helper rows meet
    edge to edge at the line where the lips close, so with the mouth open the upper lip
    hides the upper teeth (the mouth reads as a hole over the lower row). In a real mouth
    the upper incisors hang about 3 mm below the lips' line (what shows under the upper lip
    when it opens) and overlap the lower ones in front (overbite and overjet). The upper
    front teeth move down by ``OVERBITE`` of the row's height (~3.5 mm on an adult) and
    forward, the lower front teeth back, both fading out along the arch to the premolars
    (the upper edge then rises towards the back, as a smile line does).

    mesh: the teeth part with ``teeth_uvs``' UVs (their u is the arch position); upper:
    (F,) bool, its faces of the upper row. Returns the mesh with moved vertices.
    """
    return mesh.with_vertices(seat(mesh.vertices, *bite(mesh, upper)))


def bite(mesh: Mesh, upper: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(V,) float32 share of the bite's shift per vertex (1 over the incisors, fading to 0
    over the premolars) and (V,) bool the upper row's vertices, of a teeth part with
    ``teeth_uvs``' UVs; upper: (F,) bool, its faces of the upper row."""
    assert mesh.uvs is not None and mesh.face_uvs is not None, "teeth_uvs first"
    u = np.zeros(len(mesh.vertices), np.float32)
    u[mesh.faces.ravel()] = mesh.uvs[mesh.face_uvs.ravel(), 0]
    front = np.clip((SEAT_NONE - np.abs(u - 0.5)) / (SEAT_NONE - SEAT_FULL), 0, 1)
    front = front * front * (3 - 2 * front)  # smoothstep: no kink in the arch
    is_upper = np.zeros(len(mesh.vertices), bool)
    is_upper[mesh.faces[upper].ravel()] = True
    for array in (front, is_upper):
        array.flags.writeable = False  # cached and shared by model_bite
    return front, is_upper


def seat(vertices: np.ndarray, front: np.ndarray, is_upper: np.ndarray) -> np.ndarray:
    """(V, 3) teeth vertices in the bite ``bite`` describes (a few vector operations: cheap
    enough for every step of a slider drag)."""
    incisors = vertices[is_upper & (front == 1)]
    height = float(np.ptp(incisors[:, 2]))  # gum to biting edge, ~16 mm on an adult
    shift = np.where(is_upper[:, None], [0.0, -OVERJET_M[0], -OVERBITE * height],
                     [0.0, OVERJET_M[1], 0.0])  # fmt: skip
    return (vertices + front[:, None] * shift).astype(vertices.dtype)


@functools.lru_cache(maxsize=4)
def model_bite(model) -> tuple[np.ndarray, np.ndarray]:
    """``bite`` of a BodyModel's teeth part on its base mesh: the arch positions are the
    topology's, the same for every body made from the model."""
    from avatar.body.shaped import PART_GROUPS

    base = model.base
    faces = np.sort(np.concatenate([base.face_groups[g] for g in PART_GROUPS["teeth"]]))
    upper = np.isin(faces, base.face_groups["helper-upper-teeth"])
    return bite(teeth_uvs(base.subset(faces), upper), upper)


def teeth_uvs(mesh: Mesh, upper: np.ndarray) -> Mesh:
    """The teeth part (both rows of the base mesh's teeth helpers) with UVs over the teeth
    texture (``looks.skin.teeth_texture``): u along the arch by length from one end (0) to
    the other (1), v from the gum side of the strip (1) over the outer face, the biting
    edge and the inner face (0).

    mesh: the teeth part, quads; upper: (F,) bool, its faces of the upper row. Each row is
    a grid strip four vertices deep; the gum side is its long boundary side highest up
    (upper row) or lowest down (lower row). Returns the mesh with one UV per face corner.
    """
    corners = np.zeros(mesh.faces.shape + (2,), np.float32)
    for rows, down in ((upper, 1.0), (~upper, -1.0)):
        faces = mesh.faces[rows]
        used, local = np.unique(faces, return_inverse=True)
        points = mesh.vertices[used]
        strip = Mesh(points, local.reshape(faces.shape).astype(np.int32))
        # Far above (upper) or below (lower): the nearest long side is the gum side.
        uv = strip_uvs(strip, points.mean(axis=0) + [0.0, 0.0, down])
        uv[:, 0] = _arch_length(points, uv)
        uv[:, 1] = 1.0 - uv[:, 1]
        corners[rows] = uv[local.reshape(faces.shape)]
    return per_corner(mesh, corners.reshape(-1, 2))


def _arch_length(points: np.ndarray, uv: np.ndarray) -> np.ndarray:
    """(V,) u of a teeth strip by length along the arch: each column's distance from the
    first, measured along the gum-side row and normalised to [0, 1]."""
    columns = np.unique(uv[:, 0])
    gum = np.stack([points[(uv[:, 0] == c) & (uv[:, 1] == 0)].mean(axis=0) for c in columns])
    length = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(gum, axis=0), axis=1))])
    return np.interp(uv[:, 0], columns, length / length[-1]).astype(np.float32)


# ---------------------------------------------------------------------------- facial hair


def mouth_frame(body: AuthoringBody) -> tuple[np.ndarray, np.ndarray, float, float]:
    """(skull centre (3,), mouth (3,): the upper teeth's centre, eye height z, chin z: the
    lowest skin of the face's front) of the authoring body."""
    centre, eye_z = head_frame(body)
    mouth = body.centre("helper-upper-teeth")
    skin = body.vertices[:BODY_VERTICES]
    head = skin[(body.part[:BODY_VERTICES] == "head") & (skin[:, 1] < centre[1] - 0.05)]
    return centre, mouth, eye_z, float(head[:, 2].min())


def facial_hair_density(body: AuthoringBody, part: str, points: np.ndarray) -> np.ndarray:
    """(N,) how densely facial hair grows at ``points`` (N, 3) on the skin, 0..1: 1 well
    inside, falling off smoothly at every edge (over ``EDGE_M``, 1 cm; up the cheeks over
    ``CHEEK_FADE_M``, ``looks.facial_hair.cheek_fade``), along a line that wanders by a
    few millimetres (a beard's edge is neither straight nor sharp).

    part "beard": chin, jaw, cheeks below the cheek line (``CHEEK_*``), sideburns,
    moustache and the throat under the chin; "moustache": the upper lip from under the
    nose, tapering down to points at the corners of the mouth. Lips are left to
    ``facial_hair_mask``."""
    centre, mouth, eye_z, chin_z = mouth_frame(body)
    turn = around(points, centre)
    rel_z = points[:, 2] - mouth[2]
    if part == "moustache":
        # Across the lip (0 middle, 1 corner of the mouth): the upper edge falls from
        # under the nose towards the corners, the lower one follows the lip line down.
        # Its top thins out over 6 mm under the nose (a 3 mm edge drew a hard top line).
        across = np.abs(points[:, 0]) / MOUSTACHE_HALF_M
        top = 0.018 - 0.03 * across**1.4
        bottom = -0.004 - 0.008 * across**2
        return (
            _soft((top - rel_z) / 0.006)
            * _soft((rel_z - bottom) / 0.002)
            * _soft((1 - across) / 0.12)
        )
    under = points[:, 2] - (chin_z - 0.02) + 0.5 * cheek_wobble(turn)  # the throat, down 2 cm
    return beard_edge(turn, rel_z) * _soft(under / EDGE_M) * (points[:, 2] < eye_z)


MOUSTACHE_HALF_M = 0.028  # from the middle of the lip to the corner of the mouth


def _soft(x: np.ndarray) -> np.ndarray:
    """(N,) a smooth step from 0 (x <= -0.5) to 1 (x >= 0.5): a line with a soft edge,
    x measured in units of the edge's width, centred on the line."""
    t = np.clip(x + 0.5, 0, 1)
    return t * t * (3 - 2 * t)


def facial_hair_mask(body: AuthoringBody, part: str) -> np.ndarray:
    """(F,) bool skin faces where facial hair may grow (``facial_hair_density`` above 0 at
    the face's centre): ``part`` "beard" or "moustache". Lips and the mouth's lining are
    left bare (MakeHuman's lips and inside-mouth region masks, by the skin's UVs), and
    only skin looking away from the head's axis (or down, under the chin) grows hair."""
    centre, mouth, *_ = mouth_frame(body)
    c = body.vertices[body.skin_faces].mean(axis=1)
    front = c[:, 1] < centre[1] - 0.01  # ahead of the ears
    bare = _region(body, "lips", 0.25) | _region(body, "inside-mouth", 0.1)
    # Skin facing away from the head's axis, or down (under the chin): not the mouth's
    # lining, which faces in.
    normal = body.skin_normals[body.skin_faces].mean(axis=1)
    radial = (c - centre)[:, :2]
    outside = (np.einsum("fd,fd->f", normal[:, :2], radial) > 0) | (normal[:, 2] < -0.5)
    grows = facial_hair_density(body, part, c) > 0.02
    if part == "moustache":
        grows &= c[:, 1] < mouth[1] - 0.01
    return grows & front & ~bare & outside


def _region(body: AuthoringBody, name: str, level: float) -> np.ndarray:
    """(F,) bool skin faces whose UV centre lies in a MakeHuman skin region mask."""
    from avatar.looks.skin import region_masks

    mask = region_masks(256)[name]
    base = body.base
    assert base.uvs is not None and base.face_uvs is not None, "the base mesh has UVs"
    uv = base.uvs[base.face_uvs[base.face_groups["body"]]].mean(axis=1)
    rows = np.clip(((1 - uv[:, 1]) * 256).astype(int), 0, 255)
    cols = np.clip((uv[:, 0] * 256).astype(int), 0, 255)
    return mask[rows, cols] > level


def _beard_flow(centre: np.ndarray):
    """Beard hair grows down the face and, under the chin, back down the throat; the
    moustache's down and out from the middle of the lip."""

    def flow(points: np.ndarray) -> np.ndarray:
        d = np.zeros_like(points)
        d[:, 2] = -1.0
        d[:, 1] = 0.6 * (points[:, 1] < centre[1] - 0.06)  # under the chin: towards the neck
        d[:, 0] = 0.25 * np.sign(points[:, 0]) * (np.abs(points[:, 0]) < 0.03)
        return d

    return flow


def beard(body: AuthoringBody, count: int = 1800, length=(0.007, 0.013)) -> Piece:
    """A short full beard: a dense undercoat of hair on the skin where it grows
    (``beard_undercoat``) under strand cards combed down the face (``beard_cards``).

    Cards alone, however many, left skin showing between them: 2,400 cards 4.4 mm wide
    with two in five of their texture's hairs kept covered some 70 % of the chin and
    cheeks, and the rest read as skin blotches (a grey beard on pale skin most).

    The cards grow in clumps, longest at the chin (``beard_reach``), over an undercoat in
    their shade, and single stray hairs break up its soft edges (``beard_strays``): one
    even pile of cards of one length, as light as the undercoat, read as felt. 1,800
    cards (7,200 vertices), a 780-vertex undercoat and ~480 strays stay under 10,000."""
    return join([beard_undercoat(body), beard_cards(body, count, length), beard_strays(body)])


BEARD_UNDERCOAT_EASE_M = 0.0006  # off the skin (stubble lies at 0.5 mm, under it)
UNDERCOAT_TILE_M = 0.04  # m of skin round the face across the hair texture's width


def beard_undercoat(body: AuthoringBody) -> Piece:
    """The beard's skin lifted 0.6 mm, mapped onto the undercoat rows of the beard
    material (``looks.facial_hair.beard_material``): u the arc round the face (in
    ``UNDERCOAT_TILE_M`` a texture width, so hairs keep their size), v from how thickly
    the beard grows there (``facial_hair_density`` -> ``facial_hair.undercoat_v``): fully
    covered well inside, thinning out to bare skin over the beard's soft edges."""
    from avatar.looks import facial_hair as fh

    faces = body.skin_faces
    mesh = cut(body, faces, facial_hair_mask(body, "beard"), BEARD_UNDERCOAT_EASE_M, relax=4)
    centre, *_ = mouth_frame(body)
    p = mesh.vertices.astype(np.float64)
    angle = np.arctan2(p[:, 0], -(p[:, 1] - centre[1]))
    u = (angle * fh.ARC_RADIUS_M + undercoat_wave(angle, p[:, 2])) / UNDERCOAT_TILE_M
    # Where the beard is full, v also climbs up the face (within the fully covered rows):
    # at one v the texture's tangent along v (the hairs' direction for the anisotropic
    # highlight) was undefined, and the chin shone as one smooth shell.
    density = facial_hair_density(body, "beard", p)
    up = (p[:, 2] - p[:, 2].min()) / max(float(np.ptp(p[:, 2])), 1e-6)
    v = fh.undercoat_v(density) + fh.UNDERCOAT_CLIMB * np.clip(density, 0, 1) * up
    uv = np.stack([u, v], -1)[mesh.faces].reshape(-1, 2)
    return bound(body, per_corner(mesh, uv.astype(np.float32)), faces)


UNDERCOAT_WAVE_M = 0.0012  # how far the undercoat's hairs wander sideways (m)


def undercoat_wave(angle: np.ndarray, z: np.ndarray) -> np.ndarray:
    """(N,) m the undercoat's u moves round the face at ``angle`` (radians round the
    head) and height ``z`` (m): two waves up the face whose phase turns round it, so its
    hairs lean some 10-20 degrees this way and that, patch by patch (u the arc alone
    combed every hair straight down the face, parallel, as corduroy's wales run)."""
    return UNDERCOAT_WAVE_M * (0.6 * np.sin(2 * np.pi * z / 0.021 + 3.1 * angle)
                               + 0.4 * np.sin(2 * np.pi * z / 0.013 - 5.3 * angle + 1.1))


def beard_cards(body: AuthoringBody, count: int = 2200, length=(0.007, 0.013)) -> Piece:
    """A short beard's strand cards rooted where ``facial_hair_density(body, "beard",
    ...)`` lets them grow, combed down the face, about a centimetre long, lying close to
    the skin, thinning out (sparser, shorter, flatter) over the last centimetre to its
    edges (up the cheeks over some two: ``looks.facial_hair.cheek_fade``). The hair
    above the mouth (the moustache) and the rest are bound apart: one rides the upper
    lip, the other the jaw, so opening the mouth parts them.

    One segment a card (4 vertices: a centimetre-long card bends over the jaw by a tenth
    of a millimetre between its ends)."""
    centre, mouth, *_ = mouth_frame(body)
    keep = facial_hair_mask(body, "beard")
    c = body.vertices[body.skin_faces].mean(axis=1)
    upper = (c[:, 2] > mouth[2] - 0.004) & (np.abs(c[:, 0]) < 0.035)
    share = (keep & upper).sum() / keep.sum()
    flow, lift = _beard_flow(centre), (0.001, 0.003)

    def density(points: np.ndarray) -> np.ndarray:
        return facial_hair_density(body, "beard", points)

    return join([
        cards_on(body, keep & upper, flow, int(count * share), length, BEARD_CARD_M, lift,
                 segments=1, density=density, strip=BEARD_STRIP, clump=BEARD_CLUMP,
                 taper=BEARD_TAPER),
        cards_on(body, keep & ~upper, flow, count - int(count * share), length, BEARD_CARD_M,
                 lift, segments=1, seed=2, density=density, strip=BEARD_STRIP,
                 reach=beard_reach(body), clump=BEARD_CLUMP, stand=0.8, taper=BEARD_TAPER),
    ])  # fmt: skip


BEARD_CLUMP = 7  # cards per clump (some 5 mm across where the beard is full)
# A short beard's length by where it grows: this factor on the cards' length on the cheeks
# (beyond ``BEARD_CHEEK_DEG`` round the face) and at the front of the chin; under the
# chin the throat's hair is shorter again.
BEARD_REACH = (0.7, 1.6)
BEARD_CHEEK_DEG = (25, 50)


def beard_reach(body: AuthoringBody):
    """points (N, 3) -> (N,) a factor on a short beard's card length: longest at the
    front of the chin below the lower lip (``BEARD_REACH[1]``), shortest on the cheeks
    (``BEARD_REACH[0]``), shorter under the chin, blending smoothly between."""
    centre, mouth, _, chin_z = mouth_frame(body)
    cheek, chin = BEARD_REACH

    def reach(points: np.ndarray) -> np.ndarray:
        turn = around(points, centre)
        front = np.clip((BEARD_CHEEK_DEG[1] - turn) / np.ptp(BEARD_CHEEK_DEG), 0, 1)
        below = np.clip((mouth[2] - 0.012 - points[:, 2]) / 0.025, 0, 1)
        throat = np.clip((chin_z - 0.005 - points[:, 2]) / 0.015, 0, 1)
        return (cheek + (chin - cheek) * front * below) * (1 - 0.3 * throat)

    return reach


BEARD_STRAY_M = 0.0015  # a stray card's width: a hair or two (``BEARD_STRAY_STRIP``)
BEARD_STRAY_STRIP = 0.015


def beard_strays(body: AuthoringBody, count: int = 480) -> Piece:
    """Single hairs over a short beard's soft edges (where ``facial_hair_density`` is
    between 0.02 and 0.7: the cheek line, the neck line, round the sideburns): narrow
    cards of a hair or two, standing a little off the skin, so the beard's edge breaks up
    into hairs instead of ending in a thinning mat."""
    centre, *_ = mouth_frame(body)
    c = body.vertices[body.skin_faces].mean(axis=1)
    d = facial_hair_density(body, "beard", c)
    keep = facial_hair_mask(body, "beard") & (d > 0.02) & (d < 0.7)

    def density(points: np.ndarray) -> np.ndarray:
        g = facial_hair_density(body, "beard", points)
        return np.clip(1 - np.abs(g - 0.3) / 0.35, 0, 1)

    return cards_on(body, keep, _beard_flow(centre), count, (0.006, 0.014), BEARD_STRAY_M,
                    (0.0015, 0.0055), segments=1, seed=6, density=density,
                    strip=BEARD_STRAY_STRIP)  # fmt: skip


BEARD_CARD_M = 0.0034  # a beard card's width at its root
# ... and at its tip, this share of it: a clump of cards ends in a point of a few hairs.
# Cards 4.4 mm wide ending at 70 % of it laid blunt, rounded tips over the next clump's
# roots, and the beard read as scales (flakes) rather than hair.
BEARD_TAPER = 0.3
# A beard or moustache card shows this share of the hair texture's width: some six of
# its kept hairs, each a few tenths of a millimetre (facial hair is coarse). Scalp cards'
# 0.12 drew some forty hairs a tenth as thick, under a pixel at any distance: a felt.
FACIAL_STRIP = 0.05
BEARD_STRIP = 0.08  # (a short beard's hairs, a centimetre long, as dashes at 0.05)


def moustache(body: AuthoringBody, count: int = 600) -> Piece:
    """A moustache: narrow strand cards (2.4 mm, a dozen hairs) over the upper lip, of
    uneven length, combed down and fanning out over it, full under the nose and tapering
    to points at the corners of the mouth (``facial_hair_density(body, "moustache",
    ...)``). Along the lip the hair grows in locks of their own length (``_lip_locks``),
    so its lower edge wanders over the lip instead of ending on one line."""
    centre, *_ = mouth_frame(body)
    keep = facial_hair_mask(body, "moustache")

    def density(points: np.ndarray) -> np.ndarray:
        return facial_hair_density(body, "moustache", points)

    return cards_on(body, keep, _moustache_flow(), count, (0.007, 0.015), 0.0024,
                    (0.001, 0.0025), seed=1, density=density, reach=_lip_locks(),
                    strip=FACIAL_STRIP)  # fmt: skip


def _lip_locks(seed: int = 5, spread: float = 0.4):
    """A factor on moustache cards' length by their place along the lip, points (N, 3) ->
    (N,): locks 3-6 mm wide, each up to ``spread`` longer or shorter than the mean (the
    cards' own random lengths alone averaged out, under 600 overlapping cards, into a
    straight lower edge a millimetre from a line)."""
    rng = np.random.default_rng(seed)
    knots = np.arange(-MOUSTACHE_HALF_M - 0.006, MOUSTACHE_HALF_M + 0.006, 0.0045)
    knots = knots + rng.uniform(-0.001, 0.001, len(knots))
    factor = 1 + spread * rng.uniform(-1, 1, len(knots))

    def reach(points: np.ndarray) -> np.ndarray:
        return np.interp(points[:, 0], knots, factor)

    return reach


def _moustache_flow():
    """Moustache hair grows down from the middle of the lip and fans out towards the
    corners of the mouth (a comb's chevron, not every card straight down: parallel cards
    read as a felt block)."""

    def flow(points: np.ndarray) -> np.ndarray:
        d = np.zeros_like(points)
        d[:, 2] = -1.0
        d[:, 0] = 0.15 * np.sign(points[:, 0]) + 0.7 * points[:, 0] / MOUSTACHE_HALF_M
        return d

    return flow


STUBBLE_TILE = 0.03  # m of skin one repeat of the stubble's stubs covers


def stubble(body: AuthoringBody) -> Piece:
    """Stubble: the beard's skin lifted half a millimetre, with UVs over the stubble atlas
    (``looks.facial_hair.stubble_material``) in metres along the skin, so the stubs keep
    their size everywhere: u the distance round the face from its midline (signed, over
    ``facial_hair.STUBBLE_SPAN_U``), v the height above the mouth on the face and, below
    the chin's tip, the distance down the skin from there (``STUBBLE_V``). Heights and
    angles alone squeezed the stubs into streaks under the chin, where the skin runs back
    level and close to the head's axis; under the chin and on the throat u is the arc
    round the neck and v the distance down the face's midline profile
    (``_down_the_face``). v is never stretched: where the cut reaches further down than
    ``STUBBLE_THROAT_M`` the stubble thins out under the jaw, above the cut's edge (a
    shorter face is squeezed onto it). The atlas's density fades out at the beard's cheek
    line, sideburns, throat and lips."""
    from avatar.looks import facial_hair as fh

    faces = body.skin_faces
    mesh = cut(body, faces, facial_hair_mask(body, "beard"), 0.0005, relax=4)
    centre, mouth, _, chin_z = mouth_frame(body)
    p = mesh.vertices.astype(np.float64)
    rel_z = p[:, 2] - mouth[2]
    normal = vertex_normals(mesh.vertices, mesh.faces)
    normal *= np.sign(np.einsum("vd,vd->", normal, p - centre))  # outward, whatever the winding
    # u: the arc round the face at ARC_RADIUS_M (the atlas's cheek line is drawn in
    # angles); nearer the head's axis (under the chin, the throat), where that arc would
    # squeeze the stubs, the arc round the neck at the point's own distance from the
    # neck's axis (under the chin, far in front of it, about x). (Measured over the cut's
    # edges, it wound round the holes the mask leaves under the jaw: 10 cm for a point
    # 2 cm off the midline; the skull's axis is 2 cm behind the throat: stubs squeezed
    # 2.4 times across the throat.)
    axis = centre - [0.0, fh.STUBBLE_BACK_M, 0.0]
    angle = np.arctan2(p[:, 0], -(p[:, 1] - axis[1]))
    near = np.clip((fh.ARC_RADIUS_M - np.hypot(p[:, 0], p[:, 1] - axis[1])) / 0.02, 0, 1)
    # ... below the jaw or facing down under it, not on the cheeks.
    near *= np.maximum(np.clip((chin_z + 0.01 - p[:, 2]) / 0.02, 0, 1),
                       np.clip((-normal[:, 2] - 0.3) / 0.3, 0, 1))  # fmt: skip
    neck = p[:, 1] - _neck_axis_y(body, chin_z - 0.035, centre)
    u_m = (1 - near) * angle * fh.ARC_RADIUS_M + near * np.hypot(p[:, 0], neck) * np.arctan2(
        p[:, 0], -neck)  # fmt: skip
    # v: the face's own height down to the chin's tip, then over the skin.
    v_m = np.where(rel_z >= 0, rel_z, _down_the_face(mesh, p, rel_z, normal, chin_z - mouth[2]))
    # The atlas's stubble thins out STUBBLE_THROAT_M down the skin from the mouth (just
    # under the jaw). A face whose cut reaches less far down is fitted to it (the stubs
    # a little shorter); one that reaches further is not stretched to it (stubs half as
    # long again under the chin): its stubble thins out under the jaw, before the cut.
    edge = np.median(v_m[np.abs(p[:, 2] - (chin_z - 0.02)) < 0.004])  # the throat's edge
    squeeze = max(1.0, fh.STUBBLE_THROAT_M / min(edge, -0.01))
    # (Below the atlas, where no stubble grows, v stays on its last, empty row.)
    v_m = np.maximum(np.where(v_m < 0, v_m * squeeze, v_m), fh.STUBBLE_V[0])
    u = (u_m / fh.STUBBLE_SPAN_U + 1) / 2
    v = (v_m - fh.STUBBLE_V[0]) / (fh.STUBBLE_V[1] - fh.STUBBLE_V[0])
    uv = np.stack([u, v], -1)[mesh.faces].reshape(-1, 2)
    return bound(body, per_corner(mesh, uv.astype(np.float32)), faces)


def _neck_axis_y(body: AuthoringBody, z: float, centre: np.ndarray) -> float:
    """y of the neck's vertical axis at height ``z``: the middle of its front-to-back
    extent there (the skin within 10 cm of the skull's centre line)."""
    skin = body.vertices[:BODY_VERTICES]
    ring = skin[(np.abs(skin[:, 2] - z) < 0.004) & (np.abs(skin[:, 0]) < 0.1)
                & (np.abs(skin[:, 1] - centre[1]) < 0.1)]  # fmt: skip
    return float(ring[:, 1].min() + ring[:, 1].max()) / 2 if len(ring) else float(centre[1])


def _down_the_face(mesh: Mesh, p: np.ndarray, rel_z: np.ndarray, normal: np.ndarray,
                   chin: float) -> np.ndarray:  # fmt: skip
    """(V,) m down from the mouth (negative) of the stubble's vertices below it: on the
    upright face its height (``rel_z``); under the chin and down the throat the distance
    over the skin from the chin's tip (``chin`` m below the mouth) along the face's
    midline profile, taken at the nearest point of that profile seen from the side, so
    that v runs straight down the throat whatever x. (Measured over the skin from the
    whole upright face, it ran in from the jaw's sides as much as down from the chin: v
    and u turned parallel on the throat and squeezed the stubs there 2.4 times.)"""
    upright = (rel_z >= chin) & (normal[:, 2] > -0.4)
    seeds = np.flatnonzero(upright & (np.abs(p[:, 0]) < 0.01))  # the chin's, not the jaw's
    down = -_over_the_skin(mesh, seeds, np.maximum(-rel_z[seeds], 0.0))
    profile = np.flatnonzero((np.abs(p[:, 0]) < 0.006) & ~upright)
    if len(profile) < 3:
        return np.where(upright, rel_z, down)
    profile = profile[np.argsort(-down[profile])]  # from the chin down the throat
    along = np.minimum(_along_polyline(p[profile, 1:], down[profile], p[:, 1:]), chin)
    # Under the jaw above the chin's tip: also the height above it (v = the height where
    # it meets the upright face; flat at the chin's, the stubs there were streaks).
    return np.where(upright, rel_z, along + np.maximum(rel_z - chin, 0.0))


def _along_polyline(line: np.ndarray, value: np.ndarray, points: np.ndarray) -> np.ndarray:
    """(N,) ``value`` (L,) interpolated at the nearest point of the polyline ``line``
    (L, 2) to each of ``points`` (N, 2)."""
    a, b = line[:-1], line[1:]  # (S, 2) segments
    d = b - a
    t = np.einsum("nsd,sd->ns", points[:, None] - a[None], d) / np.maximum(
        np.einsum("sd,sd->s", d, d), 1e-12)  # fmt: skip
    t = np.clip(t, 0, 1)
    gap = np.linalg.norm(points[:, None] - (a[None] + t[..., None] * d[None]), axis=2)
    s = gap.argmin(axis=1)
    k = np.arange(len(points))
    return value[:-1][s] + t[k, s] * (value[1:][s] - value[:-1][s])


def _over_the_skin(mesh: Mesh, seeds: np.ndarray, start: np.ndarray) -> np.ndarray:
    """(V,) metres over the mesh's edges from the nearest of the ``seeds`` (vertex
    indices), each already ``start`` (len(seeds),) m from the origin of the measure
    (a shortest-path search from a virtual source joined to each seed by its start)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import dijkstra

    n = len(mesh.vertices)
    a = mesh.faces.reshape(-1)
    b = np.roll(mesh.faces, -1, axis=1).reshape(-1)
    # Each edge once (a sparse matrix sums repeated entries: shared edges came doubled).
    edges = np.unique(np.sort(np.stack([a, b], 1)[a != b], axis=1), axis=0)
    a, b = edges.T
    length = np.linalg.norm(mesh.vertices[a] - mesh.vertices[b], axis=1).astype(np.float64)
    rows = np.concatenate([a, b, np.full(len(seeds), n)])
    cols = np.concatenate([b, a, seeds])
    weights = np.concatenate([length, length, np.asarray(start, np.float64) + 1e-9])
    graph = coo_matrix((weights, (rows, cols)), shape=(n + 1, n + 1)).tocsr()
    distance = dijkstra(graph, indices=n)[:n]
    return np.where(np.isfinite(distance), distance, 0.0)
