"""The body built-in garments are modelled on, and the geometry tools they are cut with.

The authoring body is the default human (all macros 0.5). Garments are cut from its
``helper-tights`` and ``helper-skirt`` shells (which MakeHuman's targets reshape for every
body) or from its skin, eased outward along the skin normal, given their own UVs, and then
bound with ``binder.bind`` to the surface they came from, so they follow every shape.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
from scipy.spatial import cKDTree

from avatar.body.model import BODY_VERTICES
from avatar.body.shaped import Body
from avatar.clothes import regions
from avatar.clothes.binder import bind
from avatar.clothes.binding import Binding, axis_scale, make_binding
from avatar.geometry.shell import boundary_edges
from avatar.looks.fabrics import TILE_METRES
from avatar.looks.tailored import Layout
from avatar.mesh import Mesh, face_edges, face_normals, vertex_normals


class AuthoringBody:
    """The default human with the derived data garment builders need."""

    def __init__(self, body: Body):
        self.body = body
        self.vertices = np.asarray(body.vertices, dtype=np.float64)
        self.base: Mesh = body.model.base
        self.marks = regions.landmarks(body.skeleton)
        self.part = regions.part_labels(body.skeleton.names, body.weights.indices[:, 0])

    @cached_property
    def skin_faces(self) -> np.ndarray:
        return self.base.faces[self.base.face_groups["body"]]

    @cached_property
    def skin_normals(self) -> np.ndarray:
        return vertex_normals(self.vertices[:BODY_VERTICES].astype(np.float32), self.skin_faces)

    @cached_property
    def skin_tree(self) -> cKDTree:
        return cKDTree(self.vertices[:BODY_VERTICES])

    def outward(self, points: np.ndarray) -> np.ndarray:
        """(N, 3) skin normal at the nearest skin vertex: 'away from the body' everywhere."""
        _, i = self.skin_tree.query(points)
        return self.skin_normals[i].astype(np.float64)

    def group_faces(self, group: str) -> np.ndarray:
        return self.base.faces[self.base.face_groups[group]]

    def centre(self, group: str) -> np.ndarray:
        return self.vertices[self.base.groups[group]].mean(axis=0)


@dataclass(frozen=True)
class Piece:
    """Garment geometry on the authoring body, bound to the surface it came from.

    layout: what to paint on a tailored garment's own texture (``looks.tailored``); None
    for garments textured with a tiling fabric.
    """

    mesh: Mesh
    binding: Binding
    layout: Layout | None = None


def cut(
    body: AuthoringBody,
    faces: np.ndarray,
    keep: np.ndarray,
    ease,
    relax: int = 0,
    loose: bool = False,
    sided: bool = False,
) -> Mesh:
    """A surface of the chosen faces, pushed ``ease`` metres out along the skin normal.

    faces: (F, 4) base-mesh faces of the source surface; keep: (F,) bool.
    ease: float or callable (points (N, 3), arm (N,), leg (N,)) -> (N,) metres.
    relax: smoothing passes over the cut's edges (``relax_boundary``); 0 keeps the mesh's
    staircase of whole faces.
    loose: ease along the source surface's own normal (``surface_normals``, for a surface
    standing off the body such as ``helper-skirt``), else along the skin's.
    sided: every move kept to its side of the body's midplane (``on_their_side``), for cloth
    that spans the cleft of the buttocks (a loose top) rather than following it.
    Returns a Mesh (own vertex numbering) with box-projected UVs; faces face outward.
    """
    chosen = faces[keep]
    used, inverse = np.unique(chosen, return_inverse=True)
    points = body.vertices[used]
    local = inverse.reshape(chosen.shape).astype(np.int32)
    normals = surface_normals(body, faces)[used] if loose else body.outward(points)
    if relax:
        points = relax_boundary(points, local, normals, relax, sided)
    if callable(ease):
        arm, leg = regions.limb_coordinates(points, body.marks)
        ease = ease(points, arm, leg)
    ease = np.broadcast_to(np.asarray(ease, dtype=np.float64), (len(points),))
    points = _eased(points, local, normals, ease, sided)
    ridge = float(body.marks.shoulder[:, 1].mean())
    mesh = with_box_uvs(orient_outward(body, points.astype(np.float32), local), ridge_y=ridge)
    return with_limb_uvs(mesh, body.part[used], body.marks)


# cos of the angle between two neighbouring faces below which cloth counts as folded back
# on itself (``_eased``); the ease kept each round at the folds' vertices, and the rounds.
FOLDED = -0.2
FOLD_EASE = 0.75
FOLD_ROUNDS = 12
# m either side of the midplane where folds are left alone: the cleft of the buttocks folds
# the eased cloth too, and ``builtin.bridged``/``spanned`` span it (less ease there left a
# groove down the back).
FOLD_MIDLINE = 0.05


def _eased(points: np.ndarray, faces: np.ndarray, normals: np.ndarray, ease: np.ndarray,
           sided: bool) -> np.ndarray:  # fmt: skip
    """(N, 3) points moved ``ease`` (N,) m along ``normals`` (N, 3), less where that folds
    the cloth: in a crease tighter than the ease (the armpit) the moved points cross over
    and faces turn 180 degrees against their neighbours (a dark triangle under the
    hoodie's and the jacket's arms). Each round, the folded faces' vertices and the ring
    round them keep ``FOLD_EASE`` of their ease (smoothed over their neighbours, so the
    cloth does not step), until no face folds."""
    ease = ease.copy()
    first, second = face_pairs(faces)
    a = faces.reshape(-1)
    b = np.roll(faces, -1, axis=1).reshape(-1)
    real = a != b
    a, b = np.concatenate([a[real], b[real]]), np.concatenate([b[real], a[real]])
    degree = np.maximum(np.bincount(a, minlength=len(points)), 1)
    for _ in range(FOLD_ROUNDS + 1):
        moves = ease[:, None] * normals
        out = points + (on_their_side(points, moves) if sided else moves)
        n = face_normals(out, faces)
        n /= np.maximum(np.linalg.norm(n, axis=1), 1e-12)[:, None]
        folded = np.einsum("nd,nd->n", n[first], n[second]) < FOLDED
        if not folded.any():
            break
        near = np.zeros(len(points), bool)
        near[faces[np.concatenate([first[folded], second[folded]])].ravel()] = True
        near[b[near[a]]] = True
        near &= np.abs(points[:, 0]) > FOLD_MIDLINE
        if not near.any():
            break
        ease[near] *= FOLD_EASE
        for _ in range(2):  # no step between the eased and the kept cloth
            mean = np.bincount(a, ease[b], minlength=len(points)) / degree
            ease = np.minimum(ease, 0.5 * (ease + mean))
    return out


def face_pairs(faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(P,), (P,) the two faces of every edge two faces (F, C) share."""
    edges, owner = face_edges(faces)
    order = np.lexsort(edges.T[::-1])
    edges, owner = edges[order], owner[order]
    shared = np.all(edges[1:] == edges[:-1], axis=1)
    return owner[:-1][shared], owner[1:][shared]


MIDPLANE = 1e-5  # m: a vertex this close to x = 0 lies on the body's plane of symmetry
CLEFT = 0.01  # m either side of the midplane: the half-width of the cleft of the buttocks


def on_their_side(points: np.ndarray, moves: np.ndarray, keep_length: bool = True) -> np.ndarray:
    """``moves`` (N, 3) m of ``points`` (N, 3), less their sideways part wherever it would
    carry a vertex across the body's midplane (x = 0), off it, over halfway to it or, within
    ``CLEFT`` of it, any nearer (``keep_length``: rescaled
    to their length, so an ease still clears the skin by as much).

    In a cleft (of the buttocks, between the breasts) the skin's normals point at the other
    side: eased along them the vertices either side of the midline crossed over (the left
    wall's 1 cm to the right of the right wall's), folding the cloth into itself, a thin
    dark slit on the back of every top. A move kept to its own side still clears the skin
    (its normal's other components point out of it too)."""
    moves = np.array(moves, dtype=np.float64)
    x = points[:, 0]
    on_plane = np.abs(x) < MIDPLANE
    # Halfway to the plane at most, and not at all within a cleft's width of it: closer,
    # the faces between a vertex and its mirror image collapse to slivers turning every way.
    towards = (x + moves[:, 0]) * np.sign(x) < np.where(np.abs(x) < CLEFT, np.abs(x), np.abs(x) / 2)
    crosses = on_plane | towards
    if not crosses.any() or not keep_length:
        moves[crosses, 0] = 0.0
        return moves
    length = np.linalg.norm(moves[crosses], axis=1)
    kept = moves[crosses] * np.array([0.0, 1.0, 1.0])
    kept_length = np.linalg.norm(kept, axis=1)
    scale = np.divide(length, kept_length, out=np.zeros_like(length), where=kept_length > 1e-9)
    moves[crosses] = kept * scale[:, None]
    return moves


def surface_normals(body: AuthoringBody, faces: np.ndarray) -> np.ndarray:
    """(V, 3) unit vertex normals of a source surface (base-mesh faces), turned to face away
    from the body. Easing along the surface's own normal keeps a loose surface smooth: the
    skin's normal would push neighbours of a skirt between the legs towards opposite legs.
    (A body-hugging surface eases along the skin's: its own folds into the crotch.)"""
    normals = vertex_normals(body.vertices.astype(np.float32), faces).astype(np.float64)
    used = np.unique(faces)
    agree = np.einsum("nd,nd->n", normals[used], body.outward(body.vertices[used]))
    return normals if agree.sum() >= 0 else -normals


def relax_boundary(
    points: np.ndarray, faces: np.ndarray, normals: np.ndarray, passes: int, sided: bool = False
) -> np.ndarray:
    """(N, 3) points with the open edges of a cut smoothed into curves.

    A cut along mesh faces ends in a staircase. Each pass smooths every boundary loop along
    itself (Taubin's shrink-free lambda/mu pair), then lets the next ring of vertices settle
    between their neighbours so the border faces keep their shape; every move stays in the
    surface's tangent plane at the vertex's original position (normals (N, 3)).
    Vertices where two loops touch stay put. ``sided``: moves kept to their side of the
    body's midplane (``on_their_side``).
    """
    edges, _ = boundary_edges(faces)
    count = len(points)
    seen = np.bincount(edges[:, 0], minlength=count)
    nxt = np.full(count, -1)
    prv = np.full(count, -1)
    nxt[edges[:, 0]], prv[edges[:, 1]] = edges[:, 1], edges[:, 0]
    loop = np.flatnonzero((seen == 1) & (nxt >= 0) & (prv >= 0))
    a = faces.reshape(-1)
    b = np.roll(faces, -1, axis=1).reshape(-1)
    ring = np.setdiff1d(np.unique(np.concatenate([b[np.isin(a, loop)], a[np.isin(b, loop)]])),
                        np.flatnonzero(seen > 0))  # fmt: skip
    origin, n = points.astype(np.float64), normals / np.linalg.norm(normals, axis=1)[:, None]
    p = origin.copy()

    def settle(moved: np.ndarray, which: np.ndarray) -> None:
        step = moved - origin[which]
        step -= np.einsum("nd,nd->n", step, n[which])[:, None] * n[which]
        if sided:  # a hem across a cleft: the walls' tangent planes slid it past itself
            step = on_their_side(origin[which], step, keep_length=False)
        p[which] = origin[which] + step

    for _ in range(passes):
        for weight in (0.5, -0.53):
            target = (p[nxt[loop]] + p[prv[loop]]) / 2
            settle(p[loop] + weight * (target - p[loop]), loop)
        total = np.zeros_like(p)
        degree = np.zeros(count)
        np.add.at(total, a, p[b])
        np.add.at(total, b, p[a])
        np.add.at(degree, a, 1)
        np.add.at(degree, b, 1)
        settle(0.5 * p[ring] + 0.5 * total[ring] / degree[ring, None], ring)
    return p


def orient_outward(body: AuthoringBody, points: np.ndarray, faces: np.ndarray) -> Mesh:
    """Flip faces whose normal points into the body (so shells extrude the right way)."""
    v = points[faces]
    n = np.cross(v[:, 2] - v[:, 0], v[:, 3 % faces.shape[1]] - v[:, 1])
    inward = np.einsum("fd,fd->f", n, body.outward(v.mean(axis=1))) < 0
    faces = faces.copy()
    faces[inward] = (
        faces[inward][:, [2, 1, 0, 3]] if faces.shape[1] == 4 else faces[inward][:, [0, 2, 1]]
    )
    return Mesh(vertices=points, faces=faces)


def with_box_uvs(mesh: Mesh, tile: float = TILE_METRES, ridge_y: float | None = None) -> Mesh:
    """Per-corner UVs by projecting each face on the plane its normal faces most (in tiles).

    Vertical faces keep z as v, so the fabric's warp runs down the body. ``ridge_y``: the
    y of the shoulders' ridge: faces facing up or down take v = z - |y - ridge_y|, rising
    towards the ridge from the front and from the back as the faces below them do, so a
    directional weave (a knit's V-loops) turns over only along the ridge, as at a
    shoulder seam (with v = y it turned over at the back of the shoulders, a chevron).
    """
    f = mesh.faces
    v = mesh.vertices[f].astype(np.float64)  # (F, C, 3)
    n = np.abs(np.cross(v[:, 2] - v[:, 0], v[:, -1] - v[:, 1]))
    axis = np.argmax(n, axis=1)[:, None]
    u = np.where(axis == 0, v[..., 1], v[..., 0])
    flat = v[..., 1] if ridge_y is None else v[..., 2] - np.abs(v[..., 1] - ridge_y)
    w = np.where(axis == 2, flat, v[..., 2])
    uvs = np.stack([u, w], -1).reshape(-1, 2) / tile
    face_uvs = np.arange(f.size, dtype=np.int32).reshape(f.shape)
    return Mesh(mesh.vertices, f, uvs.astype(np.float32), face_uvs)


def with_limb_uvs(mesh: Mesh, part: np.ndarray, marks, tile: float = TILE_METRES) -> Mesh:
    """Sleeves and trouser legs get cylinder UVs: u around the limb, v along it (in tiles).

    Box projection changes axis around a limb, which shows as seams where the weave turns;
    around a cylinder the fabric runs on, with one seam along the limb's underside.
    part: (V,) body part of each vertex; faces all of whose corners are "arm" (or "leg")
    are re-mapped, the rest keep their UVs.
    """
    assert mesh.uvs is not None, "with_limb_uvs re-maps per-corner UVs (with_box_uvs)"
    v = mesh.vertices.astype(np.float64)
    uvs = mesh.uvs.copy().reshape(mesh.faces.shape + (2,))
    for name, joints in (("arm", (marks.shoulder, marks.elbow, marks.wrist)),
                         ("leg", (marks.hip, marks.knee, marks.ankle))):  # fmt: skip
        faces = np.flatnonzero((part[mesh.faces] == name).all(axis=1))
        if len(faces) == 0:
            continue
        corners = v[mesh.faces[faces]]  # (F, C, 3)
        side = (corners.mean(axis=1)[:, 0] < 0).astype(int)  # 0: left (+x), 1: right
        a, b, c = (j[side][:, None, :] for j in joints)
        t = np.einsum("fcd,fcd->fc", corners - a, b - a) / np.einsum("fcd,fcd->fc", b - a, b - a)
        lower = t > 1
        start = np.where(lower[..., None], b, a)
        axis = np.where(lower[..., None], c - b, b - a)
        along = np.where(lower, np.linalg.norm(b - a, axis=-1), 0) + np.einsum(
            "fcd,fcd->fc", corners - start, axis / np.linalg.norm(axis, axis=-1, keepdims=True)
        )
        direction = axis / np.linalg.norm(axis, axis=-1, keepdims=True)
        radial = corners - start
        radial -= np.einsum("fcd,fcd->fc", radial, direction)[..., None] * direction
        front = np.cross(direction, [0.0, 0.0, 1.0]) if name == "arm" else np.array([0, -1.0, 0])
        front = front - np.einsum("...d,...d->...", front, direction)[..., None] * direction
        front /= np.linalg.norm(front, axis=-1, keepdims=True)
        up = np.cross(direction, front)
        angle = np.arctan2(np.einsum("fcd,fcd->fc", radial, up),
                           np.einsum("fcd,fcd->fc", radial, front))  # fmt: skip
        # One seam, at the angle facing away from the front; faces across it unwrapped.
        angle = np.where(angle.max(axis=1, keepdims=True) - angle > np.pi, angle + 2 * np.pi, angle)
        radius = np.linalg.norm(radial, axis=-1)  # per corner: a vertex maps the same in each face
        uvs[faces] = np.stack([angle * radius, -along], -1) / tile
    return Mesh(mesh.vertices, mesh.faces, uvs.reshape(-1, 2).astype(np.float32), mesh.face_uvs)


def bound(
    body: AuthoringBody, mesh: Mesh, surface_faces: np.ndarray, midline: float = 0.0
) -> Piece:
    """Bind a mesh on the authoring body to a surface (base-mesh faces); ``midline`` > 0:
    the vertices on the back within that many m of the midplane by ``across_the_cleft``."""
    binding = bind(mesh.vertices, body.vertices, surface_faces)
    if midline > 0:
        binding = across_the_cleft(body, mesh.vertices, binding, surface_faces, midline)
        binding = across_the_seat(body, mesh.vertices, binding, surface_faces)
    return Piece(mesh, binding)


SEAT_TOP = 0.08  # m above the hip joints where cloth on the back stops spanning the seat
SEAT_FADE = 0.04  # m below SEAT_TOP over which the span hands over to the local binding
SEAT_ROW = 0.012  # m up or down the body that counts as the same horizontal row
SEAT_REACH = (0.03, 0.14)  # m from the midplane where a buttock's crown is looked for


def seat_crowns(points: np.ndarray, candidates: np.ndarray, hip: np.ndarray) -> np.ndarray:
    """(N,) index into candidates (M, 3) of the rearmost one in each point's horizontal row
    on the right of the back (``SEAT_REACH`` from the midplane, within ``SEAT_ROW`` of the
    point's height): the crown of the right buttock at that height; -1 where none.
    hip: the right hip joint (3,)."""
    c = np.asarray(candidates, dtype=np.float64)
    side = (c[:, 0] > SEAT_REACH[0]) & (c[:, 0] < SEAT_REACH[1]) & (c[:, 1] > hip[1])
    pick = np.flatnonzero(side)
    if len(pick) == 0:
        return np.full(len(points), -1)
    row = np.abs(points[:, None, 2] - c[None, pick, 2]) < SEAT_ROW  # (N, M')
    depth = np.where(row, c[None, pick, 1], -np.inf)
    best = np.argmax(depth, axis=1)
    return np.where(row.any(axis=1), pick[best], -1)


def seat_share(body: AuthoringBody, points: np.ndarray) -> np.ndarray:
    """(N,) 0..1: how much each point (N, 3) belongs to the seat on the back, where loose
    cloth spans from buttock to buttock: 1 below ``SEAT_TOP - SEAT_FADE`` above the hip
    joints, fading to 0 at ``SEAT_TOP``; 0 on the front."""
    hip = body.marks.hip[0]
    t = np.clip((hip[2] + SEAT_TOP - points[:, 2]) / SEAT_FADE, 0, 1)
    return np.where(points[:, 1] > hip[1], t * t * (3 - 2 * t), 0.0)


def across_the_seat(body: AuthoringBody, points: np.ndarray, binding: Binding,
                    surface_faces: np.ndarray) -> Binding:  # fmt: skip
    """``binding`` with the points (N, 3) on the seat between the buttocks' crowns
    re-anchored on the straight line from the left crown to the right one at their height
    (``seat_crowns`` on the surface), handing over to their nearest surface vertex at the
    top of the seat (``seat_share``).

    Loose cloth hangs from the crowns of the buttocks and spans the cleft between them.
    Bound to the surface under it, a cardigan's back hem followed the elderly woman's
    sagging body: the buttocks drop more than the cleft, and the hem stood 3 cm higher at
    the midline than 8.5 cm to the side and 29 mm forward, a heart shape from behind.
    Anchored on the crowns it drops with them and stays level."""
    v = np.asarray(points, dtype=np.float64)
    x = body.vertices.astype(np.float64)
    shell = np.unique(surface_faces)
    share = seat_share(body, v)
    crown = seat_crowns(v, x[shell], body.marks.hip[0])
    right = shell[np.maximum(crown, 0)]
    tree = cKDTree(x[shell])
    left = shell[tree.query(x[right] * np.array([-1.0, 1.0, 1.0]))[1]]
    pick = np.flatnonzero((share > 0) & (crown >= 0) & (np.abs(v[:, 0]) < x[right, 0]))
    if len(pick) == 0:
        return binding
    right, left, s = right[pick], left[pick], share[pick]
    span = x[right, 0] - x[left, 0]
    u = np.clip((v[pick, 0] - x[left, 0]) / span, 0, 1)  # along the line, left to right
    near = _nearest_on_its_side(x[shell], v[pick], shell)
    indices, weights = binding.indices.copy(), binding.weights.copy()
    offsets = binding.offsets.copy()
    indices[pick] = np.stack([left, right, near], axis=1)
    weights[pick] = np.stack([s * (1 - u), s * u, 1 - s], axis=1)
    anchor = np.einsum("nk,nkd->nd", weights[pick], x[indices[pick]])
    offsets[pick] = (v[pick] - anchor) / axis_scale(binding, x)
    return make_binding(indices, weights, offsets, binding.scale_refs, binding.scale_lengths)


def across_the_cleft(body: AuthoringBody, points: np.ndarray, binding: Binding,
                     surface_faces: np.ndarray, width: float) -> Binding:  # fmt: skip
    """``binding`` with the points (N, 3) on the back within ``width`` m of the midplane
    re-anchored half-way between their nearest surface vertex and its mirror image, their
    sideways offset scaling with the body's width.

    Cloth spanning the cleft of the buttocks was bound to the cleft's nearest wall; on
    another body the wall turned and the fixed offset carried the vertices on the midline
    past their neighbours (a heavy man's hoodie folded 174 degrees into itself, a thin
    dark slit above the hem). Anchored on the midplane they keep their side and order on
    every (symmetric) body, and follow the height of the walls beside them."""
    v = np.asarray(points, dtype=np.float64)
    x = body.vertices.astype(np.float64)
    pick = np.flatnonzero((np.abs(v[:, 0]) < width) & (v[:, 1] > body.marks.hip[0, 1]))
    if len(pick) == 0:
        return binding
    shell = np.unique(surface_faces)
    tree = cKDTree(x[shell])
    near = _nearest_on_its_side(x[shell], v[pick], shell)
    mirror = shell[tree.query(x[near] * np.array([-1.0, 1.0, 1.0]))[1]]
    indices, weights = binding.indices.copy(), binding.weights.copy()
    offsets = binding.offsets.copy()
    indices[pick] = np.stack([near, mirror, near], axis=1)
    weights[pick] = (0.5, 0.5, 0.0)
    anchor = (x[near] + x[mirror]) / 2
    offsets[pick] = (v[pick] - anchor) / axis_scale(binding, x)
    return make_binding(indices, weights, offsets, binding.scale_refs, binding.scale_lengths)


def _nearest_on_its_side(surface: np.ndarray, points: np.ndarray, ids: np.ndarray) -> np.ndarray:
    """(N,) ids of the nearest of surface (M, 3) to each point (N, 3) on the same side of
    the midplane, midplane points to a midplane vertex: a point on the midline then stays
    on it on every (symmetric) body, as its left and right neighbours stay apart."""
    side = np.sign(np.where(np.abs(surface[:, 0]) < 1e-4, 0.0, surface[:, 0]))
    want = np.sign(np.where(np.abs(points[:, 0]) < 1e-4, 0.0, points[:, 0]))
    out = np.zeros(len(points), dtype=ids.dtype)
    for s in np.unique(want):
        mine = np.flatnonzero(side == s)
        if len(mine) == 0:
            mine = np.arange(len(surface))
        rows = want == s
        out[rows] = ids[mine[cKDTree(surface[mine]).query(points[rows])[1]]]
    return out


def single_references(body: AuthoringBody, group: str, uvs_from_base: bool = True) -> Piece:
    """A helper group used as is, each vertex a single-vertex reference (MakeHuman's
    eyelashes are bound this way), with the base mesh's UVs."""
    fidx = body.base.face_groups[group]
    mesh = body.base.with_vertices(body.vertices.astype(np.float32)).subset(fidx)
    used = np.unique(body.base.faces[fidx])
    n = len(used)
    binding = make_binding(
        np.repeat(used[:, None], 3, 1),
        np.tile([1.0, 0, 0], (n, 1)),
        np.zeros((n, 3)),
        single=np.ones(n, bool),
    )
    return Piece(mesh, binding)


def join(pieces: list[Piece]) -> Piece:
    """One garment from several pieces (e.g. a dress's bodice and skirt)."""
    meshes = [p.mesh for p in pieces]
    if any(m.uvs is None or m.face_uvs is None for m in meshes):
        raise ValueError("join needs pieces with UVs")
    offset = np.cumsum([0, *(len(m.vertices) for m in meshes)])
    uv_offset = np.cumsum([0, *(len(m.uvs) for m in meshes)])  # type: ignore[arg-type]
    width = max(m.faces.shape[1] for m in meshes)
    faces = np.concatenate([_pad(m.faces, width) + o for m, o in zip(meshes, offset, strict=False)])
    fuv = np.concatenate(
        [_pad(m.face_uvs, width) + o for m, o in zip(meshes, uv_offset, strict=False)]  # type: ignore[arg-type]
    )
    mesh = Mesh(
        np.concatenate([m.vertices for m in meshes]),
        faces.astype(np.int32),
        np.concatenate([m.uvs for m in meshes]),
        fuv.astype(np.int32),
    )
    b = [p.binding for p in pieces]
    binding = make_binding(
        np.concatenate([x.indices for x in b]),
        np.concatenate([x.weights for x in b]),
        np.concatenate([x.offsets for x in b]),
        b[0].scale_refs,
        b[0].scale_lengths,
        np.concatenate([x.single for x in b]),
    )
    layout = next((p.layout for p in pieces if p.layout is not None), None)
    return Piece(mesh, binding, layout)


def _pad(a: np.ndarray, width: int) -> np.ndarray:
    if a.shape[1] == width:
        return a
    return np.concatenate([a, np.repeat(a[:, -1:], width - a.shape[1], 1)], 1)


def covered_skin(body: AuthoringBody, mesh: Mesh, reach: float = 0.02) -> np.ndarray:
    """(D,) int32 skin vertices within ``reach`` of the garment (to hide if the user asks)."""
    tree = cKDTree(mesh.vertices)
    d, _ = tree.query(body.vertices[:BODY_VERTICES], distance_upper_bound=reach)
    return np.flatnonzero(np.isfinite(d)).astype(np.int32)


def banded(mesh: Mesh, width=0.015, lift: float = 0.0015) -> Mesh:
    """The mesh with a band along every open edge (neckline rib, hem, cuffs): the faces
    within ``width`` m of an edge again, ``lift`` m further out, and a lip joining the edge
    to the band's, so the edge has a thickness and the band stands proud of the cloth.
    width: metres, or a callable (R, 3) edge points -> (R,) metres (a waistband wider than
    the hems).

    mesh: an outward-facing garment surface with per-corner UVs (``with_box_uvs``); the
    band's faces keep the UVs of the faces they copy. Returns a new Mesh.
    """
    assert mesh.uvs is not None and mesh.face_uvs is not None, "banded needs per-corner UVs"
    edges, owner = boundary_edges(mesh.faces)
    if len(edges) == 0:
        return mesh
    v = mesh.vertices.astype(np.float64)
    rim = np.unique(edges)
    near, which = cKDTree(v[rim]).query(v)
    widths = np.asarray(width(v[rim]) if callable(width) else np.full(len(rim), width))
    inside = near < widths[which]
    band = _band_runs(mesh.faces, np.flatnonzero(inside[mesh.faces].all(axis=1)), v, edges,
                      owner[:, 0])  # fmt: skip
    normals = vertex_normals(mesh.vertices, mesh.faces).astype(np.float64)
    n = len(v)
    copied = np.unique(np.concatenate([mesh.faces[band].ravel(), rim]))  # only these lift
    new = np.full(n, -1)
    new[copied] = n + np.arange(len(copied))
    lifted = v[copied] + lift * normals[copied]
    faces = [mesh.faces, new[mesh.faces[band]]]
    face_uvs = [mesh.face_uvs, mesh.face_uvs[band]]
    # The lip: a quad per open edge, from the edge up to the band's edge.
    lip = np.stack([edges[:, 1], edges[:, 0], new[edges[:, 0]], new[edges[:, 1]]], 1)
    faces.append(_pad(lip, mesh.faces.shape[1]))
    corner_uv = np.zeros((n, 2), np.float32)
    corner_uv[mesh.faces.ravel()] = mesh.uvs[mesh.face_uvs.ravel()]
    source = np.stack([edges[:, 1], edges[:, 0], edges[:, 0], edges[:, 1]], 1)
    uvs = np.concatenate([mesh.uvs, corner_uv[source.ravel()]])
    lip_uvs = len(mesh.uvs) + np.arange(lip.size, dtype=np.int32).reshape(lip.shape)
    face_uvs.append(_pad(lip_uvs, mesh.faces.shape[1]))
    return Mesh(np.concatenate([v, lifted]).astype(np.float32),
                np.concatenate(faces).astype(np.int32), uvs.astype(np.float32),
                np.concatenate(face_uvs).astype(np.int32))  # fmt: skip


# m of open edge a band must run along: where an edge's faces are wider than the band, one
# or two narrower faces made a lone patch, 1.5 mm proud with lips on its sides only, that
# rendered as a dark rectangle (two at the jacket's opening, at the waist).
BAND_MIN_RUN = 0.08


def _band_runs(faces: np.ndarray, band: np.ndarray, v: np.ndarray, edges: np.ndarray,
               edge_face: np.ndarray) -> np.ndarray:  # fmt: skip
    """The faces of ``band`` (B,) in runs (joined through shared edges) along at least
    ``BAND_MIN_RUN`` m of the open ``edges`` (E, 2) (``edge_face`` (E,): each one's face)."""
    if len(band) == 0:
        return band
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    pairs, owner = face_edges(faces[band])
    _, key, count = np.unique(pairs, axis=0, return_inverse=True, return_counts=True)
    key = key.ravel()
    order = np.argsort(key, kind="stable")
    shared = (key[order][1:] == key[order][:-1]) & (count[key[order][1:]] == 2)
    a, b = owner[order][:-1][shared], owner[order][1:][shared]
    graph = coo_matrix((np.ones(len(a)), (a, b)), shape=(len(band), len(band)))
    _, run = connected_components(graph, directed=False)
    slot = np.full(len(faces), -1)
    slot[band] = np.arange(len(band))
    mine = slot[edge_face] >= 0
    length = np.linalg.norm(v[edges[mine, 0]] - v[edges[mine, 1]], axis=1)
    along = np.bincount(run[slot[edge_face[mine]]], length, minlength=run.max() + 1)
    return band[along[run] >= BAND_MIN_RUN]


def boundary_loops(faces: np.ndarray) -> list[np.ndarray]:
    """Vertex indices of each open boundary loop of faces (F, C) (unordered)."""
    edges, _ = boundary_edges(faces)
    if len(edges) == 0:
        return []
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    rim, local = np.unique(edges, return_inverse=True)
    local = local.reshape(edges.shape)
    graph = coo_matrix((np.ones(len(local)), (local[:, 0], local[:, 1])),
                       shape=(len(rim), len(rim)))  # fmt: skip
    count, label = connected_components(graph, directed=False)
    return [rim[label == k] for k in range(count)]


def level_hems(mesh: Mesh, reach: float = 0.035, flat: float = 0.1,
               open_front: bool = False) -> Mesh:  # fmt: skip
    """The mesh with each nearly flat open edge (a hem, a cuff, a waist; not a scooped
    neckline or an armhole) laid on its best-fit plane, the move fading out over ``reach``
    m into the cloth: a cut that follows the helper mesh's faces wanders 5-12 mm about
    that plane, a wavy hem. ``flat``: largest RMS distance from the plane, as a share of
    the loop's mean radius, of a loop that is levelled. ``open_front``: a garment open
    down the front, whose hem runs on up the opening and round the neck in one loop that
    is not flat: its hem run (``hem_run``) is levelled alone."""
    v = mesh.vertices.astype(np.float64)
    shift = np.zeros_like(v)
    ends: list[np.ndarray] = []
    for loop in boundary_loops(mesh.faces):
        if len(loop) < 8:
            continue
        if not _flat(v[loop], flat):
            if not open_front:
                continue
            loop = hem_run(v, in_order(loop, mesh.faces))
            if len(loop) < 8:
                continue
        p = v[loop]
        centre = p.mean(axis=0)
        normal = np.linalg.svd(p - centre)[2][2]
        shift[loop] = -((p - centre) @ normal)[:, None] * normal
        ends.append(loop)
    if not ends:
        return mesh
    rim = np.concatenate(ends)
    distance, nearest = cKDTree(v[rim]).query(v)
    t = np.clip(1 - distance / reach, 0, 1)
    moved = v + (t * t * (3 - 2 * t))[:, None] * shift[rim[nearest]]
    return Mesh(moved.astype(np.float32), mesh.faces, mesh.uvs, mesh.face_uvs)


def _flat(p: np.ndarray, flat: float) -> bool:
    """Whether points (L, 3) lie within ``flat`` x their mean radius (RMS) of a plane."""
    p = p - p.mean(axis=0)
    off = p @ np.linalg.svd(p)[2][2]
    return bool(np.sqrt(np.mean(off**2)) <= flat * np.linalg.norm(p, axis=1).mean())


def hem_run(v: np.ndarray, loop: np.ndarray) -> np.ndarray:
    """The vertices of a boundary ``loop`` (in order round it, over v (N, 3)) along its
    hem: from its lowest vertex on either way while the loop runs more across than down
    from each vertex's neighbour before to the one after (an open cardigan's hem, up to
    the corners where it turns up the opening; over two edges, as the cut dips 5 mm into
    the cleft of the buttocks across one short edge at the back's midline)."""
    p = v[loop]
    d = np.roll(p, -1, axis=0) - np.roll(p, 1, axis=0)
    across = np.abs(d[:, 2]) < 0.5 * np.hypot(d[:, 0], d[:, 1])
    if across.all():
        return loop
    n, low = len(loop), int(np.argmin(p[:, 2]))
    last = first = low
    while across[(last + 1) % n]:
        last += 1
    while across[(first - 1) % n]:
        first -= 1
    return loop[np.arange(first, last + 1) % n]


def in_order(loop: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """The vertices of one open boundary ``loop`` (as ``boundary_loops`` gives them) in
    order round it, as the faces (F, C) wind; where the rim pinches (a vertex on it twice)
    only the part from its first vertex round to the pinch."""
    edges, _ = boundary_edges(faces)
    mine = np.isin(edges[:, 0], loop)
    following = dict(zip(edges[mine, 0].tolist(), edges[mine, 1].tolist(), strict=True))
    order = [int(loop[0])]
    seen = set(order)
    step = following.get(order[0], order[0])
    while step not in seen:
        order.append(step)
        seen.add(step)
        step = following.get(step, order[0])
    return np.asarray(order, np.intp)
