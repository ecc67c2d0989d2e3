"""Atomic file writes: the one way every writer in ``avatar.io`` puts a file on disk.

Each file is written to a temporary name beside its destination (same folder, so the final
``os.replace`` is an atomic rename within one filesystem) and renamed into place only once
every file of the write succeeded. If anything raises, the temporary files are removed and
the exception propagates: an existing destination is left untouched, no partial file remains.

    with atomic.replacing(path) as tmp:          # one file, written by any code
        image.save(tmp)
    atomic.write_text(path, text)                # the common case
    atomic.write_all({bin_path: write_bin,       # several files committed together
                      gltf_path: write_gltf})
"""

from __future__ import annotations

import contextlib
import os
import secrets
from collections.abc import Callable, Iterator, Mapping, Sequence
from pathlib import Path

StrPath = str | os.PathLike[str]


@contextlib.contextmanager
def _staged(paths: Sequence[Path]) -> Iterator[list[Path]]:
    """Temporary paths beside ``paths``; renamed onto them, in order, on a clean exit and
    removed in every case. (Each rename is atomic; several files are committed together in
    that nothing is replaced unless every file was written.)"""
    token = f"{os.getpid()}.{secrets.token_hex(4)}"
    temps = [path.with_name(f".{path.name}.{token}.part") for path in paths]
    try:
        yield temps
        for path, tmp in zip(paths, temps, strict=True):
            os.replace(tmp, path)
    finally:
        for tmp in temps:
            with contextlib.suppress(FileNotFoundError):
                tmp.unlink()


@contextlib.contextmanager
def replacing(path: StrPath) -> Iterator[Path]:
    """Yield a temporary path beside ``path`` to write; on a clean exit it replaces ``path``."""
    with _staged([Path(path)]) as (tmp,):
        yield tmp


def write_all(writers: Mapping[StrPath, Callable[[Path], object]]) -> None:
    """Call each ``write(tmp)`` on a temporary path beside its destination, then rename them
    all into place in the mapping's order: nothing is replaced unless every write returned."""
    with _staged([Path(p) for p in writers]) as temps:
        for tmp, write in zip(temps, writers.values(), strict=True):
            write(tmp)


def write_text(path: StrPath, text: str, encoding: str | None = "utf-8") -> None:
    """``Path(path).write_text(text, encoding)``, atomically."""
    with replacing(path) as tmp:
        tmp.write_text(text, encoding=encoding)


def write_bytes(path: StrPath, data: bytes) -> None:
    """``Path(path).write_bytes(data)``, atomically."""
    with replacing(path) as tmp:
        tmp.write_bytes(data)
