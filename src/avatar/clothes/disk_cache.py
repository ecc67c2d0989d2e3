"""Built garments kept on disk, so processes that build the same garments share one build.

A built-in garment takes 0.1-2.5 s of CPU to build (its cut, shell and 1K/2K maps); a
process keeps what it built in memory (``library``'s lru caches), but every dataset worker
and every recycled worker process starts empty, so two workers built the same garments
twice (+37% dressing CPU over 40 samples, docs/benchmarks.md). With the cache enabled the
first process to build an item writes it here and every later process reads it back
(~10 ms for 7-30 MB).

    disk_cache.enable()    # $AVATAR_GARMENT_CACHE or $AVATAR_CACHE/garments, + /<code>/
    garment = disk_cache.fetch(("builtin", name, 1024, assets), lambda: build(...))

The folder is named by a hash of Avatar's source code, numpy's version and the pickle
format, so a build from other code is never read back; the key names the item, its variant,
its texture size and the MakeHuman assets' fingerprint. A file is written under a temporary
name and renamed, so a reader sees a whole file or none (two workers building the same item
both write the same bytes; the last rename wins). The cache is an optimisation only: an
unreadable file is rebuilt and rewritten, a failed write is logged and the build returned.
Pickles are read only from this folder, which only Avatar writes.
"""

from __future__ import annotations

import hashlib
import logging
import os
import pickle
import shutil
import time
from collections.abc import Callable
from pathlib import Path
from typing import TypeVar

import numpy as np

log = logging.getLogger(__name__)
T = TypeVar("T")
ENV_ROOT = "AVATAR_GARMENT_CACHE"
KEEP_OLD = 2  # other code versions' folders kept (e.g. two checkouts in use); older go
STALE_TMP_S = 600  # s; a temporary file this old was left by a killed writer (a write: ~0.1 s)
_FOLDER: list[Path] = []  # the enabled folder, if any


def enable(root: str | os.PathLike[str] | None = None) -> Path:
    """Keep built garments under ``root`` (default ``$AVATAR_GARMENT_CACHE``, else
    ``$AVATAR_CACHE/garments``, i.e. ``~/.cache/avatar/garments``) in a folder for this
    code; returns that folder. Drops the folders of all but the ``KEEP_OLD`` most recently
    used other code versions."""
    if root is None:
        from avatar.body.assets import cache_root

        root = os.environ.get(ENV_ROOT) or cache_root() / "garments"
    folder = Path(root) / code_fingerprint()
    try:
        folder.mkdir(parents=True, exist_ok=True)
        os.utime(folder)
        _prune(folder)
    except OSError as exc:
        log.warning("garment cache %s unusable (%s); building in memory only", folder, exc)
        disable()
        return folder
    _FOLDER[:] = [folder]
    return folder


def disable() -> None:
    _FOLDER.clear()


def enabled() -> Path | None:
    return _FOLDER[0] if _FOLDER else None


def fetch(key: tuple, build: Callable[[], T]) -> T:
    """The value stored under ``key`` (a tuple of plain values), else ``build()``, stored."""
    if not _FOLDER:
        return build()
    path = _FOLDER[0] / (hashlib.sha256(repr(key).encode()).hexdigest()[:32] + ".pickle")
    try:
        with open(path, "rb") as f:
            return pickle.load(f)
    except FileNotFoundError:
        pass
    except Exception as exc:  # a damaged file (disk trouble): rebuild and rewrite it
        log.warning("garment cache: %s unreadable (%s); rebuilding", path, exc)
    value = build()
    _store(path, value)
    return value


def _store(path: Path, value: object) -> None:
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        with open(tmp, "wb") as f:
            pickle.dump(value, f, protocol=pickle.HIGHEST_PROTOCOL)
        os.replace(tmp, path)
    except OSError as exc:  # full or read-only disk: the build still serves this process
        log.warning("garment cache: could not write %s (%s)", path, exc)
        try:
            tmp.unlink(missing_ok=True)
        except OSError:
            pass


def code_fingerprint() -> str:
    """Hash of every Avatar source file's bytes (not times: fresh clones of one commit
    agree), numpy's version and the pickle protocol."""
    package = Path(__file__).resolve().parents[1]
    h = hashlib.sha256(f"garments-1|{np.__version__}|{pickle.HIGHEST_PROTOCOL}".encode())
    for path in sorted(package.rglob("*.py")):
        h.update(str(path.relative_to(package)).encode())
        h.update(path.read_bytes())
    return h.hexdigest()[:16]


def _prune(current: Path) -> None:
    """Drop old code versions' folders and temporary files a killed writer left behind."""
    now = time.time()
    for tmp in current.glob(".*.tmp"):
        if now - _used(tmp) > STALE_TMP_S:
            tmp.unlink(missing_ok=True)
    others = [p for p in current.parent.iterdir() if p.is_dir() and p != current]
    others.sort(key=_used, reverse=True)
    for old in others[KEEP_OLD:]:
        shutil.rmtree(old, ignore_errors=True)


def _used(path: Path) -> float:
    try:
        return path.stat().st_mtime
    except OSError:  # another process pruned it meanwhile
        return 0.0
