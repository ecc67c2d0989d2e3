"""Where on the body a vertex is: part labels and limb coordinates for cutting garments.

Measured on the authoring body (the default human) from its skeleton and skin weights:
``part`` is the body part of the dominant bone; ``arm`` and ``leg`` run 0 at the shoulder or
hip, 0.5 at the elbow or knee, 1 at the wrist or ankle, so "sleeves to mid upper arm" is
``arm < 0.25`` on every body the garment is later fitted to.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

PARTS = ("torso", "arm", "leg", "foot", "head", "hand")
_PART_OF_PREFIX = (
    ("upperarm", "arm"), ("lowerarm", "arm"), ("shoulder", "arm"), ("wrist", "hand"),
    ("finger", "hand"), ("metacarpal", "hand"), ("upperleg", "leg"), ("lowerleg", "leg"),
    ("foot", "foot"), ("toe", "foot"), ("head", "head"), ("jaw", "head"), ("eye", "head"),
    ("tongue", "head"), ("special", "head"), ("levator", "head"), ("oris", "head"),
    ("temporalis", "head"), ("risorius", "head"), ("orbicularis", "head"), ("oculi", "head"),
)  # fmt: skip


@dataclass(frozen=True)
class Landmarks:
    """Joint positions (m) of the authoring body used to cut garments."""

    shoulder: np.ndarray  # (2, 3) left, right
    elbow: np.ndarray
    wrist: np.ndarray
    hip: np.ndarray
    knee: np.ndarray
    ankle: np.ndarray
    neck: np.ndarray  # (3,)
    head: np.ndarray
    waist_z: float
    chest_z: float


def landmarks(skeleton) -> Landmarks:
    """Landmarks from a placed default-rig skeleton."""

    def both(name: str) -> np.ndarray:
        return np.stack([skeleton.heads[skeleton.index(f"{name}.{s}")] for s in "LR"])

    def one(name: str) -> np.ndarray:
        return skeleton.heads[skeleton.index(name)]

    return Landmarks(
        shoulder=both("upperarm01"),
        elbow=both("lowerarm01"),
        wrist=both("wrist"),
        hip=both("upperleg01"),
        knee=both("lowerleg01"),
        ankle=both("foot"),
        neck=one("neck01"),
        head=one("head"),
        waist_z=float(one("spine04")[2]),
        chest_z=float(one("spine02")[2]),
    )


def part_labels(bone_names, dominant_bone: np.ndarray) -> np.ndarray:
    """(V,) str body part of each vertex's dominant bone (see PARTS)."""
    table = []
    for name in bone_names:
        table.append(next((part for pre, part in _PART_OF_PREFIX if name.startswith(pre)), "torso"))
    return np.asarray(table)[dominant_bone]


def _chain(points: np.ndarray, a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """(N,) 0 at a, 0.5 at b, 1 at c along the two-segment chain a-b-c (extrapolates)."""
    t1 = _along(points, a, b)
    t2 = _along(points, b, c)
    return np.where(t1 < 1.0, 0.5 * t1, 0.5 + 0.5 * t2)


def _along(points: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    d = b - a
    return (points - a) @ d / float(d @ d)


def limb_coordinates(points: np.ndarray, marks: Landmarks) -> tuple[np.ndarray, np.ndarray]:
    """(arm (N,), leg (N,)) chain coordinates on each point's own side (x > 0 is left)."""
    side = (points[:, 0] < 0).astype(int)  # 0 = left (.L is +x), 1 = right
    arm = np.empty(len(points))
    leg = np.empty(len(points))
    for s in (0, 1):
        m = side == s
        arm[m] = _chain(points[m], marks.shoulder[s], marks.elbow[s], marks.wrist[s])
        leg[m] = _chain(points[m], marks.hip[s], marks.knee[s], marks.ankle[s])
    return arm, leg


@dataclass(frozen=True)
class FaceFeatures:
    """Per-face features of a source surface (F faces)."""

    part: np.ndarray  # (F,) str, majority part of the face's vertices
    arm: np.ndarray  # (F,) arm coordinate of the face centre
    leg: np.ndarray
    centre: np.ndarray  # (F, 3)


def face_features(vertices, faces, vertex_part, marks: Landmarks) -> FaceFeatures:
    """Features of faces (F, 4) over vertices (V, 3) with per-vertex part labels (V,)."""
    centre = vertices[faces].mean(axis=1)
    arm, leg = limb_coordinates(centre, marks)
    labels = vertex_part[faces]  # (F, 4)
    part = np.empty(len(faces), dtype=labels.dtype)
    best = np.zeros(len(faces), int)
    for name in PARTS:
        count = (labels == name).sum(axis=1)
        take = count > best
        part[take], best[take] = name, count[take]
    return FaceFeatures(part, arm, leg, centre)
