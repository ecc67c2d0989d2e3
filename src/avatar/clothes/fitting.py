"""Put garments on a body: fit each binding, push it out of the body, stack layers, solidify.

    outfit = dress(human, [load_garment("tshirt"), load_garment("jeans")])
    outfit.garments          # FittedGarment per garment, rest pose of this body
    outfit.frame(matrices)   # (per posed frame) garment vertices, skinned and resolved

Layers: garments are processed from the lowest ``z_depth`` up. Each one records, per body
vertex, how far out it reaches; a garment above must clear that height plus ``LAYER_GAP``,
so a jacket stays over a shirt and a shirt over its wearer, frame after frame.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property, lru_cache

import numpy as np
from scipy.spatial import cKDTree

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
REMOTE_REACH = 0.03  # m; intrusions of another part deeper than about this are not sought
FOLD = 0.3  # cosine between anchor and nearest-skin normals below which the skin folded
REMOTE = 0.02  # m at rest between a point's anchor and its nearest skin: another body part
FLOOR_REACH = 0.04  # m; garment parts further out (loose hems, hair ends) define no layer


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


def body_surface(faces: np.ndarray) -> collision.BodySurface:
    """The collision surface of the skin (faces of vertices < 13,380), cached by topology."""
    faces = np.asarray(faces, dtype=np.int32)
    skin = faces[(faces < BODY_VERTEX_COUNT).all(axis=1)]
    return _surface_cached(np.ascontiguousarray(skin).tobytes(), skin.shape)


class Pose:
    """One pose of the body as a collider: positions, vertex normals and a cKDTree."""

    def __init__(self, surface: collision.BodySurface, vertices: np.ndarray):
        self.surface = surface
        self.vertices = np.asarray(vertices[:BODY_VERTEX_COUNT], dtype=np.float32)
        self.normals = surface.normals(self.vertices)
        self.tree = cKDTree(self.vertices, balanced_tree=False, compact_nodes=False)
        self.floor = np.zeros(BODY_VERTEX_COUNT, np.float32)

    def query(self, points: np.ndarray, k: int = 1) -> collision.SurfaceQuery:
        return collision.query(
            self.vertices, self.surface, points, k=k, tree=self.tree, normals=self.normals
        )

    def resolve(self, points: np.ndarray, garment: Garment, iterations: int = 6):
        """Push a garment's bound surface (N, 3) out of the body and the layers below.

        Returns (points (N, 3) float32, query at the final positions).
        """
        # k=4 candidate rings: one nearest vertex can miss the closest triangle where the
        # body folds (armpits, crotch), leaving points inside that a finer query finds.
        q = self.query(points, k=4)
        need = np.float32(garment.clearance)
        for _ in range(iterations):
            need = np.maximum(garment.clearance, self._floor_at(q.vertex) + LAYER_GAP)
            if np.all(q.distance >= need - 1e-5):
                break
            points = collision.push_out(points, q, need)
            q = self.query(points, k=4)
        self._raise_floor(q, garment.thickness)
        self.last_need = np.broadcast_to(need, q.distance.shape).astype(np.float32)
        return points, q

    def _floor_at(self, vertex: np.ndarray) -> np.ndarray:
        ring = self.surface.triangles[self.surface.rings[vertex]]  # (N, R, 3) neighbours
        return self.floor[ring].reshape(len(vertex), -1).max(axis=1)

    def _raise_floor(self, q: collision.SurfaceQuery, thickness: float) -> None:
        top = q.distance + np.float32(thickness)
        near = q.distance < FLOOR_REACH
        np.maximum.at(self.floor, q.vertex[near], top[near])


def _body_faces(human) -> np.ndarray:
    faces = getattr(human, "faces", None)
    if faces is None:
        faces = human.model.base.faces
    return np.asarray(faces)


def garment_weights(garment: Garment, body_weights: SkinWeights, bone_names=None) -> SkinWeights:
    """(N, K) skin weights of the garment's bound surface: its ``.mhw`` or the body's."""
    if garment.bone_weights is not None and bone_names is not None:
        return weights.from_file(garment.bone_weights, bone_names, len(garment.binding))
    return weights.transfer(garment.binding, body_weights)


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
    return pose.resolve(points, garment)


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

    def frame(
        self, body_posed: np.ndarray, matrices: np.ndarray, exact: bool = False
    ) -> list[np.ndarray]:
        """Garment vertices (M_i, 3) for one posed frame.

        body_posed: (V, 3) the body skinned with ``matrices`` (J, 4, 4) skinning matrices.
        exact: search the whole body for every vertex (finds contacts with other body parts,
            ~10x slower); by default each vertex keeps its clearance above the skin it was
            closest to at rest, which moves with it (real time).
        """
        if not exact and len(self.anchors) == len(self.garments):
            return self._frame_anchored(body_posed, matrices)
        pose = Pose(self.surface, body_posed)
        out = []
        for g, rest, w in zip(self.garments, self.rest_surfaces, self.surface_weights, strict=True):
            points = linear_blend(rest, w, matrices)
            if not g.garment.collide:
                out.append(_shell_frame(g, points, None))
                continue
            points, q = pose.resolve(points, g.garment, iterations=1)
            out.append(_shell_frame(g, points, q))
        return out

    def _frame_anchored(self, body_posed: np.ndarray, matrices: np.ndarray) -> list[np.ndarray]:
        x = np.asarray(body_posed[:BODY_VERTEX_COUNT], dtype=np.float32)
        normals = self.surface.normals(x)
        tree = cKDTree(x, balanced_tree=False, compact_nodes=False)
        out = []
        for g, rest, w, anchor in zip(
            self.garments, self.rest_surfaces, self.surface_weights, self.anchors, strict=True
        ):
            points = linear_blend(rest, w, matrices)
            if anchor is None:
                out.append(points)
                continue
            q = collision.anchored(x, normals, self.surface, points, anchor[0], anchor[1])
            points = _shell_frame(g, collision.push_out(points, q, anchor[2]), q)
            facing = q.normal
            if len(anchor) > 4:  # the outer layer keeps clear of the skin it is closest to
                n = len(anchor[2])
                qo = collision.anchored(x, normals, self.surface, points[n:], anchor[4], anchor[5])
                points[n:] = collision.push_out(points[n:], qo, anchor[6])
                facing = np.concatenate([q.normal, qo.normal])
            # Both shell layers: where the body folds, the outer one can reach the next part.
            need, near = anchor[2], anchor[3]
            if len(anchor) > 4:
                need, near = np.concatenate([need, need]), np.concatenate([near, anchor[7]])
            out.append(self._remote_contacts(x, normals, tree, points, need, near, facing))
        return out

    def _remote_contacts(self, x, normals, tree, points, need, rest_near, facing) -> np.ndarray:
        """Push points out of body parts other than the skin they are anchored to (an arm
        swinging into a shirt's side, one thigh into the other trouser leg). Such a point's
        nearest skin vertex now lies far, at rest, from its nearest one at rest, or faces
        another way than its anchor (a fold closing, as in the crotch); only those few, and
        only when close to the skin, get the exact search."""
        dist, near = tree.query(points, k=1, distance_upper_bound=REMOTE_REACH)
        close = np.isfinite(dist)
        near = np.where(close, near, 0)
        apart = np.linalg.norm(self.rest_body[near] - self.rest_body[rest_near], axis=1)
        turned = np.einsum("nd,nd->n", normals[near], facing) < FOLD
        remote = np.flatnonzero(close & ((apart > REMOTE) | turned))
        if len(remote) == 0:
            return points
        exact = collision.query(x, self.surface, points[remote], k=4, tree=tree, normals=normals)
        points = points.copy()
        points[remote] = collision.push_out(points[remote], exact, need[remote])
        return points


def _shell_frame(g: FittedGarment, points: np.ndarray, q) -> np.ndarray:
    if g.garment.shell is None or q is None:
        return points
    return extrude(points, q.normal, g.garment.thickness)


def outward(garment: Garment, points: np.ndarray, body_normal: np.ndarray) -> np.ndarray:
    """(N, 3) the garment surface's own unit normals, turned to the body's outside.

    The shell grows along these, not along the body normal: where the body folds (the
    crotch, an armpit) the body normal points into the neighbouring part, the cloth's not.
    """
    n = garment.topology.normals(points)
    flip = np.einsum("nd,nd->n", n, body_normal) < 0
    n[flip] *= -1
    return n


def _anchors(pose: Pose, garment: Garment, q, mesh: Mesh) -> tuple | None:
    """Rest-pose anchors of a garment for posed frames (see ``Outfit.anchors``); a shell's
    outer layer gets its own (triangle, barycentrics, clearance)."""
    if q is None:
        return None
    inner = (q.triangle, q.bary, pose.last_need, q.vertex)
    n = len(q.distance)
    if len(mesh.vertices) == n:
        return inner
    qo = pose.query(mesh.vertices[n:], k=4)
    keep = np.minimum(qo.distance, pose.last_need + np.float32(garment.thickness))
    return (*inner, qo.triangle, qo.bary, np.maximum(keep, 0).astype(np.float32), qo.vertex)


def dress(human, garments: list[Garment], bone_names=None) -> Outfit:
    """Fit garments on a body, lowest ``z_depth`` first (see module docstring).

    human: anything with ``vertices`` (19158, 3), ``weights`` (SkinWeights over all
        vertices) and ``faces`` (or ``model.base.faces``); an ``avatar.human.Human`` works.
    Returns an Outfit whose ``garments`` keep the input's layer order.
    """
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
        ws.append(w)
        anchors.append(_anchors(pose, garment, q, mesh))
    return Outfit(fitted, surface, rests, ws, anchors, pose.vertices.copy())
