"""Recording a live stream onto a rig, and replaying a clip as VMC.

``record_vmc`` keeps every frame the sender completed (one per ``/VMC/Ext/OK`` or bundle),
each retargeted onto the rig as it arrives, and stamps the take with the sender's rate
(the median step of its ``/VMC/Ext/T`` clock, else of the arrival times).
"""

from __future__ import annotations

import logging
import os
import time

import numpy as np

from avatar.errors import AvatarError
from avatar.io import bvh
from avatar.mocap import live, vmc
from avatar.mocap.unity import UnityRig
from avatar.rig.skeleton import Animation, Skeleton

log = logging.getLogger(__name__)


def frame_rate(times: list[float], fallback: float = 30.0) -> float:
    """Frames per second from the median step of increasing timestamps (seconds)."""
    steps = np.diff(np.asarray(times, dtype=np.float64))
    steps = steps[steps > 0]
    return float(1.0 / np.median(steps)) if len(steps) else fallback


def to_animation(poses: list[live.LivePose], skeleton: Skeleton) -> Animation:
    """Recorded poses -> an Animation at the sender's rate (AvatarError when empty)."""
    if not poses:
        raise AvatarError("nothing was received")
    sent = [p.sent for p in poses if p.sent is not None]
    times = sent if len(sent) == len(poses) else [p.arrival for p in poses]
    rotations = np.stack([p.rotations for p in poses])
    translations = np.stack([p.translations for p in poses])
    return Animation(rotations, translations, round(frame_rate(times), 3), skeleton.names)


def record_vmc(skeleton: Skeleton, host: str, port: int, seconds: float,
               on_tick=None) -> Animation:  # fmt: skip
    """Listen for VMC on ``host:port`` for ``seconds``; every frame onto ``skeleton``.

    on_tick: called about ten times a second with the ``LiveRig`` (progress, stats).
    Raises AvatarError when no frame arrived.
    """
    poses: list[live.LivePose] = []
    with live.open_vmc(skeleton, host, port) as rig:
        end = time.perf_counter() + seconds
        while time.perf_counter() < end:
            time.sleep(min(0.1, max(end - time.perf_counter(), 0.0)))
            poses.extend(rig.take())
            if on_tick is not None:
                on_tick(rig)
        poses.extend(rig.take())
        log.info("VMC %s:%d: %s", host, port, rig.stats().summary())
    if not poses:
        raise AvatarError(f"no VMC frames arrived on {host}:{port} in {seconds:g} s")
    return to_animation(poses, skeleton)


def send_clip(path: str | os.PathLike[str], host: str, port: int, realtime: bool = True,
              speed: float = 1.0) -> int:  # fmt: skip
    """Replay a BVH clip (any humanoid skeleton) as VMC to ``host:port``, at the clip's rate
    (``realtime``) or as fast as possible; returns the frames sent."""
    skeleton, clip = bvh.load(path)
    return send_animation(skeleton, clip, host, port, realtime, speed)


def send_animation(skeleton: Skeleton, clip: Animation, host: str, port: int,
                   realtime: bool = True, speed: float = 1.0) -> int:  # fmt: skip
    rig = UnityRig(skeleton)
    start = time.perf_counter()
    with vmc.VmcSender(host, port) as sender:
        for i in range(clip.frames):
            t = i / clip.fps
            if realtime:
                delay = start + t / speed - time.perf_counter()
                if delay > 0:
                    time.sleep(delay)
            sender.send(rig.to_unity(clip.rotations[i], clip.translations[i]), t)
    return clip.frames
