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
no vertex of any frame more than ``ERROR_BOUND`` (0.5 mm) from its exact delta. Because A is
a blend of rotations (its norm is at most 1), a bind-space error e moves the played-back
vertex by at most e.

Segments. A long clip is not low-rank (CMU's jumps: 16 shapes leave 2 cm over 2,752 frames),
so it is cut into equal windows of at most ``SEGMENT`` (300) frames (``segments``), each with
its own basis, fitted and checked on its frames alone. The file holds per garment and
segment s the morph targets ``correction_s<s>_offset`` (held at 1, so that every weight lies
in [0, 1], the range players keep) and ``correction_s<s>_00``.., and one (T, targets) weights
channel in which a segment's targets are 0 outside its frames: the file grows linearly with
the clip (a segment's shapes and n x its targets weights), and one segment's shapes play at
a time. Windows switch hard at a frame: the weights are keyed with STEP interpolation, each
frame plays its own correction exactly, so a cross-fade would only ask two bases to hold the
same frames. A clip of at most ``SEGMENT`` frames is one segment, as it was before segments.

Play-back checks. Within a segment, 16 shapes still miss the exact resolves of a jump by
millimetres; those errors matter only where they go into the body, and the exact resolve
is only one way out of it. So the bake plays every frame back as a viewer will
(``REFINE_PASSES`` checks): vertices more than ``ERROR_BOUND`` inside the skin are pushed
out (``MARGIN`` beyond it). The first ``REFITS`` checks solve the frame's weights again with
them weighted ``HEAVY`` and refit the shapes to the mended frames (low-rank by
construction); the later ones give the frames they mend a few sparse shapes of their own
that play the push-outs (``correction_basis.grow``, at most ``GROW`` a check, the last one
as many as it takes), which converges: only those frames change, so only those are checked
again (cloth caught between two body parts can still be left inside). A check measures
only vertices that can be that deep: the distance to the skin changes at most as much as the
point moves, so a played-back vertex closer to its exact position than that position's
clearance (+ bound) is skipped. The basis maths (fit, weights, grow, morph targets) is
``correction_basis``; what is left is measured in docs/benchmarks.md.

    parts, weights = bake(human.body, human.outfit, animation, human.parts())
    gltf.write(path, parts, human.skeleton, {"walk": animation}, morph_weights={"walk": weights})
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Iterable
from dataclasses import dataclass, replace
from functools import partial

import numpy as np

from avatar.body.model import BODY_VERTICES
from avatar.body.shaped import Body
from avatar.clothes.correction_basis import (
    ERROR_BOUND,
    Basis,
    Corrections,
    fit,
    grow,
    refit,
    segment_targets,
    solve_weights,
)
from avatar.clothes.outfit import Outfit
from avatar.errors import AvatarError
from avatar.geometry import collision
from avatar.io.gltf_weights import MAX_INFLUENCES, pack_weights
from avatar.part import MeshPart
from avatar.rig import kinematics, skinning
from avatar.rig.skeleton import Animation

log = logging.getLogger(__name__)

TOLERANCE = 5e-5  # m; smaller corrections are left out (the targets stay sparse)
SINGULAR = 1e-6  # |det A| below which a vertex's blended matrix is inverted by pseudo-inverse
SEGMENT = 300  # most frames one basis holds: longer clips are cut into equal windows
GROW = 8  # most shapes a late check adds to a segment's basis for the frames it mended
BASIS_PREFIX = "correction_"
REFINE_PASSES = 12  # play-back checks; each pushes out what went inside (stops when none did)
REFITS = 6  # the first checks that also refit the shapes to the mended frames
MARGIN = 1.5e-3  # m: how far outside the skin a check puts a vertex it pushes out
SLACK = 2e-4  # m: checks measure vertices this near their bound (the skin query is approximate)


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
    segment: int = SEGMENT,
) -> tuple[list[MeshPart], dict[str, np.ndarray]]:
    """Add each garment's correction bases (a few morph targets a segment) to the garment parts.

    body: the shaped body; outfit: the garments fitted on it (``Human.outfit``).
    parts: the parts to export (``Human.parts(...)``): its last ``len(outfit)`` parts are
        the outfit's garments, as ``library.parts`` makes them.
    animation: (T frames) on ``body.skeleton``.
    progress: show a progress bar (tqdm) over the frames.
    skin: the weights the player will skin with (default ``file_skin`` with
        ``max_influences``, a glTF viewer's; ``vertex_group_skin`` for Blender's Armature).
    bound: the largest distance (m) a played-back vertex may be from its exact frame.
    segment: the most frames one basis holds (``segments``).
    Returns the parts (garments with extra morphs ``correction_s00_offset``,
    ``correction_s00_00``.. after any they had; deltas (M, 3) float32 metres in bind space)
    and part name -> (T, targets) float32 morph weights (0 for the morphs they had before,
    and for a segment's morphs outside its frames), for garments that need a correction.
    """
    from tqdm import tqdm

    garments = _garment_parts(parts, outfit)
    joints = len(body.skeleton.names)
    skin_of = skin or partial(file_skin, limit=max_influences)
    faces = body.model.base.faces[body.model.base.face_groups["body"]]
    job = _Job(body, outfit, garments, [skin_of(p, joints) for p in garments],
               [g.garment.collide for g in outfit.garments], collision.body_surface(faces),
               bound)  # fmt: skip
    windows = segments(animation.frames, segment)
    with tqdm(total=animation.frames, desc="resolving garments", unit="frame",
              disable=not progress, leave=False) as bar:  # fmt: skip
        per_window = [job.settle(job.resolve(animation, w, bar)) for w in windows]
    baked = [_with_bases(part, windows, [b[i] for b in per_window], bound, animation.frames)
             for i, part in enumerate(garments)]  # fmt: skip
    out = parts[: len(parts) - len(garments)] + [part for part, _ in baked]
    return out, {part.name: w for part, w in baked if w is not None}


def segments(frames: int, length: int = SEGMENT) -> list[range]:
    """The clip's frames cut into the fewest equal windows of at most ``length`` frames
    (a clip of up to ``length`` frames is one window), in order, covering 0..frames-1."""
    if length < 1:
        raise AvatarError(f"segment length {length}: use at least 1 frame")
    count = max(1, -(-frames // length))
    edges = np.linspace(0, frames, count + 1).round().astype(int)
    return [range(a, b) for a, b in zip(edges[:-1], edges[1:], strict=True)]


@dataclass
class _Window:
    """One segment's frames as the bake needs them again after resolving them: skinned body
    (n, BODY_VERTICES, 3) float32, skinning matrices (n, J, 4, 4), per garment its exact
    frames (n, M, 3) float32, their signed distances to the skin (n, M) float32 (NaN until
    a check needs them), and its corrections."""

    bodies: np.ndarray
    matrices: np.ndarray
    exact: list[np.ndarray]
    clearance: list[np.ndarray]
    corrections: list[Corrections]
    checked: bool = False  # whether a check ran (the first measures no clearance)


@dataclass
class _Job:
    """The fixed inputs of one bake: body, outfit, the garment parts with the skins the
    player uses, which garments collide with the body, the body's surface and the bound."""

    body: Body
    outfit: Outfit
    garments: list[MeshPart]
    skins: list[skinning.SkinWeights]
    collide: list[bool]
    surface: collision.BodySurface
    bound: float

    def resolve(self, animation: Animation, window: range, bar) -> _Window:
        """Every frame of ``window`` resolved exactly (``Outfit.frame(exact=True)``) and turned
        into bind-space corrections (``bind_correction``)."""
        skeleton = self.body.skeleton
        rows = slice(window.start, window.stop)
        world = kinematics.forward(
            skeleton, animation.rotations[rows], animation.translations[rows]
        )
        matrices = kinematics.skinning_matrices(skeleton, world)
        n = len(window)
        sizes = [len(p.mesh.vertices) for p in self.garments]
        out = _Window(np.empty((n, BODY_VERTICES, 3), np.float32), matrices,
                      [np.empty((n, m, 3), np.float32) for m in sizes],
                      [np.full((n, m), np.nan, np.float32) for m in sizes],
                      [Corrections(m, n) for m in sizes])  # fmt: skip
        for t in range(n):
            posed = skinning.linear_blend(self.body.vertices, self.body.weights, matrices[t])
            out.bodies[t] = posed[:BODY_VERTICES]
            resolved = self.outfit.frame(posed, matrices[t], exact=True)
            for i, part in enumerate(self.garments):
                out.exact[i][t] = resolved[i]
                delta = bind_correction(part.mesh.vertices, self.skins[i], matrices[t], resolved[i])
                if delta is not None:
                    out.corrections[i].add(t, delta)
            bar.update()
        return out

    def settle(self, window: _Window) -> list[Basis | None]:
        """Each garment's basis of the window, played back and mended (``check``) until no
        vertex is more than ``bound`` inside the skin or ``REFINE_PASSES`` checks ran.

        The first ``REFITS`` checks re-solve the weights of the frames they mend and refit
        the shapes to the mended frames (every frame is then checked again); the later ones
        add the mended frames' push-outs as a few sparse shapes of their own (``grow``, at
        most ``GROW``; the last one as many as it takes to play them exactly), which only
        those frames play, so only those are checked again.
        """
        bases = [fit(c, self.bound) for c in window.corrections]
        heavy: list[dict[int, np.ndarray]] = [{} for _ in self.garments]  # t -> pushed vertices
        frames: Iterable[int] = range(len(window.bodies))
        for step in range(REFINE_PASSES + 1):
            refitting = step < REFITS
            mended = self.check(window, bases, heavy, frames, solve=refitting)
            if not any(mended):
                break
            if step == REFINE_PASSES:  # after the exact grow: only the skin query's slack
                log.warning("%d frames keep a garment vertex over %.1f mm inside",
                            len(set().union(*mended)), self.bound * 1e3)  # fmt: skip
            elif refitting:
                pairs = zip(window.corrections, heavy, strict=True)
                bases = [refit(c, self.bound, h) for c, h in pairs]
                frames = range(len(window.bodies))
            else:
                most = GROW if step < REFINE_PASSES - 1 else len(window.bodies)
                bases = [
                    b if b is None or not m else grow(b, c, sorted(m), most)
                    for b, c, m in zip(bases, window.corrections, mended, strict=True)
                ]
                frames = sorted(set().union(*mended))
        return bases

    def check(self, window: _Window, bases: list[Basis | None], heavy: list[dict],
              frames: Iterable[int], solve: bool) -> list[set[int]]:  # fmt: skip
        """Play ``frames`` back as the file will (each basis, the player's skin); where a
        garment vertex lands more than ``bound`` inside the skin, make that frame's target
        the played frame with those vertices pushed out (MARGIN outside) and solve the
        frame's weights again (``solve``) with them ``HEAVY`` (``solve_weights``); a refit
        of the shapes carries them. Returns the frames it mended, per garment.

        The exact resolves are one way out of the body among many: the played-back frame, a
        low-rank one, mended only where it goes in, is as valid and far easier for the basis
        to hold (corrections of long clips are not low-rank at ERROR_BOUND). ``heavy``: per
        garment, t -> the vertices pushed at frame t so far (updated).
        """
        mended: list[set[int]] = [set() for _ in bases]
        pushed = 0
        played = [self._played(b, i) for i, b in enumerate(bases)]
        for t in frames:
            skin = None
            for i, play in enumerate(played):
                if play is None:
                    continue
                basis, points, sub = play(t, window.matrices[t])
                suspect = self._suspects(window, i, t, basis.moved, points)
                if not len(suspect):
                    continue
                skin = skin or collision.PosedBody(self.surface, window.bodies[t])
                deep, out = self._deep(window, i, t, basis.moved, points, suspect, skin)
                if not len(deep):
                    continue
                target = np.asarray(points, dtype=np.float64)
                target[deep] = out
                rest = self.garments[i].mesh.vertices
                part = bind_correction(rest[basis.moved], sub, window.matrices[t], target)
                if part is None:
                    continue
                delta = np.zeros((len(rest), 3), np.float32)
                delta[basis.moved] = part
                window.corrections[i].add(t, delta)
                heavy[i][t] = np.union1d(heavy[i].get(t, np.zeros(0, np.int64)), basis.moved[deep])
                if solve:
                    solve_weights(basis, window.corrections[i], t, heavy[i][t])
                mended[i].add(t)
                pushed += len(deep)
        window.checked = True
        log.info("played-back check: %d garment vertex-frames pushed out", pushed)
        return mended

    def _played(self, basis: Basis | None, i: int):
        """t, matrices -> (basis, played moved vertices (U, 3) float32, their skin), or None
        when garment i has nothing to check."""
        if basis is None or not len(basis.shapes) or not self.collide[i]:
            return None
        moved = basis.moved
        rest = self.garments[i].mesh.vertices[moved].astype(np.float64)
        sub = skinning.SkinWeights(self.skins[i].indices[moved], self.skins[i].weights[moved])

        def play(t: int, matrices: np.ndarray):
            return basis, skinning.linear_blend(rest + basis.moved_delta(t), sub, matrices), sub

        return play

    def _suspects(self, window: _Window, i: int, t: int, moved: np.ndarray,
                  points: np.ndarray) -> np.ndarray:  # fmt: skip
        """Rows of ``moved`` whose played positions may be more than ``bound`` inside: the
        signed distance to the skin moves at most as far as the point does, so a point
        within (clearance of the exact point + bound - SLACK) of it cannot be that deep.
        NaN clearance (not yet measured) makes a row a suspect."""
        gap = np.linalg.norm(points - window.exact[i][t, moved], axis=1)
        return np.flatnonzero(~(gap <= window.clearance[i][t, moved] + self.bound - SLACK))

    def _deep(self, window: _Window, i: int, t: int, moved: np.ndarray, points: np.ndarray,
              suspect: np.ndarray, skin: collision.PosedBody):  # fmt: skip
        """(rows of ``moved`` more than ``bound`` inside, where to put them (D, 3)), measuring
        the exact points' clearance of suspects not yet measured.

        A deep vertex goes MARGIN outside the skin along its normal, the least move out;
        where that lands inside another part of the body (cloth caught between arm and
        chest) it goes to its exact position instead, when that one is out.
        """
        clearance = window.clearance[i][t]
        unknown = suspect[np.isnan(clearance[moved[suspect]])]
        if len(unknown) and window.checked:  # a first check (often the only one) skips it
            exact = window.exact[i][t, moved[unknown]]
            clearance[moved[unknown]] = skin.query(exact, k=6, sheets=True).distance
            suspect = self._suspects(window, i, t, moved, points)
        if not len(suspect):
            return suspect, np.zeros((0, 3), np.float32)
        q = skin.query(points[suspect], k=6, sheets=True)  # skin pressed into skin: inside
        deep = suspect[q.distance < -self.bound]
        pushed = (q.closest + MARGIN * q.normal)[q.distance < -self.bound]
        if len(deep):
            caught = skin.query(pushed, k=6, sheets=True).distance < -self.bound
            caught &= clearance[moved[deep]] >= -self.bound + SLACK
            pushed[caught] = window.exact[i][t, moved[deep[caught]]]
        return deep, pushed


def _with_bases(part: MeshPart, windows: list[range], bases: list[Basis | None], bound: float,
                frames: int) -> tuple[MeshPart, np.ndarray | None]:  # fmt: skip
    """The part with each segment's correction shapes as morphs, and its (T, targets) weights
    (a segment's morphs are 0 outside its frames: one segment's shapes play at a time)."""
    morphs = dict(part.morphs)
    keyed: list[tuple[range, int, np.ndarray]] = []  # (window, first column, weights)
    for s, (window, basis) in enumerate(zip(windows, bases, strict=True)):
        if basis is None or not len(basis.shapes):
            continue
        targets, weights = segment_targets(basis, len(part.mesh.vertices))
        keyed.append((window, len(morphs), weights))
        morphs |= {f"{BASIS_PREFIX}s{s:02d}_{name}": d for name, d in targets.items()}
    if not keyed:
        return part, None
    _log_bases(part.name, [b for b in bases if b is not None], bound)
    out = np.zeros((frames, len(morphs)), dtype=np.float32)
    for window, column, weights in keyed:
        out[window.start : window.stop, column : column + weights.shape[1]] = weights
    return replace(part, morphs=morphs), out


def _log_bases(name: str, bases: list[Basis], bound: float) -> None:
    """One line a garment: segments, shapes, worst reconstruction error (a warning when a
    basis misses the bound: the play-back checks then kept it out of the body)."""
    shapes = sum(len(b.shapes) for b in bases)
    error = max(b.error for b in bases)
    level = logging.WARNING if error > bound else logging.INFO
    log.log(level, "%s: %d segments, %d correction shapes, worst error %.2f mm (bound %.2f mm)",
            name, len(bases), shapes, error * 1e3, bound * 1e3)  # fmt: skip


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
