"""A small, strict OSC 1.0 decoder for the receivers (what VMC senders put on the wire).

``decode(datagram)`` -> [(address, arguments)], every message of a packet in order, the
elements of (nested) bundles flattened. Arguments become Python values: ``i`` ``h`` int,
``f`` ``d`` float, ``s`` ``S`` str, ``b`` bytes, ``T`` ``F`` bool, ``N`` None, ``I`` inf,
``t`` int (the raw timetag), ``c`` str, ``r`` ``m`` int, ``[``...``]`` a list.

Why not python-osc's ``OscPacket``: it builds an object per message and per argument and
takes ~1 ms for a VMC frame of 55 bones (57 messages) in Python; this walks the bytes with
precompiled ``struct`` formats, one ``unpack_from`` per message for the usual type tags
(~0.1 ms a frame). python-osc still builds what Avatar sends (``vmc.VmcSender``) and is the
independent implementation the tests and the benchmark talk to.

Anything that is not OSC raises ``OscError`` (one message, no traceback worth keeping):
truncated packets, sizes running past the end, strings without their terminator or not
UTF-8, a message without its type tag comma, an unknown type tag. A whole datagram is
rejected when any element is bad (python-osc skips bad bundle elements): half a frame is
worse than none.
"""

from __future__ import annotations

import struct

BUNDLE = b"#bundle\x00"
_INT = struct.Struct(">i")
_UNPACK_CACHE: dict[str, struct.Struct] = {}
_MAX_DEPTH = 8  # nested bundles deeper than this are garbage, not a sender's frame


class OscError(ValueError):
    """The bytes are not an OSC 1.0 packet."""


def decode(datagram: bytes) -> list[tuple[str, list]]:
    """Every message of an OSC packet (a message or a bundle), in order."""
    out: list[tuple[str, list]] = []
    _packet(bytes(datagram), 0, len(datagram), out, 0)
    return out


def _packet(data: bytes, start: int, end: int, out: list, depth: int) -> None:
    if data.startswith(BUNDLE, start):
        if depth >= _MAX_DEPTH:
            raise OscError("bundles nested too deep")
        at = start + 16  # "#bundle\0" and the 8-byte timetag
        if at > end:
            raise OscError("truncated bundle header")
        while at < end:
            if at + 4 > end:
                raise OscError("truncated bundle element size")
            size = _INT.unpack_from(data, at)[0]
            at += 4
            if size <= 0 or size % 4 or at + size > end:
                raise OscError(f"bad bundle element size {size}")
            _packet(data, at, at + size, out, depth + 1)
            at += size
        return
    out.append(_message(data, start, end))


def _string(data: bytes, at: int, end: int) -> tuple[str, int]:
    """An OSC string at ``at``: (text, offset after its padding)."""
    stop = data.find(b"\x00", at, end)
    if stop < 0:
        raise OscError("unterminated string")
    try:
        text = data[at:stop].decode("utf-8")
    except UnicodeDecodeError:
        raise OscError("string is not UTF-8") from None
    after = (stop + 4) & ~3
    if after > end:
        raise OscError("truncated string padding")
    return text, after


def _message(data: bytes, start: int, end: int) -> tuple[str, list]:
    if data[start : start + 1] != b"/":
        raise OscError("not an OSC message (no address)")
    address, at = _string(data, start, end)
    if at == end:  # OSC 1.0 allows a message without a type tag: no arguments
        return address, []
    if data[at : at + 1] != b",":
        raise OscError("type tag does not start with ','")
    tags, at = _string(data, at, end)
    tags = tags[1:]
    if _FIXED.issuperset(tags):
        return address, _fixed(tags, data, at, end)
    rest = tags.lstrip("s")
    if _FIXED.issuperset(rest):  # strings first, then numbers: VMC's "s fffffff" and kin
        args = []
        for _ in range(len(tags) - len(rest)):
            text, at = _string(data, at, end)
            args.append(text)
        return address, args + _fixed(rest, data, at, end)
    args, at = _general(tags, data, at, end)
    if at != end:
        raise OscError("bytes after the last argument")
    return address, args


# Fixed-size type tags -> struct codes (T F N I take no bytes and are filled in after).
_CODES = {"i": "i", "f": "f", "d": "d", "h": "q", "t": "Q", "c": "i", "r": "I", "m": "I"}
_NO_DATA = {"T": True, "F": False, "N": None, "I": float("inf")}
_FIXED = frozenset(_CODES) | frozenset(_NO_DATA)


def _fixed(tags: str, data: bytes, at: int, end: int) -> list:
    """Arguments of only fixed-size types: one ``unpack_from`` (formats cached per tags)."""
    fmt = _UNPACK_CACHE.get(tags)
    if fmt is None:
        fmt = struct.Struct(">" + "".join(_CODES[c] for c in tags if c not in _NO_DATA))
        if len(_UNPACK_CACHE) < 256:
            _UNPACK_CACHE[tags] = fmt
    if at + fmt.size != end:
        raise OscError("argument bytes do not match the type tags")
    values = list(fmt.unpack_from(data, at))
    if len(values) != len(tags):
        it = iter(values)
        values = [_NO_DATA[c] if c in _NO_DATA else next(it) for c in tags]
    if "c" in tags:
        values = [chr(v) if c == "c" and 0 <= v < 0x110000 else v
                  for c, v in zip(tags, values, strict=True)]  # fmt: skip
    return values


def _general(tags: str, data: bytes, at: int, end: int) -> tuple[list, int]:
    """Arguments of any types (strings, blobs, arrays), one at a time."""
    stack: list[list] = [[]]
    for c in tags:
        args = stack[-1]
        if c in ("s", "S"):
            text, at = _string(data, at, end)
            args.append(text)
        elif c == "b":
            if at + 4 > end:
                raise OscError("truncated blob size")
            size = _INT.unpack_from(data, at)[0]
            stop = at + 4 + size
            if size < 0 or (stop + 3) & ~3 > end:
                raise OscError(f"bad blob size {size}")
            args.append(data[at + 4 : stop])
            at = (stop + 3) & ~3
        elif c in _NO_DATA:
            args.append(_NO_DATA[c])
        elif c == "[":
            stack.append([])
        elif c == "]":
            if len(stack) == 1:
                raise OscError("']' without '['")
            inner = stack.pop()
            stack[-1].append(inner)
        elif c in _CODES:
            fmt = _UNPACK_CACHE.get(c) or struct.Struct(">" + _CODES[c])
            _UNPACK_CACHE.setdefault(c, fmt)
            if at + fmt.size > end:
                raise OscError("truncated argument")
            value = fmt.unpack_from(data, at)[0]
            args.append(chr(value) if c == "c" and 0 <= value < 0x110000 else value)
            at += fmt.size
        else:
            raise OscError(f"unknown type tag {c!r}")
    if len(stack) != 1:
        raise OscError("'[' without ']'")
    return stack[0], at
