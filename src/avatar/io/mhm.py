"""MakeHuman 1.1 character files (``.mhm``): read/write, lossless.

Format: one ``key value...`` statement per line, ``#`` comments. ``modifier <group/name>
<value>`` lines carry the body; ``skeleton``, ``clothes``, ``eyebrows``, ``eyelashes``,
``hair``, ``skinMaterial``, ... the rest. Avatar-only parameters (``pca/*``,
``expression/*``) are written as ``avatar-param <name> <value>``, a key MakeHuman ignores.
Every other line is kept verbatim so a MakeHuman file survives read -> write.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from pathlib import Path

from avatar.errors import FormatError
from avatar.io import atomic

AVATAR_KEY = "avatar-param"
LIST_KEYS = ("clothes",)
RIG_OF_SKELETON = {
    "default.mhskel": "default",
    "default_no_toes.mhskel": "default_no_toes",
    "game_engine.mhskel": "game_engine",
    "game_engine_with_breast.mhskel": "game_engine_with_breast",
    "cmu_mb.mhskel": "cmu_mb",
    "mixamo.mhskel": "mixamo",
}


@dataclass
class CharacterFile:
    """A parsed ``.mhm``: modifiers by MakeHuman name, Avatar extras, and the other lines."""

    name: str = ""
    version: str = "v1.1.1"
    modifiers: dict[str, float] = field(default_factory=dict)
    avatar_params: dict[str, float] = field(default_factory=dict)
    skeleton: str | None = None
    clothes: list[str] = field(default_factory=list)
    other: list[tuple[str, str]] = field(default_factory=list)  # (key, rest of line)

    @property
    def rig(self) -> str | None:
        """Avatar rig name for the ``skeleton`` line (None when absent or unknown)."""
        if not self.skeleton:
            return None
        return RIG_OF_SKELETON.get(Path(self.skeleton).name.lower())


def loads(text: str, path: str | os.PathLike[str] | None = None) -> CharacterFile:
    """Parse ``.mhm`` text. Raises FormatError naming the line on malformed statements."""
    out = CharacterFile()
    for lineno, raw in enumerate(text.splitlines(), 1):
        line = raw.strip()
        if not line or line.startswith("#"):
            continue
        key, _, rest = line.partition(" ")
        rest = rest.strip()
        if key in ("modifier", AVATAR_KEY):
            name, value = _modifier(rest, path, lineno)
            (out.modifiers if key == "modifier" else out.avatar_params)[name] = value
        elif key == "name":
            out.name = rest
        elif key == "version":
            out.version = rest
        elif key == "skeleton":
            out.skeleton = rest or None
        elif key == "clothes":
            out.clothes.append(rest)
        else:
            out.other.append((key, rest))
    return out


def _modifier(rest: str, path: str | os.PathLike[str] | None, lineno: int) -> tuple[str, float]:
    parts = rest.split()
    if len(parts) != 2:
        raise FormatError(path, lineno, f"expected 'modifier <name> <value>', got {rest!r}")
    try:
        value = float(parts[1])
    except ValueError:
        raise FormatError(path, lineno, f"modifier value {parts[1]!r} is not a number") from None
    if not math.isfinite(value):
        raise FormatError(path, lineno, f"modifier value {parts[1]!r} is not finite")
    return parts[0], value


def dumps(character: CharacterFile) -> str:
    """``.mhm`` text; values with 6 decimals as MakeHuman writes them (repr when finer)."""
    lines = ["# Written by Avatar", f"version {character.version}"]
    if character.name:
        lines.append(f"name {character.name}")
    lines += [f"modifier {k} {_number(v)}" for k, v in character.modifiers.items()]
    lines += [f"{AVATAR_KEY} {k} {_number(v)}" for k, v in character.avatar_params.items()]
    if character.skeleton:
        lines.append(f"skeleton {character.skeleton}")
    lines += [f"clothes {c}" for c in character.clothes]
    lines += [f"{k} {r}".rstrip() for k, r in character.other]
    return "\n".join(lines) + "\n"


def _number(v: float) -> str:
    text = f"{v:.6f}"
    return text if float(text) == v else repr(float(v))


def read(path: str | os.PathLike[str]) -> CharacterFile:
    try:
        text = Path(path).read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise FormatError(path, 0, f"cannot read character file: {exc}") from None
    return loads(text, path)


def write(path: str | os.PathLike[str], character: CharacterFile) -> None:
    """Write a ``.mhm`` file atomically."""
    atomic.write_text(path, dumps(character))
