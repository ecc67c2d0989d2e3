"""Bake per-frame garment resolves into a few morph targets, so exported animations do not clip.

A glTF viewer skins a garment with plain linear blend skinning (LBS), which drives it into
the body where the body bends; ``Outfit.frame(..., exact=True)`` pushes it back out. For
every frame t this module takes the resolved vertices V_t and what the viewer will compute,
L_t = LBS of the exported part mesh with the weights exactly as the file stores them
(``gltf_weights.pack_weights``: at most 8 (or 4) influences, renormalised), and turns the
posed correction D_t = V_t - L_t into a bind-space delta. LBS is linear in the rest
position: skin(p + d) = skin(p) + A d with A = sum_j w_j R_j, the blend of the skinning
matrices' 3x3 parts, so d_t = A^-1 D_t.

Compact form. The per-frame deltas of one garment, stacked as X (T, 3U) over the U vertices
that ever move, are close to low-rank (the same folds at elbows, knees, hips recur), so each
garment gets a small basis: the principal components of X (no centring: a frame without
correction has weights 0), the fewest k <= ``MAX_BASIS`` (16) whose reconstruction leaves
no vertex of any frame more than ``ERROR_BOUND`` (0.5 mm) from its exact delta. The file
holds those k morph targets ``correction_00``.. per garment (plus ``correction_offset``,
held at 1, so that every weight lies in [0, 1], the range players keep) and a (T, k + 1)
weights channel: it grows linearly with the clip (k + 1 weights a frame), not with its
square. Because A is a blend of rotations (its norm is at most 1), a bind-space error e
moves the played-back vertex by at most e.

Long, varied clips (CMU's jumps) are not low-rank at that bound: 16 shapes leave centimetres
between some frames and their exact resolves. Those errors matter only where they go into
the body, and the exact resolve is only one way out of it; so the bake then plays every frame
back as a viewer will (``REFINE_PASSES`` checks): vertices more than ``ERROR_BOUND`` inside
the skin are pushed out (``MARGIN`` beyond it), the frame's weights are solved again with
them weighted ``HEAVY``, and (the first ``REFITS`` checks) the shapes are refitted to the mended
frames, which are low-rank by construction. What is left is measured in docs/benchmarks.md.

    parts, weights = bake(human.body, human.outfit, animation, human.parts())
    gltf.write(path, parts, human.skeleton, {"walk": animation}, morph_weights={"walk": weights})
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from functools import partial

import numpy as np

from avatar.body.model import BODY_VERTICES
from avatar.body.shaped import Body
from avatar.clothes.outfit import Outfit
from avatar.errors import AvatarError
from avatar.geometry import collision
from avatar.io.gltf_weights import MAX_INFLUENCES, pack_weights
from avatar.part import MeshPart
from avatar.rig import kinematics, skinning
from avatar.rig.skeleton import Animation

log = logging.getLogger(__name__)

TOLERANCE = 5e-5  # m; smaller corrections are left out (the targets stay sparse)
CHUNK = 256  # frames whose bone matrices are computed together
SINGULAR = 1e-6  # |det A| below which a vertex's blended matrix is inverted by pseudo-inverse
ERROR_BOUND = 5e-4  # m: worst distance of a played-back garment vertex from its exact frame
MAX_BASIS = 16  # correction shapes a garment gets when they meet ERROR_BOUND (the usual case)
LIMIT = 64  # most shapes a garment gets when ERROR_BOUND needs more than MAX_BASIS
BASIS_PREFIX = "correction_"
REFINE_PASSES = 12  # play-back checks; each pushes out what went inside (stops when none did)
REFITS = 6  # the first checks that also refit the shapes to the mended frames
MARGIN = 1.5e-3  # m: how far outside the skin a check puts a vertex it pushes out
HEAVY = 100.0  # weight of pushed-out vertices in a frame's least-squares weights


SkinOf = Callable[[MeshPart, int], skinning.SkinWeights]  # (part, joint count) -> its skin


def bake(
    body: Body,
    outfit: Outfit,
    animation: Animation,
    parts: list[MeshPart],
    progress: bool = False,
    skin: SkinOf | None = None,
    max_influences: int = MAX_INFLUENCES,
    bound: float = ERROR_BOUND,
) -> tuple[list[MeshPart], dict[str, np.ndarray]]:
    """Add each garment's correction basis (a few morph targets) to the garment parts.

    body: the shaped body; outfit: the garments fitted on it (``Human.outfit``).
    parts: the parts to export (``Human.parts(...)``): its last ``len(outfit)`` parts are
        the outfit's garments, as ``library.parts`` makes them.
    animation: (T frames) on ``body.skeleton``.
    progress: show a progress bar (tqdm) over the frames.
    skin: the weights the player will skin with (default ``file_skin`` with
        ``max_influences``, a glTF viewer's; ``vertex_group_skin`` for Blender's Armature).
    bound: the largest distance (m) a played-back vertex may be from its exact frame.
    Returns the parts (garments with extra morphs ``correction_offset``, ``correction_00``..
    after any they had;
    deltas (M, 3) float32 metres in bind space) and part name -> (T, targets) float32 morph
    weights (0 for the morphs they had before), for garments that need a correction.
    """
    garments = _garment_parts(parts, outfit)
    joints = len(body.skeleton.names)
    skin_of = skin or partial(file_skin, limit=max_influences)
    skins = [skin_of(p, joints) for p in garments]
    corrections = [Corrections(len(p.mesh.vertices), animation.frames) for p in garments]
    for t, posed, matrices in _frames(body, animation, progress):
        resolved = outfit.frame(posed, matrices, exact=True)
        for i, part in enumerate(garments):
            delta = bind_correction(part.mesh.vertices, skins[i], matrices, resolved[i])
            if delta is not None:
                corrections[i].add(t, delta)
    bases = [fit(c, bound) for c in corrections]
    collide = [g.garment.collide for g in outfit.garments]
    heavy: list[dict[int, np.ndarray]] = [{} for _ in garments]  # t -> pushed vertices
    for step in range(REFINE_PASSES):
        if not _played_back_fixes(body, animation, garments, skins, corrections, bases, collide,
                                  heavy, bound):  # fmt: skip
            break
        if step < REFITS:  # refit the shapes to the mended frames, then the weights
            bases = [fit(c, bound) for c in corrections]
            for i, basis in enumerate(bases):
                if basis is None:
                    continue
                for t, pushed in heavy[i].items():
                    _solve_weights(basis, corrections[i], t, pushed)
    pairs = zip(garments, corrections, bases, strict=True)
    baked = [_with_basis(p, c, b, bound) for p, c, b in pairs]
    out = parts[: len(parts) - len(garments)] + [part for part, _ in baked]
    return out, {part.name: w for part, w in baked if w is not None}


@dataclass
class Corrections:
    """One garment's per-frame bind-space deltas, stored sparsely as they are computed."""

    vertices: int
    frames: int
    rows: dict[int, np.ndarray] = field(default_factory=dict)  # t -> (n,) moved vertices
    deltas: dict[int, np.ndarray] = field(default_factory=dict)  # t -> (n, 3) float32

    def add(self, t: int, delta: np.ndarray) -> None:
        rows = np.flatnonzero(np.any(delta != 0, axis=1))
        self.rows[t], self.deltas[t] = rows, np.asarray(delta[rows], dtype=np.float32)

    def matrix(self) -> tuple[np.ndarray, np.ndarray]:
        """(moved (U,) vertex indices, X (T, U, 3) float32 deltas of those vertices)."""
        moved = np.unique(np.concatenate([np.zeros(0, np.int64), *self.rows.values()]))
        x = np.zeros((self.frames, len(moved), 3), dtype=np.float32)
        for t, rows in self.rows.items():
            x[t, np.searchsorted(moved, rows)] = self.deltas[t]
        return moved, x


@dataclass(frozen=True)
class Basis:
    """A garment's compact correction: shapes (k, U, 3) over vertices ``moved`` (U,),
    weights (T, k), and the worst per-vertex reconstruction error (m)."""

    moved: np.ndarray
    shapes: np.ndarray
    weights: np.ndarray
    error: float

    def delta(self, t: int, vertices: int) -> np.ndarray:
        """(vertices, 3) float64 bind-space correction this basis plays at frame t."""
        out = np.zeros((vertices, 3))
        out[self.moved] = np.einsum("k,kvc->vc", self.weights[t], self.shapes)
        return out


def _solve_weights(basis: Basis, corrections: Corrections, t: int, pushed: np.ndarray) -> None:
    """Frame t's weights (in place): least squares to its target, vertices ``pushed`` (garment
    indices) weighted ``HEAVY``, so the frame keeps them out with the shapes it has."""
    if not len(basis.shapes):
        return
    target = np.zeros((len(basis.moved), 3))
    at = np.searchsorted(basis.moved, corrections.rows[t])
    inside = at < len(basis.moved)
    inside[inside] = basis.moved[at[inside]] == corrections.rows[t][inside]
    target[at[inside]] = corrections.deltas[t][inside]
    cost = np.ones(len(basis.moved))
    rows = np.searchsorted(basis.moved, pushed)
    found = rows < len(basis.moved)
    found[found] = basis.moved[rows[found]] == pushed[found]
    cost[rows[found]] = HEAVY
    shapes = basis.shapes.reshape(len(basis.shapes), -1).astype(np.float64)
    scaled = shapes * np.repeat(cost, 3)[None]
    lhs, rhs = scaled @ shapes.T, scaled @ target.reshape(-1)
    basis.weights[t] = np.linalg.lstsq(lhs, rhs, rcond=None)[0].astype(np.float32)


def fit(corrections: Corrections, bound: float = ERROR_BOUND) -> Basis | None:
    """The compact basis of one garment's corrections (``fit_basis``), None without any."""
    if not corrections.rows:
        return None
    moved, x = corrections.matrix()
    shapes, weights, error = fit_basis(x, bound, MAX_BASIS)
    return Basis(moved, shapes, weights, error)


def _played_back_fixes(body, animation, garments, skins, corrections, bases, collide, heavy,
                       bound: float) -> int:  # fmt: skip
    """Play every frame back as the file will (each basis, the file's skin); where a garment
    vertex lands more than ``bound`` inside the skin, make that frame's target the played
    frame with those vertices pushed out (MARGIN outside) and solve the frame's weights again
    with those vertices ``HEAVY`` (``_solve_weights``); a refit of the shapes carries them.

    The exact resolves are one way out of the body among many: the played-back frame, a
    low-rank one, mended only where it goes in, is as valid and far easier for the basis to
    hold (corrections of long clips are not low-rank at ERROR_BOUND). ``heavy``: per garment,
    t -> the vertices pushed at frame t so far (updated). Returns how many vertex-frames
    were pushed out.
    """
    faces = body.model.base.faces[body.model.base.face_groups["body"]]
    surface = collision.body_surface(faces)
    fixed = 0
    for t, posed, matrices in _frames(body, animation, False):
        skin = None
        for i, part in enumerate(garments):
            if bases[i] is None or not collide[i]:
                continue
            rest = part.mesh.vertices.astype(np.float64)
            played = skinning.linear_blend(rest + bases[i].delta(t, len(rest)), skins[i],
                                           matrices)  # fmt: skip
            # Only vertices the basis moves can go in: the others play plain skinning, which
            # the exact resolve left where it was (outside).
            moved = bases[i].moved
            skin = skin or collision.PosedBody(surface, posed[:BODY_VERTICES])
            q = skin.query(np.asarray(played[moved], dtype=np.float32), k=6)
            deep = np.flatnonzero(q.distance < -bound)
            if not len(deep):
                continue
            inside = moved[deep]
            target = np.asarray(played, dtype=np.float64)
            target[inside] = q.closest[deep] + MARGIN * q.normal[deep]
            delta = bind_correction(rest, skins[i], matrices, target)
            if delta is not None:
                corrections[i].add(t, delta)
                heavy[i][t] = np.union1d(heavy[i].get(t, np.zeros(0, np.int64)), inside)
                _solve_weights(bases[i], corrections[i], t, heavy[i][t])
                fixed += len(inside)
    log.info("played-back check: %d garment vertex-frames pushed out", fixed)
    return fixed


def fit_basis(x: np.ndarray, bound: float = ERROR_BOUND, limit: int = LIMIT) -> tuple[
    np.ndarray, np.ndarray, float
]:  # fmt: skip
    """The fewest principal shapes of per-frame deltas that reproduce every frame within
    ``bound``: x (T, U, 3) -> shapes (k, U, 3) float32 orthonormal (flattened), weights
    (T, k) float32 (projections, so frames without correction get 0), worst error (m).

    k is the smallest count meeting ``bound``, at most ``limit`` (then the error says how
    far off it is).
    """
    frames = len(x)
    flat = x.reshape(frames, -1)
    if not flat.size or not np.any(flat):
        return np.zeros((0,) + x.shape[1:], np.float32), np.zeros((frames, 0), np.float32), 0.0
    directions = _principal_directions(flat, limit)  # (L, N) float64 orthonormal rows
    weights = flat.astype(np.float64) @ directions.T  # (T, L)
    residual = flat.astype(np.float64)
    for k in range(len(directions) + 1):
        error = float(np.sqrt((residual.reshape(frames, -1, 3) ** 2).sum(axis=2).max()))
        if error <= bound or k == len(directions):
            break
        residual -= np.outer(weights[:, k], directions[k])
    shapes = directions[:k].reshape((k,) + x.shape[1:]).astype(np.float32)
    return shapes, weights[:, :k].astype(np.float32), error


def _principal_directions(flat: np.ndarray, limit: int) -> np.ndarray:
    """The top ``limit`` right singular vectors (L, N) of flat (T, N), through the smaller
    of the two Gram matrices (T x T or N x N), in float64."""
    a = flat.astype(np.float64)
    frames, size = a.shape
    if frames <= size:
        values, vectors = np.linalg.eigh(a @ a.T)
        order = np.argsort(values)[::-1][:limit]
        keep = order[values[order] > values[order[0]] * 1e-12]
        out = vectors[:, keep].T @ a
        return out / np.linalg.norm(out, axis=1, keepdims=True)
    values, vectors = np.linalg.eigh(a.T @ a)
    order = np.argsort(values)[::-1][:limit]
    keep = order[values[order] > values[order[0]] * 1e-12]
    return vectors[:, keep].T


def _with_basis(
    part: MeshPart, corrections: Corrections, basis: Basis | None, bound: float
) -> tuple[MeshPart, np.ndarray | None]:
    """The part with its correction shapes as morphs, and its (T, targets) weights."""
    if basis is None or not len(basis.shapes):
        return part, None
    moved, shapes, weights, error = basis.moved, basis.shapes, basis.weights, basis.error
    if len(shapes) > MAX_BASIS or error > bound:
        log.warning("%s: %d correction shapes, worst error %.2f mm (bound %.2f mm)",
                    part.name, len(shapes), error * 1e3, bound * 1e3)  # fmt: skip
    log.info("%s: %d frames corrected -> %d shapes, worst error %.3f mm", part.name,
             len(corrections.rows), len(shapes), error * 1e3)  # fmt: skip
    # Weights in [0, 1], which every player keeps (Blender's shape-key sliders and Unity clamp
    # to it): w = lo + (hi - lo) u, so x = sum lo_k s_k + sum u_k (hi_k - lo_k) s_k, the
    # first term an "offset" target held at 1 over the clip (the rest mesh is unchanged).
    lo, hi = np.minimum(weights.min(axis=0), 0.0), np.maximum(weights.max(axis=0), 0.0)
    span = np.where(hi - lo > 0, hi - lo, 1.0)
    morphs = dict(part.morphs)
    before = len(morphs)
    offset = np.zeros((corrections.vertices, 3), dtype=np.float32)
    offset[moved] = np.einsum("k,kvc->vc", lo, shapes)
    morphs[f"{BASIS_PREFIX}offset"] = offset
    for k, shape in enumerate(shapes):
        delta = np.zeros((corrections.vertices, 3), dtype=np.float32)
        delta[moved] = shape * span[k]
        morphs[f"{BASIS_PREFIX}{k:02d}"] = delta
    out = np.zeros((corrections.frames, len(morphs)), dtype=np.float32)
    out[:, before] = 1.0
    out[:, before + 1 :] = np.clip((weights - lo) / span, 0.0, 1.0)
    return replace(part, morphs=morphs), out


def file_skin(part: MeshPart, joints: int, limit: int = MAX_INFLUENCES) -> skinning.SkinWeights:
    """The part's skin weights as the glTF file stores them (what a viewer skins with), at
    most ``limit`` (4 or 8) influences a vertex."""
    if part.skin is None:
        raise AvatarError(f"garment part {part.name!r} has no skin weights")
    idx, w = pack_weights(part.skin[0], part.skin[1], joints, limit)
    return skinning.SkinWeights(idx.astype(np.int32), w)


def vertex_group_skin(part: MeshPart, joints: int) -> skinning.SkinWeights:
    """The part's skin weights as Blender's Armature modifier blends its vertex groups:
    every positive influence (no cap at 8), divided by the vertex's sum."""
    if part.skin is None:
        raise AvatarError(f"garment part {part.name!r} has no skin weights")
    idx = np.array(part.skin[0], dtype=np.int32)
    w = np.clip(np.asarray(part.skin[1], dtype=np.float64), 0.0, None)
    if np.any(idx[w > 0] >= joints) or np.any(idx[w > 0] < 0):
        raise AvatarError(f"skin of {part.name!r} has a joint index out of range 0..{joints - 1}")
    empty = w.sum(axis=1) <= 0
    if empty.any():  # Blender leaves these at rest, which LBS cannot say: the root's, as glTF
        log.warning("%s: %d vertices without skin weight follow the root", part.name, empty.sum())
        w[empty, 0], idx[empty, 0] = 1.0, 0
    w /= w.sum(axis=1, keepdims=True)
    return skinning.SkinWeights(np.where(w > 0, idx, 0), w.astype(np.float32))


def bind_correction(
    rest: np.ndarray, skin: skinning.SkinWeights, matrices: np.ndarray, resolved: np.ndarray
) -> np.ndarray | None:
    """(M, 3) float32 bind-space deltas that make LBS of ``rest`` land on ``resolved``.

    rest: (M, 3) the part's bind positions; skin: its file weights; matrices: (J, 4, 4)
    skinning matrices of the frame; resolved: (M, 3) wanted posed positions.
    Rows whose posed correction is under TOLERANCE are zero; None when all are.
    """
    # 1. The blended 3x4 matrix per vertex, in float64 (a viewer blends in float32; the
    #    difference is far below TOLERANCE).
    m = np.asarray(matrices, dtype=np.float64)[skin.indices, :3, :]  # (M, K, 3, 4)
    blend = np.einsum("mk,mkab->mab", skin.weights.astype(np.float64), m)
    rest = np.asarray(rest, dtype=np.float64)
    # 2. The posed correction D = V - L, kept where it matters.
    posed = np.einsum("mab,mb->ma", blend[:, :, :3], rest) + blend[:, :, 3]
    moved = np.asarray(resolved, dtype=np.float64) - posed
    rows = np.flatnonzero(np.linalg.norm(moved, axis=1) > TOLERANCE)
    if not len(rows):
        return None
    # 3. Back to bind space: d = A^-1 D.
    out = np.zeros(rest.shape, dtype=np.float32)
    out[rows] = _solve(blend[rows, :, :3], moved[rows])
    return out


def _solve(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(N, 3) x with a x = b for (N, 3, 3) a; a pseudo-inverse where a is near singular
    (weights split between bones turned far apart)."""
    det = np.linalg.det(a)
    ok = np.abs(det) > SINGULAR
    x = np.empty_like(b)
    if ok.any():
        x[ok] = np.linalg.solve(a[ok], b[ok][..., None])[..., 0]
    if (~ok).any():
        x[~ok] = np.einsum("nab,nb->na", np.linalg.pinv(a[~ok]), b[~ok])
    return x


def _garment_parts(parts: list[MeshPart], outfit) -> list[MeshPart]:
    """The garment parts of ``parts`` (the last ones), checked against the outfit."""
    count = len(outfit.garments)
    garments = parts[len(parts) - count :] if count else []
    for part, g in zip(garments, outfit.garments, strict=True):
        if part.name != g.name or len(part.mesh.vertices) != len(g.mesh.vertices):
            raise AvatarError(f"part {part.name!r} is not the outfit's garment {g.name!r}")
    return garments


def _frames(body: Body, animation: Animation, progress: bool):
    """(t, body (V, 3), skinning matrices (J, 4, 4)) for every frame of the animation."""
    from tqdm import tqdm

    bar = tqdm(total=animation.frames, desc="resolving garments", unit="frame",
               disable=not progress, leave=False)  # fmt: skip
    with bar:
        for start in range(0, animation.frames, CHUNK):  # bounded memory on long clips
            rows = slice(start, start + CHUNK)
            world = kinematics.forward(
                body.skeleton, animation.rotations[rows], animation.translations[rows]
            )
            for k, matrices in enumerate(kinematics.skinning_matrices(body.skeleton, world)):
                yield (
                    start + k,
                    skinning.linear_blend(body.vertices, body.weights, matrices),
                    matrices,
                )
                bar.update()
