"""A plain keypoints stream for custom estimators: one JSON object per UDP datagram.

Format (UTF-8 JSON, one frame per datagram, at most 65,507 bytes)::

    {"seq": 17,                 # required, int, increasing: older or repeated -> dropped
     "t": 12.345,               # optional, seconds on the sender's clock
     "set": "coco17",           # optional; when given it must be the receiver's set
     "axes": "camera",          # optional, a key of keypoints.AXES (default: the set's)
     "points": [[x, y, z, c], [x, y, z], null, ...]}   # K entries, metres; c confidence
                                                       # 0..1 (default 1); null = missing

Dropped and counted, never raised: not JSON or not an object ("malformed"), a wrong set,
point count or axes, non-numbers ("bad_frame"), NaN/inf coordinates make that point missing,
``seq`` not after the last accepted ("out_of_order"). Default port 39540.
"""

from __future__ import annotations

import json
import math

import numpy as np

from avatar.mocap.keypoints import AXES, KeypointSet
from avatar.mocap.stream import Frame, UdpSource

DEFAULT_PORT = 39540


def encode(seq: int, points: np.ndarray, confidence: np.ndarray | None = None,
           t: float | None = None, set_name: str | None = None,
           axes: str | None = None) -> bytes:  # fmt: skip
    """One datagram: points (K, 3) metres (NaN rows: missing), confidence (K,) or None."""
    rows: list[list[float] | None] = []
    for k, p in enumerate(np.asarray(points, dtype=np.float64)):
        if not np.isfinite(p).all():
            rows.append(None)
        else:
            row = [round(float(v), 6) for v in p]
            if confidence is not None:
                row.append(round(float(confidence[k]), 4))
            rows.append(row)
    obj: dict = {"seq": int(seq), "points": rows}
    if t is not None:
        obj["t"] = float(t)
    if set_name:
        obj["set"] = set_name
    if axes:
        obj["axes"] = axes
    return json.dumps(obj, separators=(",", ":")).encode()


class KeypointParser:
    """Datagrams -> frames whose data is (points (K, 3), confidence (K,), axes)."""

    def __init__(self, keypoints: KeypointSet, counters):
        self.keypoints = keypoints
        self.counters = counters
        self.last_seq: int | None = None

    def feed(self, datagram: bytes, arrival: float) -> Frame | None:
        self.counters.packet()
        try:
            obj = json.loads(datagram.decode("utf-8"))
        except (UnicodeDecodeError, ValueError, RecursionError):
            self.counters.drop("malformed")
            return None
        parsed = self._frame(obj) if isinstance(obj, dict) else None
        if parsed is None:
            self.counters.drop("malformed" if not isinstance(obj, dict) else "bad_frame")
            return None
        seq, sent, data = parsed
        if self.last_seq is not None and seq <= self.last_seq:
            self.counters.drop("out_of_order")
            return None
        self.last_seq = seq
        frame = Frame(data, sent, arrival)
        self.counters.accept(frame)
        return frame

    def _frame(self, obj: dict):
        seq, rows = obj.get("seq"), obj.get("points")
        if isinstance(seq, bool) or not isinstance(seq, int) or not isinstance(rows, list):
            return None
        if "set" in obj and obj["set"] != self.keypoints.name:
            return None
        axes = obj.get("axes", self.keypoints.axes)
        t = obj.get("t")
        if axes not in AXES or len(rows) != len(self.keypoints.names):
            return None
        if t is not None and (isinstance(t, bool) or not isinstance(t, (int, float))
                              or not math.isfinite(t)):  # fmt: skip
            return None
        points = np.full((len(rows), 3), np.nan)
        confidence = np.zeros(len(rows))
        for k, row in enumerate(rows):
            if row is None:
                continue
            if (
                not isinstance(row, list)
                or len(row) not in (3, 4)
                or not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in row)
            ):
                return None
            values = [float(v) for v in row]
            if all(math.isfinite(v) for v in values):
                points[k] = values[:3]
                confidence[k] = min(max(values[3], 0.0), 1.0) if len(values) == 4 else 1.0
        return seq, (None if t is None else float(t)), (points, confidence, axes)


class KeypointReceiver(UdpSource):
    """Listens for the keypoints stream of one set on UDP ``host:port`` (0: any port)."""

    def __init__(self, keypoints: KeypointSet, host: str = "0.0.0.0", port: int = DEFAULT_PORT):
        super().__init__(host, port)
        self.parser = KeypointParser(keypoints, self.counters)

    def feed(self, data: bytes, arrival: float) -> None:
        self.parser.feed(data, arrival)
