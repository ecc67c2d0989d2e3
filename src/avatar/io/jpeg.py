"""Baseline JPEG reader (ITU-T T.81), enough for MakeHuman's texture masks and skins.

MakeHuman ships its region masks as baseline JPEGs and Avatar does not depend on Pillow, so
this module decodes sequential-DCT Huffman JPEGs: greyscale or YCbCr (JFIF), any chroma
subsampling, restart intervals. Progressive and arithmetic-coded files raise FormatError.
Huffman decoding is plain Python (mostly-empty mask blocks decode fast); dequantisation,
the inverse DCT and colour conversion are vectorised.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field

import numpy as np

from avatar.errors import FormatError

# Zig-zag order: position k of the coded sequence -> row-major index in the 8x8 block.
ZIGZAG = np.array(
    [0, 1, 8, 16, 9, 2, 3, 10, 17, 24, 32, 25, 18, 11, 4, 5, 12, 19, 26, 33, 40, 48, 41, 34,
     27, 20, 13, 6, 7, 14, 21, 28, 35, 42, 49, 56, 57, 50, 43, 36, 29, 22, 15, 23, 30, 37, 44,
     51, 58, 59, 52, 45, 38, 31, 39, 46, 53, 60, 61, 54, 47, 55, 62, 63]
)  # fmt: skip

# Progressive, lossless and arithmetic-coded frames (T.81 table B.1).
UNSUPPORTED_SOF = {0xC2, 0xC3, 0xC5, 0xC6, 0xC7, 0xC9, 0xCA, 0xCB, 0xCD, 0xCE, 0xCF}


@dataclass
class _Component:
    ident: int
    h: int
    v: int
    quant: int
    dc_table: int = 0
    ac_table: int = 0
    blocks: list = field(default_factory=list)


@dataclass
class _Frame:
    height: int = 0
    width: int = 0
    components: list[_Component] = field(default_factory=list)
    quant: dict[int, np.ndarray] = field(default_factory=dict)
    huffman: dict[tuple[int, int], tuple[list[int], list[int]]] = field(default_factory=dict)
    restart: int = 0


def read(path: str | os.PathLike[str]) -> np.ndarray:
    """Decode a baseline JPEG file -> (H, W) uint8 greyscale or (H, W, 3) uint8 RGB."""
    with open(path, "rb") as f:
        data = f.read()
    return decode(data, path)


def decode(data: bytes, path: str | os.PathLike[str] | None = None) -> np.ndarray:
    """Decode baseline JPEG bytes; see ``read``."""
    try:
        frame, scan_start = _parse_headers(data, path)
        _decode_scan(data, scan_start, frame)
    except (IndexError, KeyError, ValueError) as exc:
        raise FormatError(path, 0, f"corrupt JPEG data ({exc})") from None
    return _assemble(frame)


def _parse_headers(data: bytes, path) -> tuple[_Frame, int]:
    """Read markers up to the first scan; return the frame and the entropy data offset."""
    if data[:2] != b"\xff\xd8":
        raise FormatError(path, 0, "not a JPEG file (no SOI marker)")
    frame, pos = _Frame(), 2
    while pos < len(data):
        if data[pos] != 0xFF:
            raise FormatError(path, 0, f"expected a marker at byte {pos}")
        marker = data[pos + 1]
        if marker == 0xFF:  # fill byte
            pos += 1
            continue
        length = int.from_bytes(data[pos + 2 : pos + 4], "big")
        body = data[pos + 4 : pos + 2 + length]
        if marker in UNSUPPORTED_SOF:
            raise FormatError(
                path,
                0,
                f"unsupported JPEG coding (SOF{marker - 0xC0}); only baseline and "
                "extended sequential Huffman JPEGs are read",
            )
        if marker == 0xDB:
            _read_dqt(body, frame)
        elif marker == 0xC4:
            _read_dht(body, frame)
        elif marker in (0xC0, 0xC1):
            _read_sof(body, frame)
        elif marker == 0xDD:
            frame.restart = int.from_bytes(body[:2], "big")
        elif marker == 0xDA:
            _read_sos(body, frame)
            return frame, pos + 2 + length
        pos += 2 + length
    raise FormatError(path, 0, "no image data (missing SOS marker)")


def _read_dqt(body: bytes, frame: _Frame) -> None:
    i = 0
    while i < len(body):
        precision, ident = body[i] >> 4, body[i] & 15
        n = 128 if precision else 64
        raw = np.frombuffer(body[i + 1 : i + 1 + n], dtype=">u2" if precision else np.uint8)
        table = np.zeros(64, dtype=np.float32)
        table[ZIGZAG] = raw  # stored in zig-zag order
        frame.quant[ident] = table
        i += 1 + n


def _read_dht(body: bytes, frame: _Frame) -> None:
    i = 0
    while i < len(body):
        cls, ident = body[i] >> 4, body[i] & 15
        counts = list(body[i + 1 : i + 17])
        symbols = list(body[i + 17 : i + 17 + sum(counts)])
        frame.huffman[(cls, ident)] = _lookup_table(counts, symbols)
        i += 17 + sum(counts)


def _lookup_table(counts: list[int], symbols: list[int]) -> tuple[list[int], list[int]]:
    """16-bit peek -> (symbol, code length) tables; canonical Huffman codes (T.81 C.2)."""
    sym = [0] * 65536
    length = [0] * 65536
    code, k = 0, 0
    for bits in range(1, 17):
        for _ in range(counts[bits - 1]):
            lo = code << (16 - bits)
            hi = lo + (1 << (16 - bits))
            sym[lo:hi] = [symbols[k]] * (hi - lo)
            length[lo:hi] = [bits] * (hi - lo)
            code, k = code + 1, k + 1
        code <<= 1
    return sym, length


def _read_sof(body: bytes, frame: _Frame) -> None:
    frame.height = int.from_bytes(body[1:3], "big")
    frame.width = int.from_bytes(body[3:5], "big")
    for c in range(body[5]):
        ident, hv, quant = body[6 + 3 * c : 9 + 3 * c]
        frame.components.append(_Component(ident, hv >> 4, hv & 15, quant))


def _read_sos(body: bytes, frame: _Frame) -> None:
    by_id = {c.ident: c for c in frame.components}
    if body[0] != len(frame.components):
        raise ValueError("non-interleaved multi-scan files are not supported")
    for s in range(body[0]):
        comp = by_id[body[1 + 2 * s]]
        comp.dc_table, comp.ac_table = body[2 + 2 * s] >> 4, body[2 + 2 * s] & 15


def _entropy_segments(data: bytes, start: int) -> list[bytes]:
    """Unstuffed entropy-coded segments between restart markers, up to EOI."""
    end = data.find(b"\xff\xd9", start)
    raw = data[start : end if end >= 0 else len(data)]
    for rst in range(0xD0, 0xD8):  # normalise every RSTn to one separator
        raw = raw.replace(bytes([0xFF, rst]), b"\xff\x01")
    return [piece.replace(b"\xff\x00", b"\xff") for piece in raw.split(b"\xff\x01")]


class _Bits:
    """MSB-first bit reader over one entropy segment, peeking 16 bits at a time."""

    def __init__(self, segment: bytes):
        padded = np.frombuffer(segment + b"\x00\x00\x00\x00", dtype=np.uint8).astype(np.uint32)
        # window[i] = bytes i..i+3 as one big-endian word, so any 16-bit peek is one lookup.
        self.window = (
            (padded[:-3] << 24) | (padded[1:-2] << 16) | (padded[2:-1] << 8) | padded[3:]
        ).tolist()
        self.pos = 0

    def peek16(self) -> int:
        pos = self.pos
        return (self.window[pos >> 3] >> (16 - (pos & 7))) & 0xFFFF

    def receive(self, n: int) -> int:
        """Read n bits and sign-extend them as T.81's EXTEND does."""
        if n == 0:
            return 0
        pos = self.pos
        value = (self.window[pos >> 3] >> (32 - (pos & 7) - n)) & ((1 << n) - 1)
        self.pos = pos + n
        return value if value >= 1 << (n - 1) else value - (1 << n) + 1


def _decode_scan(data: bytes, start: int, frame: _Frame) -> None:
    """Huffman-decode every block of every component into comp.blocks (zig-zag lists)."""
    hmax = max(c.h for c in frame.components)
    vmax = max(c.v for c in frame.components)
    single = len(frame.components) == 1
    comps = frame.components
    if single:  # a lone component is coded block by block, whatever its sampling factors
        comps[0].h = comps[0].v = hmax = vmax = 1
    mcus_x = -(-frame.width // (8 * hmax))
    mcus_y = -(-frame.height // (8 * vmax))
    total = mcus_x * mcus_y
    per_segment = frame.restart or total
    segments = _entropy_segments(data, start)
    for c in comps:
        c.blocks = []
    for m0 in range(0, total, per_segment):
        bits = _Bits(segments[m0 // per_segment])
        preds = [0] * len(comps)
        for _ in range(min(per_segment, total - m0)):
            for ci, c in enumerate(comps):
                dc = frame.huffman[(0, c.dc_table)]
                ac = frame.huffman[(1, c.ac_table)]
                for _ in range(c.h * c.v):
                    block = _decode_block(bits, dc, ac, preds[ci])
                    preds[ci] = block[0]
                    c.blocks.append(block)


def _decode_block(bits: _Bits, dc, ac, pred: int) -> list[int]:
    """One 8x8 block's 64 coefficients in zig-zag order (T.81 F.2.2)."""
    coef = [0] * 64
    peek = bits.peek16()
    s = dc[0][peek]
    bits.pos += dc[1][peek]
    coef[0] = pred + bits.receive(s)
    sym_table, len_table = ac
    k = 1
    while k < 64:
        peek = bits.peek16()
        rs = sym_table[peek]
        bits.pos += len_table[peek]
        r, s = rs >> 4, rs & 15
        if s == 0:
            if r != 15:
                break  # end of block
            k += 16
            continue
        k += r
        coef[k] = bits.receive(s)
        k += 1
    return coef


def _idct_matrix() -> np.ndarray:
    """(8, 8) orthonormal DCT-II basis C, so that block = C.T @ coefficients @ C."""
    n = np.arange(8)
    c = np.cos((2 * n[None, :] + 1) * n[:, None] * np.pi / 16) * np.sqrt(2 / 8)
    c[0] /= np.sqrt(2)
    return c


def _assemble(frame: _Frame) -> np.ndarray:
    """Dequantise, inverse-DCT and tile every component, then convert to RGB."""
    hmax = max(c.h for c in frame.components)
    vmax = max(c.v for c in frame.components)
    mcus_x = -(-frame.width // (8 * hmax))
    mcus_y = -(-frame.height // (8 * vmax))
    idct = _idct_matrix().astype(np.float32)
    planes = []
    for c in frame.components:
        coef = np.asarray(c.blocks, dtype=np.float32)
        natural = np.zeros_like(coef)
        natural[:, ZIGZAG] = coef * frame.quant[c.quant][ZIGZAG]
        pixels = idct.T @ natural.reshape(-1, 8, 8) @ idct + 128.0
        # Blocks arrive MCU by MCU, each MCU holding v rows of h blocks.
        tiles = pixels.reshape(mcus_y, mcus_x, c.v, c.h, 8, 8)
        plane = tiles.transpose(0, 2, 4, 1, 3, 5).reshape(mcus_y * c.v * 8, mcus_x * c.h * 8)
        plane = plane.repeat(vmax // c.v, axis=0).repeat(hmax // c.h, axis=1)
        planes.append(plane[: frame.height, : frame.width])
    if len(planes) == 1:
        return np.clip(np.rint(planes[0]), 0, 255).astype(np.uint8)
    return _ycbcr_to_rgb(*planes[:3])


def _ycbcr_to_rgb(y: np.ndarray, cb: np.ndarray, cr: np.ndarray) -> np.ndarray:
    """JFIF YCbCr planes -> (H, W, 3) uint8 RGB."""
    cb, cr = cb - 128.0, cr - 128.0
    rgb = np.stack([y + 1.402 * cr, y - 0.344136 * cb - 0.714136 * cr, y + 1.772 * cb], -1)
    return np.clip(np.rint(rgb), 0, 255).astype(np.uint8)
