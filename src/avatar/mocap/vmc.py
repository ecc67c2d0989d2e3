"""The VMC protocol (Virtual Motion Capture; OSC 1.0 over UDP): receiver and sender.

Spec: https://protocol.vmc.info/english (the performer -> marionette messages):

- ``/VMC/Ext/Root/Pos`` s name, f px py pz, f qx qy qz qw [, f sx sy sz, f ox oy oz]
- ``/VMC/Ext/Bone/Pos`` s HumanBodyBones name, f px py pz, f qx qy qz qw (local, Unity)
- ``/VMC/Ext/Blend/Val`` s name, f value; ``/VMC/Ext/Blend/Apply``
- ``/VMC/Ext/OK`` i loaded [, i calibration state, i calibration mode, i tracking]
- ``/VMC/Ext/T`` f time (the sender's clock, seconds)

Receivers listen on UDP 39539 by convention. Axes and handedness: ``avatar.mocap.unity``.

Frames. A frame completes at the end of a bundle that carried an ``/VMC/Ext/OK`` or bone
data (senders put ``/VMC/Ext/T`` after OK), or at an ``/VMC/Ext/OK`` datagram of its own;
its bones are the latest value of every bone received so far (senders may send only what
changed).

Dropped and counted, never raised: undecodable datagrams ("malformed"), messages with wrong
argument types or counts, non-finite numbers or non-unit quaternions ("bad_message"),
frames whose ``/VMC/Ext/T`` is not after the last accepted one ("out_of_order"), frames
with more bone messages than a humanoid has ("oversize"). Unknown bone names are ignored
("unknown_bone").
"""

from __future__ import annotations

import logging
import math
import socket
from collections.abc import Sequence

from pythonosc.osc_bundle_builder import IMMEDIATELY, OscBundleBuilder
from pythonosc.osc_message_builder import OscMessageBuilder

from avatar.errors import ParameterError
from avatar.mocap import osc
from avatar.mocap.stream import Frame, UdpSource
from avatar.mocap.unity import UnityPose, human_bones

log = logging.getLogger(__name__)

DEFAULT_PORT = 39539
_MAX_BONE_MESSAGES = 512  # a humanoid has 55 bones; more in one frame is garbage


def parse_address(text: str, default_host: str = "127.0.0.1") -> tuple[str, int]:
    """ "HOST:PORT", ":PORT" or "PORT" -> (host, port); ParameterError otherwise."""
    host, _, port = str(text).rpartition(":")
    try:
        number = int(port)
    except ValueError:
        raise ParameterError(f"expected HOST:PORT, got {text!r}") from None
    if not 0 <= number <= 65535:
        raise ParameterError(f"port out of range in {text!r}")
    return (host.strip("[]") or default_host), number


def _numbers(args: Sequence, count: int) -> list[float] | None:
    """``count`` finite numbers (int or float, not bool) as floats, or None."""
    if len(args) != count:
        return None
    out = []
    for a in args:
        if isinstance(a, bool) or not isinstance(a, (int, float)):
            return None
        v = float(a)
        if v - v != 0.0:  # inf or NaN
            return None
        out.append(v)
    return out


def _pose_args(params: list) -> tuple[str, tuple, tuple] | None:
    """(name, position (3 floats), unit quaternion xyzw (4 floats)) from
    ``s f f f f f f f``, or None."""
    if len(params) < 8 or not isinstance(params[0], str):
        return None
    values = _numbers(params[1:8], 7)
    if values is None:
        return None
    px, py, pz, x, y, z, w = values
    norm = math.sqrt(x * x + y * y + z * z + w * w)
    if not 0.5 < norm < 2.0:  # a rotation is a unit quaternion; far off is garbage
        return None
    return params[0], (px, py, pz), (x / norm, y / norm, z / norm, w / norm)


class VmcAssembler:
    """Datagrams -> complete VMC frames (no sockets; the receiver's logic, testable)."""

    def __init__(self, counters):
        self.counters = counters
        self.known = {b[0] for b in human_bones()}
        self.bones: dict[str, tuple] = {}  # name -> (position, quaternion xyzw): floats
        self.root: tuple = ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0))
        self.blends: dict[str, float] = {}
        self.last_sent: float | None = None
        self._reset_pending()

    def _reset_pending(self) -> None:
        self.pending_bones: dict[str, tuple] = {}
        self.pending_count = 0
        self.pending_root: tuple | None = None
        self.pending_time: float | None = None

    def feed(self, datagram: bytes, arrival: float) -> list[Frame]:
        """Frames completed by one datagram (usually zero or one)."""
        self.counters.packet()
        try:
            messages = osc.decode(datagram)
        except osc.OscError:
            self.counters.drop("malformed")
            return []
        if not messages:  # an empty bundle
            self.counters.drop("malformed")
            return []
        # In a bundle the frame completes at its end: senders put /VMC/Ext/T after OK.
        bundle = datagram[:8] == b"#bundle\x00"
        out: list[Frame] = []
        ok = False
        for address, params in messages:
            if self._message(address, params):
                ok = True
                if not bundle:
                    out += self._complete(arrival)
        if bundle and (ok or self.pending_count):
            out += self._complete(arrival)
        return out

    def _message(self, address: str, params: list) -> bool:
        """Take one message into the pending frame; True for /VMC/Ext/OK."""
        if address == "/VMC/Ext/Bone/Pos":
            parsed = _pose_args(params)
            if parsed is None:
                self.counters.drop("bad_message")
            elif parsed[0] not in self.known:
                self.counters.drop("unknown_bone")
            else:
                self.pending_count += 1
                self.pending_bones[parsed[0]] = (parsed[1], parsed[2])
        elif address == "/VMC/Ext/Root/Pos":
            parsed = _pose_args(params)
            if parsed is None or (len(params) not in (8, 14)):
                self.counters.drop("bad_message")
            else:
                self.pending_root = (parsed[1], parsed[2])
        elif address == "/VMC/Ext/T":
            values = _numbers(params, 1)
            if values is None:
                self.counters.drop("bad_message")
            else:
                self.pending_time = values[0]
        elif address == "/VMC/Ext/Blend/Val":
            values = _numbers(params[1:], 1)
            if len(params) != 2 or not isinstance(params[0], str) or values is None:
                self.counters.drop("bad_message")
            else:
                self.blends[params[0]] = values[0]
        elif address == "/VMC/Ext/OK":
            return True
        return False

    def _complete(self, arrival: float) -> list[Frame]:
        count, sent = self.pending_count, self.pending_time
        bones, root = self.pending_bones, self.pending_root
        self._reset_pending()
        if count > _MAX_BONE_MESSAGES:
            self.counters.drop("oversize")
            return []
        if not bones and root is None:
            return []  # an OK alone: a heartbeat
        if sent is not None and self.last_sent is not None and sent <= self.last_sent:
            self.counters.drop("out_of_order")
            return []
        if sent is not None:
            self.last_sent = sent
        self.bones.update(bones)
        if root is not None:
            self.root = root
        frame = Frame(UnityPose(self.root, dict(self.bones)), sent, arrival)
        self.counters.accept(frame)
        return [frame]


class VmcReceiver(UdpSource):
    """Listens for VMC on UDP ``host:port`` (port 0: any free port, see ``address``).

    ``poll()``/``take()`` give ``Frame``s whose ``data`` is a ``unity.UnityPose``; drive a
    rig with ``live.VmcOnRig`` (or ``unity.UnityRig.from_unity``).
    """

    def __init__(self, host: str = "0.0.0.0", port: int = DEFAULT_PORT):
        super().__init__(host, port)
        self.assembler = VmcAssembler(self.counters)

    def feed(self, data: bytes, arrival: float) -> None:
        self.assembler.feed(data, arrival)


class VmcSender:
    """Sends VMC frames to ``host:port`` over UDP, one OSC bundle per frame."""

    def __init__(self, host: str = "127.0.0.1", port: int = DEFAULT_PORT):
        self.target = (host, port)
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)

    def send(self, pose: UnityPose, t: float, blends: dict[str, float] | None = None) -> int:
        """One frame (root, bones, blend shapes, OK, T) as a bundle; returns its size."""
        bundle = OscBundleBuilder(IMMEDIATELY)
        pos, q = pose.root
        bundle.add_content(_message("/VMC/Ext/Root/Pos", ["root", *pos, *q]))
        for name, (p, r) in pose.bones.items():
            bundle.add_content(_message("/VMC/Ext/Bone/Pos", [name, *p, *r]))
        for name, value in (blends or {}).items():
            bundle.add_content(_message("/VMC/Ext/Blend/Val", [name, value]))
        if blends:
            bundle.add_content(_message("/VMC/Ext/Blend/Apply", []))
        bundle.add_content(_message("/VMC/Ext/OK", [1]))
        bundle.add_content(_message("/VMC/Ext/T", [float(t)]))
        data = bundle.build().dgram
        self.sock.sendto(data, self.target)
        return len(data)

    def close(self) -> None:
        self.sock.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def _message(address: str, args: list):
    m = OscMessageBuilder(address)
    for a in args:
        if isinstance(a, str):
            m.add_arg(a, "s")
        elif isinstance(a, int) and not isinstance(a, bool):
            m.add_arg(a, "i")
        else:
            m.add_arg(float(a), "f")
    return m.build()
