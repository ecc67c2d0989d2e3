"""Motion capture from video against ground truth: render an Avatar character performing
a known clip (the Blender bridge), run the video through ``video``, compare the solved
motion with the clip.

Metrics on the 17 COCO joints of the same rig (``keypoints`` "coco17"), in millimetres:
MPJPE after moving both skeletons' pelvis (mid-hips) onto each other (the clip first
turned into the camera's axes, which MediaPipe's world landmarks use), PA-MPJPE after the
best similarity transform per frame (Procrustes: rotation, translation, scale), and the
direction error per bone (degrees between the clip's and the solved segment, camera axes).

The clip is rendered on the spot (its travel removed: a camera tracking the pelvis), since
world landmarks carry no travel either.
"""

from __future__ import annotations

import os
import tempfile
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from avatar.mocap import keypoints
from avatar.rig.kinematics import world_pose
from avatar.rig.skeleton import Animation, Skeleton

BONES = {  # COCO segments whose direction error is reported
    "upper arm L": ("left_shoulder", "left_elbow"), "forearm L": ("left_elbow", "left_wrist"),
    "upper arm R": ("right_shoulder", "right_elbow"),
    "forearm R": ("right_elbow", "right_wrist"),
    "thigh L": ("left_hip", "left_knee"), "shin L": ("left_knee", "left_ankle"),
    "thigh R": ("right_hip", "right_knee"), "shin R": ("right_knee", "right_ankle"),
    "shoulders": ("right_shoulder", "left_shoulder"), "hips": ("right_hip", "left_hip"),
}  # fmt: skip


@dataclass(frozen=True)
class Comparison:
    """mpjpe, pa_mpjpe: mm, mean over frames and the 17 joints; per_frame: (T,) PA-MPJPE mm;
    bones: segment name -> mean direction error in degrees; frames: frames compared;
    jerk: (solved, truth) mean joint acceleration, mm per frame^2 (jitter shows as the
    solved motion's being higher than the clip's)."""

    mpjpe: float
    pa_mpjpe: float
    per_frame: np.ndarray
    bones: dict[str, float]
    frames: int
    jerk: tuple[float, float] = (float("nan"), float("nan"))

    def summary(self) -> str:
        worst = max(self.bones, key=self.bones.__getitem__)
        mean = float(np.mean(list(self.bones.values())))
        return (f"{self.frames} frames: MPJPE {self.mpjpe:.1f} mm, PA-MPJPE "
                f"{self.pa_mpjpe:.1f} mm, bone direction {mean:.1f} deg mean "
                f"(worst {worst} {self.bones[worst]:.1f} deg), acceleration {self.jerk[0]:.1f} "
                f"mm/frame^2 (clip {self.jerk[1]:.1f})")  # fmt: skip


def in_place(skeleton: Skeleton, animation: Animation) -> Animation:
    """The clip with the root's horizontal travel removed (its height and turns kept)."""
    _, heads = world_pose(skeleton, animation.rotations, animation.translations)
    root = int(np.flatnonzero(skeleton.parents < 0)[0])
    travel = heads[:, root] - skeleton.heads[root]
    travel[:, 2] = 0.0
    moves = animation.translations.copy()
    moves[:, root] -= travel @ skeleton.rest[root, :3, :3]  # world -> the root's rest axes
    return replace(animation, translations=moves)


def camera_axes(camera: np.ndarray) -> np.ndarray:
    """(3, 3) turning world vectors into the axes MediaPipe's world landmarks use, taken to
    Avatar's frame (``keypoints.AXES["camera"]``): rows camera x, -camera z (away from the
    camera... towards the subject's back), camera y. camera: Blender's (4, 4) world matrix
    (the camera looks down its -Z with +Y up)."""
    x, y, z = camera[:3, 0], camera[:3, 1], camera[:3, 2]
    return np.stack([x, -z, y]) / np.linalg.norm(x)


def compare(skeleton: Skeleton, truth: Animation, solved: Animation,
            axes: np.ndarray | None = None) -> Comparison:  # fmt: skip
    """Compare two animations of one rig (same frame count) on the COCO joints; ``axes``
    (3, 3) turns the truth's world into the solved motion's frame (``camera_axes``)."""
    rig = keypoints.bind("coco17", skeleton)
    count = min(truth.frames, solved.frames)
    a = rig.positions(truth)[:count] @ (np.eye(3) if axes is None else axes).T
    b = rig.positions(solved)[:count]
    names = rig.keypoints.names
    hips = [names.index("left_hip"), names.index("right_hip")]
    ra = a - a[:, hips].mean(axis=1, keepdims=True)
    rb = b - b[:, hips].mean(axis=1, keepdims=True)
    mpjpe = float(np.linalg.norm(ra - rb, axis=-1).mean() * 1000)
    per_frame = np.array([_procrustes_error(x, y) for x, y in zip(a, b, strict=True)]) * 1000
    bones = {}
    for name, (s, e) in BONES.items():
        i, j = names.index(s), names.index(e)
        da, db = a[:, j] - a[:, i], b[:, j] - b[:, i]
        cos = (da * db).sum(-1) / (np.linalg.norm(da, axis=-1) * np.linalg.norm(db, axis=-1))
        bones[name] = float(np.degrees(np.arccos(np.clip(cos, -1.0, 1.0))).mean())
    return Comparison(mpjpe, float(per_frame.mean()), per_frame, bones, count,
                      (_acceleration(b), _acceleration(a)))  # fmt: skip


def _acceleration(points: np.ndarray) -> float:
    """Mean length of the joints' second difference over frames (T, K, 3), mm/frame^2."""
    if len(points) < 3:
        return float("nan")
    return float(np.linalg.norm(np.diff(points, 2, axis=0), axis=-1).mean() * 1000)


def _procrustes_error(truth: np.ndarray, got: np.ndarray) -> float:
    """Mean joint distance (metres) after the similarity transform of ``got`` (K, 3) that
    best fits ``truth`` (K, 3) (Umeyama)."""
    ca, cb = truth.mean(0), got.mean(0)
    x, y = got - cb, truth - ca
    u, s, vt = np.linalg.svd(x.T @ y)
    d = np.sign(np.linalg.det(u @ vt)) or 1.0
    fix = np.diag([1.0, 1.0, d])
    r = (u @ fix @ vt).T
    scale = float((s * np.diag(fix)).sum() / (x * x).sum())
    return float(np.linalg.norm(scale * x @ r.T - y, axis=1).mean())


def render_video(character, path: str | os.PathLike[str], fps: float,
                 resolution: tuple[int, int] = (320, 400),
                 direction: tuple[float, float, float] = (0.25, -1.0, 0.12),
                 engine: str = "WORKBENCH",
                 camera: np.ndarray | None = None,
                 only: list[int] | None = None) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """Render a staged character's clip (``avatar.export.character``) to an MP4 video
    (OpenCV, mp4v). Returns (the frames (T, H, W, 3) uint8 RGB, the camera (4, 4)).
    camera: reuse this (4, 4) camera; only: render just these frames."""
    import cv2

    from avatar.blender import frames as frame_bridge

    frame_bridge.stage_empty()
    with tempfile.TemporaryDirectory(prefix="avatar-mocap-gt-") as tmp:
        paths, matrix = frame_bridge.render_frames(character, tmp, resolution, direction,
                                                   engine, camera=camera, only=only)  # fmt: skip
        pictures = np.array([cv2.cvtColor(cv2.imread(str(p)), cv2.COLOR_BGR2RGB) for p in paths])
    fourcc = cv2.VideoWriter_fourcc(*"mp4v")  # type: ignore[attr-defined]
    writer = cv2.VideoWriter(str(path), fourcc, float(fps), resolution)
    try:
        for rgb in pictures:
            writer.write(cv2.cvtColor(rgb, cv2.COLOR_RGB2BGR))
    finally:
        writer.release()
    if not Path(path).is_file():
        raise OSError(f"{path}: OpenCV wrote no video")
    return pictures, matrix


def upright(animation: Animation, skeleton: Skeleton, axes: np.ndarray) -> Animation:
    """A motion solved in camera axes turned back into the world (``axes``: the
    ``camera_axes`` of the camera that filmed it), e.g. to render it beside the input."""
    from avatar.rig import quaternion

    root = int(np.flatnonzero(skeleton.parents < 0)[0])
    rest = skeleton.rest[root, :3, :3]
    turn = rest.T @ axes.T @ rest  # in the root's rest axes
    q = quaternion.from_matrix(turn)
    rotations = animation.rotations.copy()
    rotations[:, root] = quaternion.multiply(q, rotations[:, root])
    moves = animation.translations.copy()
    head = skeleton.heads[root]
    solved = head + moves[:, root] @ rest.T  # the root's head in the solved frame
    world = solved @ axes  # solved -> world (axes is a rotation: its inverse is .T)
    moves[:, root] = (world - head) @ rest
    return replace(animation, rotations=rotations, translations=moves)
