"""Video -> motion: MediaPipe Pose on each frame of a video (OpenCV), its world landmarks
solved onto an Avatar rig (``solver``, the MediaPipe-33 set).

Needs the optional ``mocap`` extra: ``mediapipe==0.10.14`` (its wheel ships the pose
detector and the "full" landmark model, so nothing is downloaded at run time; the "lite"
and "heavy" models are not in the wheel, hence ``model_complexity=1`` only) and
``opencv-python-headless``.

MediaPipe's world landmarks are metres in camera axes (x right in the image, y down, z away
from the camera) with the origin between the hips, so the solved motion is the body's
pose and orientation as the camera sees it, its lowest ankle on the floor in every frame
(``floor="ground"``: a crouch lowers the hips, a jump stays on the floor) with no travel: a
walk across the room becomes a walk on the spot. Landmark ``visibility`` is
the solver's confidence (below 0.5: the joint is held and relaxes to rest).
"""

from __future__ import annotations

import contextlib
import logging
import os
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from avatar.errors import AvatarError, FormatError
from avatar.mocap import filters, keypoints, solver, temporal
from avatar.rig.skeleton import Animation, Skeleton

log = logging.getLogger(__name__)

INSTALL = "pip install 'avatar[mocap]' (mediapipe==0.10.14, opencv-python-headless)"


@dataclass(frozen=True)
class VideoPose:
    """MediaPipe Pose over a video.

    points: (T, 33, 3) world landmarks in Avatar's axes, metres (NaN: no person found).
    confidence: (T, 33) landmark visibility 0..1 (0 where no person was found).
    image: (T, 33, 2) landmarks in pixels (x right, y down; NaN: none).
    fps: the video's frame rate; size: (width, height) pixels.
    """

    points: np.ndarray
    confidence: np.ndarray
    image: np.ndarray
    fps: float
    size: tuple[int, int]

    @property
    def found(self) -> np.ndarray:
        """(T,) bool: frames where MediaPipe found a person."""
        return np.isfinite(self.points).all(axis=(1, 2))


def _modules():
    """(cv2, mediapipe pose module), or AvatarError saying how to install them."""
    os.environ.setdefault("GLOG_minloglevel", "2")  # MediaPipe's C++ info/warning lines
    try:
        import cv2

        _protobuf_compat()  # before mediapipe's import, which already reads messages
        import mediapipe.python.solutions.pose as mp_pose
    except ImportError as exc:
        raise AvatarError(f"video capture needs OpenCV and MediaPipe: {INSTALL} "
                          f"({exc.name or exc} is missing)") from None  # fmt: skip
    return cv2, mp_pose


def _protobuf_compat() -> None:
    """mediapipe 0.10.14 reads its results with ``SymbolDatabase.GetPrototype``, which
    protobuf 5 removed (``message_factory.GetMessageClass`` is its replacement); environments
    that need a newer protobuf for other packages (ray, opentelemetry) would otherwise get
    no landmarks at all."""
    from google.protobuf import message_factory, symbol_database

    def prototype(self, descriptor):
        return message_factory.GetMessageClass(descriptor)

    for cls in (symbol_database.SymbolDatabase, message_factory.MessageFactory):
        if not hasattr(cls, "GetPrototype"):
            cls.GetPrototype = prototype  # type: ignore[attr-defined]


def frames(path: str | os.PathLike[str]) -> tuple[float, tuple[int, int], Iterator[np.ndarray]]:
    """(fps, (width, height), iterator of (H, W, 3) uint8 RGB frames) of a video file.

    FormatError (one line) when the file is missing, not a video OpenCV can decode, or has
    no frames."""
    cv2, _ = _modules()
    p = Path(path)
    if not p.is_file():
        raise FormatError(p, 0, "no such video file")
    with _quiet_stderr():  # FFmpeg logs its own complaint ("moov atom not found")
        capture = cv2.VideoCapture(str(p))
        ok, first = capture.read() if capture.isOpened() else (False, None)
    if not ok or first is None:
        capture.release()
        raise FormatError(p, 0, "not a video OpenCV can read (no decodable frame)")
    fps = float(capture.get(cv2.CAP_PROP_FPS)) or 30.0
    if not np.isfinite(fps) or fps <= 0 or fps > 1000:
        fps = 30.0
    size = (int(first.shape[1]), int(first.shape[0]))

    def read() -> Iterator[np.ndarray]:
        try:
            frame = first
            while frame is not None:
                yield cv2.cvtColor(frame, cv2.COLOR_BGR2RGB)
                ok, frame = capture.read()
                frame = frame if ok else None
        finally:
            capture.release()

    return fps, size, read()


@contextlib.contextmanager
def _quiet_stderr() -> Iterator[None]:
    """Silence the process's stderr (file descriptor 2: C libraries) for a moment, so a bad
    file gives Avatar's one-line error only."""
    try:
        saved = os.dup(2)
    except OSError:
        yield
        return
    try:
        with open(os.devnull, "w") as null:
            os.dup2(null.fileno(), 2)
            yield
    finally:
        os.dup2(saved, 2)
        os.close(saved)


def estimate(path: str | os.PathLike[str], most: int | None = None,
             progress: Callable[[int], None] | None = None) -> VideoPose:  # fmt: skip
    """MediaPipe Pose (full model, tracking mode, its own landmark smoothing) on each frame
    of a video, at most ``most`` frames; ``progress(i)`` after each."""
    _, mp_pose = _modules()
    fps, size, stream = frames(path)
    pts, conf, image = [], [], []
    with mp_pose.Pose(static_image_mode=False, model_complexity=1, smooth_landmarks=True,
                      min_detection_confidence=0.5,
                      min_tracking_confidence=0.5) as pose:  # fmt: skip
        for i, rgb in enumerate(stream):
            if most is not None and i >= most:
                break
            p, c, xy = _landmarks(pose.process(rgb), size)
            pts.append(p)
            conf.append(c)
            image.append(xy)
            if progress is not None:
                progress(i)
    found = sum(bool(np.isfinite(p).all()) for p in pts)
    log.info("MediaPipe found a person in %d of %d frames", found, len(pts))
    points = keypoints.to_avatar(np.array(pts).reshape(-1, 33, 3), "camera")
    return VideoPose(points, np.array(conf).reshape(-1, 33), np.array(image).reshape(-1, 33, 2),
                     fps, size)  # fmt: skip


def _landmarks(result, size: tuple[int, int]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(33, 3) world landmarks (camera axes), (33,) visibility, (33, 2) pixels; NaN/0 when
    no person was found."""
    world = result.pose_world_landmarks
    if world is None:
        return np.full((33, 3), np.nan), np.zeros(33), np.full((33, 2), np.nan)
    p = np.array([(m.x, m.y, m.z) for m in world.landmark], dtype=np.float64)
    c = np.array([m.visibility for m in world.landmark], dtype=np.float64)
    flat = result.pose_landmarks
    xy = np.array([(m.x * size[0], m.y * size[1]) for m in flat.landmark], dtype=np.float64)
    return p, np.clip(c, 0.0, 1.0), xy


# The solver's settings for MediaPipe's output: its graph already One-Euro-filters the
# landmarks and ``solve`` smooths them over time without lag, so the solver does not
# filter again (that would only add latency). World
# landmarks are centred on the hips and say nothing of the body's height above the floor:
# each frame stands on its lowest ankle ("ground"; with "auto", one floor for the clip,
# the hips stayed at standing height and a crouch lifted the feet 4 cm off the floor).
VIDEO_SETTINGS = solver.SolverSettings(smoothing=filters.OneEuro.off(), floor="ground")


def solve(pose: VideoPose, skeleton: Skeleton, settings: solver.SolverSettings | None = None,
          smooth: float = temporal.SIGMA) -> Animation:  # fmt: skip
    """The video's motion on a rig: an Animation at the video's frame rate (frames with no
    person hold the last pose and relax to rest). The landmarks are first smoothed over
    time without lag (``temporal.smooth``, sigma ``smooth`` seconds; 0: not)."""
    if not len(pose.points):
        raise AvatarError("the video has no frames")
    if not pose.found.any():
        raise AvatarError("MediaPipe found no person in the video")
    rig = keypoints.bind("mediapipe33", skeleton)
    points = temporal.smooth(pose.points, pose.confidence, pose.fps, smooth)
    return solver.solve(rig, points, pose.confidence, pose.fps, settings or VIDEO_SETTINGS)
