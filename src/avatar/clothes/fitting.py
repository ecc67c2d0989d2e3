"""Put garments on a body: fit each binding, push it out of the body, stack layers, solidify.

    outfit = dress(human, [load_garment("tshirt"), load_garment("jeans")])
    outfit.garments          # FittedGarment per garment, rest pose of this body
    outfit.frame(matrices)   # (per posed frame) garment vertices, skinned and resolved

Layers: garments are processed from the lowest ``z_depth`` up. Each one records, per body
vertex, how far out it reaches; a garment above must clear that height plus ``LAYER_GAP``,
so a jacket stays over a shirt and a shirt over its wearer, frame after frame.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from functools import cached_property, lru_cache

import numpy as np

from avatar.clothes import collision, weights
from avatar.clothes.binding import Binding, fit
from avatar.clothes.shell import Shell, extrude, solidify
from avatar.io.mhw import BoneWeights
from avatar.material import Material
from avatar.mesh import Mesh
from avatar.rig.skinning import SkinWeights, linear_blend

BODY_VERTEX_COUNT = 13380  # hm08 skin; helpers follow
CLEARANCE = 0.002  # m between skin and a garment's inside
LAYER_GAP = 0.0015  # m between stacked garments
REMOTE_K = 3  # nearest skin vertices whose rest places tell another body part
CLOSING = 0.01  # m that skin may come closer to a point's anchor before it is another part
REMOTE_REACH = 0.06  # m; points further than this from every skin vertex are not checked
FOLD = 0.3  # cosine between anchor and nearest-skin normals below which the skin folded
PLANE_SLACK = 0.002  # m the tangent-plane estimate may fall short before it is checked
CAUGHT = -0.3  # cosine between two successive push directions: caught between two parts
REMOTE = 0.02  # m at rest between a point's anchor and its nearest skin: another body part
FLOOR_REACH = 0.04  # m; garment parts further out (loose hems, hair ends) define no layer
FRAME_INFLUENCES = 4  # bones per vertex when skinning garments frame by frame (speed)
NEAR_BAND = 0.03  # m; points closer to the skin than this get the finer (4-ring) query


@dataclass(frozen=True, eq=False)
class Garment:
    """A garment that fits any body: its mesh as authored, its binding, its look.

    mesh: topology and UVs; vertices as authored (metres). For a garment with thickness
        this is the single bound surface; the shell is added when fitted.
    binding: one reference per mesh vertex.
    bone_weights: the garment's own ``.mhw`` weights, or None to transfer the body's.
    thickness: m; > 0 solidifies the surface into a shell with hems.
    collide: False for face proxies (eyebrows, eyelashes) that sit on the skin by design.
    delete_verts: (D,) int32 base-mesh vertices the garment covers (hidden if the user asks).
    """

    name: str
    mesh: Mesh
    binding: Binding
    material: Material | None = None
    z_depth: int = 50
    delete_verts: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int32))
    bone_weights: BoneWeights | None = None
    thickness: float = 0.0
    clearance: float = CLEARANCE
    collide: bool = True
    category: str = ""
    tags: tuple[str, ...] = ()
    source: str = "builtin"
    licence: str = ""

    @cached_property
    def anchor_cache(self) -> dict:
        """Closest skin triangles of the garment's layers, found once by the exact search on
        the model's default body (or the first body it meets, for bodies without a model);
        the body's topology never changes, so later fits and frames measure against the
        same triangles in O(N) (``collision.anchored``)."""
        return {}

    @cached_property
    def weight_cache(self) -> list:
        """The last (body weights, bone names, result) of ``garment_weights``: the body's
        skin weights belong to the rig, not the shape, so every body of a rig reuses it."""
        return []

    @cached_property
    def shell(self) -> Shell | None:
        """The solidified topology (computed once), or None without thickness."""
        return solidify(self.mesh) if self.thickness > 0 else None


@dataclass(frozen=True, eq=False)
class FittedGarment:
    """A garment on one body in rest pose.

    mesh: vertices (M, 3) on this body (M = 2N with a shell), faces, UVs.
    weights: (M, K) skin weights over the body's skeleton.
    delete_verts: base-mesh vertices it covers (the caller hides them only if asked).
    """

    name: str
    mesh: Mesh
    material: Material | None
    weights: SkinWeights
    z_depth: int
    delete_verts: np.ndarray
    garment: Garment


@lru_cache(maxsize=8)
def _surface_cached(key: bytes, faces_shape: tuple[int, int]) -> collision.BodySurface:
    faces = np.frombuffer(key, dtype=np.int32).reshape(faces_shape)
    return collision.body_surface(faces)


_LAST_SURFACE: list = []  # [(faces array, surface)]: skips hashing the same faces again


def body_surface(faces: np.ndarray) -> collision.BodySurface:
    """The collision surface of the skin (faces of vertices < 13,380), cached by topology."""
    if _LAST_SURFACE and _LAST_SURFACE[0][0] is faces:
        return _LAST_SURFACE[0][1]
    key = faces
    faces = np.asarray(faces, dtype=np.int32)
    skin = faces[(faces < BODY_VERTEX_COUNT).all(axis=1)]
    surface = _surface_cached(np.ascontiguousarray(skin).tobytes(), skin.shape)
    _LAST_SURFACE[:] = [(key, surface)]  # holds the faces array: its id cannot be reused
    return surface


class Pose(collision.PosedBody):
    """One pose of the skin as a collider (``collision.PosedBody``) that also keeps the
    layer floors of the garments fitted on it so far."""

    def __init__(self, surface: collision.BodySurface, vertices: np.ndarray):
        super().__init__(surface, vertices[:BODY_VERTEX_COUNT], tree_now=True)
        self.floor = np.zeros(BODY_VERTEX_COUNT, np.float32)

    def query_near(self, points: np.ndarray) -> collision.SurfaceQuery:
        """Closest skin of points: one vertex ring each, four rings near the skin.

        One nearest vertex can miss the closest triangle where the body folds (armpits,
        crotch); that only matters for points close to the skin, which get four rings.
        """
        q = self.query(points, k=1)
        close = np.flatnonzero(np.abs(q.distance) < NEAR_BAND)
        return _put(q, close, self.query(points[close], k=4)) if len(close) else q

    def resolve(self, points: np.ndarray, garment: Garment, iterations: int = 6):
        """Push a garment's bound surface (N, 3) out of the body and the layers below.

        Returns (points (N, 3) float32, query at the final positions).
        """
        q = self.query_near(points)
        need = np.full(len(points), garment.clearance, np.float32)
        for _ in range(iterations):
            need = np.maximum(garment.clearance, self._floor_at(q.vertex) + LAYER_GAP)
            short = np.flatnonzero(q.distance < need - 1e-5)
            if len(short) == 0:
                break
            # Only the points that moved need a new query.
            points = points.copy()
            points[short] = collision.push_out(points[short], _take(q, short), need[short])
            q = _put(q, short, self.query(points[short], k=4))
        self._raise_floor(q, garment.thickness)
        self.last_need = np.broadcast_to(need, q.distance.shape).astype(np.float32)
        return points, q

    def resolve_anchored(self, points: np.ndarray, garment: Garment):
        """``resolve`` against the garment's cached anchors: O(N) plus an exact search for
        the few points near another body part. Returns (points, query)."""
        tri, bary, near = garment.anchor_cache["inner"]
        q = self.anchored(points, tri, bary)
        need = np.maximum(garment.clearance, self._floor_at(q.vertex) + LAYER_GAP)
        fitted = points
        pushed = collision.push_out(points, q, need)
        points = remote_contacts(self, None, pushed, need, near, q.normal, 4)
        moved = np.flatnonzero(np.any(points != pushed, axis=1))
        if len(moved) and np.any(self.query(points[moved], k=4).distance < 0):
            return self.resolve(fitted, garment)  # squeezed between parts: the full search
        q = self.anchored(points, tri, bary)
        self._raise_floor(q, garment.thickness)
        self.last_need = need.astype(np.float32)
        return points, q

    def _floor_at(self, vertex: np.ndarray) -> np.ndarray:
        return self.floor[self.surface.neighbours[vertex]].max(axis=1)

    def _raise_floor(self, q: collision.SurfaceQuery, thickness: float) -> None:
        top = q.distance + np.float32(thickness)
        near = q.distance < FLOOR_REACH
        np.maximum.at(self.floor, q.vertex[near], top[near])


_QUERY_FIELDS = ("distance", "closest", "normal", "vertex", "triangle", "bary")


def _take(q: collision.SurfaceQuery, index: np.ndarray) -> collision.SurfaceQuery:
    return collision.SurfaceQuery(*(getattr(q, f)[index] for f in _QUERY_FIELDS))


def _put(q, index: np.ndarray, part) -> collision.SurfaceQuery:
    """q with rows ``index`` replaced by ``part``'s."""
    fields = []
    for f in _QUERY_FIELDS:
        whole = getattr(q, f).copy()
        whole[index] = getattr(part, f)
        fields.append(whole)
    return collision.SurfaceQuery(*fields)


def _body_faces(human) -> np.ndarray:
    faces = getattr(human, "faces", None)
    if faces is None:
        faces = human.model.base.faces
    return np.asarray(faces)


def garment_weights(garment: Garment, body_weights: SkinWeights, bone_names=None) -> SkinWeights:
    """(N, K) skin weights of the garment's bound surface: its ``.mhw`` or the body's."""
    names = tuple(bone_names) if bone_names is not None else None
    for cached_weights, cached_names, result in garment.weight_cache:
        if cached_weights is body_weights and cached_names == names:
            return result
    if garment.bone_weights is not None and names is not None:
        result = weights.from_file(garment.bone_weights, names, len(garment.binding))
    else:
        result = weights.transfer(garment.binding, body_weights)
    garment.weight_cache[:] = [(body_weights, names, result)]  # holds body_weights: no id reuse
    return result


def _with_shell(garment: Garment, inner: np.ndarray, q, w: SkinWeights):
    shell = garment.shell
    if shell is None:
        return garment.mesh.with_vertices(inner), w
    verts = extrude(inner, q.normal, garment.thickness)
    both = SkinWeights(np.concatenate([w.indices] * 2), np.concatenate([w.weights] * 2))
    return shell.mesh.with_vertices(verts), both


def fit_garment(
    pose: Pose, garment: Garment, body_vertices: np.ndarray
) -> tuple[np.ndarray, object]:
    """(N, 3) bound surface of a garment on a body (rest), resolved when it collides."""
    points = fit(garment.binding, body_vertices)
    if not garment.collide:
        return points, None
    if "inner" in garment.anchor_cache:
        return pose.resolve_anchored(points, garment)
    points, q = pose.resolve(points, garment)
    garment.anchor_cache["inner"] = (q.triangle, q.bary, q.vertex)
    return points, q


@dataclass(eq=False)
class Outfit:
    """Garments fitted on one body, able to follow it through posed frames."""

    garments: list[FittedGarment]
    surface: collision.BodySurface
    rest_surfaces: list[np.ndarray]  # (N, 3) resolved bound surface per garment
    surface_weights: list[SkinWeights]
    # Per colliding garment: the rest-pose closest triangle, its barycentrics, the clearance
    # each vertex must keep (skin clearance or the layer below plus a gap), and the nearest
    # skin vertex at rest.
    anchors: list[tuple[np.ndarray, ...] | None] = field(default_factory=list)
    rest_body: np.ndarray | None = None  # (13380, 3) skin at rest, to tell remote contacts

    # An Outfit reads as the list of its FittedGarments.
    def __iter__(self):
        return iter(self.garments)

    def __len__(self) -> int:
        return len(self.garments)

    def __getitem__(self, i: int) -> FittedGarment:
        return self.garments[i]

    @cached_property
    def rest_rows(self) -> np.ndarray:
        """(3, 13380) float32 the rest skin's coordinate rows (``remote_contacts``)."""
        return np.ascontiguousarray(np.asarray(self.rest_body, dtype=np.float32).T)

    def frame(
        self, body_posed: np.ndarray, matrices: np.ndarray, exact: bool = False
    ) -> list[np.ndarray]:
        """Garment vertices (M_i, 3) for one posed frame.

        body_posed: (V, 3) the body skinned with ``matrices`` (J, 4, 4) skinning matrices.
        exact: guarantee that no garment vertex is inside the body (for datasets and
            exports; several times slower): after the real-time resolve, every garment
            vertex is tested by winding number, which stays right where skinning drove one
            body part into another, and any inside is moved out (``collision.escape``).
            By default each vertex keeps its clearance above the skin it was closest to at
            rest, which moves with it, and is checked against other parts that come near.
        """
        body = self.posed_body(body_posed)
        out = self._frame_anchored(body, matrices)
        return self._escape(body, out) if exact else out

    def posed_body(self, body_posed: np.ndarray) -> collision.PosedBody:
        """The skin of a posed body (V, 3) as a collider for this outfit's garments."""
        return collision.PosedBody(self.surface, body_posed[:BODY_VERTEX_COUNT], tree_now=True)

    def _escape(self, skin: collision.PosedBody, vertices: list[np.ndarray]) -> list[np.ndarray]:
        """Each colliding garment's vertices (M_i, 3) with any inside the skin moved out of
        it by ``collision.escape``, keeping its clearance (``_frame_need``)."""
        out = list(vertices)
        colliding = [(i, a) for i, a in enumerate(self.anchors) if a is not None]
        if not colliding:
            return out
        index = [i for i, _ in colliding]
        need = [_frame_need(self.garments[i], a, len(out[i])) for i, a in colliding]
        # All garments at once: one winding grid and one tree serve every search.
        points = np.concatenate([out[i] for i in index])
        moved = collision.escape(points, skin.vertices, self.surface, np.concatenate(need),
                                 skin.tree, skin.normals)  # fmt: skip
        sizes = np.cumsum([len(out[i]) for i in index])[:-1]
        for i, part in zip(index, np.split(moved, sizes), strict=True):
            out[i] = part
        return out

    def _frame_anchored(self, body: collision.PosedBody, matrices: np.ndarray) -> list:
        """Each garment skinned, kept clear of the skin it is anchored to (a shell's outer
        layer too), then all colliding points checked together against other body parts."""
        lay = self._layout
        skinned = linear_blend(lay.rest, lay.weights, matrices)
        if not lay.colliding_garments:
            return np.split(skinned, lay.splits)
        points = skinned[lay.colliding]
        q = body.anchored(points, lay.triangle, lay.bary)
        inner = collision.push_out(points, q, lay.need)
        # Shells: the outer layer grown along the skin normal, then kept clear of the skin
        # it is closest to.
        outer = inner[lay.shell] + lay.thickness[:, None] * q.normal[lay.shell]
        qo = body.anchored(outer, lay.outer_triangle, lay.outer_bary)
        outer = collision.push_out(outer, qo, lay.outer_need)
        # One search for all garments, both shell layers (where the body folds, the outer
        # one can reach the next part); each point is checked on its own.
        order = lay.remote_order
        joined = remote_contacts(
            body,
            self.rest_rows,
            np.concatenate([inner, outer])[order],
            lay.remote_need,
            lay.remote_near,
            np.concatenate([q.normal, qo.normal])[order],
            iterations=4,
        )
        out = np.split(skinned, lay.splits)
        for i, part in zip(lay.colliding_garments, np.split(joined, lay.remote_splits),
                           strict=True):  # fmt: skip
            out[i] = part
        return out

    @cached_property
    def _layout(self) -> _FrameLayout:
        return _FrameLayout.of(self)


@dataclass(frozen=True, eq=False)
class _FrameLayout:
    """An outfit's garments laid end to end, so that a posed frame skins and anchors them
    all in a few whole-array steps (``Outfit._frame_anchored``)."""

    rest: np.ndarray  # (N, 3) every garment's bound surface at rest, garment after garment
    weights: SkinWeights  # (N, K) their frame weights
    splits: np.ndarray  # where each garment's rows start (np.split)
    colliding: np.ndarray  # (C,) rows of colliding garments
    triangle: np.ndarray  # (C,) their rest anchors, barycentrics (C, 3), clearances (C,)
    bary: np.ndarray
    need: np.ndarray
    shell: np.ndarray  # (S,) which of the C rows carry a shell's outer layer
    thickness: np.ndarray  # (S,) float32 that shell's thickness
    outer_triangle: np.ndarray  # (S,) the outer layer's anchors and clearances
    outer_bary: np.ndarray
    outer_need: np.ndarray
    remote_order: np.ndarray  # rows of [inner; outer] in output order (inner, outer per garment)
    remote_need: np.ndarray  # their clearances and rest nearest skin vertices, in that order
    remote_near: np.ndarray
    remote_splits: np.ndarray
    colliding_garments: list[int]

    @classmethod
    def of(cls, outfit: Outfit) -> _FrameLayout:
        rests, ws = outfit.rest_surfaces, outfit.surface_weights
        width = max(w.indices.shape[1] for w in ws)
        weights = SkinWeights(_cat([_pad(w.indices, width) for w in ws], np.int32),
                              _cat([_pad(w.weights, width) for w in ws], np.float32))  # fmt: skip
        starts = np.cumsum([0] + [len(r) for r in rests])
        pairs = enumerate(zip(outfit.garments, outfit.anchors, strict=True))
        hits = [(i, g, a) for i, (g, a) in pairs if a is not None]
        shells = [(g, a) for _, g, a in hits if len(a) > 4]
        # Rows of [inner; outer] as the garments' outputs take them: each garment's inner
        # layer, then its outer layer if it is a shell.
        inner_at = np.cumsum([0] + [len(a[2]) for _, _, a in hits])
        outer_at = inner_at[-1] + np.cumsum([0] + [len(a[2]) for _, a in shells])
        order, need, near, sizes, s = [], [], [], [], 0
        for k, (_, _, a) in enumerate(hits):
            order.append(np.arange(inner_at[k], inner_at[k + 1]))
            need.append(a[2])
            near.append(a[3])
            if len(a) > 4:
                order.append(np.arange(outer_at[s], outer_at[s + 1]))
                need.append(a[2])
                near.append(a[7])
                s += 1
            sizes.append(len(a[2]) * (2 if len(a) > 4 else 1))
        return cls(
            rest=_cat(rests, np.float32),
            weights=weights,
            splits=starts[1:-1],
            colliding=_cat([np.arange(starts[i], starts[i + 1]) for i, _, _ in hits], np.intp),
            triangle=_cat([a[0] for _, _, a in hits], np.int32),
            bary=_cat([a[1] for _, _, a in hits], np.float32, 3),
            need=_cat([a[2] for _, _, a in hits], np.float32),
            shell=_cat([np.arange(inner_at[k], inner_at[k + 1])
                        for k, (_, _, a) in enumerate(hits) if len(a) > 4], np.intp),  # fmt: skip
            thickness=_cat([np.full(len(a[2]), g.garment.thickness) for g, a in shells],
                           np.float32),  # fmt: skip
            outer_triangle=_cat([a[4] for _, a in shells], np.int32),
            outer_bary=_cat([a[5] for _, a in shells], np.float32, 3),
            outer_need=_cat([a[6] for _, a in shells], np.float32),
            remote_order=_cat(order, np.intp),
            remote_need=_cat(need, np.float32),
            remote_near=_cat(near, np.intp),
            remote_splits=np.cumsum(sizes)[:-1],
            colliding_garments=[i for i, _, _ in hits],
        )


def _cat(arrays: list, dtype, width: int | None = None) -> np.ndarray:
    """The arrays end to end as ``dtype`` (an empty (0,) or (0, width) array for none)."""
    if not arrays:
        return np.zeros((0,) if width is None else (0, width), dtype)
    return np.concatenate(arrays).astype(dtype)


def _pad(a: np.ndarray, width: int) -> np.ndarray:
    """(N, width) a padded on the right with zeros (index 0, weight 0: no influence)."""
    return np.pad(a, ((0, 0), (0, width - a.shape[1])))


def _frame_need(g: FittedGarment, anchor: tuple, count: int) -> np.ndarray:
    """(M,) m each posed garment vertex keeps from the skin: its rest clearance (the
    layer below plus a gap), and for a shell's outer layer that plus the thickness."""
    need = anchor[2]
    if count > len(need):
        need = np.concatenate([need, need + np.float32(g.garment.thickness)])
    return need


def remote_contacts(body: collision.PosedBody, rest_rows: np.ndarray | None, points, need,
                    rest_near, facing, iterations: int = 1):  # fmt: skip
    """Push points out of body parts other than the skin they are anchored to (an arm
    swinging into a shirt's side, one thigh into the other trouser leg). Such a point's
    nearest skin vertex now lies far, at rest, from its nearest one at rest; or one of
    its three nearest came closer to that one than it was at rest (skin pressing in,
    even where its vertex is not the nearest); or it faces another way than its anchor
    (a fold closing, as in the crotch). Only those few get the exact search."""
    # All garments in one query: the largest single cost of a posed frame.
    x, normals, tree = body.vertices, body.normals, body.tree
    # At rest (no rest_rows: the body is at rest) no skin moved, so the nearest one tells all.
    k = 1 if rest_rows is None else REMOTE_K
    dist, near3 = tree.query(points, k=k, reach=REMOTE_REACH)
    dist, near3 = dist.reshape(len(points), k), near3.reshape(len(points), k)
    close = np.isfinite(dist[:, 0])
    near3 = np.where(np.isfinite(dist), near3, near3[:, :1])
    far = np.flatnonzero(~close)
    if len(far):
        near3[far] = tree.query(points[far], k=1)[1][:, None]
    near = near3[:, 0]
    remote: np.ndarray | float = REMOTE
    if rest_rows is not None:
        # In a pose, a point's own skin can lie as far from its anchor's vertex as the point
        # is from both (a loose hem's nearest vertex drifts as the body moves): only skin
        # further than that, at rest, is another part. This halves the exact searches.
        anchor = np.take(x, rest_near, axis=0)
        remote = REMOTE + dist[:, 0] + np.sqrt(_dot_rows(points - anchor, points - anchor))
    other = _other_part(body.rows if rest_rows is None else rest_rows, body.rows, near3,
                        rest_near, remote)  # fmt: skip
    normal = np.take(normals, near, axis=0)
    turned = _dot_rows(normal, facing) < FOLD
    # The nearest vertex's tangent plane is a second, independent opinion: where it says
    # "too close" although the anchor did not, look properly. It also catches points far
    # from every skin vertex because they are deep inside another part (a skirt's hem
    # swept into the belly by a raised thigh), not far outside.
    plane = _dot_rows(points - np.take(x, near, axis=0), normal) < need - PLANE_SLACK
    remote = np.flatnonzero((close & (other | turned)) | plane)
    if len(remote) == 0:
        return points
    points = points.copy()
    before = None
    for _ in range(iterations):
        exact = body.query(points[remote], k=4)
        short = exact.distance < need[remote] - 1e-5
        if not short.any():
            break
        # Points far enough out stay put, so only the short ones are looked at again.
        keep = np.flatnonzero(short)
        remote, exact = remote[keep], _take(exact, keep)
        moved = collision.push_out(points[remote], exact, need[remote])
        if before is not None:
            # Pushed out of one part straight into the facing one (an arm against the
            # chest): the middle of the gap between the two is as far from both as it gets.
            prior = _take(before, keep)
            caught = np.einsum("nd,nd->n", exact.normal, prior.normal) < CAUGHT
            moved[caught] = 0.5 * (exact.closest[caught] + prior.closest[caught])
        before = exact
        points[remote] = moved
    return points


def _other_part(rest_rows, rows, near3, rest_near, remote) -> np.ndarray:
    """(N,) bool: a point's nearest skin vertex lay further than ``remote`` (m, scalar or
    (N,)), at rest, from its anchor's vertex; or one of its three nearest came closer to
    that vertex than it was at rest.
    rest_rows, rows: (3, V) the skin's coordinate rows at rest and now."""
    rest_gap = _distances(rest_rows, near3, rest_near)
    gap = rest_gap if rows is rest_rows else _distances(rows, near3, rest_near)
    return (rest_gap[:, 0] > remote) | ((rest_gap - gap).max(axis=1) > CLOSING)


def _distances(rows: np.ndarray, near: np.ndarray, anchor: np.ndarray) -> np.ndarray:
    """(N, K) distances between the vertices ``near`` (N, K) and ``anchor`` (N,) of a
    skin given by its coordinate rows (3, V)."""
    square = np.zeros(near.shape, np.float32)
    for row in rows:
        d = np.take(row, near) - np.take(row, anchor)[:, None]
        square += d * d
    return np.sqrt(square)


def _dot_rows(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.einsum("nd,nd->n", a, b)


def _anchors(pose: Pose, garment: Garment, q, mesh: Mesh) -> tuple:
    """Rest-pose anchors of a garment for posed frames (see ``Outfit.anchors``); a shell's
    outer layer gets its own (triangle, barycentrics, clearance). Returns (anchors or
    None, the outer layer's anchored query or None)."""
    if q is None:
        return None, None
    tri, bary, near = garment.anchor_cache["inner"]
    inner = (tri, bary, pose.last_need, near)
    n = len(q.distance)
    if len(mesh.vertices) == n:
        return inner, None
    outer = mesh.vertices[n:]
    if "outer" not in garment.anchor_cache:
        qo = pose.query_near(outer)
        garment.anchor_cache["outer"] = (qo.triangle, qo.bary, qo.vertex)
    tri_o, bary_o, near_o = garment.anchor_cache["outer"]
    qo = pose.anchored(outer, tri_o, bary_o)
    keep = np.minimum(qo.distance, pose.last_need + np.float32(garment.thickness))
    return (*inner, tri_o, bary_o, np.maximum(keep, 0).astype(np.float32), near_o), qo


def _check_outer(pose: Pose, mesh: Mesh, anchor: tuple, qo) -> Mesh:
    """A shell's outer layer, grown along the body normal, checked against the whole body
    (in a fold it can reach the skin opposite); qo: its anchored query (``_anchors``)."""
    n = len(anchor[2])
    outer = mesh.vertices[n:]
    outer = fixed = collision.push_out(outer, qo, anchor[6])
    outer = remote_contacts(pose, None, outer, anchor[6], anchor[7], qo.normal, 4)
    # Squeezed between two body parts there may be no room for the shell: it thins there.
    moved = np.flatnonzero(np.any(outer != fixed, axis=1))
    if len(moved):
        stuck = moved[pose.query(outer[moved], k=4).distance < 0]
        outer[stuck] = mesh.vertices[stuck]
    return mesh.with_vertices(np.concatenate([mesh.vertices[:n], outer]))


def dress(human, garments: list[Garment], bone_names=None, exact: bool = False) -> Outfit:
    """Fit garments on a body, lowest ``z_depth`` first (see module docstring).

    human: anything with ``vertices`` (19158, 3), ``weights`` (SkinWeights over all
        vertices) and ``faces`` (or ``model.base.faces``); an ``avatar.human.Human`` works.
    exact: then test every garment vertex by winding number and move any inside out
        (``collision.escape``; ~0.1 s an outfit): for exports and datasets. Without it,
        fitting takes a few milliseconds a garment and a vertex in a deep fold (crotch,
        armpit) of a heavy body can stay up to ~1 mm inside.
    Returns an Outfit whose ``garments`` keep the input's layer order.
    """
    _anchor_on_default_body(human, garments)
    outfit = _dress(human, garments, bone_names)
    return _escape_rest(outfit) if exact else outfit


def _escape_rest(outfit: Outfit) -> Outfit:
    """The outfit with every garment vertex inside the rest body moved out of it."""
    assert outfit.rest_body is not None  # _dress sets it
    rest = [g.mesh.vertices for g in outfit.garments]
    for i, moved in enumerate(outfit._escape(outfit.posed_body(outfit.rest_body), rest)):
        if moved is rest[i] or np.array_equal(moved, rest[i]):
            continue
        outfit.garments[i] = replace(outfit.garments[i], mesh=outfit[i].mesh.with_vertices(moved))
        outfit.rest_surfaces[i] = moved[: len(outfit.rest_surfaces[i])]
    return outfit


def _dress(human, garments: list[Garment], bone_names) -> Outfit:
    vertices = np.asarray(human.vertices, dtype=np.float32)
    surface = body_surface(_body_faces(human))
    pose = Pose(surface, vertices)
    if bone_names is None and hasattr(human, "skeleton"):
        bone_names = human.skeleton.names
    fitted, rests, ws, anchors = [], [], [], []
    for garment in sorted(garments, key=lambda g: g.z_depth):
        inner, q = fit_garment(pose, garment, vertices)
        w = garment_weights(garment, human.weights, bone_names)
        mesh, mesh_w = (
            _with_shell(garment, inner, q, w)
            if q is not None
            else (garment.mesh.with_vertices(inner), w)
        )
        fitted.append(
            FittedGarment(
                garment.name,
                mesh,
                garment.material,
                mesh_w,
                garment.z_depth,
                garment.delete_verts,
                garment,
            )
        )
        rests.append(inner)
        ws.append(w.limit(FRAME_INFLUENCES))
        anchor, qo = _anchors(pose, garment, q, mesh)
        anchors.append(anchor)
        if qo is not None:
            mesh = _check_outer(pose, mesh, anchor, qo)
            fitted[-1] = replace(fitted[-1], mesh=mesh)
    return Outfit(fitted, surface, rests, ws, anchors, pose.vertices.copy())


def _anchor_on_default_body(human, garments: list[Garment]) -> None:
    """Find new garments' anchor triangles (``Garment.anchor_cache``) on the model's default
    body, each garment alone: a garment then fits a body the same way whichever bodies it
    met before (a dataset does not depend on its order)."""
    new = [g for g in garments if g.collide and "inner" not in g.anchor_cache]
    model = getattr(human, "model", None)
    if not new or model is None:
        return
    from avatar.human import Human

    default = Human({}, human.recipe.rig, model)
    for garment in new:
        _dress(default, [garment], None)
