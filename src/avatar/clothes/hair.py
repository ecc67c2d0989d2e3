"""Head pieces grown from the skin: hair caps, hair cards, a cap's brim, eyebrows.

Hair textures share one layout: v in [0.5, 1] is dense (caps), v in [0, 0.5] is strand cards
from root (v = 0.5) to tip (v = 0), their alpha thinning towards the tips.
"""

from __future__ import annotations

import numpy as np

from avatar.clothes.authoring import (
    SKIN,
    AuthoringBody,
    Piece,
    bound,
    cut,
    join,
    orient_outward,
    single_references,
)
from avatar.clothes.shell import boundary_edges
from avatar.mesh import Mesh


def eye_level(body: AuthoringBody) -> tuple[np.ndarray, float]:
    """(head centre (3,), eye height z) of the authoring body."""
    left, right = body.centre("helper-l-eye"), body.centre("helper-r-eye")
    head = body.vertices[:SKIN][body.part[:SKIN] == "head"]
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
# curving over each ear and down to the nape.
HAIRLINE_DEG = (0, 30, 45, 60, 72, 76, 84, 88, 112, 120, 140, 180)
HAIRLINE_M = (0.07, 0.068, 0.072, 0.05, 0.03, -0.012, -0.012, 0.035, 0.035, -0.02, -0.055, -0.065)


def head_frame(body: AuthoringBody) -> tuple[np.ndarray, float]:
    """(centre of the skull (3,), eye height z): the middle of the head's front-to-back and
    side-to-side extent at eye height (the face's dense vertices do not pull it forward)."""
    _, eye_z = eye_level(body)
    head = body.vertices[:SKIN][body.part[:SKIN] == "head"]
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
    near = np.hypot(c[:, 0], c[:, 1] - centre[1]) < 0.11
    return near & (c[:, 2] > line) & ~ear


def base_cap(body: AuthoringBody, ease: float = 0.002) -> Piece:
    """The scalp inside the hairline as a dense hair surface (what shows between cards)."""
    faces = body.skin_faces
    mesh = cut(body, faces, hairline_mask(body), ease, relax=8)
    centre, _ = head_frame(body)
    return bound(body, cap_uvs(mesh, centre), faces)


def flow_crown(crown_offset=(0.0, 0.035, 0.1), sweep: float = 0.6):
    """A hair flow field radiating from the crown, the front swept towards +x."""

    def flow(points: np.ndarray, centre: np.ndarray, eye_z: float) -> np.ndarray:
        crown = centre + np.asarray(crown_offset)
        d = points - crown
        front = np.clip((centre[1] - points[:, 1]) / 0.08, 0, 1) * np.clip(
            (points[:, 2] - eye_z - 0.04) / 0.04, 0, 1
        )
        d[:, 0] += sweep * front * np.linalg.norm(d, axis=1)
        return d

    return flow


def flow_tied(tie_offset=(0.0, 0.07, 0.0)):
    """A hair flow field drawn back to a tie point behind the head."""

    def flow(points: np.ndarray, centre: np.ndarray, eye_z: float) -> np.ndarray:
        return centre + np.asarray(tie_offset) - points

    return flow


def grow_cards(
    body: AuthoringBody,
    flow,
    count: int = 700,
    length=(0.035, 0.055),
    width: float = 0.015,
    lift=(0.006, 0.022),
    segments: int = 4,
    seed: int = 0,
) -> Piece:
    """Hair cards rooted inside the hairline, lying along a flow field above the scalp.

    Each card starts a few millimetres above the scalp and rises to its lift as it runs
    ``length`` metres along the flow, so higher cards cover lower ones the way layered hair
    does; ``lift`` (low, high) grows from the hairline (low) to the top of the head (high).
    UVs: a random column strip of the strand half of the hair texture, roots at v = 0.5.
    """
    rng = np.random.default_rng([seed, count])
    centre, eye_z = head_frame(body)
    roots = _scatter(body, hairline_mask(body, 0.004), count, rng)
    depth = roots[:, 2] - eye_z - np.interp(around(roots, centre), HAIRLINE_DEG, HAIRLINE_M)
    top = lift[0] + (lift[1] - lift[0]) * np.clip(depth / 0.06, 0, 1)
    top *= rng.uniform(0.55, 1.0, count)
    # Short at the hairline (a fringe would hang over the face), full length further in.
    size = rng.uniform(*length, count) * (0.45 + 0.55 * np.clip(depth / 0.04, 0, 1))
    rows = [roots]
    point = roots
    for k in range(1, segments + 1):
        step = _tangent(body, point, flow(point, centre, eye_z))
        point = _above_skin(body, point + step * (size / segments)[:, None],
                            0.002 + (top - 0.002) * (k / segments) ** 0.7)  # fmt: skip
        rows.append(point)
    path = np.stack(rows, 1)  # (N, K+1, 3)
    side = np.cross(
        body.outward(path.reshape(-1, 3)).reshape(path.shape), np.gradient(path, axis=1)
    )
    side /= np.linalg.norm(side, axis=-1, keepdims=True)
    half = (
        (width / 2)
        * rng.uniform(0.7, 1.2, count)[:, None, None]
        * np.linspace(1, 0.7, segments + 1)[None, :, None]
    )
    verts = np.concatenate([path - half * side, path + half * side], 1)  # (N, 2(K+1), 3)
    n = segments + 1
    k = np.arange(segments)
    quad = np.stack([k, k + 1, n + k + 1, n + k], 1)
    faces = (quad[None] + (2 * n * np.arange(count))[:, None, None]).reshape(-1, 4)
    u0 = rng.uniform(0, 1, count)[:, None]
    t = np.linspace(0, 1, n)[None, :]
    uv = np.concatenate(
        [np.stack(np.broadcast_arrays(u0, 0.5 * (1 - t)), -1),
         np.stack(np.broadcast_arrays(u0 + 0.12, 0.5 * (1 - t)), -1)], 1
    )  # fmt: skip
    mesh = orient_outward(body, verts.reshape(-1, 3).astype(np.float32), faces.astype(np.int32))
    mesh = Mesh(mesh.vertices, mesh.faces, uv.reshape(-1, 2).astype(np.float32), mesh.faces.copy())
    return bound(body, mesh, body.skin_faces)


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


def helper_cards(body: AuthoringBody, layers=(0.006, 0.014, 0.022)) -> Piece:
    """Long hair: MakeHuman's ``helper-hair`` strips, repeated in layers for volume, with
    strand UVs (v 0.5 at the roots down to 0 at the tips)."""
    src = body.group_faces("helper-hair")
    centre, eye_z = eye_level(body)
    mid = body.vertices[src].mean(axis=1)
    # MakeHuman's strips include fringe locks over the face; a style you can see through keeps
    # only those beside and behind the eyes.
    src = src[~((mid[:, 1] < centre[1] - 0.02) & (mid[:, 2] < eye_z + 0.04))]
    used, inv = np.unique(src, return_inverse=True)
    pts = body.vertices[used]
    local = inv.reshape(src.shape).astype(np.int32)
    top, low = pts[:, 2].max(), pts[:, 2].min()
    meshes = []
    for k, ease in enumerate(layers):
        p = pts + ease * body.outward(pts)
        rel = p - centre
        u = (np.arctan2(rel[:, 0], -rel[:, 1]) / np.pi + 1) * 3.0 + 0.37 * k
        v = 0.5 * (p[:, 2] - low) / (top - low)
        meshes.append((p, np.stack([u, v], 1)))
    verts = np.concatenate([m[0] for m in meshes]).astype(np.float32)
    uvs = np.concatenate([m[1] for m in meshes]).astype(np.float32)
    faces = np.concatenate([local + i * len(pts) for i in range(len(layers))])
    mesh = orient_outward(body, verts, faces)
    mesh = Mesh(mesh.vertices, mesh.faces, uvs, mesh.faces.copy())
    return bound(body, mesh, body.skin_faces)


def ponytail(body: AuthoringBody, length: float = 0.3, cards: int = 4, rows: int = 12) -> Piece:
    """A tied-back tail: crossed strand cards hanging from the back of the head."""
    centre, eye_z = eye_level(body)
    back = body.vertices[:SKIN][body.part[:SKIN] == "head"][:, 1].max()
    root = np.array([0.0, back + 0.01, eye_z + 0.02])
    t = np.linspace(0, 1, rows + 1)
    # The tail falls back and down, then down along the upper back.
    spine = root + np.stack([0 * t, 0.05 * np.sin(t * np.pi / 2) + 0.03 * t, -length * t], 1)
    width = 0.045 * (1 - 0.6 * t) + 0.01
    verts, uvs, faces = [], [], []
    for c in range(cards):
        angle = np.pi * c / cards
        side = np.array([np.cos(angle), np.sin(angle) * 0.5, 0.0])
        start = len(verts) and sum(len(x) for x in verts)
        left = spine - width[:, None] * side
        right = spine + width[:, None] * side
        verts.append(np.concatenate([left, right]))
        u0 = 0.3 * c
        uvs.append(
            np.concatenate(
                [
                    np.stack([np.full_like(t, u0), 0.5 * (1 - t)], 1),
                    np.stack([np.full_like(t, u0 + 0.25), 0.5 * (1 - t)], 1),
                ]
            )
        )
        i = np.arange(rows)
        n = rows + 1
        faces.append(np.stack([i, i + 1, n + i + 1, n + i], 1) + start)
    mesh = Mesh(
        np.concatenate(verts).astype(np.float32),
        np.concatenate(faces).astype(np.int32),
        np.concatenate(uvs).astype(np.float32),
        np.concatenate(faces).astype(np.int32),
    )
    return bound(body, mesh, body.skin_faces)


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
    fuv = mesh.face_uvs.copy()
    fuv[flip] = fuv[flip][:, [2, 1, 0, 3]]
    return Mesh(mesh.vertices, faces, mesh.uvs, fuv)


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
    side nearest ``eye`` (the root side), u the hop distance from one short side, both
    scaled to [0, 1]."""
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
    short = sorted(sides, key=len)[0]
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
