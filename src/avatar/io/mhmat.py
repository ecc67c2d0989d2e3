"""MakeHuman material files (``.mhmat``).

Spec: MakeHuman 1.1 ``lib/material.py`` (``Material.fromFile``): one ``key value`` per line,
``#`` comments; colours are three floats, textures are paths relative to the ``.mhmat``'s
folder (or absolute); keys such as ``shaderConfig`` and ``shaderParam`` repeat. The record
keeps every line in order, so write -> read is lossless, and offers typed accessors.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

from avatar.errors import FormatError
from avatar.io import atomic

TEXTURE_KEYS = (
    "diffuseTexture",
    "normalmapTexture",
    "bumpmapTexture",
    "displacementmapTexture",
    "specularmapTexture",
    "transparencymapTexture",
    "aomapTexture",
    "roughnessmapTexture",
    "metallicmapTexture",
)
COLOR_KEYS = ("diffuseColor", "ambientColor", "specularColor", "emissiveColor")
FLOAT_KEYS = (
    "shininess",
    "opacity",
    "translucency",
    "roughness",
    "metallic",
    "normalmapIntensity",
    "bumpmapIntensity",
    "aomapIntensity",
)


@dataclass(frozen=True)
class MaterialFile:
    """The lines of a ``.mhmat`` file: (key, value text) pairs in file order, plus comments."""

    entries: tuple[tuple[str, str], ...]
    comments: tuple[str, ...] = ()

    def get(self, key: str, default: str | None = None) -> str | None:
        """The value of the last line with this key (MakeHuman: later lines win)."""
        for k, v in reversed(self.entries):
            if k == key:
                return v
        return default

    @property
    def name(self) -> str:
        return self.get("name", "") or ""

    @property
    def tags(self) -> tuple[str, ...]:
        return tuple(v.lower() for k, v in self.entries if k == "tag")

    def color(self, key: str = "diffuseColor", default=(1.0, 1.0, 1.0)) -> tuple[float, ...]:
        """A colour as floats (0..1)."""
        value = self.get(key)
        return default if value is None else tuple(float(x) for x in value.split()[:3])

    def number(self, key: str, default: float | None = None) -> float | None:
        value = self.get(key)
        return default if value is None else float(value.split()[0])

    def flag(self, key: str, default: bool = False) -> bool:
        value = self.get(key)
        return default if value is None else value.strip().lower() in ("true", "1", "yes")

    def textures(self) -> dict[str, str]:
        """Texture key -> path text as written."""
        return {k: v for k, v in self.entries if k in TEXTURE_KEYS and v}


def _check_value(path, lineno: int, key: str, value: str) -> None:
    """Colours and numbers must parse, so a bad file fails at read time, not at render."""
    try:
        if key in COLOR_KEYS:
            parts = value.split()
            if len(parts) < 3:
                raise ValueError
            [float(x) for x in parts[:3]]
        elif key in FLOAT_KEYS:
            float(value.split()[0])
    except (ValueError, IndexError):
        raise FormatError(path, lineno, f"bad {key} value {value!r}") from None


def loads(text: str, path: str | os.PathLike[str] | None = None) -> MaterialFile:
    """Parse ``.mhmat`` text; FormatError on a malformed colour or number."""
    entries: list[tuple[str, str]] = []
    comments: list[str] = []
    for lineno, raw in enumerate(text.splitlines(), 1):
        line = raw.strip()
        if not line:
            continue
        if line.startswith("#"):
            comments.append(line)
            continue
        key, _, value = line.partition(" ")
        value = value.strip()
        _check_value(path, lineno, key, value)
        entries.append((key, value))
    return MaterialFile(tuple(entries), tuple(comments))


def read(path: str | os.PathLike[str]) -> MaterialFile:
    """Read a ``.mhmat`` file."""
    try:
        text = Path(path).read_text(encoding="utf-8", errors="replace")
    except OSError as exc:
        raise FormatError(path, 0, f"cannot read: {exc.strerror}") from None
    return loads(text, path)


def dumps(material: MaterialFile) -> str:
    """``.mhmat`` text (comments first, then every line in order)."""
    lines = list(material.comments)
    if lines:
        lines.append("")
    lines += [f"{k} {v}".rstrip() for k, v in material.entries]
    return "\n".join(lines) + "\n"


def write(path: str | os.PathLike[str], material: MaterialFile) -> None:
    """Write a ``.mhmat`` file atomically."""
    atomic.write_text(path, dumps(material))


def resolve_texture(value: str, folder: str | os.PathLike[str]) -> Path | None:
    """A texture's file as MakeHuman finds it: absolute, relative to the material's folder,
    or its base name in that folder (files moved between machines). None when missing."""
    value = value.strip().strip('"')
    folder = Path(folder)
    for candidate in (Path(value), folder / value, folder / Path(value.replace("\\", "/")).name):
        if candidate.is_file():
            return candidate
    return None


def texture_paths(
    material: MaterialFile,
    folder: str | os.PathLike[str],
    path: str | os.PathLike[str] | None = None,
    required: tuple[str, ...] = ("diffuseTexture",),
) -> dict[str, Path]:
    """Texture key -> existing file. A missing file whose key is in ``required`` raises
    FormatError naming the material file; other missing maps are left out (MakeHuman shows
    a placeholder for them too)."""
    out: dict[str, Path] = {}
    for key, value in material.textures().items():
        found = resolve_texture(value, folder)
        if found is not None:
            out[key] = found
        elif key in required:
            raise FormatError(path, 0, f"{key} {value!r} not found next to the material")
    return out
