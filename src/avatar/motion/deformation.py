"""How much a motion deforms the skin: per-bone mesh stretch, the face, the eyes.

A retarget can put every bone where the source's is and still tear the mesh: a face bone
turned against the head stretches the skin between them (eyes pulled out, the mouth
collapsed) while every segment direction is right. These measures look at the skin.

Stretch of an edge in a frame: ``|L / L0 - 1|``, its length posed (linear-blend skinning)
against its rest length. A bone's stretch: the mean over frames and over the skin's edges,
each edge weighted by the bone's mean skin weight at its two ends. A rigid motion (any
pose of a limb about its joint) stretches the skin around the joint a little; a bone
turned against its neighbours stretches its own region by its turn.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from avatar.body.shaped import Body
from avatar.errors import AvatarError
from avatar.motion import bonemap
from avatar.rig import kinematics, skinning
from avatar.rig.skeleton import Animation, Skeleton

FACE_LIMIT = 0.10
"""Mean edge stretch (a fraction) over which a face bone's region (a bone below the head)
counts as deformed: MakeHuman's face units at full strength stretch theirs by up to 7%; a
face bone turned 30 degrees against the head by over 10% (the old retarget: 50-90%)."""

BODY_LIMIT = 0.80
"""The same for every other bone: deep bends legitimately stretch the skin around a joint
under linear-blend skinning (MakeHuman's sit01: the hips' region 35-50% on every rig;
CMU's dance: the spine's ~40%); a limb turned inside out goes far over."""

MOST_FRAMES = 64  # frames sampled evenly from a long clip: the mean settles well before


@dataclass(frozen=True)
class Stretch:
    """Skin stretch of one motion on one body.

    per_bone: target bone name -> mean edge stretch (fraction) of the skin weighted to it,
        for every bone that carries skin.
    face: (S,) mean edge stretch of the face (skin on the head and the bones below it)
        in each sampled frame.
    eyes: (S,) the farther eyeball's centre from where the head's own motion carries it,
        metres, in each sampled frame (0 when the rig cannot find its head).
    frames: (S,) the sampled frame indices.
    """

    per_bone: dict[str, float]
    face: np.ndarray
    eyes: np.ndarray
    frames: np.ndarray
    face_bones: frozenset[str] = frozenset()  # the bones below the head

    def limit(self, bone: str) -> float:
        """The stretch over which ``bone``'s region counts as deformed."""
        return FACE_LIMIT if bone in self.face_bones else BODY_LIMIT

    def deformed(self) -> tuple[str, ...]:
        """Bones whose region stretches over their limit, worst (relative to it) first."""
        bad = [b for b, v in self.per_bone.items() if v > self.limit(b)]
        return tuple(sorted(bad, key=lambda b: -self.per_bone[b] / self.limit(b)))


def measure(body: Body, animation: Animation, most_frames: int = MOST_FRAMES) -> Stretch:
    """The skin stretch of ``animation`` (T, J on ``body.skeleton``) on ``body``."""
    frames = np.unique(np.linspace(0, animation.frames - 1, min(animation.frames, most_frames))
                       .astype(int))  # fmt: skip
    skeleton = body.skeleton
    world = kinematics.forward(skeleton, animation.rotations[frames],
                               animation.translations[frames])  # fmt: skip
    mats = kinematics.skinning_matrices(skeleton, world)
    rest = np.asarray(body.vertices, dtype=np.float64)
    posed = skinning.linear_blend(rest, body.weights, mats)  # (S, V, 3)
    edges = skin_edges(body)
    length0 = np.linalg.norm(rest[edges[:, 0]] - rest[edges[:, 1]], axis=-1)
    length = np.linalg.norm(posed[:, edges[:, 0]] - posed[:, edges[:, 1]], axis=-1)
    stretch = np.abs(length / np.maximum(length0, 1e-9) - 1.0)  # (S, E)
    mean_edge = stretch.mean(axis=0)
    dense = _dense_weights(body)  # (V, J)
    on_edge = (dense[edges[:, 0]] + dense[edges[:, 1]]) / 2  # (E, J)
    total = on_edge.sum(axis=0)
    carries = np.flatnonzero(total > 1e-6)
    per_bone = (mean_edge @ on_edge[:, carries]) / total[carries]
    face = _face(body, edges)
    below_head = head_bones(skeleton)
    below_head[np.flatnonzero(below_head)[:1]] = False  # the head itself bends at the neck
    return Stretch(
        per_bone={skeleton.names[j]: float(v) for j, v in zip(carries, per_bone, strict=True)},
        face=stretch[:, face].mean(axis=1) if face.any() else np.zeros(len(frames)),
        eyes=_eye_drift(body, posed, world),
        frames=frames,
        face_bones=frozenset(skeleton.names[j] for j in np.flatnonzero(below_head)),
    )


def skin_edges(body: Body) -> np.ndarray:
    """(E, 2) int64 the skin's unique mesh edges (indices into ``body.vertices``)."""
    faces = body.faces[body.model.base.face_groups["body"]].astype(np.int64)
    ring = np.stack([faces, np.roll(faces, -1, axis=1)], axis=-1).reshape(-1, 2)
    ring = ring[ring[:, 0] != ring[:, 1]]  # triangles stored as quads repeat a corner
    return np.unique(np.sort(ring, axis=1), axis=0)


def _dense_weights(body: Body) -> np.ndarray:
    """(V, J) skin weights of every vertex over the skeleton's bones."""
    w = body.weights
    out = np.zeros((len(w.indices), len(body.skeleton.names)))
    np.add.at(out, (np.arange(len(w.indices))[:, None], w.indices), w.weights)
    return out


def head_bones(skeleton: Skeleton) -> np.ndarray:
    """(J,) bool: the head (by its bone-map role) and every bone below it; all False when
    the rig has no recognisable head."""
    try:
        head = bonemap.detect(skeleton).bones.get("head")
    except AvatarError:  # a skeleton without hips has no head either
        head = None
    out = np.zeros(len(skeleton.names), dtype=bool)
    if head is None:
        return out
    for j in range(len(skeleton.names)):
        k = j
        while k >= 0 and k != head:
            k = int(skeleton.parents[k])
        out[j] = k == head
    return out


def face_vertices(body: Body) -> np.ndarray:
    """Indices of the skin vertices weighted mostly (over half) to the head and the bones
    below it: the face, the scalp and the ears."""
    on_head = _dense_weights(body)[:, head_bones(body.skeleton)].sum(axis=1)
    skin = body.skin_index
    return skin[on_head[skin] > 0.5]


def _face(body: Body, edges: np.ndarray) -> np.ndarray:
    """(E,) bool: the edges with both ends on the face (``face_vertices``)."""
    inside = np.zeros(len(body.vertices), dtype=bool)
    inside[face_vertices(body)] = True
    return inside[edges].all(axis=1)


def _eye_drift(body: Body, posed: np.ndarray, world: np.ndarray) -> np.ndarray:
    """(S,) metres: the farther eyeball centre from where the head bone's motion alone
    carries its rest position (an eye pulled out of its socket moves away from it)."""
    heads = np.flatnonzero(head_bones(body.skeleton))
    groups = body.model.base.face_groups
    if not len(heads) or "helper-l-eye" not in groups:
        return np.zeros(len(posed))
    head = int(heads[0])  # parents come first: the head itself
    carry = world[:, head] @ np.linalg.inv(body.skeleton.rest[head])  # (S, 4, 4)
    drift = np.zeros(len(posed))
    for group in ("helper-l-eye", "helper-r-eye"):
        index = np.unique(body.faces[groups[group]])
        centre = np.asarray(body.vertices[index], dtype=np.float64).mean(axis=0)
        expected = carry[:, :3, :3] @ centre + carry[:, :3, 3]
        drift = np.maximum(drift, np.linalg.norm(posed[:, index].mean(axis=1) - expected, axis=1))
    return drift
