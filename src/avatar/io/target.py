"""MakeHuman ``.target`` files: sparse vertex offsets, ``index dx dy dz`` per line.

Offsets are in decimetres, Y-up (MakeHuman's frame); ``parse``/``read`` return them in
Avatar's frame (metres, Z-up) as ``(x, -z, y) * 0.1``, converted here and nowhere else.
"""

from __future__ import annotations

import gzip
from pathlib import Path

import numpy as np

from avatar.errors import FormatError


def loads(text: str, path: str | Path) -> tuple[np.ndarray, np.ndarray]:
    """Parse MakeHuman ``.target`` text (``index dx dy dz`` lines, dm, Y-up).

    Returns (index (n,) int32, delta (n, 3) float32 in Avatar's frame: metres, Z-up).
    """
    rows: list[str] = []
    for lineno, line in enumerate(text.splitlines(), 1):
        s = line.strip()
        if not s or s.startswith("#"):
            continue
        fields = s.split()
        if len(fields) != 4:
            raise FormatError(path, lineno, f"expected 'index dx dy dz', got {s[:60]!r}")
        rows.append(s)
    if not rows:
        return np.zeros(0, np.int32), np.zeros((0, 3), np.float32)
    try:
        table = np.array(" ".join(rows).split(), dtype=np.float64).reshape(-1, 4)
    except ValueError:
        for lineno, line in enumerate(text.splitlines(), 1):
            s = line.strip()
            if s and not s.startswith("#"):
                try:
                    [float(x) for x in s.split()]
                except ValueError:
                    raise FormatError(path, lineno, f"non-numeric value in {s[:60]!r}") from None
        raise
    index = table[:, 0]
    bad = ~np.isfinite(table).all(axis=1) | (index < 0) | (index != np.round(index))
    if bad.any():
        bad_line = _data_line(text, int(np.argmax(bad)))
        raise FormatError(path, bad_line, "bad index or non-finite offset")
    d = table[:, 1:]
    delta = np.stack([d[:, 0], -d[:, 2], d[:, 1]], axis=1) * 0.1
    return table[:, 0].astype(np.int32), delta.astype(np.float32)


def _data_line(text: str, k: int) -> int:
    """1-based line number of the k-th data line."""
    seen = -1
    for lineno, line in enumerate(text.splitlines(), 1):
        s = line.strip()
        if s and not s.startswith("#"):
            seen += 1
            if seen == k:
                return lineno
    return 0


def read(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """Read a ``.target`` or ``.target.gz`` file (see ``loads``)."""
    try:
        raw = gzip.decompress(path.read_bytes()) if path.suffix == ".gz" else path.read_bytes()
    except (OSError, EOFError, gzip.BadGzipFile) as exc:
        raise FormatError(path, 0, f"cannot read target: {exc}") from None
    return loads(raw.decode("utf-8", errors="replace"), path)
