"""Live sources on a rig: the non-blocking API a UI timer (the Blender panel) or a loop
calls.

    live = live.open_vmc(human.skeleton, port=39539)   # or open_keypoints(...)
    while running:                                   # e.g. a 60 Hz timer
        pose = live.poll()                           # newest pose or None, never blocks
        if pose is not None:
            apply(pose.rotations, pose.translations) # (J, 4) and (J, 3), Animation's layout
        stats = live.stats()                         # rate, dropped, latency (ms)
    live.close()

``take()`` returns every pose since the last call, for recording at the sender's rate.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from avatar.mocap import keypoint_stream, vmc
from avatar.mocap.keypoints import RigKeypoints, to_avatar
from avatar.mocap.solver import PoseSolver, SolverSettings
from avatar.mocap.stream import Frame, Source, StreamStats
from avatar.mocap.unity import UnityRig
from avatar.rig.skeleton import Skeleton


@dataclass(frozen=True)
class LivePose:
    """A pose on the rig: rotations (J, 4), translations (J, 3) (``Animation`` layout),
    ``sent`` (the sender's clock, s, or None) and ``arrival`` (``time.perf_counter()``)."""

    rotations: np.ndarray
    translations: np.ndarray
    sent: float | None
    arrival: float


class LiveRig:
    """A source and the conversion of its frames onto one rig."""

    def __init__(self, source: Source, convert: Callable[[Frame], LivePose | None]):
        self.source = source
        self.convert = convert
        self._solve_ms: list[float] = []

    def poll(self) -> LivePose | None:
        """The newest pose since the last call, or None; never blocks."""
        frame = self.source.poll()
        return None if frame is None else self._convert(frame)

    def take(self) -> list[LivePose]:
        """Every pose since the last call, oldest first."""
        out = [self._convert(f) for f in self.source.take()]
        return [p for p in out if p is not None]

    def _convert(self, frame: Frame) -> LivePose | None:
        t0 = time.perf_counter()
        pose = self.convert(frame)
        self._solve_ms = (self._solve_ms + [1000.0 * (time.perf_counter() - t0)])[-100:]
        return pose

    def stats(self) -> StreamStats:
        """The source's counters; ``latency_ms`` includes the conversion onto the rig."""
        s = self.source.stats()
        extra = float(np.mean(self._solve_ms)) if self._solve_ms else 0.0
        return replace(s, latency_ms=s.latency_ms + extra)

    @property
    def address(self) -> tuple[str, int]:
        return getattr(self.source, "address", ("", 0))

    def close(self) -> None:
        self.source.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def open_vmc(skeleton: Skeleton, host: str = "0.0.0.0", port: int = vmc.DEFAULT_PORT) -> LiveRig:
    """Listen for VMC and drive ``skeleton`` (any Avatar rig) with it."""
    rig = UnityRig(skeleton)
    source = vmc.VmcReceiver(host, port).start()

    def convert(frame: Frame) -> LivePose:
        rotations, translations = rig.from_unity(frame.data)
        return LivePose(rotations, translations, frame.sent, frame.arrival)

    return LiveRig(source, convert)


def open_keypoints(rig: RigKeypoints, host: str = "0.0.0.0",
                   port: int = keypoint_stream.DEFAULT_PORT,
                   settings: SolverSettings | None = None) -> LiveRig:  # fmt: skip
    """Listen for the JSON keypoint stream (``keypoint_stream``) of ``rig``'s keypoint set
    and solve each frame onto the rig."""
    solver = PoseSolver(rig, settings)
    source = keypoint_stream.KeypointReceiver(rig.keypoints, host, port).start()

    def convert(frame: Frame) -> LivePose:
        points, confidence, axes = frame.data
        t = frame.sent if frame.sent is not None else frame.arrival
        solved = solver(to_avatar(points, axes), confidence, t)
        return LivePose(solved.rotations, solved.translations, frame.sent, frame.arrival)

    return LiveRig(source, convert)
