"""Put garments on a body: fit each binding, push it out of the body, stack layers, solidify.

    outfit = dress(body, [load_garment("tshirt"), load_garment("jeans")])  # body: Human.body
    outfit.garments                # FittedGarment per garment, rest pose of this body
    outfit.frame(body, matrices)   # per posed frame: garment vertices (``outfit`` module)

Layers: garments are processed from the lowest ``z_depth`` up. Each one records, per body
vertex, how far out it reaches; a garment above must clear that height plus ``LAYER_GAP``,
so a jacket stays over a shirt and a shirt over its wearer, frame after frame.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from functools import cached_property

import numpy as np

from avatar.body.model import BODY_VERTICES
from avatar.body.shaped import Body, default_vertices
from avatar.clothes import weights
from avatar.clothes.binding import Binding, axis_scale, fit
from avatar.clothes.contacts import remote_contacts
from avatar.clothes.outfit import Outfit
from avatar.geometry import collision
from avatar.geometry.shell import Shell, corner_gather, extrude, solidify, summed_normals
from avatar.io.mhw import BoneWeights
from avatar.material import Material
from avatar.mesh import Mesh, face_normals
from avatar.rig.skinning import SkinWeights

CLEARANCE = 0.002  # m between skin and a garment's inside
LAYER_GAP = 0.0015  # m between stacked garments
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
    swing_below: m (height on the authored mesh); a skirt's (from the hips) or a loose
        top's (from the waist) transferred skin weights are smoothed over its cloth below
        it (``weights.swing``). None: as transferred.
    fly_share: (N,) loose trousers' bridge across the fly: each vertex's transferred
        weights shared this much with its mirror twin's (``weights.shared_across``).
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
    swing_below: float | None = None
    fly_share: np.ndarray | None = None

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
    def untangling(self) -> tuple:
        """(first (P,), second (P,)): the two faces of each shared edge; (N, N) sparse
        average of each vertex with its edge neighbours (``untangled``)."""
        from avatar.clothes.authoring import face_pairs
        from avatar.clothes.outfit import _spread_matrix

        n = len(self.mesh.vertices)
        return (*face_pairs(self.mesh.faces),
                _spread_matrix([self.mesh.faces], np.arange(n), 1))  # fmt: skip

    @cached_property
    def footwear_fairing(self) -> tuple:
        """((N, F) sparse: the faces at each vertex, ``corner_gather``; (N, 3) the made
        surface's detail, what ``DETAIL_PASSES`` neighbour averages take away): footwear's
        ``fitted_surface`` and ``shell_directions``, computed once."""
        spread = self.untangling[2]
        made = self.mesh.vertices.astype(np.float64)
        shape = made
        for _ in range(DETAIL_PASSES):
            shape = spread @ shape
        return corner_gather(self.mesh.faces, len(made)), made - shape

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


class Pose(collision.PosedBody):
    """One pose of the skin as a collider (``collision.PosedBody``) that also keeps the
    layer floors of the garments fitted on it so far."""

    def __init__(self, surface: collision.BodySurface, vertices: np.ndarray):
        super().__init__(surface, vertices[:BODY_VERTICES], tree_now=True)
        self.floor = np.zeros(BODY_VERTICES, np.float32)

    def query_near(self, points: np.ndarray) -> collision.SurfaceQuery:
        """Closest skin of points: one vertex ring each, four rings near the skin.

        One nearest vertex can miss the closest triangle where the body folds (armpits,
        crotch); that only matters for points close to the skin, which get four rings.
        """
        q = self.query(points, k=1)
        close = np.flatnonzero(np.abs(q.distance) < NEAR_BAND)
        return q.put(close, self.query(points[close], k=4)) if len(close) else q

    def resolve(self, points: np.ndarray, garment: Garment, iterations: int = 6):
        """Push a garment's bound surface (N, 3) out of the body and the layers below.

        Returns (points (N, 3) float32, query at the final positions).
        """
        bound = points
        q = self.query_near(points)
        need = np.full(len(points), garment.clearance, np.float32)
        for _ in range(iterations):
            need = np.maximum(garment.clearance, self._floor_at(q.vertex) + LAYER_GAP)
            short = np.flatnonzero(q.distance < need - 1e-5)
            if len(short) == 0:
                break
            # Only the points that moved need a new query.
            points = points.copy()
            points[short] = collision.push_out(points[short], q.take(short), need[short])
            q = q.put(short, self.query(points[short], k=4))
        points, moved = untangled(bound, points, garment)
        if len(moved):
            q = q.put(moved, self.query(points[moved], k=4))
            need = np.broadcast_to(need, q.distance.shape).copy()
            need[moved] = np.minimum(need[moved], np.maximum(q.distance[moved], garment.clearance))
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
        points, untangled_ = untangled(fitted, points, garment)
        q = self.anchored(points, tri, bary)
        kept = np.union1d(moved, untangled_)
        if len(kept):  # frames keep the clearance the squeezed, untangled cloth has
            exact = np.minimum(self.query(points[kept], k=4).distance, q.distance[kept])
            need = need.copy()
            need[kept] = np.minimum(need[kept], np.maximum(exact, garment.clearance))
        self._raise_floor(q, garment.thickness)
        self.last_need = need.astype(np.float32)
        return points, q

    def _floor_at(self, vertex: np.ndarray) -> np.ndarray:
        return self.floor[self.surface.neighbours[vertex]].max(axis=1)

    def _raise_floor(self, q: collision.SurfaceQuery, thickness: float) -> None:
        top = q.distance + np.float32(thickness)
        near = q.distance < FLOOR_REACH
        np.maximum.at(self.floor, q.vertex[near], top[near])


FOLDED = -0.2  # cos between neighbouring faces below which cloth counts as folded over
UNTANGLE_ROUNDS = 12


def untangled(bound: np.ndarray, points: np.ndarray, garment: Garment,
              like: np.ndarray | None = None) -> tuple:  # fmt: skip
    """(points (N, 3) float32, (M,) the vertices moved): ``points``, pushed out from
    ``bound`` (N, 3), with the pushes round faces they fold over (more than ~100 degrees
    against a neighbour, where ``bound`` does not) averaged with their neighbours' until
    none does. In a crease tighter than a layer's need (the armpit: a jacket over a T-shirt
    asks 2.4 cm where the binding left it 1.3 cm from arm and chest) neighbouring points
    were pushed along their own skin's normals the opposite ways, some towards the chest,
    some towards the arm: they crossed and 12 face pairs folded under a man's arms (a
    crumpled armpit, its stitching zig-zagging). ``like``: the surface whose folds are
    meant (default ``bound``)."""
    first, second, spread = garment.untangling
    faces = garment.mesh.faces
    points = np.asarray(points, np.float32)
    move = (points - bound).astype(np.float64)
    touched = np.zeros(len(points), bool)
    was = None  # (bands turned over at a hem fold by design; like: the surface whose folds are)
    for _ in range(UNTANGLE_ROUNDS):
        folded = _folds(bound + move, faces, first, second)
        if folded.any():
            if was is None:
                was = _folds((bound if like is None else like).astype(np.float64), faces,
                             first, second)  # fmt: skip
            folded &= ~was
        if not folded.any():
            break
        near = np.zeros(len(points), np.float64)
        near[faces[np.concatenate([first[folded], second[folded]])].ravel()] = 1.0
        near = (spread @ near) > 0  # and the ring round them
        move[near] = (spread @ move)[near]
        touched |= near
    if not touched.any():
        return points, np.zeros(0, np.intp)
    return (bound + move).astype(np.float32), np.flatnonzero(touched)


def _folds(v: np.ndarray, faces: np.ndarray, first: np.ndarray, second: np.ndarray) -> np.ndarray:
    """(P,) bool: faces ``first`` (P,) and ``second`` (P,) of ``v`` turned over each other."""
    n = face_normals(v, faces)
    n /= np.maximum(np.linalg.norm(n, axis=1), 1e-12)[:, None]
    return np.einsum("nd,nd->n", n[first], n[second]) < FOLDED


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
        if garment.swing_below is not None:
            result = weights.swing(result, garment.mesh, garment.swing_below)
        if garment.fly_share is not None:
            result = weights.shared_across(result, garment.mesh, garment.fly_share)
    garment.weight_cache[:] = [(body_weights, names, result)]  # holds body_weights: no id reuse
    return result


def _frame_weights(garment: Garment, w: SkinWeights) -> SkinWeights:
    """(N, K) the weights frames skin ``garment``'s surface with: its 4 largest, except
    where a skirt's weights ramp (``weights.swing``): there up to 8 bones each fade in and
    out smoothly, and a cut to 4 dropped a bone's last few percent between two vertices;
    and over a bridge across the fly (``weights.shared_across``: both legs' thighs, the
    spine and pelvis, up to 21% of a vertex's weight past the 4th, dropped unevenly).
    Items drawn on the skin with no push-out (stubble, brows, lashes: ``collide`` False)
    keep all theirs: nothing holds them out of the skin, and cut to 4 the stubble sank
    2-3 mm into the corners of the mouth with the neck bent (the face has many bones)."""
    if not garment.collide:
        return w
    limited = w.limit(FRAME_INFLUENCES)
    if (garment.swing_below is None and garment.fly_share is None) or limited is w:
        return limited
    held = np.ones(len(garment.mesh.vertices), bool)
    if garment.swing_below is not None:
        held &= garment.mesh.vertices[:, 2] >= garment.swing_below
    if garment.fly_share is not None:
        held &= garment.fly_share <= 0
    idx, wt = w.indices.copy(), w.weights.copy()
    idx[held], wt[held] = 0, 0.0
    k = limited.indices.shape[1]
    idx[held, :k], wt[held, :k] = limited.indices[held], limited.weights[held]
    return SkinWeights(idx, wt)


def _with_shell(garment: Garment, inner: np.ndarray, q, w: SkinWeights):
    shell = garment.shell
    if shell is None:
        return garment.mesh.with_vertices(inner), w
    verts = extrude(inner, shell_directions(garment, inner, q.normal), garment.thickness)
    both = SkinWeights(np.concatenate([w.indices] * 2), np.concatenate([w.weights] * 2))
    return shell.mesh.with_vertices(verts), both


def shell_directions(garment: Garment, inner: np.ndarray, skin_normal: np.ndarray) -> np.ndarray:
    """(N, 3) the directions a shell's outer layer grows along at rest: the skin's normal,
    except footwear's, along the shoe's own normals out on the side its faces face
    (``shoes._facing_out``), as frames grow it (``Outfit``). Grown along the skin's normal,
    which turns from toe to toe, a toe cap's outer surface turned 6 degrees more than its
    inner one between neighbouring faces (one edge in twenty; up to 150 on a child's) and
    its highlights showed blotches. A shoe is no skin-tight cloth: where it stands off the
    foot (the toe box past the toes, the sole's rim) the skin's normal says nothing of its
    outside. Turned to the skin's side, the sole's bottom rim grew inwards and was pulled
    back (a man's sole 0.6 mm off the floor); grown along the skin's normal where the shoe
    is edge-on to it, the nose's top grew forwards between points growing up (90 degrees
    between neighbouring faces on a man's)."""
    if garment.category != "footwear":
        return skin_normal
    normal = summed_normals(inner, garment.mesh.faces, garment.footwear_fairing[0])
    size = np.linalg.norm(normal, axis=1)[:, None]
    return np.where(size > 1e-12, normal / np.maximum(size, 1e-12), skin_normal).astype(np.float32)


# Neighbour averages that part a shoe's shape on a body from its detail: one evens the toe
# cap's faces (2 evened them a little more, but widened a child's sneaker for its foot by
# 0.6%, past the adults' range).
DETAIL_PASSES = 1


def fitted_surface(garment: Garment, body_vertices: np.ndarray) -> np.ndarray:
    """(N, 3) float32 a garment's surface on a body by its binding; footwear's smoothed:
    its broad shape from the binding, its detail (what ``DETAIL_PASSES`` neighbour
    averages take away) as made on the authoring body, scaled by the foot. A shoe's faces
    are each bound to the helper's nearest face, and on other feet neighbouring vertices'
    nearest faces jump across the helper's edges: the toe cap, faired to turn under 15
    degrees between neighbouring faces for all but one edge in twenty, turned 21 on a man's
    foot (up to 61): ripples over the toes."""
    points = fit(garment.binding, body_vertices)
    if garment.category != "footwear":
        return points
    spread = garment.untangling[2]
    shape = points.astype(np.float64)
    for _ in range(DETAIL_PASSES):
        shape = spread @ shape
    scale = axis_scale(garment.binding, np.asarray(body_vertices, np.float64))
    return (shape + scale * garment.footwear_fairing[1]).astype(np.float32)


def fit_garment(
    pose: Pose, garment: Garment, body_vertices: np.ndarray
) -> tuple[np.ndarray, object]:
    """(N, 3) bound surface of a garment on a body (rest), resolved when it collides."""
    points = fitted_surface(garment, body_vertices)
    if not garment.collide:
        return points, None
    if "inner" in garment.anchor_cache:
        return pose.resolve_anchored(points, garment)
    points, q = pose.resolve(points, garment)
    garment.anchor_cache["inner"] = (q.triangle, q.bary, q.vertex)
    return points, q


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


def _check_outer(pose: Pose, mesh: Mesh, anchor: tuple, qo, garment: Garment) -> Mesh:
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
    # The outer layer is the one seen: where it folds over and the inner layer does not,
    # its pushes are shared (``untangled``; grown along the skin's normals, which turn
    # through a crease, it folded under the arm where the inner layer did not).
    outer = untangled(mesh.vertices[:n], outer, garment)[0]
    return mesh.with_vertices(np.concatenate([mesh.vertices[:n], outer]))


def dress(body: Body, garments: list[Garment], exact: bool = False) -> Outfit:
    """Fit garments on a body, lowest ``z_depth`` first (see module docstring).

    body: the shaped body (``avatar.body.shaped.Body``, e.g. ``Human.body``); garments are
        skinned to its skeleton.
    exact: then test every garment vertex by winding number and move any inside out
        (``collision.escape``; ~0.1 s an outfit): for exports and datasets. Without it,
        fitting takes a few milliseconds a garment and a vertex in a deep fold (crotch,
        armpit) of a heavy body can stay up to ~1 mm inside.
    Returns an Outfit whose ``garments`` keep the input's layer order.
    """
    _anchor_on_default_body(body, garments)
    garments = [_worn_by(body, g) for g in garments]
    outfit = _dress(body.vertices, body.faces, body.weights, body.skeleton.names, garments)
    return _escape_rest(outfit) if exact else outfit


def worn_thickness(garment: Garment, vertices: np.ndarray) -> float:
    """m: a garment's shell thickness on the body of ``vertices`` (19158, 3). Footwear on a
    smaller foot than it was made on (its binding scaled by the foot: the built-in shoes'
    ``shoes._scaled_by_the_foot``) is made of thinner material alike (a child's shoe's
    leather, ~1.5 mm): the authored thickness x the foot's mean scale, never thicker. At a
    fixed 2.5 mm, a child's sneakers stood 1.35 x the foot's width, an adult's 1.27-1.33."""
    if garment.category != "footwear" or garment.thickness <= 0:
        return garment.thickness
    scale = float(np.mean(axis_scale(garment.binding, np.asarray(vertices, np.float64))))
    return garment.thickness * min(1.0, scale)


def _worn_by(body: Body, garment: Garment) -> Garment:
    """The garment with its ``worn_thickness`` on ``body``; anchors, weights and the
    shell's topology its own (shared: nothing is found again)."""
    thickness = worn_thickness(garment, body.vertices)
    if thickness == garment.thickness:
        return garment
    thin = replace(garment, thickness=thickness)
    for key in ("anchor_cache", "weight_cache", "shell", "untangling", "footwear_fairing"):
        thin.__dict__[key] = getattr(garment, key)
    return thin


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


def _dress(
    vertices: np.ndarray,
    faces: np.ndarray,
    body_weights: SkinWeights,
    bone_names,
    garments: list[Garment],
) -> Outfit:
    """The outfit of ``garments`` fitted on the body of ``vertices`` (19158, 3)."""
    vertices = np.asarray(vertices, dtype=np.float32)
    surface = collision.skin_surface(faces)
    pose = Pose(surface, vertices)
    fitted, rests, ws, anchors = [], [], [], []
    for garment in sorted(garments, key=lambda g: g.z_depth):
        inner, q = fit_garment(pose, garment, vertices)
        w = garment_weights(garment, body_weights, bone_names)
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
        ws.append(_frame_weights(garment, w))
        anchor, qo = _anchors(pose, garment, q, mesh)
        anchors.append(anchor)
        if qo is not None:
            mesh = _check_outer(pose, mesh, anchor, qo, garment)
            fitted[-1] = replace(fitted[-1], mesh=mesh)
    return Outfit(fitted, surface, rests, ws, anchors, pose.vertices.copy())


def _anchor_on_default_body(body: Body, garments: list[Garment]) -> None:
    """Find new garments' anchor triangles (``Garment.anchor_cache``) on the model's default
    body, each garment alone: a garment then fits a body the same way whichever bodies it
    met before (a dataset does not depend on its order). Skin weights belong to the rig,
    not the shape, so the default body borrows ``body``'s."""
    new = [g for g in garments if g.collide and "inner" not in g.anchor_cache]
    if not new:
        return
    default = default_vertices(body.model)
    for garment in new:
        _dress(default, body.faces, body.weights, body.skeleton.names, [garment])
