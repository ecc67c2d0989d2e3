"""Checks on the files and folders a command names, made before any work starts.

A command that would fail to write its output after a minute of work (or with an
``OSError`` traceback) fails up front instead, with one line naming the path and why.
"""

from __future__ import annotations

import argparse
import math
import os
from pathlib import Path

from avatar.errors import AvatarError, ParameterError


def positive_number(text: str) -> float:
    """argparse ``type`` for rates such as ``--fps``: a finite number above zero (a usage
    error, exit status 2, otherwise)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not math.isfinite(value) or value <= 0:
        raise argparse.ArgumentTypeError(f"must be a positive number, got {text}")
    return value


def positive_count(text: str) -> int:
    """argparse ``type`` for counts such as ``--bake-segment``: a whole number of at least 1
    (a usage error, exit status 2, otherwise)."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be at least 1, got {text}")
    return value


def input_file(path: str | os.PathLike[str], what: str, hint: str = "") -> Path:
    """``path`` as a Path when it is an existing, readable file; else ParameterError
    (``hint`` ends the message: what else the option accepts)."""
    p = Path(path).expanduser()
    tail = f" ({hint})" if hint else ""
    if not p.exists():
        raise ParameterError(f"{what} {str(path)!r}: no such file{tail}")
    if not p.is_file():
        raise ParameterError(f"{what} {str(path)!r}: not a file{tail}")
    if not os.access(p, os.R_OK):
        raise ParameterError(f"{what} {str(path)!r}: not readable (permission denied)")
    return p


def output_file(path: str | os.PathLike[str], what: str = "output") -> Path:
    """``path`` as a Path when a file can be written there: its folder exists, is a folder
    and is writable, and ``path`` is not a folder. Raises AvatarError naming the problem."""
    p = Path(path).expanduser()
    folder = p.parent
    if p.is_dir():
        raise AvatarError(f"cannot write {what} {str(path)!r}: it is a folder")
    _writable_folder(folder, f"cannot write {what} {str(path)!r}")
    return p


def output_folder(path: str | os.PathLike[str], what: str = "output folder") -> Path:
    """``path`` as a Path when it is a writable folder or can be made one (every missing
    part below an existing, writable folder). Creates nothing; raises AvatarError."""
    p = Path(path).expanduser()
    if p.exists() and not p.is_dir():
        raise AvatarError(f"cannot write into {what} {str(path)!r}: it is a file")
    existing = p
    while not existing.exists():  # the nearest existing folder above it
        if existing.parent == existing:
            break
        existing = existing.parent
    _writable_folder(existing, f"cannot write into {what} {str(path)!r}")
    return p


def _writable_folder(folder: Path, prefix: str) -> None:
    """Raise AvatarError(``prefix``: reason) unless ``folder`` is an existing writable folder
    (a path under a file, a missing folder or a read-only one says which)."""
    above = folder
    while not above.exists() and above.parent != above:
        above = above.parent
    if above.exists() and not above.is_dir():
        raise AvatarError(f"{prefix}: {str(above)!r} is a file, not a folder")
    if not folder.exists():
        raise AvatarError(f"{prefix}: folder {str(folder)!r} does not exist")
    if not os.access(folder, os.W_OK | os.X_OK):
        raise AvatarError(f"{prefix}: folder {str(folder)!r} is not writable")


def os_error(error: OSError) -> AvatarError:
    """The one-line error for an ``OSError`` the checks up front could not foresee (a full
    disk, a folder that went away, a read-only one ``os.access`` called writable)."""
    reason = error.strerror or str(error)
    return AvatarError(f"{error.filename}: {reason}" if error.filename else reason)
