"""An outfit: garments fitted on one body, and their posed frames.

``Outfit.frame(body, matrices)`` skins every garment, keeps each point clear of the skin it
was anchored to at rest, and checks the points near other body parts
(``contacts.remote_contacts``); ``exact=True`` then tests every vertex by winding number.
A frame is a pure function of the pose: frames can be made in any order.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from typing import TYPE_CHECKING

import numpy as np
from scipy.sparse import csc_matrix, csr_matrix

from avatar.body.model import BODY_VERTICES
from avatar.clothes.contacts import REMOTE_K, remote_contacts
from avatar.clothes.hems import HemSpread
from avatar.geometry import collision
from avatar.geometry.nearest import PointTree
from avatar.rig.skinning import SkinWeights, linear_blend

if TYPE_CHECKING:
    from avatar.clothes.fitting import FittedGarment



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
        return collision.PosedBody(self.surface, body_posed[:BODY_VERTICES], tree_now=True)

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
        both = linear_blend(lay.rest, lay.weights, matrices)
        skinned = both[: lay.count]
        if not lay.colliding_garments:
            return np.split(skinned, lay.splits)
        points = skinned[lay.colliding]
        q = body.anchored(points, lay.triangle, lay.bary)
        inner = collision.push_out(points, q, lay.need)
        inner = _spread_pushes(body, lay, points, inner)
        # Shells: the outer layer grown off the inner one along the cloth's normal (as
        # pushed out), then kept clear of the skin it is closest to.
        turned = both[lay.count:] - points[lay.shell]  # the rest normal, skinned
        cloth = lay.shell_cloth.normals(inner, turned)
        outer = inner[lay.shell] + lay.thickness[:, None] * cloth
        qo = body.anchored(outer, lay.outer_triangle, lay.outer_bary)
        outer = collision.push_out(outer, qo, lay.outer_need)
        # One search for all garments, both shell layers (where the body folds, the outer
        # one can reach the next part); each point is checked on its own, except points
        # that moved with one bone as all skin near them did (they sit as at rest).
        joined = np.concatenate([inner, outer])[lay.remote_order]
        check = self._rigid.changed(body.vertices, joined, matrices)
        joined[check] = remote_contacts(
            body,
            self.rest_rows,
            joined[check],
            lay.remote_need[check],
            lay.remote_near[check],
            np.concatenate([q.normal, qo.normal])[lay.remote_order][check],
            iterations=4,
        )
        _keep_apart(joined, lay, cloth)
        out = np.split(skinned, lay.splits)
        for i, part in zip(lay.colliding_garments, np.split(joined, lay.remote_splits),
                           strict=True):  # fmt: skip
            out[i] = part
        return out

    @cached_property
    def _layout(self) -> _FrameLayout:
        return _FrameLayout.of(self)

    @cached_property
    def _rigid(self) -> _RigidPoints:
        return _RigidPoints.of(self, self._layout)


@dataclass(frozen=True, eq=False)
class _FrameLayout:
    """An outfit's garments laid end to end, so that a posed frame skins and anchors them
    all in a few whole-array steps (``Outfit._frame_anchored``)."""

    # (N + S, 3) every garment's bound surface at rest, garment after garment, then the
    # shells' outer layers (S rows), and (N + S, K) their frame weights (an outer point
    # has its inner point's)
    rest: np.ndarray
    weights: SkinWeights
    count: int  # N
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
    shell_cloth: _ShellCloth  # the shells' faces, for their normals in a frame
    spread: csc_matrix  # (S, S) a shell point's push shared with its cloth neighbours
    hem: HemSpread  # and, where a skirt swings, with all its cloth near it
    pair_inner: np.ndarray  # (S,) the remote rows of each shell point's inner and outer layer
    pair_outer: np.ndarray
    remote_order: np.ndarray  # rows of [inner; outer] in output order (inner, outer per garment)
    remote_need: np.ndarray  # their clearances and rest nearest skin vertices, in that order
    remote_near: np.ndarray
    remote_splits: np.ndarray
    colliding_garments: list[int]

    @classmethod
    def of(cls, outfit: Outfit) -> _FrameLayout:
        rests, ws = outfit.rest_surfaces, outfit.surface_weights
        starts = np.cumsum([0] + [len(r) for r in rests])
        pairs = enumerate(zip(outfit.garments, outfit.anchors, strict=True))
        hits = [(i, g, a) for i, (g, a) in pairs if a is not None]
        shells = [(g, a) for _, g, a in hits if len(a) > 4]
        # The shells' outer layers at rest, along the cloth's normals (``_outer_at_rest``),
        # skinned with their inner points' weights.
        outer_rest = [_outer_at_rest(g, len(a[2])) for g, a in shells]
        both = list(rests) + outer_rest
        outer_ws = [ws[i] for i, _, a in hits if len(a) > 4]
        width = max(w.indices.shape[1] for w in ws)
        weights = SkinWeights(_cat([_pad(w.indices, width) for w in ws + outer_ws], np.int32),
                              _cat([_pad(w.weights, width) for w in ws + outer_ws],
                                   np.float32))  # fmt: skip
        # Rows of [inner; outer] as the garments' outputs take them: each garment's inner
        # layer, then its outer layer if it is a shell.
        inner_at = np.cumsum([0] + [len(a[2]) for _, _, a in hits])
        outer_at = inner_at[-1] + np.cumsum([0] + [len(a[2]) for _, a in shells])
        order, need, near, sizes, s = [], [], [], [], 0
        shell_rows = _cat([np.arange(inner_at[k], inner_at[k + 1])
                           for k, (_, _, a) in enumerate(hits) if len(a) > 4], np.intp)  # fmt: skip
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
        position = np.empty(sum(sizes), np.intp)  # row of [inner; outer] -> remote row
        position[_cat(order, np.intp)] = np.arange(sum(sizes))
        return cls(
            rest=_cat(both, np.float32),
            weights=weights,
            count=int(starts[-1]),
            splits=starts[1:-1],
            colliding=_cat([np.arange(starts[i], starts[i + 1]) for i, _, _ in hits], np.intp),
            triangle=_cat([a[0] for _, _, a in hits], np.int32),
            bary=_cat([a[1] for _, _, a in hits], np.float32, 3),
            need=_cat([a[2] for _, _, a in hits], np.float32),
            shell=shell_rows,
            thickness=_cat([np.full(len(a[2]), g.garment.thickness) for g, a in shells],
                           np.float32),  # fmt: skip
            outer_triangle=_cat([a[4] for _, a in shells], np.int32),
            outer_bary=_cat([a[5] for _, a in shells], np.float32, 3),
            outer_need=_cat([a[6] for _, a in shells], np.float32),
            shell_cloth=_ShellCloth.of(
                [g.garment.mesh.faces + inner_at[k] for k, (_, g, a) in enumerate(hits)
                 if len(a) > 4], shell_rows),  # fmt: skip
            spread=_spread_matrix(
                [g.garment.mesh.faces + inner_at[k] for k, (_, g, a) in enumerate(hits)
                 if len(a) > 4], shell_rows),  # fmt: skip
            hem=HemSpread.of(_cat([rests[i] for i, _, a in hits if len(a) > 4], np.float32, 3),
                             _cat([_swinging(g, len(a[2])) for g, a in shells],
                                  bool)),  # fmt: skip
            pair_inner=position[shell_rows],
            pair_outer=position[inner_at[-1] + np.arange(len(shell_rows))],
            remote_order=_cat(order, np.intp),
            remote_need=_cat(need, np.float32),
            remote_near=_cat(near, np.intp),
            remote_splits=np.cumsum(sizes)[:-1],
            colliding_garments=[i for i, _, _ in hits],
        )


RIGID_POINTS = 1000  # fewest garment points moving mostly with one bone worth the shortcut
CLEAR = 0.01  # m: skin further than this beyond a point's REMOTE_K-th nearest is no contact
STILL = 2e-4  # m a vertex may move in a bone's frame and still count as unmoved


@dataclass(frozen=True, eq=False)
class _RigidPoints:
    """Garment points that move with one bone, as the skin round them does (short hair on
    the head: ~9,000 card vertices, most of a frame's remote-contact search). Where such
    a point and all skin within its reach (its REMOTE_K-th nearest skin vertex at rest, plus
    CLEAR) have moved less than STILL in the bone's frame, the skin round it is as at rest,
    so the point sits on it as at rest and the search can leave it out: the full search
    would move it at most about 2 STILL (0.4 mm; clearances are millimetres). Skin that
    moved (the neck under a nodding head, a hand raised to the hair) is found in the bone's
    frame, and only points it has come within reach of are searched."""

    count: int  # remote-contact rows
    bones: list[int]
    rows: list[np.ndarray]  # per bone: (P,) remote rows of the points it moves most
    rest_points: list[np.ndarray]  # per bone: (P, 3) float32 their rest positions
    reach: list[np.ndarray]  # per bone: (P,) float32 m within which moved skin matters
    box: list[np.ndarray]  # per bone: (2, 3) the points' rest box, grown by their reach
    rest: np.ndarray  # (V, 3) float32 the rest skin

    @classmethod
    def of(cls, outfit: Outfit, lay: _FrameLayout) -> _RigidPoints:
        from scipy.spatial import cKDTree

        skin = np.zeros((0, 3), np.float32)
        if outfit.rest_body is not None:
            skin = np.asarray(outfit.rest_body[:BODY_VERTICES], np.float32)
        found = cls(len(lay.remote_order), [], [], [], [], [], skin)
        # Inner-layer rows only (a shell's outer layer also follows the skin's normals).
        at = np.flatnonzero(lay.remote_order < len(lay.colliding))
        if len(skin) == 0 or len(at) == 0:
            return found
        inner = lay.colliding[lay.remote_order[at]]
        bone_of = _top_bone(lay.weights, inner)
        points = lay.rest[inner].astype(np.float32)
        reach = cKDTree(skin).query(points, k=REMOTE_K)[0][:, -1] + CLEAR
        for bone in np.unique(bone_of[bone_of >= 0]):
            rows = np.flatnonzero(bone_of == bone)
            if len(rows) < RIGID_POINTS:
                continue
            grow = reach[rows].max()
            box = np.stack([points[rows].min(0) - grow, points[rows].max(0) + grow])
            found.bones.append(int(bone))
            found.rows.append(at[rows])
            found.rest_points.append(points[rows])
            found.reach.append(reach[rows].astype(np.float32))
            found.box.append(box.astype(np.float32))
        return found

    def changed(self, skin: np.ndarray, points: np.ndarray, matrices: np.ndarray) -> np.ndarray:
        """(count,) bool: the remote rows to search in this pose (skin (V, 3) and the
        remote-contact points (count, 3) posed by the skinning matrices (J, 4, 4))."""
        check = np.ones(self.count, bool)
        for bone, rows, rest_points, reach, box in zip(
            self.bones, self.rows, self.rest_points, self.reach, self.box, strict=True
        ):
            back = np.linalg.inv(matrices[bone]).astype(np.float32)  # posed -> the bone's rest
            local = skin @ back[:3, :3].T + back[:3, 3]
            near = _inside(local, box)  # skin further out is beyond every point's reach
            moved = near[_lengths(local[near] - self.rest[near]) > STILL]
            own = points[rows] @ back[:3, :3].T + back[:3, 3] - rest_points
            still = np.flatnonzero(_lengths(own) <= STILL)
            if len(moved) and len(still):
                gap, _ = PointTree(local[moved]).query(rest_points[still], reach=float(reach.max()))
                still = still[gap > reach[still]]
            check[rows[still]] = False
        return check


def _keep_apart(joined: np.ndarray, lay: _FrameLayout, cloth: np.ndarray) -> None:
    """Move each shell's outer points (in ``joined``, the remote-contact rows) out along
    the cloth's normals ``cloth`` (S, 3) until they stand the thickness off their inner
    ones: pushed out of another body part each to its own clearance along that skin's
    normal, which a fold meets at a slant, the two layers of a skirt's hem pressed by the
    other calf came within 0.1 mm along the cloth's normal and showed through each other."""
    inner, outer = joined[lay.pair_inner], joined[lay.pair_outer]
    gap = np.einsum("nd,nd->n", outer - inner, cloth)
    short = np.flatnonzero(gap < lay.thickness - 1e-5)
    joined[lay.pair_outer[short]] = outer[short] + (lay.thickness - gap)[short, None] * cloth[short]


SPREAD_PASSES = 2  # neighbour averages a shell point's push is shared over (rings of cloth)
SPREAD_LEAST = 5e-4  # m: shorter pushes are left alone (no visible step)


def _spread_pushes(body: collision.PosedBody, lay: _FrameLayout, points: np.ndarray,
                   pushed: np.ndarray) -> np.ndarray:  # fmt: skip
    """(C, 3) the colliding points ``pushed`` out of the skin they are anchored to from
    ``points`` (C, 3), with each shell point's push shared with the cloth round it
    (``_shared``), those moved kept clear of their own skin again. Pushed alone, the
    points of a child's dress's hem that the calf of the back leg swept into stood 8-15 mm
    out of their rows early in the stride, their neighbours where they were: two faces of
    the cloth turned 56 degrees against each other (a faceted flap at the hem, light or
    dark by its slant; 41 degrees shared)."""
    push = pushed[lay.shell] - points[lay.shell]
    take, shared = _over(_shared(lay.spread, push), lay.hem.shared(push), len(push))
    if len(take) == 0:
        return pushed
    rows = lay.shell[take]
    out = pushed.copy()
    grown = points[rows] + shared
    q = body.anchored(grown, lay.triangle[rows], lay.bary[rows])
    out[rows] = collision.push_out(grown, q, lay.need[rows])
    return out


def _shared(spread: csc_matrix, push: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Points' pushes (S, 3) shared with their cloth neighbours by ``spread`` (S, S):
    (T,) the points whose neighbourhood's mean push is longer than their own and (T, 3)
    that push (a point keeps its own push where it is the longer)."""
    size = np.einsum("nd,nd->n", push, push)
    moved = np.flatnonzero(size > SPREAD_LEAST**2)
    if len(moved) == 0:
        return np.zeros(0, np.intp), np.zeros((0, 3), np.float32)
    shared = np.asarray(spread[:, moved] @ push[moved], np.float32)
    take = np.flatnonzero(np.einsum("nd,nd->n", shared, shared) > size + 1e-10)
    return take, shared[take]


def _over(a: tuple, b: tuple, count: int) -> tuple[np.ndarray, np.ndarray]:
    """Two sets of shared pushes ((T,) rows, (T, 3) pushes) merged, ``b``'s where a row is
    in both."""
    if len(b[0]) == 0:
        return a
    push = np.zeros((count, 3), np.float32)
    push[a[0]] = a[1]
    push[b[0]] = b[1]
    take = np.union1d(a[0], b[0])
    return take, push[take]


def _swinging(g: FittedGarment, count: int) -> np.ndarray:
    """(count,) bool a shell's inner rows that swing (below ``Garment.swing_below``)."""
    below = g.garment.swing_below
    if below is None or len(g.garment.mesh.vertices) != count:
        return np.zeros(count, bool)
    return g.garment.mesh.vertices[:, 2] < below


def _spread_matrix(faces: list[np.ndarray], shell: np.ndarray,
                   passes: int = SPREAD_PASSES) -> csc_matrix:  # fmt: skip
    """(S, S) float32 ``SPREAD_PASSES`` averages of each shell row with its edge neighbours
    (faces: each shell's (F_i, C) faces as colliding rows; shell: (S,) those rows)."""
    n = len(shell)
    if not faces:
        return csc_matrix((n, n), dtype=np.float32)
    joined = np.concatenate(faces)
    where = np.full(int(max(joined.max(), shell.max())) + 1, -1, np.intp)
    where[shell] = np.arange(n)
    a = where[joined.reshape(-1)]
    b = where[np.roll(joined, -1, axis=1).reshape(-1)]
    keep = (a >= 0) & (b >= 0)
    a, b = a[keep], b[keep]
    step = csr_matrix((np.ones(2 * len(a) + n, np.float32),
                       (np.concatenate([a, b, np.arange(n)]),
                        np.concatenate([b, a, np.arange(n)]))), shape=(n, n))  # fmt: skip
    step.data[:] = 1.0  # an edge shared by two faces counts once
    step = csr_matrix(step.multiply(1.0 / np.asarray(step.sum(axis=1))), dtype=np.float32)
    out = step
    for _ in range(passes - 1):
        out = out @ step
    return csc_matrix(out, dtype=np.float32)  # columns: the few pushed points' shares


def _top_bone(weights: SkinWeights, rows: np.ndarray) -> np.ndarray:
    """(R,) the bone that moves each of the vertices ``rows`` most (at least half), else -1."""
    w, idx = weights.weights[rows], weights.indices[rows]
    top = np.argmax(w, axis=1)
    at = np.arange(len(rows))
    return np.where(w[at, top] >= 0.5, idx[at, top], -1)


def _inside(points: np.ndarray, box: np.ndarray) -> np.ndarray:
    """(N,) indices of the points (N, 3) inside the box (2, 3), one axis at a time (a third
    of the time of a whole (N, 3) comparison)."""
    at = np.arange(len(points))
    for axis in range(3):
        column = points[at, axis]
        at = at[(column >= box[0, axis]) & (column <= box[1, axis])]
    return at


def _lengths(v: np.ndarray) -> np.ndarray:
    return np.sqrt(np.einsum("nd,nd->n", v, v))


def _cat(arrays: list, dtype, width: int | None = None) -> np.ndarray:
    """The arrays end to end as ``dtype`` (an empty (0,) or (0, width) array for none)."""
    if not arrays:
        return np.zeros((0,) if width is None else (0, width), dtype)
    return np.concatenate(arrays).astype(dtype)


def _pad(a: np.ndarray, width: int) -> np.ndarray:
    """(N, width) a padded on the right with zeros (index 0, weight 0: no influence)."""
    return np.pad(a, ((0, 0), (0, width - a.shape[1])))


@dataclass(frozen=True, eq=False)
class _ShellCloth:
    """The shells' inner layers as cloth, for their vertex normals in a posed frame: the
    outer layer is grown along them. Grown along the skin's normal, which loose cloth meets
    at a slant and which turns with the limb under it, a flared skirt's two layers met and
    crossed mid-stride (-0.4 mm apart at the hem behind the shin): the inner layer's faces
    showed through the outer's in jagged dark and light flaps."""

    faces: np.ndarray  # (F, C) the shells' faces, as colliding rows
    gather: csr_matrix  # (S, F) which faces meet at each shell row

    @classmethod
    def of(cls, faces: list[np.ndarray], shell: np.ndarray) -> _ShellCloth:
        """faces: each shell's (F_i, C) faces as colliding rows; shell: (S,) those rows."""
        if not faces:
            return cls(np.zeros((0, 3), np.intp), csr_matrix((len(shell), 0), dtype=np.float32))
        joined = np.concatenate(faces)
        where = np.full(int(joined.max()) + 1, -1, np.intp)
        where[shell] = np.arange(len(shell))
        pairs = np.unique(np.stack([where[joined].ravel(),
                                    np.repeat(np.arange(len(joined)), joined.shape[1])], 1),
                          axis=0)  # fmt: skip
        gather = csr_matrix((np.ones(len(pairs), np.float32), (pairs[:, 0], pairs[:, 1])),
                            shape=(len(shell), len(joined)))  # fmt: skip
        return cls(joined, gather)

    def normals(self, points: np.ndarray, turned: np.ndarray) -> np.ndarray:
        """(S, 3) float32 unit normals of the shells' cloth (colliding points (C, 3)) at
        their rows, on the side of ``turned`` (S, 3), the rest normals skinned; those where
        the cloth is edge-on to that side (a rolled band's rim) or has no normal."""
        c = points[self.faces]
        across = np.cross(c[:, 2] - c[:, 0], c[:, -1] - c[:, 1])
        normal = np.asarray(self.gather @ across, np.float32)
        size = np.maximum(_lengths(normal), 1e-12)
        length = np.maximum(_lengths(turned), 1e-12)
        cos = np.einsum("nd,nd->n", normal, turned) / (size * length)
        unit = normal * (np.sign(cos) / size)[:, None]
        return np.where((np.abs(cos) > EDGE_ON)[:, None], unit,
                        turned / length[:, None]).astype(np.float32)  # fmt: skip


EDGE_ON = 0.2  # cosine between the cloth's and the skin's normals below which cloth is edge-on


def _outer_at_rest(g: FittedGarment, count: int) -> np.ndarray:
    """(count, 3) float32 a shell's outer layer at rest for posed frames: its inner layer
    (the first ``count`` vertices) grown by the thickness along the cloth's own normals.
    The fitted outer layer is grown along the skin's normal, which loose cloth meets at a
    slant (a flared skirt's hem, 1.2-1.5 mm apart along the cloth's normal instead of 3):
    skinned with a stride, its two layers met and showed through each other."""
    inner = g.mesh.vertices[:count].astype(np.float64)
    grown = g.mesh.vertices[count:].astype(np.float64) - inner
    faces = g.garment.mesh.faces
    corners = inner[faces]
    across = np.cross(corners[:, 2] - corners[:, 0], corners[:, -1] - corners[:, 1])
    normal = np.zeros_like(inner)
    for k in range(faces.shape[1]):
        np.add.at(normal, faces[:, k], across)
    length = np.linalg.norm(normal, axis=1)
    unit = normal / np.maximum(length, 1e-12)[:, None]
    cos = np.einsum("nd,nd->n", unit, grown) / np.maximum(np.linalg.norm(grown, axis=1), 1e-12)
    unit *= np.sign(cos)[:, None]  # outwards, as grown
    # Where the cloth turns edge-on to the skin (a band rolled over at an armhole), its
    # normal is no way out: the grown direction stays.
    unit = np.where((np.abs(cos) > EDGE_ON)[:, None], unit, grown)
    unit /= np.maximum(np.linalg.norm(unit, axis=1), 1e-12)[:, None]
    return (inner + g.garment.thickness * unit).astype(np.float32)


def _frame_need(g: FittedGarment, anchor: tuple, count: int) -> np.ndarray:
    """(M,) m each posed garment vertex keeps from the skin: its rest clearance (the
    layer below plus a gap), and for a shell's outer layer that plus the thickness."""
    need = anchor[2]
    if count > len(need):
        need = np.concatenate([need, need + np.float32(g.garment.thickness)])
    return need
