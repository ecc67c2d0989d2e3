"""The clothes library: built-in garments plus any MakeHuman/MPFB asset folders a user adds.

    list_garments(search="jeans")         # LibraryEntry records (name, category, tags, ...)
    garment = load_garment("tshirt")       # or a path to a .mhclo
    find_garment("tshrt")                  # ParameterError: ... did you mean tshirt?
    outfit = dress(body, [garment, "jeans"])  # body: a shaped Body (``Human.body``)
    parts = [g.part() for g in outfit]    # MeshParts for exporters and the Blender bridge

User folders come from ``AVATAR_CLOTHES_PATH`` (os.pathsep-separated) and the ``folders``
arguments; each is scanned recursively for ``.mhclo`` files (see ``scan``).
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Sequence
from functools import lru_cache
from pathlib import Path

from avatar.body.model import BodyModel
from avatar.body.shaped import Body, default_body
from avatar.clothes import builtin, fitting
from avatar.clothes.asset import read_garment
from avatar.clothes.authoring import AuthoringBody
from avatar.clothes.fitting import FittedGarment, Garment, Outfit
from avatar.clothes.scan import LibraryEntry, scan
from avatar.errors import AvatarError, unknown_name
from avatar.part import MeshPart

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


@lru_cache(maxsize=4)
def authoring_body(model: BodyModel | None = None) -> AuthoringBody:
    """The default body the built-ins are cut from (built once per model)."""
    return AuthoringBody(default_body(model or BodyModel.shared()))


@lru_cache(maxsize=64)
def _builtin(name: str, texture_size: int, model: BodyModel | None) -> Garment:
    return builtin.build(builtin.BY_NAME[name], authoring_body(model), texture_size)


def find_garment(
    name_or_path: str | os.PathLike[str], folders: Iterable[str | os.PathLike[str]] = ()
) -> str:
    """Where a garment comes from, checked without building it: a built-in name, or the
    ``.mhclo`` path of a file or of a user asset found by name (``folders``,
    ``$AVATAR_CLOTHES_PATH``). Raises ParameterError naming close matches for an unknown
    name, AvatarError for a missing ``.mhclo`` file."""
    text = str(name_or_path)
    if text in builtin.BY_NAME:
        return text
    path = Path(text)
    if path.is_file():
        return text
    if path.suffix.lower() == ".mhclo":
        raise AvatarError(f"{text}: no such garment file")
    entries = list_garments(folders=folders)
    for entry in entries:
        if entry.source != "builtin" and text in (entry.name, Path(entry.source).stem):
            return entry.source
    raise unknown_name("garment", text, [e.name for e in entries])


def load_garment(
    name_or_path: str | os.PathLike[str],
    folders: Iterable[str | os.PathLike[str]] = (),
    texture_size: int = 1024,
    model: BodyModel | None = None,
) -> Garment:
    """A Garment by built-in name, by a user asset's name, or from a ``.mhclo`` path.

    model: the body model built-ins are cut from (default ``BodyModel.shared()``).
    Raises ParameterError (with close matches) for an unknown name, FormatError for a
    broken file.
    """
    source = find_garment(name_or_path, folders)
    if source in builtin.BY_NAME:
        return _builtin(source, texture_size, model)
    return read_garment(source)


def dress(
    body: Body,
    garments: Sequence[Garment | str] = DEFAULT_OUTFIT,
    exact: bool = False,
    folders: Iterable[str | os.PathLike[str]] = (),
) -> Outfit:
    """Fit garments (Garment records, or names/paths: ``load_garment``) on a shaped body
    (``Human.body``); see ``fitting.dress``."""
    loaded = [
        g if isinstance(g, Garment) else load_garment(g, folders, model=body.model)
        for g in garments
    ]
    return fitting.dress(body, loaded, exact)


def parts(outfit: Outfit) -> list[MeshPart]:
    """MeshParts of an outfit's garments (skin indices into the body's skeleton)."""
    return [garment_part(g) for g in outfit.garments]


def garment_part(g: FittedGarment) -> MeshPart:
    """One fitted garment as a MeshPart for exporters and the Blender bridge."""
    return MeshPart(g.name, g.mesh, g.material, (g.weights.indices, g.weights.weights))


__all__ = [
    "DEFAULT_OUTFIT",
    "FittedGarment",
    "Garment",
    "LibraryEntry",
    "Outfit",
    "dress",
    "find_garment",
    "garment_part",
    "list_garments",
    "load_garment",
    "parts",
    "user_folders",
]
