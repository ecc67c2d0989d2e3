"""A live session: one source driving one rig, smoothed, optionally recorded into a take.

What a UI timer (the Blender Mocap panel) runs, with no Blender in it::

    session = LiveSession(skeleton, LiveSettings("vmc", port=39539, smoothing=0.3))
    pose = session.step(record=True)   # the newest smoothed pose, or None; never blocks
    session.stats()                    # packet rate, dropped packets, latency
    take = session.close()             # the recorded Animation (sender's rate), or None

Sources: ``"vmc"`` (listens on UDP), ``"keypoints"`` (the JSON keypoint stream, UDP) and
``"bvh"`` (connects to a BVH-over-TCP server such as Axis Neuron). BVH frames reach the rig
the way VMC does: the stream's skeleton -> Unity's humanoid (``unity.UnityRig.to_unity``)
-> the rig (``from_unity``), so any humanoid BVH skeleton drives any Avatar rig per frame.

Smoothing: one strength in [0, 1] (``filters.OneEuro.strength``: 0 off, 0.5 the One Euro
defaults, 1 strongest). Keypoints are filtered in the solver (on positions); rotation
streams on the rig (``pose_filter``). While recording, every frame the sender completed
is kept (``take()``), so the take has the sender's rate; otherwise only the newest frame is
converted each step (a backlog after a UI stall costs one conversion, not hundreds).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass

import numpy as np

from avatar.errors import AvatarError, ParameterError
from avatar.mocap import bvhstream, keypoint_stream, keypoints, live, record, vmc
from avatar.mocap.filters import OneEuro
from avatar.mocap.pose_filter import PoseFilter
from avatar.mocap.solver import SolverSettings
from avatar.mocap.stream import Frame, StreamStats
from avatar.mocap.unity import UnityRig
from avatar.rig.skeleton import Animation, Skeleton

log = logging.getLogger(__name__)

SOURCES = ("vmc", "bvh", "keypoints")
DEFAULT_PORTS = {"vmc": vmc.DEFAULT_PORT, "bvh": 7001, "keypoints": keypoint_stream.DEFAULT_PORT}
DEFAULT_HOSTS = {"vmc": "0.0.0.0", "bvh": "127.0.0.1", "keypoints": "0.0.0.0"}


@dataclass(frozen=True)
class LiveSettings:
    """source: one of ``SOURCES``. host/port: where to listen (VMC, keypoints; "" = every
    interface) or the server to connect to (BVH; "" = 127.0.0.1). smoothing: strength in
    [0, 1]. keypoint_set: the keypoints stream's set. bvh_header: text of a BVH file with
    the stream's skeleton, for servers that send no header."""

    source: str = "vmc"
    host: str = ""
    port: int = vmc.DEFAULT_PORT
    smoothing: float = 0.0
    keypoint_set: str = "mediapipe33"
    bvh_header: str | None = None

    def check(self) -> LiveSettings:
        """Raises ParameterError on a bad source, port or strength."""
        if self.source not in SOURCES:
            raise ParameterError(f"unknown source {self.source!r}; use one of {', '.join(SOURCES)}")
        if not 0 <= int(self.port) <= 65535:
            raise ParameterError(f"port {self.port} is out of range (0-65535)")
        if not math.isfinite(self.smoothing) or not 0.0 <= self.smoothing <= 1.0:
            raise ParameterError(f"smoothing {self.smoothing} is not in [0, 1]")
        return self

    @property
    def address(self) -> tuple[str, int]:
        return self.host.strip() or DEFAULT_HOSTS[self.source], int(self.port)


def open_source(skeleton: Skeleton, settings: LiveSettings) -> live.LiveRig:
    """The settings' source, listening (or connected) and converting onto ``skeleton``.
    Raises ParameterError (port in use, no server, unknown keypoint set) with nothing open."""
    settings.check()
    host, port = settings.address
    if settings.source == "vmc":
        return live.open_vmc(skeleton, host, port)
    if settings.source == "keypoints":
        rig = keypoints.bind(settings.keypoint_set, skeleton)
        solve = SolverSettings(smoothing=OneEuro.strength(settings.smoothing))
        return live.open_keypoints(rig, host, port, solve)
    return open_bvh_stream(skeleton, host, port, settings.bvh_header)


def open_bvh_stream(skeleton: Skeleton, host: str, port: int,
                    header: str | None = None) -> live.LiveRig:  # fmt: skip
    """Connect to a BVH-over-TCP server and drive ``skeleton`` with its frames (through
    Unity's humanoid, as VMC). Frames arriving before the stream's header are skipped."""
    source = bvhstream.BvhStreamReceiver(host, port, header)
    target = UnityRig(skeleton)
    bridge: list[UnityRig] = []  # the stream's rig, made once its header is known

    def convert(frame: Frame) -> live.LivePose | None:
        stream_skeleton, clip = source.to_animation([frame.data])
        if not bridge:
            bridge.append(UnityRig(stream_skeleton))
        pose = bridge[0].to_unity(clip.rotations[0], clip.translations[0])
        rotations, translations = target.from_unity(pose)
        return live.LivePose(rotations, translations, frame.sent, frame.arrival)

    source.start()
    return live.LiveRig(source, convert)


class TakeBuffer:
    """Poses kept for a take: (J, 4) rotations with each bone's sign continuous from frame
    to frame (so keys interpolate the short way), (J, 3) translations, times (seconds)."""

    def __init__(self) -> None:
        self.rotations: list[np.ndarray] = []
        self.translations: list[np.ndarray] = []
        self.times: list[float] = []

    def __len__(self) -> int:
        return len(self.times)

    def append(self, rotations: np.ndarray, translations: np.ndarray, t: float) -> None:
        q = np.asarray(rotations, dtype=np.float64)
        if self.rotations:
            q = q * np.where(np.sum(q * self.rotations[-1], axis=1, keepdims=True) < 0, -1.0, 1.0)
        self.rotations.append(q.astype(np.float32))
        self.translations.append(np.asarray(translations, dtype=np.float32))
        self.times.append(float(t))

    def animation(self, skeleton: Skeleton) -> Animation:
        """The take at the sender's rate (median step of its clock). AvatarError if empty."""
        if not self.times:
            raise AvatarError("nothing was recorded")
        return Animation(np.stack(self.rotations).astype(np.float64),
                         np.stack(self.translations).astype(np.float64),
                         round(record.frame_rate(self.times), 3), skeleton.names)  # fmt: skip


class LiveSession:
    """One live source on one rig: ``step()`` each UI tick, ``close()`` at the end."""

    def __init__(self, skeleton: Skeleton, settings: LiveSettings):
        self.skeleton = skeleton
        self.settings = settings.check()
        self.rig = open_source(skeleton, settings)
        params = OneEuro.strength(settings.smoothing)
        rotation_stream = settings.source != "keypoints"  # keypoints: smoothed in the solver
        self.filter = PoseFilter(len(skeleton.names), params if rotation_stream else OneEuro.off())
        self.take = TakeBuffer()
        self.closed = False

    @property
    def address(self) -> tuple[str, int]:
        return self.rig.address

    def step(self, record: bool = False) -> live.LivePose | None:
        """The newest pose since the last step, smoothed, or None; never blocks. With
        ``record``, every pose since the last step is smoothed and kept in the take."""
        if self.closed:
            return None
        try:
            if record:
                poses = self.rig.take()
            else:
                newest = self.rig.poll()
                poses = [] if newest is None else [newest]
        except Exception:  # a frame that passed the receiver but not the conversion
            log.exception("mocap: converting a frame failed; dropped")
            self.rig.source.counters.drop("conversion")
            return None
        out = None
        for pose in poses:
            t = pose.sent if pose.sent is not None else pose.arrival
            rotations, translations = self.filter(pose.rotations, pose.translations, t)
            if record:
                self.take.append(rotations, translations, t)
            out = live.LivePose(rotations, translations, pose.sent, pose.arrival)
        return out

    def stats(self) -> StreamStats:
        return self.rig.stats()

    def close(self) -> Animation | None:
        """Stop listening (the port is free again); the recorded take, or None."""
        if not self.closed:
            self.closed = True
            self.rig.close()
            log.info("mocap session %s: %s", self.settings.source, self.rig.stats().summary())
        return self.take.animation(self.skeleton) if len(self.take) else None
