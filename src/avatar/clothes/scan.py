"""Scan MakeHuman/MPFB asset folders for garments: name, category, tags, licence, thumbnail.

Reads only each ``.mhclo``'s header lines (fast on folders of hundreds of assets); a file that
cannot be parsed is listed with its error in ``description`` rather than hiding the folder.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

CATEGORIES = ("clothes", "hair", "eyebrows", "eyelashes", "proxymeshes", "shoes")


@dataclass(frozen=True)
class LibraryEntry:
    """One garment in the library.

    source: "builtin" or the ``.mhclo`` path; thumbnail: a ``.thumb``/``.png`` path or None.
    uuid: the asset's ``uuid`` line (MakeHuman's identity of an asset in ``.mhm`` files;
    built-ins get a fixed one), "" when it has none.
    """

    name: str
    category: str
    tags: tuple[str, ...]
    source: str
    licence: str
    thumbnail: str | None
    description: str = ""
    uuid: str = ""

    @property
    def haystack(self) -> str:
        return " ".join([self.name, self.category, *self.tags, self.description]).lower()


def scan(folder: str | os.PathLike[str]) -> list[LibraryEntry]:
    """Library entries of every ``.mhclo`` under folder (recursively), sorted by name."""
    root = Path(folder)
    if not root.is_dir():
        return []
    return sorted((entry(p) for p in root.rglob("*.mhclo")), key=lambda e: e.name)


def entry(path: Path) -> LibraryEntry:
    """The entry of one ``.mhclo`` file from its header (keywords before the numbers)."""
    name, tags, licence, description, uuid = path.stem, [], "", "", ""
    try:
        with open(path, encoding="utf-8", errors="replace") as f:
            for line in f:
                words = line.split()
                if not words:
                    continue
                if words[0] == "verts":
                    break
                rest = line.strip()[len(words[0]) :].strip()
                if words[0] == "name":
                    name = rest
                elif words[0] == "tag":
                    tags.append(rest.lower())
                elif words[0] == "license":
                    licence = rest
                elif words[0] == "description":
                    description = rest
                elif words[0] == "uuid":
                    uuid = rest
                elif words[0].startswith("#") and "CC0" in line and not licence:
                    licence = "CC0"
    except OSError as exc:
        description = f"unreadable: {exc.strerror}"
    return LibraryEntry(name, _category(path), tuple(tags), str(path), licence,
                        _thumbnail(path), description, uuid)  # fmt: skip


def _category(path: Path) -> str:
    for part in reversed(path.parts[:-1]):
        if part.lower() in CATEGORIES:
            return part.lower()
    return "clothes"


def _thumbnail(path: Path) -> str | None:
    for suffix in (".thumb", ".png", ".jpg"):
        candidate = path.with_suffix(suffix)
        if candidate.is_file():
            return str(candidate)
    return None
