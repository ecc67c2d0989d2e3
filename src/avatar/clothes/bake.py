"""Bake per-frame garment resolves into morph targets, so exported animations do not clip.

A glTF viewer skins a garment with plain linear blend skinning (LBS), which drives it into
the body where the body bends; ``Outfit.frame(..., exact=True)`` pushes it back out. For
every frame t this module takes the resolved vertices V_t and what the viewer will compute,
L_t = LBS of the exported part mesh with the weights exactly as the file stores them
(``gltf_weights.pack_weights``: at most 8 influences, renormalised), and turns the posed
correction D_t = V_t - L_t into a bind-space morph delta. LBS is linear in the rest
position: skin(p + d) = skin(p) + A d with A = sum_j w_j R_j, the blend of the skinning
matrices' 3x3 parts, so d = A^-1 D_t. Frame t's target is switched on (weight 1) for that
frame only; frames that need no correction get no target.

    parts, weights = bake(human.body, human.outfit, animation, human.parts())
    gltf.write(path, parts, human.skeleton, {"walk": animation}, morph_weights={"walk": weights})
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import replace

import numpy as np

from avatar.body.shaped import Body
from avatar.clothes.outfit import Outfit
from avatar.errors import AvatarError
from avatar.io.gltf_weights import pack_weights
from avatar.part import MeshPart
from avatar.rig import kinematics, skinning
from avatar.rig.skeleton import Animation

log = logging.getLogger(__name__)

TOLERANCE = 5e-5  # m; smaller corrections are left out (the target stays sparse)
CHUNK = 256  # frames whose bone matrices are computed together
SINGULAR = 1e-6  # |det A| below which a vertex's blended matrix is inverted by pseudo-inverse


SkinOf = Callable[[MeshPart, int], skinning.SkinWeights]  # (part, joint count) -> its skin


def bake(
    body: Body,
    outfit: Outfit,
    animation: Animation,
    parts: list[MeshPart],
    progress: bool = False,
    skin: SkinOf | None = None,
) -> tuple[list[MeshPart], dict[str, np.ndarray]]:
    """Add one morph target per corrected frame to each garment part of ``parts``.

    body: the shaped body; outfit: the garments fitted on it (``Human.outfit``).
    parts: the parts to export (``Human.parts(...)``): its last ``len(outfit)`` parts are
        the outfit's garments, as ``library.parts`` makes them.
    animation: (T frames) on ``body.skeleton``.
    progress: show a progress bar (tqdm) over the frames.
    skin: the weights the player will skin with (default ``file_skin``, a glTF viewer's;
        ``vertex_group_skin`` for Blender's Armature modifier).
    Returns the parts (garments with extra morphs named ``frame_0007``, after any they
    had; deltas (M, 3) float32 metres in bind space) and part name -> (T, targets) float32
    morph weights: 1 for frame t's own target at frame t, else 0.
    """
    garments = _garment_parts(parts, outfit)
    joints = len(body.skeleton.names)
    skins = [(skin or file_skin)(p, joints) for p in garments]
    corrections: list[dict[int, np.ndarray]] = [{} for _ in garments]
    for t, posed, matrices in _frames(body, animation, progress):
        resolved = outfit.frame(posed, matrices, exact=True)
        for i, part in enumerate(garments):
            delta = bind_correction(part.mesh.vertices, skins[i], matrices, resolved[i])
            if delta is not None:
                corrections[i][t] = delta
    pairs = list(zip(garments, corrections, strict=True))
    baked = [_with_targets(p, c, animation.frames) for p, c in pairs]
    counts = ", ".join(f"{p.name} {len(c)}/{animation.frames}" for p, c in pairs)
    log.info("garment corrections baked (frames with a target): %s", counts)
    out = parts[: len(parts) - len(garments)] + [part for part, _ in baked]
    return out, {part.name: w for part, w in baked if w is not None}


def file_skin(part: MeshPart, joints: int) -> skinning.SkinWeights:
    """The part's skin weights as the glTF file stores them (what a viewer skins with)."""
    if part.skin is None:
        raise AvatarError(f"garment part {part.name!r} has no skin weights")
    idx, w = pack_weights(part.skin[0], part.skin[1], joints)
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


def _with_targets(
    part: MeshPart, corrections: dict[int, np.ndarray], frames: int
) -> tuple[MeshPart, np.ndarray | None]:
    """The part with one morph per corrected frame, and its (T, targets) weights."""
    if not corrections:
        return part, None
    morphs = dict(part.morphs)
    before = len(morphs)
    for t, delta in corrections.items():
        morphs[f"frame_{t:04d}"] = delta
    weights = np.zeros((frames, len(morphs)), dtype=np.float32)
    for k, t in enumerate(corrections):
        weights[t, before + k] = 1.0
    return replace(part, morphs=morphs), weights
