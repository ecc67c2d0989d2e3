"""BVH frames over TCP (Axis Neuron / Perception Neuron "BVH data" output style).

The receiver connects to a TCP server (Axis Neuron listens, 7001 by default) and reads
text: an optional BVH header (``HIERARCHY`` ... ``MOTION``, ``Frames:``, ``Frame Time:``)
and then one frame per line, the channel values in header order. Axis Neuron's framing is
accepted too: a leading ``<avatar index> <avatar name>`` and a trailing ``||``. When the
stream sends no header, pass the skeleton's BVH file (``header=``).

Dropped and counted, never raised: lines that are not numbers or have the wrong count
("malformed"), non-finite values ("bad_frame"), lines longer than 1 MB ("oversize").
Frames are (C,) float64 arrays; ``to_animation`` turns a list of them into the skeleton's
``Animation`` (``avatar.io.bvh``'s units and axes), for ``avatar.motion.retarget``.
"""

from __future__ import annotations

import dataclasses
import socket
import time

import numpy as np

from avatar.errors import FormatError, ParameterError
from avatar.io import bvh
from avatar.mocap.stream import Frame, Source
from avatar.rig.skeleton import Animation, Skeleton

_MAX_LINE = 1 << 20


def parse_header(text: str) -> bvh.BvhData:
    """A BVH header (up to and including ``MOTION``, frame lines optional) -> BvhData
    with no frames. Raises FormatError."""
    head = text.split("MOTION")[0]
    time_line = [ln for ln in text.splitlines() if ln.strip().lower().startswith("frame time")]
    frame_time = time_line[0].split(":", 1)[1].strip() if time_line else "0.0333333"
    return bvh.loads(f"{head}MOTION\nFrames: 0\nFrame Time: {frame_time}\n")


def parse_frame(line: str, width: int) -> np.ndarray | None:
    """One frame line (Axis Neuron framing tolerated) -> (width,) floats, or None."""
    text = line.strip()
    if text.endswith("||"):
        text = text[:-2]
    words = text.split()
    if len(words) == width + 2:  # "<index> <name>" in front
        words = words[2:]
    if len(words) != width:
        return None
    try:
        return np.array([float(w) for w in words])
    except ValueError:
        return None


class BvhStreamReceiver(Source):
    """Connects to ``host:port`` and reads BVH frames; ``data`` of each frame is (C,)."""

    def __init__(self, host: str, port: int, header: str | None = None, timeout: float = 5.0):
        super().__init__()
        self.data: bvh.BvhData | None = parse_header(header) if header else None
        try:
            self.sock = socket.create_connection((host, port), timeout=timeout)
        except OSError as exc:
            raise ParameterError(f"cannot connect to {host}:{port}: {exc}") from None
        self.sock.settimeout(0.05)
        self.address = (host, port)

    @property
    def skeleton(self) -> Skeleton | None:
        return None if self.data is None else self.to_animation([])[0]

    def _loop(self) -> None:
        buffer = b""
        header: list[str] = []
        while not self._stop.is_set():
            try:
                chunk = self.sock.recv(65536)
            except TimeoutError:
                continue
            except OSError:
                return
            if not chunk:
                return  # the sender closed the stream
            buffer += chunk
            *lines, buffer = buffer.split(b"\n")
            if len(buffer) > _MAX_LINE:
                self.counters.drop("oversize")
                buffer = b""
            for raw in lines:
                self._line(raw.decode("utf-8", "replace"), header)

    def _line(self, line: str, header: list[str]) -> None:
        if not line.strip():
            return
        if self.data is None:  # still reading the header
            header.append(line)
            if line.strip().lower().startswith("frame time"):
                try:
                    self.data = parse_header("\n".join(header))
                except FormatError:
                    self.counters.drop("malformed")
                    header.clear()
            return
        self.counters.packet()
        width = self.data.motion.shape[1]
        values = parse_frame(line, width)
        if values is None:
            self.counters.drop("malformed")
        elif not np.isfinite(values).all():
            self.counters.drop("bad_frame")
        else:
            self.counters.accept(Frame(values, None, time.perf_counter()))

    def to_animation(self, frames: list[np.ndarray]) -> tuple[Skeleton, Animation]:
        """The stream's skeleton and these frames as an Animation (metres, Z up)."""
        if self.data is None:
            raise ParameterError("no BVH header has arrived (pass header=)")
        width = self.data.motion.shape[1]
        motion = np.stack(frames) if frames else np.zeros((1, width))
        data = dataclasses.replace(self.data, motion=motion)
        skeleton, animation = bvh.to_animation(data)
        return skeleton, animation

    def _close(self) -> None:
        self.sock.close()
