"""The clothes library: built-in garments plus any MakeHuman/MPFB asset folders a user adds.

    list_garments(search="jeans")         # LibraryEntry records (name, category, tags, ...)
    garment = load_garment("tshirt")       # or a path to a .mhclo
    outfit = dress(human, [garment, load_garment("jeans")])
    parts = [g.part() for g in outfit]    # MeshParts for exporters and the Blender bridge

User folders come from ``AVATAR_CLOTHES_PATH`` (os.pathsep-separated) and the ``folders``
arguments; each is scanned recursively for ``.mhclo`` files (see ``scan``).
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Sequence
from functools import lru_cache
from pathlib import Path

from avatar.clothes import builtin, fitting
from avatar.clothes.asset import read_garment
from avatar.clothes.fitting import FittedGarment, Garment, Outfit
from avatar.clothes.scan import LibraryEntry, scan
from avatar.errors import unknown_name

ENV_PATH = "AVATAR_CLOTHES_PATH"
DEFAULT_OUTFIT = ("eyebrows", "eyelashes", "hair-short", "tshirt", "jeans", "shoes")


def user_folders(folders: Iterable[str | os.PathLike[str]] = ()) -> list[Path]:
    """The asset folders to scan: ``folders`` then those in ``$AVATAR_CLOTHES_PATH``."""
    env = [p for p in os.environ.get(ENV_PATH, "").split(os.pathsep) if p]
    return [Path(p) for p in [*folders, *env]]


def builtin_entries() -> list[LibraryEntry]:
    return [
        LibraryEntry(s.name, s.category, s.tags, "builtin", "CC0", None, f"{s.fabric}, {s.colour}")
        for s in builtin.SPECS
    ]


def list_garments(
    search: str | None = None, folders: Iterable[str | os.PathLike[str]] = ()
) -> list[LibraryEntry]:
    """Every garment Avatar can dress a character in, optionally filtered by a search text
    (case-insensitive, matched against name, category, tags and description)."""
    entries = builtin_entries()
    for folder in user_folders(folders):
        entries += scan(folder)
    if search:
        words = search.lower().split()
        entries = [e for e in entries if all(w in e.haystack for w in words)]
    return entries


@lru_cache(maxsize=1)
def authoring_body():
    """The default human the built-ins are cut from (built once per process)."""
    from avatar.clothes.authoring import AuthoringBody
    from avatar.human import Human

    return AuthoringBody(Human({}))


@lru_cache(maxsize=64)
def _builtin(name: str, texture_size: int) -> Garment:
    return builtin.build(builtin.BY_NAME[name], authoring_body(), texture_size)


def load_garment(
    name_or_path: str | os.PathLike[str],
    folders: Iterable[str | os.PathLike[str]] = (),
    texture_size: int = 1024,
) -> Garment:
    """A Garment by built-in name, by a user asset's name, or from a ``.mhclo`` path.

    Raises ParameterError (with close matches) for an unknown name, FormatError for a
    broken file.
    """
    text = str(name_or_path)
    if text in builtin.BY_NAME:
        return _builtin(text, texture_size)
    path = Path(text)
    if path.suffix.lower() == ".mhclo" or path.is_file():
        return read_garment(path)
    for entry in list_garments(folders=folders):
        if entry.source != "builtin" and text in (entry.name, Path(entry.source).stem):
            return read_garment(entry.source)
    raise unknown_name("garment", text, [e.name for e in list_garments(folders=folders)])


def dress(
    human,
    garments: Sequence[Garment | str] = DEFAULT_OUTFIT,
    bone_names=None,
    exact: bool = False,
) -> Outfit:
    """Fit garments (Garment records or names/paths) on a human; see ``fitting.dress``."""
    loaded = [g if isinstance(g, Garment) else load_garment(g) for g in garments]
    return fitting.dress(human, loaded, bone_names, exact)


def parts(outfit: Outfit) -> list:
    """MeshParts of an outfit's garments (skin indices into the human's skeleton)."""
    return [garment_part(g) for g in outfit.garments]


def garment_part(g: FittedGarment):
    """One fitted garment as a MeshPart for exporters and the Blender bridge."""
    from avatar.part import MeshPart

    return MeshPart(g.name, g.mesh, g.material, (g.weights.indices, g.weights.weights))


def cli_clothes_list(args) -> int:
    """``avatar clothes list [--search TEXT] [--folder DIR ...]``: print the library."""
    entries = list_garments(getattr(args, "search", None), getattr(args, "folder", None) or ())
    width = max((len(e.name) for e in entries), default=4)
    for e in entries:
        print(f"{e.name:<{width}}  {e.category:<9}  {e.licence:<6}  {', '.join(e.tags)}")
    if not entries:
        print("no garments match")
    return 0


__all__ = [
    "DEFAULT_OUTFIT",
    "FittedGarment",
    "Garment",
    "LibraryEntry",
    "Outfit",
    "cli_clothes_list",
    "dress",
    "garment_part",
    "list_garments",
    "load_garment",
    "parts",
    "user_folders",
]
