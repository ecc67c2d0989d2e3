"""Outfits: named sets of garments with their variants, saved as small JSON files.

An outfit file is ``{"clothes": ["tshirt", "jeans", ...], "options": {"tshirt":
{"colour": "navy"}}}`` (options as a recipe's ``garment_options``). Wearing an outfit
(``wear``) gives a character exactly its garments and takes off the rest, except the
character's own looks (hair, eyebrows, eyelashes, beard): those stay unless the outfit
names items of the same kind (a saved outfit that includes hair replaces the hair). The
built-in outfits name clothes only, so "business" does not shave anyone.
"""

from __future__ import annotations

import json
import os
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from avatar.clothes import library, variants
from avatar.errors import AvatarError, FormatError

LOOKS = ("hair", "face", "beard")  # categories of a character's own looks


@dataclass(frozen=True)
class Outfit:
    """A named set of garments (recipe clothes entries) and their variant options."""

    clothes: tuple[str, ...]
    options: dict[str, dict[str, str]] = field(default_factory=dict)

    def to_dict(self) -> dict:
        return {"clothes": list(self.clothes),
                "options": {k: dict(v) for k, v in self.options.items()
                            if k in self.clothes and v}}  # fmt: skip


BUILTIN: dict[str, Outfit] = {
    "casual": Outfit(("tshirt", "jeans", "socks", "sneakers"), {"tshirt": {"colour": "navy"}}),
    "business": Outfit(("longsleeve", "trousers", "socks", "shoes-black"),
                       {"longsleeve": {"colour": "white", "fabric": "cotton"},
                        "socks": {"colour": "black"}}),  # fmt: skip
    "sport": Outfit(("tanktop", "shorts", "socks", "sneakers", "cap"),
                    {"tanktop": {"colour": "red"}, "shorts": {"colour": "black"},
                     "cap": {"colour": "navy"}}),  # fmt: skip
    "winter": Outfit(("longsleeve", "jacket", "jeans", "socks", "boots"),
                     {"longsleeve": {"colour": "burgundy", "fabric": "cotton"},
                      "jeans": {"colour": "dark indigo"}}),  # fmt: skip
}


def clean_name(name: str) -> str:
    """A file-safe outfit name ("My Outfit!" -> "my_outfit"); "" when nothing is left."""
    return re.sub(r"[^A-Za-z0-9_-]+", "_", name.strip()).strip("_").lower()


def check(outfit: Outfit, folders: Sequence[str] = (), where: str = "outfit") -> Outfit:
    """``outfit`` with its garments found and options checked (normalised). Raises
    AvatarError naming ``where`` and the first bad item (unknown garment, bad option)."""
    options = {}
    for entry in outfit.clothes:
        try:
            source = library.find_garment(entry, folders)
            checked = variants.check(source, outfit.options.get(entry))
        except AvatarError as exc:
            raise AvatarError(f"{where}: {exc}") from None
        if checked:
            options[entry] = checked
    stray = sorted(set(outfit.options) - set(outfit.clothes))
    if stray:
        raise AvatarError(f"{where}: options for garments it does not list: {', '.join(stray)}")
    return Outfit(tuple(dict.fromkeys(outfit.clothes)), options)


def parse(data: object, path: str | os.PathLike[str]) -> Outfit:
    """An Outfit from a file's JSON value; FormatError for the wrong shape."""
    if not isinstance(data, Mapping) or not isinstance(data.get("clothes"), list):
        raise FormatError(path, 0, 'not an outfit: expected {"clothes": [...], "options": {}}')
    unknown = set(data) - {"clothes", "options"}
    if unknown:
        raise FormatError(path, 0, f"unknown outfit fields: {', '.join(sorted(unknown))}")
    clothes = data["clothes"]
    options = data.get("options") or {}
    if not all(isinstance(c, str) and c for c in clothes):
        raise FormatError(path, 0, "clothes must be garment names (texts)")
    if not isinstance(options, Mapping) or not all(isinstance(v, Mapping)
                                                   for v in options.values()):  # fmt: skip
        raise FormatError(path, 0, "options must map garment names to {colour, fabric}")
    return Outfit(tuple(clothes), {str(k): dict(v) for k, v in options.items()})


def load(path: str | os.PathLike[str], folders: Sequence[str] = ()) -> Outfit:
    """A checked Outfit from a JSON file. Raises FormatError (bad JSON or shape) or
    AvatarError (an unknown garment or option), naming the file."""
    try:
        text = Path(path).read_text(encoding="utf-8")
    except OSError as exc:
        raise AvatarError(f"{path}: cannot read the outfit ({exc.strerror})") from None
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise FormatError(path, exc.lineno, f"not JSON: {exc.msg}") from None
    return check(parse(data, path), folders, str(path))


def save(path: str | os.PathLike[str], outfit: Outfit) -> Path:
    """Write ``outfit`` as JSON (a temporary file renamed over the old one)."""
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    tmp = target.with_suffix(".json.tmp")
    tmp.write_text(json.dumps(outfit.to_dict(), indent=1, sort_keys=True), encoding="utf-8")
    os.replace(tmp, target)
    return target


def _category(entry: str, folders: Sequence[str]) -> str:
    return library.entry_of(entry, folders).category


def wear(clothes: Sequence[str], options: Mapping[str, Mapping[str, str]], outfit: Outfit,
         folders: Sequence[str] = ()) -> tuple[list[str], dict[str, dict[str, str]]]:  # fmt: skip
    """(clothes, garment_options) of a character wearing ``outfit`` (checked) instead of
    ``clothes``: its looks kept unless the outfit has that kind, the rest taken off."""
    replaced = {_category(e, folders) for e in outfit.clothes}
    kept = [e for e in clothes
            if (c := _category(e, folders)) in LOOKS and c not in replaced]  # fmt: skip
    new_clothes = kept + [e for e in outfit.clothes if e not in kept]
    new_options = {e: dict(options[e]) for e in kept if options.get(e)}
    new_options.update({e: dict(v) for e, v in outfit.options.items() if v})
    return new_clothes, new_options
