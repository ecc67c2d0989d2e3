"""Signed distance of points to the closed body surface, and push-out with a clearance.

The body (hm08's 13,380 body vertices, 13,378 quads) is watertight, so "inside" is well
defined. A point's signed distance is measured to its closest point on the body's triangles,
with the sign and push direction taken from the vertex normals interpolated at that point
(for a closest point on an edge or corner this matches the angle-weighted pseudo-normal's
sign on every convex or concave feature, and gives a smooth push direction).

Speed: candidate triangles are the one-rings of the k nearest body vertices (a
``nearest.PointTree``), then all candidates are tested at once with array maths on
coordinate arrays (Ericson's closest-point-on-triangle regions).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property, lru_cache

import numpy as np
from scipy.sparse import csr_matrix

from avatar.body.model import BODY_VERTICES

from .nearest import PointTree

TIE = 2e-4  # m: skin as near as the nearest within this is asked whether the point is inside
SAME = 1e-5  # m: closest points nearer each other than this are the same point of the skin


@dataclass(frozen=True)
class BodySurface:
    """Topology of a closed body surface (independent of its pose or shape).

    faces: (F, 3|4) int32 polygon faces (for vertex normals).
    triangles: (T, 3) int32 triangles (quads split on their 0-2 diagonal).
    rings: (V, R) int32 triangles around each vertex, padded by repeating the first.
    incidence: (V, F) sparse vertex-face incidence (sums face area vectors per vertex).
    """

    faces: np.ndarray
    triangles: np.ndarray
    rings: np.ndarray
    incidence: csr_matrix

    def normals(self, vertices: np.ndarray) -> np.ndarray:
        """(V, 3) float32 unit area-weighted vertex normals of the body posed at vertices."""
        x = np.asarray(vertices, dtype=np.float32)
        c = self.face_corners
        # A polygon's area vector from its diagonals (for a quad this is exactly the sum of
        # its two triangles'): half the gathers of a per-triangle cross product.
        if len(c) == 4:
            a = np.take(x, c[2], axis=0) - np.take(x, c[0], axis=0)
            b = np.take(x, c[3], axis=0) - np.take(x, c[1], axis=0)
        else:
            a = np.take(x, c[1], axis=0) - np.take(x, c[0], axis=0)
            b = np.take(x, c[2], axis=0) - np.take(x, c[0], axis=0)
        fn = np.empty_like(a)
        fn[:, 0] = a[:, 1] * b[:, 2] - a[:, 2] * b[:, 1]
        fn[:, 1] = a[:, 2] * b[:, 0] - a[:, 0] * b[:, 2]
        fn[:, 2] = a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]
        n = self.incidence @ fn
        n /= np.maximum(np.sqrt(np.einsum("vd,vd->v", n, n))[:, None], 1e-12)
        return n

    @cached_property
    def face_corners(self) -> np.ndarray:
        """(3|4, F) intp the faces' corners, one contiguous row per corner (fast gathers)."""
        return np.ascontiguousarray(self.faces.T, dtype=np.intp)

    @cached_property
    def corners(self) -> np.ndarray:
        """(3, T) intp the triangles' corners, one contiguous row per corner (fast gathers)."""
        return np.ascontiguousarray(self.triangles.T, dtype=np.intp)

    @cached_property
    def neighbours(self) -> np.ndarray:
        """(V, K) int32 each vertex and the vertices of its triangle ring, once each,
        padded by repeating the vertex (a ring's corners hold each of them 2-3 times)."""
        corners = np.sort(self.triangles[self.rings].reshape(len(self.rings), -1), axis=1)
        first = np.ones(corners.shape, bool)
        first[:, 1:] = corners[:, 1:] != corners[:, :-1]
        width = int(first.sum(axis=1).max())
        slot = np.cumsum(first, axis=1) - 1
        out = np.repeat(np.arange(len(corners), dtype=np.int32)[:, None], width, axis=1)
        rows = np.broadcast_to(np.arange(len(corners))[:, None], corners.shape)
        out[rows[first], slot[first]] = corners[first]
        return out


def body_surface(faces: np.ndarray) -> BodySurface:
    """Precompute the triangle one-rings of a body's faces (F, 3|4) int32."""
    faces = np.asarray(faces, dtype=np.int32)
    tris = (
        faces if faces.shape[1] == 3 else np.concatenate([faces[:, [0, 1, 2]], faces[:, [0, 2, 3]]])
    )
    tris = tris[
        (tris[:, 0] != tris[:, 1]) & (tris[:, 1] != tris[:, 2]) & (tris[:, 0] != tris[:, 2])
    ]
    vert = tris.ravel()
    tri = np.repeat(np.arange(len(tris), dtype=np.int32), 3)
    order = np.argsort(vert, kind="stable")
    vert, tri = vert[order], tri[order]
    count = np.bincount(vert, minlength=int(faces.max()) + 1)
    start = np.concatenate([[0], np.cumsum(count)[:-1]])
    width = int(count.max())
    slot = np.arange(len(vert)) - start[vert]
    rings = np.full((len(count), width), -1, np.int32)
    rings[vert, slot] = tri
    first = np.where(rings[:, :1] >= 0, rings[:, :1], 0)
    rings = np.where(rings >= 0, rings, first)
    corner = faces.ravel()
    incidence = csr_matrix(
        (
            np.ones(len(corner), np.float32),
            (corner, np.repeat(np.arange(len(faces)), faces.shape[1])),
        ),
        shape=(len(count), len(faces)),
    )
    return BodySurface(faces, tris.astype(np.int32), rings, incidence)


@lru_cache(maxsize=8)
def _surface_cached(key: bytes, faces_shape: tuple[int, int]) -> BodySurface:
    faces = np.frombuffer(key, dtype=np.int32).reshape(faces_shape)
    return body_surface(faces)


_LAST_SURFACE: list = []  # [(faces array, surface)]: skips hashing the same faces again


def skin_surface(faces: np.ndarray) -> BodySurface:
    """The collision surface of the skin (faces of vertices < 13,380), cached by topology."""
    if _LAST_SURFACE and _LAST_SURFACE[0][0] is faces:
        return _LAST_SURFACE[0][1]
    key = faces
    faces = np.asarray(faces, dtype=np.int32)
    skin = faces[(faces < BODY_VERTICES).all(axis=1)]
    surface = _surface_cached(np.ascontiguousarray(skin).tobytes(), skin.shape)
    _LAST_SURFACE[:] = [(key, surface)]  # holds the faces array: its id cannot be reused
    return surface


@dataclass(frozen=True)
class SurfaceQuery:
    """Closest body points for N query points.

    distance: (N,) float32 signed distance (m), negative inside the body.
    closest: (N, 3) float32 closest points on the surface.
    normal: (N, 3) float32 unit outward normals there.
    vertex: (N,) int32 the nearest body vertex (for per-vertex bookkeeping like layers).
    triangle: (N,) int32 the triangle (index into ``BodySurface.triangles``) holding the
        closest point, and bary (N, 3) float32 its barycentric weights there.
    """

    distance: np.ndarray
    closest: np.ndarray
    normal: np.ndarray
    vertex: np.ndarray
    triangle: np.ndarray | None = None
    bary: np.ndarray | None = None

    def take(self, index: np.ndarray) -> SurfaceQuery:
        """The rows ``index`` of this query."""
        return SurfaceQuery(*(getattr(self, f)[index] for f in _QUERY_FIELDS))

    def put(self, index: np.ndarray, part: SurfaceQuery) -> SurfaceQuery:
        """This query with rows ``index`` replaced by ``part``'s."""
        fields = []
        for f in _QUERY_FIELDS:
            whole = getattr(self, f).copy()
            whole[index] = getattr(part, f)
            fields.append(whole)
        return SurfaceQuery(*fields)


_QUERY_FIELDS = ("distance", "closest", "normal", "vertex", "triangle", "bary")


def closest_on_triangles(p: np.ndarray, a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """(..., 3) barycentric weights of the closest point to p on triangles abc (all (..., 3))."""
    shape = np.broadcast_shapes(p.shape, a.shape, b.shape, c.shape)
    p, a, b, c = (np.moveaxis(np.broadcast_to(v, shape), -1, 0) for v in (p, a, b, c))
    return np.stack(closest_bary(p, a, b, c), axis=-1)


def closest_bary(p, a, b, c) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Barycentric weights (u, v, w) of the closest points to p on triangles abc.

    Each argument is a point's three coordinates (x, y, z), arrays that broadcast together:
    Ericson's closest-point regions (5.1.5) on whole coordinate arrays, which numpy runs
    several times faster than the same maths on (..., 3) arrays.
    """
    ab = [b[i] - a[i] for i in range(3)]
    ac = [c[i] - a[i] for i in range(3)]
    ap = [p[i] - a[i] for i in range(3)]
    d1, d2 = _dot3(ab, ap), _dot3(ac, ap)
    # With bp = ap - ab and cp = ap - ac, the other four dots need only three more products.
    abab, acac, abac = _dot3(ab, ab), _dot3(ac, ac), _dot3(ab, ac)
    d3, d4 = d1 - abab, d2 - abac
    d5, d6 = d1 - abac, d2 - acac
    va = d3 * d6 - d5 * d4
    vb = d5 * d2 - d1 * d6
    vc = d1 * d4 - d3 * d2
    # Interior by default, then overwritten by the edge and the corner regions.
    denom = _nonzero(va + vb + vc)
    v, w = vb / denom, vc / denom
    uvw = (1.0 - v - w, v, w)
    t = _fraction(d1, d1 - d3)
    uvw = _where((vc <= 0) & (d1 >= 0) & (d3 <= 0), (1.0 - t, t, 0.0), uvw)  # edge ab
    t = _fraction(d2, d2 - d6)
    uvw = _where((vb <= 0) & (d2 >= 0) & (d6 <= 0), (1.0 - t, 0.0, t), uvw)  # edge ac
    e, f = d4 - d3, d5 - d6
    t = _fraction(e, e + f)
    uvw = _where((va <= 0) & (e >= 0) & (f >= 0), (0.0, 1.0 - t, t), uvw)  # edge bc
    uvw = _where((d1 <= 0) & (d2 <= 0), (1.0, 0.0, 0.0), uvw)  # corner a
    uvw = _where((d3 >= 0) & (d4 <= d3), (0.0, 1.0, 0.0), uvw)  # corner b
    return _where((d6 >= 0) & (d5 <= d6), (0.0, 0.0, 1.0), uvw)  # corner c


def _fraction(num: np.ndarray, den: np.ndarray) -> np.ndarray:
    return np.clip(num / _nonzero(den), 0.0, 1.0)


def _where(mask: np.ndarray, new: tuple, old: tuple) -> tuple:
    return tuple(np.where(mask, n, o) for n, o in zip(new, old, strict=True))


def _dot3(x, y) -> np.ndarray:
    return x[0] * y[0] + x[1] * y[1] + x[2] * y[2]


def _nonzero(x: np.ndarray) -> np.ndarray:
    return np.where(np.abs(x) > 1e-30, x, 1e-30)


def _dot(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    return np.einsum("...i,...i->...", x, y)


class PosedBody:
    """A body surface in one pose, laid out for a frame's searches: positions, vertex normals,
    a k-d tree, and both as (3, V) coordinate rows (numpy gathers from a contiguous row
    several times faster than rows of a (V, 3) array).

    vertices: (V, 3) positions (m); normals, tree: reuse those already made for this pose.
    """

    def __init__(
        self,
        surface: BodySurface,
        vertices: np.ndarray,
        normals: np.ndarray | None = None,
        tree: PointTree | None = None,
        tree_now: bool = False,
    ):
        """tree_now: start building the k-d tree at once, on a background thread, while the
        caller goes on (for a caller that will search)."""
        self.surface = surface
        self.vertices = np.ascontiguousarray(vertices, dtype=np.float32)
        self._tree = tree if tree is not None or not tree_now else PointTree.later(self.vertices)
        self.normals = surface.normals(self.vertices) if normals is None else normals

    @cached_property
    def tree(self) -> PointTree:
        if self._tree is None:
            return PointTree(self.vertices)
        return self._tree if isinstance(self._tree, PointTree) else self._tree.result()

    @cached_property
    def rows(self) -> np.ndarray:
        """(3, V) float32 the vertices' x, y and z rows."""
        return np.ascontiguousarray(self.vertices.T)

    @cached_property
    def normal_rows(self) -> np.ndarray:
        """(3, V) float32 the normals' x, y and z rows."""
        return np.ascontiguousarray(np.asarray(self.normals, dtype=np.float32).T)

    def query(self, points: np.ndarray, k: int = 3, sheets: bool = False) -> SurfaceQuery:
        """Closest body points of points (N, 3): the triangle rings of each one's k nearest
        vertices are all tested (more = exact further away).

        sheets: where skin passes into itself, a point as near (within ``TIE``) a sheet it
        is inside as the nearest one it is outside is inside (``_inside_another_sheet``;
        measurements and the bake's play-back checks ask it: 10-30% more time, and
        0.07% of the points near a walking body's skin change sign)."""
        p = np.asarray(points, dtype=np.float32).reshape(-1, 3)
        _, near = self.tree.query(p, k=k)
        near = near.reshape(len(p), k)
        rings = np.take(self.surface.rings, near, axis=0).reshape(len(p), -1)
        cand = _unique_rows(rings)  # (N, C)
        corner = np.take(self.surface.corners, cand, axis=1)  # (3, N, C) vertex indices
        a, b, c = ([np.take(row, corner[j]) for row in self.rows] for j in range(3))
        pc = [p[:, d, None] for d in range(3)]
        bary = closest_bary(pc, a, b, c)
        close = [bary[0] * a[d] + bary[1] * b[d] + bary[2] * c[d] for d in range(3)]
        gap = [pc[d] - close[d] for d in range(3)]
        squared = _dot3(gap, gap)  # (N, C)
        best = np.argmin(squared, axis=1)
        if sheets:
            best = self._inside_another_sheet(p, squared, best, close, bary, corner)
        rows = np.arange(len(p))
        bary = np.stack([w[rows, best] for w in bary], axis=1).astype(np.float32)
        close = np.stack([w[rows, best] for w in close], axis=1).astype(np.float32)
        triangle = cand[rows, best]
        n = self._interpolated_normals(corner[:, rows, best], bary.T)
        offset = (p - close).T
        distance = np.sqrt(_dot3(offset, offset))
        distance = np.where(_dot3(offset, n.T) < 0, -distance, distance)
        return SurfaceQuery(distance.astype(np.float32), close, n, near[:, 0].astype(np.int32),
                            triangle.astype(np.int32), bary)  # fmt: skip

    def _inside_another_sheet(self, p, squared, best, close, bary, corner) -> np.ndarray:
        """``best`` (N,) candidate columns, with a point's column moved to a candidate that
        says "inside" where one on another sheet of skin is as near (within ``TIE``) as
        the nearest one, which says "outside".

        Where a skinned body passes into itself (an arm pressed into the chest), a point can
        be as near the arm's skin, outside it, as the chest's, inside it: which one argmin
        picks is float rounding, and the point is inside the body (inside either part is
        inside the union; ``winding_number`` agrees). Candidates sharing the nearest
        point (triangles round an edge or corner) blend the same vertex normals, so only
        candidates whose closest point lies elsewhere are asked.
        """
        rows = np.arange(len(p))
        near = np.sqrt(squared[rows, best])
        within = squared <= ((near + TIE) ** 2)[:, None]
        within[rows, best] = False
        r, c = np.nonzero(within)
        if not len(r):
            return best
        apart = sum((close[d][r, c] - close[d][r, best[r]]) ** 2 for d in range(3)) > SAME**2
        r, c = r[apart], c[apart]
        if not len(r):
            return best
        weights = np.stack([w[r, c] for w in bary]).astype(np.float32)
        normal = self._interpolated_normals(corner[:, r, c], weights)
        offset = [p[r, d] - close[d][r, c] for d in range(3)]
        says_inside = _dot3(offset, normal.T) < 0
        nearest_says = self._interpolated_normals(
            corner[:, r, best[r]], np.stack([w[r, best[r]] for w in bary]).astype(np.float32)
        )
        offset_best = [p[r, d] - close[d][r, best[r]] for d in range(3)]
        best_outside = _dot3(offset_best, nearest_says.T) >= 0
        pick = says_inside & best_outside
        out = best.copy()
        order = np.argsort(-squared[r[pick], c[pick]])  # the nearest inside one written last
        out[r[pick][order]] = c[pick][order]
        return out

    def anchored(self, points: np.ndarray, triangle: np.ndarray, bary: np.ndarray) -> SurfaceQuery:
        """Signed distances of points (N, 3) to known surface anchors (a triangle and
        barycentric weights per point, e.g. the closest points found in the rest pose): no
        search, O(N).

        In a skinned pose the anchor moves with the skin under the point, which is where
        its closest point stays unless another body part comes close; callers that need
        those contacts too use ``query``.
        """
        corner = np.take(self.surface.corners, triangle, axis=1)  # (3, N)
        weights = np.ascontiguousarray(np.asarray(bary, dtype=np.float32).T)
        close = np.stack([_blend(row, corner, weights) for row in self.rows], axis=1)
        n = self._interpolated_normals(corner, weights)
        p = np.asarray(points, dtype=np.float32)
        return SurfaceQuery(
            distance=_dot3((p - close).T, n.T).astype(np.float32),
            closest=close,
            normal=n,
            vertex=corner[0],
            triangle=triangle,
            bary=bary,
        )

    def _interpolated_normals(self, corner: np.ndarray, weights: np.ndarray) -> np.ndarray:
        """(N, 3) unit normals blended from the vertex normals of corners (3, N)."""
        n = [_blend(row, corner, weights) for row in self.normal_rows]
        inverse = 1.0 / np.maximum(np.sqrt(_dot3(n, n)), 1e-12)
        return np.stack([c * inverse for c in n], axis=1).astype(np.float32)


def _blend(row: np.ndarray, corner: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """(N,) one coordinate blended over triangle corners (3, N) with weights (3, N)."""
    return (
        np.take(row, corner[0]) * weights[0]
        + np.take(row, corner[1]) * weights[1]
        + np.take(row, corner[2]) * weights[2]
    )


def query(
    body_vertices: np.ndarray,
    surface: BodySurface,
    points: np.ndarray,
    k: int = 3,
    tree: PointTree | None = None,
    normals: np.ndarray | None = None,
    sheets: bool = False,
) -> SurfaceQuery:
    """Signed distances of points (N, 3) to the body (V, 3) (see SurfaceQuery and
    ``PosedBody.query``); tree, normals: reuse those already made for this pose."""
    return PosedBody(surface, body_vertices, normals, tree).query(points, k, sheets)


def _unique_rows(cand: np.ndarray) -> np.ndarray:
    """(N, C') each row's distinct values (C' the most any row has; short rows repeat their
    first): neighbouring vertices share most of their rings, so this halves the tests."""
    cand = np.sort(cand, axis=1)
    repeat = np.zeros(cand.shape, bool)
    np.equal(cand[:, 1:], cand[:, :-1], out=repeat[:, 1:])
    gone = np.iinfo(cand.dtype).max
    cand[repeat] = gone
    cand.sort(axis=1)  # the distinct values first
    cand = cand[:, : cand.shape[1] - int(repeat.sum(axis=1).min())]
    return np.where(cand == gone, cand[:, :1], cand)


def anchored(
    body_vertices: np.ndarray,
    normals: np.ndarray,
    surface: BodySurface,
    points: np.ndarray,
    triangle: np.ndarray,
    bary: np.ndarray,
) -> SurfaceQuery:
    """``PosedBody.anchored`` on a body (V, 3) with its vertex normals (V, 3)."""
    return PosedBody(surface, body_vertices, normals).anchored(points, triangle, bary)


def penetration(
    body_vertices: np.ndarray, body_faces: np.ndarray, points: np.ndarray, tolerance: float = 0.0
) -> tuple[int, np.ndarray]:
    """How many points lie inside the body, and how deep.

    body_vertices: (V, 3) closed body surface positions (m); body_faces: (F, 3|4) int32.
    points: (N, 3) garment vertices. tolerance: depth (m) not counted as inside.
    Returns (count, depths): depths (N,) float32 metres inside (0 for points outside).
    """
    surface = body_surface(body_faces)
    q = query(body_vertices, surface, points, k=6, sheets=True)
    depth = np.maximum(-q.distance, 0.0).astype(np.float32)
    return int(np.count_nonzero(depth > tolerance)), depth


def winding_number(
    points: np.ndarray, vertices: np.ndarray, triangles: np.ndarray, cell: float = 0.005
) -> np.ndarray:
    """(N,) int winding number of a closed, outward-oriented triangle surface at points.

    1 inside, 0 outside, and 2 where a skinned body passes into itself: unlike a
    closest-point sign it stays right where the surface self-intersects. See
    ``WindingGrid``, which also serves many queries of one surface.
    """
    return WindingGrid(vertices, triangles, cell).winding(points)


class WindingGrid:
    """A closed, outward-oriented triangle surface (one pose of it) ready for winding
    numbers: its triangles filed under every ``cell`` (m) of an xy grid that their xy
    bounding box touches, once, for any number of queries.

    The winding number is counted along a ray going up from each point: +1 for each
    crossing of an upward-facing triangle (leaving), -1 for a downward-facing one
    (entering); only the triangles filed under the point's cell are tested.
    """

    def __init__(self, vertices: np.ndarray, triangles: np.ndarray, cell: float = 0.005):
        x = np.ascontiguousarray(np.asarray(vertices, dtype=np.float64).T)  # (3, V)
        t = np.ascontiguousarray(np.asarray(triangles).T, dtype=np.intp)  # (3, T)
        # Per triangle, as coordinate rows: corner a, the xy edges to b and c, their
        # determinant (orientation) and the z rises along them.
        a = [np.take(row, t[0]) for row in x]
        b = [np.take(row, t[1]) for row in x]
        c = [np.take(row, t[2]) for row in x]
        self.a = a
        self.e1 = [b[0] - a[0], b[1] - a[1], b[2] - a[2]]
        self.e2 = [c[0] - a[0], c[1] - a[1], c[2] - a[2]]
        self.det = self.e1[0] * self.e2[1] - self.e1[1] * self.e2[0]
        self.cell = cell
        lo = [np.minimum(np.minimum(a[d], b[d]), c[d]) for d in range(2)]
        hi = [np.maximum(np.maximum(a[d], b[d]), c[d]) for d in range(2)]
        self.origin = np.array([lo[0].min(), lo[1].min()])
        i0 = [np.floor((lo[d] - self.origin[d]) / cell).astype(np.int64) for d in range(2)]
        i1 = [np.floor((hi[d] - self.origin[d]) / cell).astype(np.int64) for d in range(2)]
        self.rows = int(i1[1].max()) + 1
        span = [i1[d] - i0[d] + 1 for d in range(2)]
        count = span[0] * span[1]
        tri = np.repeat(np.arange(len(count)), count)
        k = np.arange(len(tri)) - np.repeat(np.cumsum(count) - count, count)
        width = np.take(span[0], tri)
        cells = (np.take(i0[0], tri) + k % width) * self.rows + np.take(i0[1], tri) + k // width
        # Small keys sort by radix: a body's few thousand cells fit in 16 bits.
        key = cells.astype(np.uint16) if cells.max() < 2**16 else cells
        order = np.argsort(key, kind="stable")
        self.cells, self.filed = np.take(cells, order), np.take(tri, order)

    def winding(self, points: np.ndarray) -> np.ndarray:
        """(N,) int winding numbers at points (N, 3)."""
        # A fixed irrational nudge keeps rays off the shared edges of axis-aligned data.
        p = np.asarray(points, dtype=np.float64).reshape(-1, 3) + np.array([1.1e-7, 0.7e-7, 0.0])
        pair_point, pair_tri = self._pairs(p[:, :2])
        q = [np.take(p[:, d], pair_point) - np.take(self.a[d], pair_tri) for d in range(3)]
        e1 = [np.take(e, pair_tri) for e in self.e1]
        e2 = [np.take(e, pair_tri) for e in self.e2]
        det = np.take(self.det, pair_tri)
        # Barycentrics of the point's xy in the triangle's xy projection.
        safe = np.where(det != 0, det, 1.0)
        v = (q[0] * e2[1] - q[1] * e2[0]) / safe
        w = (e1[0] * q[1] - e1[1] * q[0]) / safe
        hit = (det != 0) & (v >= 0) & (w >= 0) & (v + w <= 1)
        hit &= v * e1[2] + w * e2[2] > q[2]  # the triangle is above the point
        return (
            np.bincount(pair_point[hit], weights=np.sign(det[hit]), minlength=len(p))
            .round()
            .astype(np.int64)
        )

    def _pairs(self, points_xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(point, triangle) index pairs: each point with the triangles of its cell."""
        pc = np.floor((points_xy - self.origin) / self.cell).astype(np.int64)
        valid = (pc[:, 0] >= 0) & (pc[:, 1] >= 0) & (pc[:, 1] < self.rows)
        key = np.where(valid, pc[:, 0] * self.rows + pc[:, 1], -1)
        start = np.searchsorted(self.cells, key, "left")
        stop = np.where(valid, np.searchsorted(self.cells, key, "right"), start)
        n = stop - start
        pair_point = np.repeat(np.arange(len(points_xy)), n)
        offset = np.arange(n.sum()) - np.repeat(np.cumsum(n) - n, n)
        return pair_point, self.filed[np.repeat(start, n) + offset]


def surface_distance(
    points: np.ndarray, vertices: np.ndarray, triangles: np.ndarray, chunk: int = 16
) -> np.ndarray:
    """(N,) float32 exact unsigned distance (m) from points to the nearest of all triangles.

    Brute force, O(N T): for checking a few points (``query`` only searches the rings of
    the nearest vertices, which can miss the closest triangle inside a fold).
    """
    x = np.asarray(vertices, dtype=np.float32)
    t = np.asarray(triangles)
    a, b, c = x[t[:, 0]], x[t[:, 1]], x[t[:, 2]]
    p = np.asarray(points, dtype=np.float32)
    out = np.empty(len(p), np.float32)
    for start in range(0, len(p), chunk):
        q = p[start : start + chunk, None, :]
        bary = closest_on_triangles(q, a[None], b[None], c[None])  # (n, T, 3)
        close = bary[..., :1] * a + bary[..., 1:2] * b + bary[..., 2:] * c
        gap = q - close
        out[start : start + chunk] = np.sqrt(_dot(gap, gap).min(axis=1))
    return out


def push_out(points: np.ndarray, q: SurfaceQuery, clearance: np.ndarray | float) -> np.ndarray:
    """(N, 3) float32 points moved along the body normal until each is ``clearance`` (m,
    scalar or (N,)) outside the body; points already that far out do not move."""
    lack = np.maximum(np.asarray(clearance, dtype=np.float32) - q.distance, 0.0)
    return (np.asarray(points, dtype=np.float32) + lack[:, None] * q.normal).astype(np.float32)


def escape(
    points: np.ndarray,
    vertices: np.ndarray,
    surface: BodySurface,
    clearance: np.ndarray | float,
    tree: PointTree | None = None,
    normals: np.ndarray | None = None,
    grid: WindingGrid | None = None,
) -> np.ndarray:
    """(N, 3) float32 points with every one inside the body moved out of it.

    The inside test is the winding number (exact, and right where a skinned body passes
    into itself), so this is the last word after faster, local resolves: a point found
    inside goes to its closest skin point plus ``clearance`` (m, scalar or (N,)) along the
    normal there; one still inside (that skin was itself inside another part) goes to the
    nearest skin vertex whose point ``clearance`` out along its normal is outside (among
    its 16 nearest, else among all).
    vertices: (V, 3) the body; tree, normals, grid: reuse those built for this pose.
    """
    x = np.asarray(vertices, dtype=np.float32)
    out = np.array(points, dtype=np.float32)
    need = np.broadcast_to(np.asarray(clearance, np.float32), (len(out),))
    if grid is None:
        grid = WindingGrid(x, surface.triangles)
    inside = np.flatnonzero(grid.winding(out) > 0)
    if len(inside) == 0:
        return out
    if tree is None:
        tree = PointTree(x)
    if normals is None:
        normals = surface.normals(x)
    q = query(x, surface, out[inside], k=8, tree=tree, normals=normals)
    out[inside] = q.closest + need[inside, None] * q.normal
    inside = inside[grid.winding(out[inside]) > 0]
    # Still inside: the closest skin was itself inside another part (skinning pressed them
    # together). Go to the nearest skin point whose outside really is outside.
    if len(inside):
        _, near = tree.query(out[inside], k=16)
        lifted = x[near] + need[inside, None, None] * normals[near]  # (M, 16, 3)
        free = grid.winding(lifted.reshape(-1, 3)).reshape(near.shape)
        ok = free <= 0
        first = np.argmax(ok, axis=1)  # nearest first: tree results are sorted
        found = ok[np.arange(len(inside)), first]
        out[inside[found]] = lifted[np.flatnonzero(found), first[found]]
        inside = inside[~found]
    if len(inside):  # deep in a part sunk into another (an arm into the chest): all skin
        lifted = x + need[inside].max() * normals
        free = np.flatnonzero(grid.winding(lifted) <= 0)
        _, nearest = PointTree(lifted[free]).query(out[inside])
        out[inside] = lifted[free[nearest]]
    return out
