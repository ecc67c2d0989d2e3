"""Biovision Hierarchy (BVH) motion files: text format, and conversion to Avatar's frame.

Spec: the Biovision BVH description (https://research.cs.wisc.edu/graphics/Courses/cs-838-1999/
Jeff/BVH.html) plus what real exporters write: any rotation order per joint (mixed in one
file), 3 or 6 channels on any joint, ``End Site`` blocks, tabs, ``prefix:`` names, Y-up or Z-up,
any length unit, ``Frame Time`` written as ``.0083333`` or ``8.33e-3``.

Two layers:

- ``loads``/``dumps``/``read``/``write`` move between text and ``BvhData``, the file's content
  as stored (file units and axes, degrees). Lossless round trip.
- ``to_animation``/``from_animation`` (and ``load``/``save``) convert between ``BvhData`` and
  Avatar's ``Skeleton``/``Animation`` (metres, Z-up, Blender bone convention). Units and the
  up axis are detected when not given. This is the only place BVH axes/units are converted.

A BVH channel line ``Zrotation Yrotation Xrotation`` means local rotation R = Rz @ Ry @ Rx
(rotations listed outermost first), applied to the joint's children offsets.
"""

from __future__ import annotations

import io
import logging
import os
import re
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from avatar.errors import FormatError, ParameterError
from avatar.io import atomic
from avatar.rig import quaternion, topology
from avatar.rig.placement import rest_matrices
from avatar.rig.skeleton import Animation, Skeleton

log = logging.getLogger(__name__)

_CHANNELS = {c.lower(): c for a in "XYZ" for c in (f"{a}position", f"{a}rotation")}

# Length units seen in BVH files, in metres. "cmu" is the CMU ASF unit (inches / 0.45) that
# the cgspeed conversions kept.
UNITS = {"m": 1.0, "dm": 0.1, "cm": 0.01, "mm": 0.001, "in": 0.0254, "ft": 0.3048,
         "cmu": 0.0254 / 0.45}  # fmt: skip
_HUMAN_HEIGHT = 1.7  # metres; unit detection picks the unit closest to this (log scale)


@dataclass(frozen=True)
class BvhData:
    """A BVH file's content as stored.

    names: J joint names (verbatim, prefixes kept); parents precede children.
    parents: (J,) int32 parent index, -1 for roots.
    offsets: (J, 3) float64 OFFSET values (file units, file axes).
    channels: per joint, its channel names in file order (canonical case, e.g. "Zrotation").
    end_sites: (J, 3) float64 End Site offsets, NaN rows for joints without one.
    motion: (T, C) float64 channel values in file order (degrees, file units).
    frame_time: seconds per frame.
    """

    names: tuple[str, ...]
    parents: np.ndarray
    offsets: np.ndarray
    channels: tuple[tuple[str, ...], ...]
    end_sites: np.ndarray
    motion: np.ndarray
    frame_time: float

    @property
    def frames(self) -> int:
        return int(self.motion.shape[0])

    @property
    def fps(self) -> float:
        return 1.0 / self.frame_time

    def channel_starts(self) -> np.ndarray:
        """(J,) index of each joint's first column in ``motion``."""
        counts = np.array([len(c) for c in self.channels], dtype=np.int64)
        return np.concatenate([[0], np.cumsum(counts)[:-1]]).astype(np.int64)


# ----------------------------------------------------------------------------- parsing


class _Tokens:
    """Whitespace tokens of the HIERARCHY block with their 1-based line numbers."""

    def __init__(self, lines: list[str], path: str | None):
        self.items = [(tok, n) for n, line in enumerate(lines, 1) for tok in line.split()]
        self.pos = 0
        self.path = path

    def error(self, message: str, line: int | None = None) -> FormatError:
        if line is None:
            line = self.items[min(self.pos, len(self.items) - 1)][1] if self.items else 0
        return FormatError(self.path, line, message)

    def next(self, what: str) -> tuple[str, int]:
        if self.pos >= len(self.items):
            raise self.error(f"file ends where {what} was expected")
        self.pos += 1
        return self.items[self.pos - 1]

    def expect(self, word: str) -> int:
        tok, line = self.next(repr(word))
        if tok.upper() != word.upper():
            raise self.error(f"expected {word!r}, found {tok!r}", line)
        return line

    def floats(self, n: int, what: str) -> np.ndarray:
        out = []
        for _ in range(n):
            tok, line = self.next(what)
            try:
                out.append(float(tok))
            except ValueError:
                raise self.error(f"{what}: {tok!r} is not a number", line) from None
        arr = np.array(out)
        if not np.all(np.isfinite(arr)):
            raise self.error(f"{what} is not finite", line)
        return arr


def _parse_hierarchy(tokens: _Tokens) -> dict:
    """Token stream -> names, parents, offsets, channels, end sites (recursive descent)."""
    out: dict = {"names": [], "parents": [], "offsets": [], "channels": [], "ends": []}
    tokens.expect("HIERARCHY")
    tok, line = tokens.next("ROOT")
    if tok.upper() != "ROOT":
        raise tokens.error(f"expected ROOT, found {tok!r}", line)
    _parse_joint(tokens, -1, out)
    while tokens.pos < len(tokens.items) and tokens.items[tokens.pos][0].upper() == "ROOT":
        tokens.pos += 1
        _parse_joint(tokens, -1, out)
    return out


def _read_name(tokens: _Tokens) -> str:
    """Joint name: every token up to the opening brace (names may contain spaces)."""
    words = []
    while True:
        tok, line = tokens.next("a joint name and '{'")
        if tok == "{":
            break
        if tok.endswith("{"):
            words.append(tok[:-1])
            break
        words.append(tok)
    if not words or not words[0]:
        raise tokens.error("joint without a name", line)
    return " ".join(words)


def _parse_joint(tokens: _Tokens, parent: int, out: dict) -> None:
    index = len(out["names"])
    out["names"].append(_read_name(tokens))
    out["parents"].append(parent)
    out["ends"].append(np.full(3, np.nan))
    tokens.expect("OFFSET")
    out["offsets"].append(tokens.floats(3, "OFFSET"))
    tokens.expect("CHANNELS")
    out["channels"].append(_parse_channels(tokens))
    while True:
        tok, line = tokens.next("JOINT, End Site or '}'")
        key = tok.upper()
        if key == "}":
            return
        if key == "JOINT":
            _parse_joint(tokens, index, out)
        elif key == "END":
            tokens.expect("Site")
            tokens.expect("{")
            tokens.expect("OFFSET")
            out["ends"][index] = tokens.floats(3, "End Site OFFSET")
            tokens.expect("}")
        else:
            raise tokens.error(f"unexpected {tok!r} in joint {out['names'][index]!r}", line)


def _parse_channels(tokens: _Tokens) -> tuple[str, ...]:
    tok, line = tokens.next("channel count")
    if not tok.isdigit() or not 0 <= int(tok) <= 6:
        raise tokens.error(f"channel count must be 0..6, found {tok!r}", line)
    names = []
    for _ in range(int(tok)):
        name, line = tokens.next("a channel name")
        if name.lower() not in _CHANNELS:
            raise tokens.error(f"unknown channel {name!r}", line)
        names.append(_CHANNELS[name.lower()])
    if len(set(names)) != len(names):
        raise tokens.error("repeated channel", line)
    return tuple(names)


_FRAMES = re.compile(r"^[ \t]*Frames[ \t]*:?[ \t]*(\S+)[ \t]*$", re.IGNORECASE | re.MULTILINE)
_FRAME_TIME = re.compile(r"^\s*Frame\s*Time\s*:?\s*(\S+)\s*$", re.IGNORECASE)


def _header_value(lines: list[str], n: int, pattern: re.Pattern, what: str, base: int, path):
    """The value of the header line ``what`` at or after ``lines[n]`` (blank lines before it
    are skipped: real exporters write them after ``MOTION``). Returns (value, index)."""
    while n < len(lines) and not lines[n].strip():
        n += 1
    if n >= len(lines):
        raise FormatError(path, base + n, f"file ends before '{what}'")
    match = pattern.match(lines[n])
    if not match:
        found = lines[n].strip()
        raise FormatError(path, base + n, f"expected '{what}: <value>', found {found!r}")
    return match.group(1), n


def _parse_motion_header(lines: list[str], base: int, path) -> tuple[int, float, int]:
    """The lines after ``MOTION`` (the first is file line ``base``) -> (frames, frame time in
    seconds, index in ``lines`` of the first line after the header)."""
    raw, n = _header_value(lines, 0, _FRAMES, "Frames", base, path)
    if not raw.isdigit():
        raise FormatError(path, base + n, f"frame count {raw!r} is not a whole number")
    raw_time, n = _header_value(lines, n + 1, _FRAME_TIME, "Frame Time", base, path)
    try:
        frame_time = float(raw_time.replace(",", "."))
    except ValueError:
        raise FormatError(path, base + n, f"frame time {raw_time!r} is not a number") from None
    if not np.isfinite(frame_time) or frame_time <= 0:
        raise FormatError(path, base + n, f"frame time must be positive, got {raw_time!r}")
    if frame_time >= 1.0:  # a few exporters write frames per second here
        log.warning("%s: Frame Time %s read as frames per second", path, raw_time)
        frame_time = 1.0 / frame_time
    return int(raw), frame_time, n + 1


def _parse_numbers(text: str, frames: int, width: int, first_line: int, path) -> np.ndarray:
    """The frame rows -> (frames, width) float64, in one vectorised call when well-formed."""
    if frames == 0:
        if text.strip():
            raise FormatError(path, first_line, "data after 'Frames: 0'")
        return np.zeros((0, width))
    try:
        with warnings.catch_warnings():  # numpy warns (later: raises) on junk; we check below
            warnings.simplefilter("ignore", DeprecationWarning)
            flat = np.fromstring(text, dtype=np.float64, sep=" ")
    except ValueError:
        flat = np.zeros(0)
    if flat.size == frames * width and np.all(np.isfinite(flat)):
        return flat.reshape(frames, width)
    _locate_bad_row(text, frames, width, first_line, path)  # raises with the exact line
    raise FormatError(path, first_line, "malformed motion data")  # pragma: no cover


def _locate_bad_row(text: str, frames: int, width: int, first_line: int, path) -> None:
    """Slow path, only for broken files: find the first bad row and say what is wrong."""
    rows = [(first_line + i, r) for i, r in enumerate(text.split("\n")) if r.strip()]
    for n, (line, row) in enumerate(rows):
        parts = row.split()
        if n >= frames:
            raise FormatError(path, line, f"more rows than 'Frames: {frames}'")
        if len(parts) != width:
            raise FormatError(path, line, f"frame {n} has {len(parts)} values, expected {width}")
        for p in parts:
            try:
                value = float(p)
            except ValueError:
                raise FormatError(path, line, f"frame {n}: {p!r} is not a number") from None
            if not np.isfinite(value):
                raise FormatError(path, line, f"frame {n}: value {p!r} is not finite")
    last = rows[-1][0] if rows else first_line
    raise FormatError(path, last, f"file has {len(rows)} frames, header says {frames} (truncated)")


def loads(text: str, path: str | os.PathLike[str] | None = None) -> BvhData:
    """Parse BVH text into ``BvhData``; raises ``FormatError(path, line, ...)`` on bad input."""
    path = str(path) if path is not None else None
    text = text.replace("\r\n", "\n").replace("\r", "\n")
    match = re.search(r"^[ \t]*MOTION[ \t]*$", text, re.MULTILINE | re.IGNORECASE)
    if match is None:
        raise FormatError(path, 0, "no MOTION section")
    head = text[: match.start()].split("\n")
    tokens = _Tokens(head, path)
    h = _parse_hierarchy(tokens)
    if tokens.pos != len(tokens.items):
        raise tokens.error(f"unexpected {tokens.items[tokens.pos][0]!r} after the hierarchy")
    motion_line = len(head)  # 1-based line number of "MOTION"
    lines = text[match.end() :].split("\n")[1:]
    frames, frame_time, first = _parse_motion_header(lines, motion_line + 1, path)
    width = sum(len(c) for c in h["channels"])
    data = "\n".join(lines[first:])
    motion = _parse_numbers(data, frames, width, motion_line + 1 + first, path)
    return BvhData(
        names=tuple(h["names"]),
        parents=np.array(h["parents"], dtype=np.int32),
        offsets=np.array(h["offsets"], dtype=np.float64).reshape(-1, 3),
        channels=tuple(h["channels"]),
        end_sites=np.array(h["ends"], dtype=np.float64).reshape(-1, 3),
        motion=motion,
        frame_time=frame_time,
    )


def read(path: str | os.PathLike[str]) -> BvhData:
    """Read a BVH file (UTF-8, Latin-1 tolerated)."""
    raw = Path(path).read_bytes()
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError:
        text = raw.decode("latin-1")
    return loads(text, path)


# ----------------------------------------------------------------------------- writing


def dumps(data: BvhData, precision: int = 6) -> str:
    """``BvhData`` -> BVH text (tabs for indentation, ``precision`` decimals)."""
    out = io.StringIO()
    out.write("HIERARCHY\n")
    children: list[list[int]] = [[] for _ in data.names]
    for j, p in enumerate(data.parents):
        if p >= 0:
            children[p].append(j)
    order: list[int] = []  # joints in the order the hierarchy lists them (depth first)
    for root in np.flatnonzero(data.parents < 0):
        _write_joint(out, data, children, int(root), 0, precision, order)
    out.write(f"MOTION\nFrames: {data.frames}\nFrame Time: {data.frame_time:.8g}\n")
    if data.motion.size:
        # Columns follow the hierarchy's order, which differs from the joints' own order
        # when a parent's later children come after other joints (Avatar's rigs).
        starts = data.channel_starts()
        cols = [starts[j] + k for j in order for k in range(len(data.channels[j]))]
        np.savetxt(out, data.motion[:, cols], fmt=f"%.{precision}f", delimiter=" ")
    return out.getvalue()


def _write_joint(out, data: BvhData, children, j: int, depth: int, precision: int,
                 order: list[int]) -> None:  # fmt: skip
    order.append(j)
    pad, fmt = "\t" * depth, f"%.{precision}f"
    kind = "ROOT" if data.parents[j] < 0 else "JOINT"
    offset = " ".join(fmt % v for v in data.offsets[j])
    chans = data.channels[j]
    out.write(f"{pad}{kind} {data.names[j]}\n{pad}{{\n{pad}\tOFFSET {offset}\n")
    out.write(f"{pad}\tCHANNELS {len(chans)}{''.join(' ' + c for c in chans)}\n")
    for c in children[j]:
        _write_joint(out, data, children, c, depth + 1, precision, order)
    if not np.isnan(data.end_sites[j, 0]):
        end = " ".join(fmt % v for v in data.end_sites[j])
        out.write(f"{pad}\tEnd Site\n{pad}\t{{\n{pad}\t\tOFFSET {end}\n{pad}\t}}\n")
    out.write(f"{pad}}}\n")


def write(path: str | os.PathLike[str], data: BvhData, precision: int = 6) -> None:
    """Write ``data`` as a BVH file (atomically: a temporary file renamed into place)."""
    atomic.write_text(path, dumps(data, precision))


# ----------------------------------------------------------------------------- conversion

_AXES = {"x": 0, "y": 1, "z": 2}


def up_rotation(up: str) -> np.ndarray:
    """(3, 3) rotation taking a file's up axis ("y", "-y", "z", "x", ...) to Avatar's +Z.

    "y" gives Blender's own BVH convention (x, y, z) -> (x, -z, y): a Y-up file facing +Z
    ends up facing -Y, Avatar's forward.
    """
    key = up.lower().strip()
    sign = -1.0 if key.startswith("-") else 1.0
    if key.lstrip("+-") not in _AXES:
        raise ParameterError(f"up axis must be one of x, y, z (optionally signed), got {up!r}")
    axis = np.zeros(3)
    axis[_AXES[key.lstrip("+-")]] = sign
    z = np.array([0.0, 0.0, 1.0])
    if np.allclose(axis, z):
        return np.eye(3)
    if np.allclose(axis, -z):
        return np.diag([1.0, -1.0, -1.0])
    turn = np.cross(axis, z)
    return quaternion.to_matrix(quaternion.from_axis_angle(turn, np.pi / 2))


def _euler_columns(data: BvhData) -> tuple[dict[str, list[int]], dict[str, list[int]]]:
    """Group joints with exactly three rotation channels by order: order -> joints, columns."""
    starts = data.channel_starts()
    joints: dict[str, list[int]] = {}
    cols: dict[str, list[int]] = {}
    for j, chans in enumerate(data.channels):
        rot = [(k, c[0]) for k, c in enumerate(chans) if c.endswith("rotation")]
        if not rot:
            continue
        order = "".join(axis for _, axis in rot)
        joints.setdefault(order, []).append(j)
        cols.setdefault(order, []).extend(int(starts[j]) + k for k, _ in rot)
    return joints, cols


def local_rotations(data: BvhData) -> np.ndarray:
    """(T, J, 4) local joint rotations in file axes: channels "Z Y X" give R = Rz @ Ry @ Rx."""
    q = np.zeros((data.frames, len(data.names), 4))
    q[..., 0] = 1.0
    joints, cols = _euler_columns(data)
    for order, js in joints.items():
        angles = np.radians(data.motion[:, cols[order]]).reshape(data.frames, len(js), len(order))
        if len(order) == 3:
            # from_euler's order lists the innermost rotation first: reverse the channels.
            q[:, js] = quaternion.from_euler(angles[..., ::-1], order[::-1])
            continue
        for k, axis in enumerate(order):  # 1 or 2 rotation channels: compose one by one
            unit = np.zeros(3)
            unit[_AXES[axis.lower()]] = 1.0
            step = quaternion.from_axis_angle(np.broadcast_to(unit, angles.shape[:-1] + (3,)),
                                              angles[..., k])  # fmt: skip
            q[:, js] = quaternion.multiply(q[:, js], step)
    return q


def _position_mode(values: np.ndarray, offset: np.ndarray) -> str:
    """Whether a joint's position channels hold absolute offsets or deltas from OFFSET."""
    if not np.any(offset):
        return "absolute"  # both readings agree
    to_offset = np.median(np.linalg.norm(values - offset, axis=-1))
    to_zero = np.median(np.linalg.norm(values, axis=-1))
    return "absolute" if to_offset < to_zero else "delta"


def local_translations(data: BvhData, positions: str = "auto") -> np.ndarray:
    """(T, J, 3) joint positions in the parent's frame (file units), position channels applied.

    positions: "absolute" (channels replace OFFSET, Blender's reading), "delta" (channels add
    to OFFSET) or "auto" (per joint, whichever the values sit closer to; roots read absolute).
    """
    if positions not in ("auto", "absolute", "delta"):
        raise ParameterError(f"positions must be auto, absolute or delta, got {positions!r}")
    out = np.broadcast_to(data.offsets, (data.frames,) + data.offsets.shape).copy()
    starts = data.channel_starts()
    for j, chans in enumerate(data.channels):
        pos = [k for k, c in enumerate(chans) if c.endswith("position")]
        if not pos:
            continue
        values = out[:, j].copy()
        for k in pos:
            values[:, _AXES[chans[k][0].lower()]] = data.motion[:, starts[j] + k]
        mode = positions
        if mode == "auto":
            mode = "absolute" if data.parents[j] < 0 else _position_mode(values, data.offsets[j])
        if mode == "delta":
            values = data.offsets[j] + (values - np.where(_mask(pos, chans), 0, data.offsets[j]))
        out[:, j] = values
    return out


def _mask(pos: list[int], chans: tuple[str, ...]) -> np.ndarray:
    """(3,) True on the axes that have a position channel."""
    m = np.zeros(3, dtype=bool)
    for k in pos:
        m[_AXES[chans[k][0].lower()]] = True
    return m


def world_positions(data: BvhData, frames: np.ndarray | None = None,
                    positions: str = "auto") -> np.ndarray:  # fmt: skip
    """(S, J, 3) joint positions in file units and axes at ``frames`` (all when None)."""
    rot = quaternion.to_matrix(local_rotations(data))
    trans = local_translations(data, positions)
    if frames is not None:
        rot, trans = rot[frames], trans[frames]
    world_r = np.empty_like(rot)
    world_p = np.empty_like(trans)
    for j, p in enumerate(data.parents):
        if p < 0:
            world_r[:, j], world_p[:, j] = rot[:, j], trans[:, j]
        else:
            world_r[:, j] = world_r[:, p] @ rot[:, j]
            world_p[:, j] = world_p[:, p] + np.einsum("sab,sb->sa", world_r[:, p], trans[:, j])
    return world_p


def _sample(data: BvhData, count: int = 32) -> np.ndarray:
    return np.unique(np.linspace(0, max(data.frames - 1, 0), count).astype(int))


def _named(data: BvhData, words: tuple[str, ...], avoid: tuple[str, ...] = ()) -> list[int]:
    """Joints whose prefix-free, lower-case name ends with one of ``words``."""
    out = []
    for j, name in enumerate(data.names):
        key = re.sub(r"[^a-z]", "", name.rsplit(":", 1)[-1].lower())
        if key.endswith(words) and not any(a in key for a in avoid):
            out.append(j)
    return out


def _head_and_feet(data: BvhData) -> tuple[int, list[int]] | None:
    """The head joint and the feet: by name, else from the hierarchy (``topology``)."""
    heads = _named(data, ("head",), ("fore", "end", "top"))
    feet = _named(data, ("foot", "footl", "footr", "ankle", "anklel", "ankler"))
    if heads and len(feet) >= 2:
        return heads[0], feet
    poses = world_positions(data, _sample(data, 16)) if data.frames else None
    roles = topology.upright_roles(data.parents, data.offsets, poses)
    if roles is None:
        return None
    return roles["head"], [roles["foot.L"], roles["foot.R"]]


def _rest_positions(data: BvhData) -> np.ndarray:
    """(J, 3) joint positions with every channel at zero (OFFSETs summed)."""
    out = data.offsets.copy()
    for j, p in enumerate(data.parents):
        if p >= 0:
            out[j] += out[p]
    return out


def _path_length(data: BvhData, a: int, b: int) -> float:
    """Length along the bones between joints a and b (pose independent, file units)."""

    def chain(j: int) -> list[int]:
        out = [j]
        while data.parents[out[-1]] >= 0:
            out.append(int(data.parents[out[-1]]))
        return out

    ca, cb = chain(a), chain(b)
    common = set(ca) & set(cb)
    bones = [j for j in ca + cb if j not in common]
    return float(np.linalg.norm(data.offsets[bones], axis=-1).sum())


def detect_up(data: BvhData) -> str:
    """The file's up axis as the signed axis closest to feet -> head over the clip (head
    and feet by name, else from the hierarchy); failing both, the axis the figure spans
    most, signed so that most joints sit above the root."""
    found = _head_and_feet(data)
    if found is not None:
        head, feet = found
        rest = _rest_positions(data)
        v = rest[head] - rest[feet].mean(axis=0)
        # A straight rest (T/A-pose) says it best; a folded rest (Reallusion's) does not,
        # then the clip's median pose does.
        if np.linalg.norm(v) < 0.6 * _path_length(data, head, feet[0]) and data.frames:
            pts = world_positions(data, _sample(data))
            v = np.median(pts[:, head] - pts[:, feet].mean(axis=1), axis=0)
        axis = int(np.argmax(np.abs(v)))
        return ("-" if v[axis] < 0 else "") + "xyz"[axis]
    if data.frames == 0:
        return "y"
    pts = world_positions(data, _sample(data))
    extent = np.median(pts.max(axis=1) - pts.min(axis=1), axis=0)
    axis = int(np.argmax(extent))
    above = np.median(np.sum(np.sign(pts[:, :, axis] - pts[:, :1, axis]), axis=1))
    return ("-" if above < 0 else "") + "xyz"[axis]


_FOOT_TO_HEAD = 1.45  # metres along the bones from an ankle to the head joint, adult


def detect_unit(data: BvhData, up: str) -> str:
    """The unit name in ``UNITS`` that makes the figure closest to an adult human's size:
    the bone path from a foot to the head (any pose), else the height spanned along up."""
    if data.frames == 0 and _head_and_feet(data) is None:
        return "cm"
    found = _head_and_feet(data)
    if found is not None:
        size, ref = _path_length(data, found[0], found[1][0]), _FOOT_TO_HEAD
    else:
        axis = _AXES[up.lstrip("+-").lower()]
        pts = world_positions(data, _sample(data))[:, :, axis]
        size, ref = float(np.median(pts.max(axis=1) - pts.min(axis=1))), _HUMAN_HEIGHT
    size = max(size, 1e-9)
    return min(UNITS, key=lambda u: abs(np.log(size * UNITS[u] / ref)))


def _unit_scale(unit: str | float) -> float:
    if isinstance(unit, int | float):
        return float(unit)
    if unit not in UNITS:
        raise ParameterError(f"unknown unit {unit!r}; use one of {', '.join(UNITS)} or metres")
    return UNITS[unit]


def _tails(heads: np.ndarray, parents: np.ndarray, ends: np.ndarray, height: float) -> np.ndarray:
    """(J, 3) bone tails the way Blender's importer chooses them: End Site, the only child,
    or the children's mean; a bone too short to orient gets a stub pointing up."""
    tails = heads + np.where(np.isnan(ends), 0.0, ends)
    for j in range(len(parents)):
        kids = np.flatnonzero(parents == j)
        if len(kids) and np.isnan(ends[j, 0]):
            tails[j] = heads[kids].mean(axis=0)
    short = np.linalg.norm(tails - heads, axis=-1) < 1e-3 * height
    tails[short] = heads[short] + np.array([0.0, 0.0, 0.02 * height])
    return tails


def _conjugate_by(r: np.ndarray, q: np.ndarray) -> np.ndarray:
    """r^-1 * q * r for quaternions r (..., 4) broadcast against q (..., 4)."""
    return quaternion.multiply(quaternion.multiply(quaternion.conjugate(r), q), r)


def to_animation(data: BvhData, unit: str | float = "auto", up: str = "auto",
                 positions: str = "auto") -> tuple[Skeleton, Animation]:  # fmt: skip
    """Convert file content to Avatar's ``Skeleton`` and ``Animation`` (metres, Z-up).

    unit: a name in ``UNITS``, metres per file unit, or "auto" (closest to a 1.7 m human).
    up: the file's up axis ("y", "z", "-y", ...) or "auto".
    positions: how position channels on joints are read, see ``local_translations``.
    The skeleton's bones run from each joint to its child (Blender's importer convention,
    roll 0); the animation's rotations are relative to those bone frames.
    """
    up = detect_up(data) if up == "auto" else up
    unit = detect_unit(data, up) if unit == "auto" else unit
    c, s = up_rotation(up), _unit_scale(unit)
    offsets = data.offsets @ c.T * s
    heads = offsets.copy()
    for j, p in enumerate(data.parents):
        if p >= 0:
            heads[j] += heads[p]
    height = float(np.ptp(heads[:, 2])) or 1.0
    tails = _tails(heads, data.parents, data.end_sites @ c.T * s, height)
    rest = _rest(heads, tails)
    r0 = quaternion.from_matrix(rest[:, :3, :3])
    cq = quaternion.from_matrix(c)
    local = _conjugate_by(quaternion.conjugate(cq), local_rotations(data))  # c q c^-1
    rotations = _conjugate_by(r0, local)
    delta = local_translations(data, positions) @ c.T * s - offsets
    translations = np.einsum("jba,tjb->tja", rest[:, :3, :3], delta)  # R0^T delta
    translations[np.abs(translations) < 1e-12] = 0.0
    extra: dict[str, object] = {"bvh_unit": unit, "bvh_up": up}
    skeleton = Skeleton(data.names, data.parents.copy(), rest, tails, extra)
    return skeleton, Animation(rotations, translations, data.fps, data.names)


def _rest(heads: np.ndarray, tails: np.ndarray) -> np.ndarray:
    return rest_matrices(heads, tails, np.zeros(len(heads)))  # Blender's importer: roll 0


def from_animation(skeleton: Skeleton, animation: Animation, unit: str | float = "cm",
                   up: str = "y", order: str = "ZYX") -> BvhData:  # fmt: skip
    """Avatar ``Skeleton``/``Animation`` -> ``BvhData`` in ``unit`` and ``up`` axes.

    order: rotation channels as listed in the file ("ZYX" writes ``Zrotation Yrotation
    Xrotation``). Roots, and joints with non-zero translations, get six channels holding
    absolute positions.
    """
    order = order.upper()
    if sorted(order) != ["X", "Y", "Z"]:
        raise ParameterError(f"order must be a permutation of XYZ, got {order!r}")
    c, s = up_rotation(up), _unit_scale(unit)
    names, parents = skeleton.names, skeleton.parents
    heads = skeleton.heads
    offsets = heads - np.where(parents[:, None] >= 0, heads[np.maximum(parents, 0)], 0.0)
    r0 = quaternion.from_matrix(skeleton.rest[:, :3, :3])
    cq = quaternion.from_matrix(c)
    local = _conjugate_by(cq, _conjugate_by(quaternion.conjugate(r0), animation.rotations))
    angles = np.degrees(quaternion.to_euler(local, order[::-1])[..., ::-1])
    moves = np.einsum("jab,tjb->tja", skeleton.rest[:, :3, :3], animation.translations)
    has_pos = (parents < 0) | np.any(np.abs(moves) > 1e-9, axis=(0, 2))
    channels, columns = [], []
    for j in range(len(names)):
        rot = tuple(f"{a}rotation" for a in order)
        if has_pos[j]:
            channels.append(("Xposition", "Yposition", "Zposition") + rot)
            columns.append((offsets[j] + moves[:, j]) @ c / s)
        else:
            channels.append(rot)
        columns.append(angles[:, j])
    kids = np.zeros(len(names), dtype=bool)
    kids[parents[parents >= 0]] = True
    ends = np.where(kids[:, None], np.nan, (skeleton.tails - heads) @ c / s)
    return BvhData(tuple(names), parents.astype(np.int32), offsets @ c / s, tuple(channels),
                   ends, np.concatenate(columns, axis=1), 1.0 / animation.fps)  # fmt: skip


def load(path: str | os.PathLike[str], unit: str | float = "auto", up: str = "auto",
         positions: str = "auto") -> tuple[Skeleton, Animation]:  # fmt: skip
    """Read a BVH file as Avatar ``Skeleton`` and ``Animation``; see ``to_animation``.

    Raises FormatError for a file with ``Frames: 0`` (a hierarchy without motion is a valid
    file for ``read``, but not a clip: there is no frame to load, pose or retarget).
    """
    data = read(path)
    if data.frames == 0:
        raise FormatError(path, _frames_line(path), "'Frames: 0': the file has no motion "
                          "to load (a clip needs at least one frame)")  # fmt: skip
    return to_animation(data, unit, up, positions)


def _frames_line(path: str | os.PathLike[str]) -> int:
    """1-based line number of the ``Frames:`` header (0 when not found)."""
    text = Path(path).read_bytes().decode("latin-1")
    motion = re.search(r"^[ \t]*MOTION[ \t]*$", text, re.MULTILINE | re.IGNORECASE)
    found = _FRAMES.search(text, motion.end() if motion else 0) if motion else None
    return text.count("\n", 0, found.start()) + 1 if found else 0


def save(path: str | os.PathLike[str], skeleton: Skeleton, animation: Animation,
         unit: str | float = "cm", up: str = "y", order: str = "ZYX") -> None:  # fmt: skip
    """Write an Avatar ``Skeleton``/``Animation`` as a BVH file; see ``from_animation``."""
    write(path, from_animation(skeleton, animation, unit, up, order))
