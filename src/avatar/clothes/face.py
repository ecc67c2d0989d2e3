"""Face pieces: eyebrows painted on patches of the brow skin, eyelashes on the base mesh's
lash helper strips (textures in ``textures``: ``brow_alpha``, ``lash_alpha``)."""

from __future__ import annotations

import numpy as np

from avatar.clothes.authoring import AuthoringBody, Piece, bound, cut, join, single_references
from avatar.clothes.hair import per_corner
from avatar.geometry.shell import boundary_edges
from avatar.mesh import Mesh


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
