"""Folders of BVH clips: what each holds, and which ones cannot be used.

    entries = clips.list_folder("~/mocap/cmu")    # every .bvh below the folder, sorted
    [e.name for e in entries if e.error]           # the broken ones, with their error

A folder is scanned recursively for ``.bvh`` files (any case). Each is read once (its
hierarchy and motion, ``avatar.io.bvh.read``); a clip that fails to read, or has no frame,
is still listed, with a one-line ``error``, so one bad file never hides the others.
"""

from __future__ import annotations

import logging
import os
from dataclasses import dataclass
from pathlib import Path

from avatar.errors import AvatarError, ParameterError
from avatar.io import bvh

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Clip:
    """One BVH file of a folder.

    name: the path relative to the folder, without ``.bvh`` (``walks/02_01``).
    path: the file.
    frames: number of frames (0 when unreadable); fps: frames per second (0 when unreadable).
    bones: number of joints in its hierarchy.
    error: "" for a usable clip, else why it cannot be used (one line).
    """

    name: str
    path: Path
    frames: int = 0
    fps: float = 0.0
    bones: int = 0
    error: str = ""

    @property
    def seconds(self) -> float:
        return self.frames / self.fps if self.fps else 0.0


def inspect(path: str | os.PathLike[str], name: str | None = None) -> Clip:
    """A clip's frame count, rate and joints, or its error (never raises for a bad file)."""
    path = Path(path)
    name = name if name is not None else path.stem
    try:
        data = bvh.read(path)
    except AvatarError as exc:
        return Clip(name, path, error=_one_line(exc))
    except (OSError, ValueError) as exc:  # unreadable file, undecodable number
        return Clip(name, path, error=_one_line(exc))
    if data.frames == 0:
        return Clip(name, path, 0, data.fps, len(data.names), "no frames ('Frames: 0')")
    return Clip(name, path, data.frames, float(data.fps), len(data.names))


def list_folder(folder: str | os.PathLike[str]) -> list[Clip]:
    """Every ``.bvh`` file below ``folder``, sorted by name, each inspected.

    Raises ParameterError when the folder does not exist or holds no ``.bvh`` file.
    """
    root = Path(folder).expanduser()
    if not root.is_dir():
        raise ParameterError(f"{root}: no such folder")
    files = sorted((p for p in root.rglob("*") if p.suffix.lower() == ".bvh" and p.is_file()),
                   key=lambda p: str(p.relative_to(root)).lower())  # fmt: skip
    if not files:
        raise ParameterError(f"{root}: no .bvh clips in this folder")
    out = [inspect(p, str(p.relative_to(root).with_suffix("")).replace(os.sep, "/"))
           for p in files]  # fmt: skip
    bad = [c for c in out if c.error]
    if bad:
        log.warning("%d of %d clips in %s cannot be used (first: %s: %s)", len(bad), len(out),
                    root, bad[0].name, bad[0].error)  # fmt: skip
    return out


def _one_line(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    return text[0] if text else type(exc).__name__
