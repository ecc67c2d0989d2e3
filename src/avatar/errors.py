"""Typed errors. Everything Avatar raises on bad input is an ``AvatarError``."""

from __future__ import annotations

import difflib
import os
from collections.abc import Iterable


class AvatarError(Exception):
    """Base class of every error Avatar raises on purpose (bad input, missing assets)."""


class FormatError(AvatarError):
    """A malformed file. Carries the file path and the 1-based line number (0 when unknown)."""

    def __init__(self, path: str | os.PathLike[str] | None, line: int, message: str):
        self.path = str(path) if path is not None else "<string>"
        self.line = int(line)
        self.message = message
        where = f"{self.path}:{self.line}" if self.line else self.path
        super().__init__(f"{where}: {message}")


class AssetError(AvatarError):
    """MakeHuman assets missing or corrupt; the message says how to install them."""


class ParameterError(AvatarError, KeyError):
    """Unknown parameter name or invalid value."""

    def __str__(self) -> str:  # KeyError quotes its message; we want it plain
        return str(self.args[0]) if self.args else ""


def unknown_name(kind: str, name: str, known: Iterable[str]) -> ParameterError:
    """Build a ParameterError for an unknown name, listing close matches."""
    known = list(known)
    close = difflib.get_close_matches(name, known, n=5, cutoff=0.5)
    if not close:
        close = [k for k in known if name.lower() in k.lower()][:5]
    hint = f"; did you mean {', '.join(close)}?" if close else ""
    return ParameterError(f"unknown {kind} {name!r}{hint}")
