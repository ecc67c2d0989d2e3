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
import uuid
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import replace
from functools import lru_cache
from pathlib import Path

import numpy as np

from avatar.body.model import BodyModel
from avatar.body.shaped import Body, default_body
from avatar.clothes import builtin, disk_cache, fitting, variants
from avatar.clothes.asset import read_garment
from avatar.clothes.authoring import AuthoringBody
from avatar.clothes.fitting import FittedGarment, Garment, Outfit
from avatar.clothes.scan import LibraryEntry, scan
from avatar.clothes.scan import entry as scan_entry
from avatar.errors import AvatarError, unknown_name
from avatar.geometry.shell import layer_normals
from avatar.part import MeshPart

ENV_PATH = "AVATAR_CLOTHES_PATH"
DEFAULT_OUTFIT = ("eyebrows", "eyelashes", "hair-short", "tshirt", "jeans", "shoes")
# Built-ins have fixed uuids (so .mhm files name them as MakeHuman names its assets).
_BUILTIN_NAMESPACE = uuid.UUID("6f1f8f5e-3c1a-4a8e-9a57-3e0d7c2b9a10")
# MakeHuman's proxy libraries by asset category (the key of the asset's .mhm line).
MHM_KIND = {"hair": "hair", "eyebrows": "eyebrows", "eyelashes": "eyelashes",
            "proxymeshes": "proxy"}  # fmt: skip


def user_folders(folders: Iterable[str | os.PathLike[str]] = ()) -> list[Path]:
    """The asset folders to scan: ``folders`` then those in ``$AVATAR_CLOTHES_PATH``."""
    env = [p for p in os.environ.get(ENV_PATH, "").split(os.pathsep) if p]
    return [Path(p) for p in [*folders, *env]]


def builtin_uuid(name: str) -> str:
    """The fixed uuid of a built-in garment (a name-based UUID 5)."""
    return str(uuid.uuid5(_BUILTIN_NAMESPACE, name))


def builtin_entries() -> list[LibraryEntry]:
    return [
        LibraryEntry(
            s.name,
            s.category,
            s.tags,
            "builtin",
            "CC0",
            None,
            f"{s.fabric}, {s.colour}",
            builtin_uuid(s.name),
        )  # fmt: skip
        for s in builtin.SPECS
    ]


def entry_of(name_or_path: str | os.PathLike[str],
             folders: Iterable[str | os.PathLike[str]] = ()) -> LibraryEntry:  # fmt: skip
    """The library entry (name, category, uuid, ...) of a garment as a recipe names it: a
    built-in name, a ``.mhclo`` path or a user asset's name. Errors as ``find_garment``."""
    source = find_garment(name_or_path, folders)
    if source in builtin.BY_NAME:
        return next(e for e in builtin_entries() if e.name == source)
    return scan_entry(Path(source))


def mhm_kind(item: LibraryEntry) -> str:
    """The ``.mhm`` statement that names this asset: hair, eyebrows, eyelashes, proxy or
    clothes (MakeHuman's library of that category)."""
    if item.category in MHM_KIND:
        return MHM_KIND[item.category]
    if item.category == "face":  # the built-in eyebrows and eyelashes
        return "eyebrows" if "eyebrows" in item.tags else "eyelashes"
    return "clothes"


def find_reference(
    name: str, uuid_text: str = "", folders: Iterable[str | os.PathLike[str]] = ()
) -> str | None:
    """The garment a ``.mhm`` proxy line ``<kind> <name> <uuid>`` names: by uuid first
    (MakeHuman's rule), then by name (MPFB's fallback: the asset's ``name`` line or file
    stem), over built-ins, ``folders`` and ``$AVATAR_CLOTHES_PATH``. Returns a built-in name
    or a ``.mhclo`` path, None when nothing matches."""
    entries = list_garments(folders=folders)
    found = [e for e in entries if uuid_text and e.uuid == uuid_text]
    found = found or [
        e for e in entries if name in (e.name, Path(e.source).stem if e.source != "builtin" else "")
    ]
    if not found:
        return None
    return found[0].name if found[0].source == "builtin" else found[0].source


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
def _piece(name: str, model: BodyModel | None):
    """A built-in's cut piece (geometry, binding, panel layout), cut once per model."""
    return builtin.BY_NAME[name].make(authoring_body(model))


@lru_cache(maxsize=64)
def _builtin(name: str, texture_size: int, model: BodyModel | None) -> Garment:
    """A built-in garment, built once per process (or read from ``disk_cache`` when a
    dataset worker enabled it)."""

    def build() -> Garment:
        spec = builtin.BY_NAME[name]
        return builtin.build(spec, authoring_body(model), texture_size, _piece(name, model))

    return disk_cache.fetch(("builtin", name, texture_size, _assets_key(model)), build)


@lru_cache(maxsize=64)
def _variant(name: str, options: tuple[tuple[str, str], ...], texture_size: int,
             model: BodyModel | None) -> Garment:  # fmt: skip
    """A built-in in a fabric/colour variant: the default's geometry and binding (the same
    arrays), a material of its own, made once per (garment, variant)."""

    def look():
        spec = variants.spec(name, dict(options))
        return builtin.look(spec, _piece(name, model).layout, texture_size)

    key = ("look", name, options, texture_size, _assets_key(model))
    return replace(_builtin(name, texture_size, model), material=disk_cache.fetch(key, look))


def _assets_key(model: BodyModel | None) -> str:
    """The MakeHuman assets a built-in is cut from (their compiled folder's fingerprint)."""
    return (model or BodyModel.shared()).assets.folder.name


# find_garment's answers: (name or path, folders, $AVATAR_CLOTHES_PATH) -> the .mhclo path
# found. A live slider step validates its recipe's garments every time; a hit costs one
# stat of the file found (a name may have needed a scan of every user folder).
_FOUND: dict[tuple[str, tuple[str, ...], str], str] = {}
_FOUND_SIZE = 256


def find_garment(
    name_or_path: str | os.PathLike[str], folders: Iterable[str | os.PathLike[str]] = ()
) -> str:
    """Where a garment comes from, checked without building it: a built-in name, or the
    ``.mhclo`` path of a file or of a user asset found by name (``folders``,
    ``$AVATAR_CLOTHES_PATH``). Raises ParameterError naming close matches for an unknown
    name, AvatarError for a missing ``.mhclo`` file. Answers are remembered while the file
    found still exists (a renamed or added asset with the same name is not looked for)."""
    text = str(name_or_path)
    if text in builtin.BY_NAME:
        return text
    where = tuple(str(f) for f in folders)
    key = (text, where, os.environ.get(ENV_PATH, ""))
    found = _FOUND.get(key)
    if found is not None and os.path.isfile(found):
        return found
    found = _find_user_garment(text, where)
    if len(_FOUND) >= _FOUND_SIZE:
        _FOUND.clear()
    _FOUND[key] = found
    return found


def _find_user_garment(text: str, folders: tuple[str, ...]) -> str:
    """``find_garment`` for anything but a built-in name (no memo)."""
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
    options: Mapping[str, object] | None = None,
) -> Garment:
    """A Garment by built-in name, by a user asset's name, or from a ``.mhclo`` path.

    model: the body model built-ins are cut from (default ``BodyModel.shared()``).
    options: a built-in's fabric/colour variant, e.g. {"colour": "navy"} (``variants``).
    Raises ParameterError (with close matches) for an unknown name or option, FormatError
    for a broken file.
    """
    source = find_garment(name_or_path, folders)
    checked = variants.check(source, options)
    if source in builtin.BY_NAME:
        if checked and not variants.is_default(source, checked):
            return _variant(source, tuple(sorted(checked.items())), texture_size, model)
        return _builtin(source, texture_size, model)
    return read_garment(source)


def dress(
    body: Body,
    garments: Sequence[Garment | str] = DEFAULT_OUTFIT,
    exact: bool = False,
    folders: Iterable[str | os.PathLike[str]] = (),
    options: Mapping[str, Mapping[str, object]] | None = None,
    age: float | None = None,
) -> Outfit:
    """Fit garments (Garment records, or names/paths: ``load_garment``) on a shaped body
    (``Human.body``); see ``fitting.dress``. options: {entry: a built-in's variant}.
    age: the wearer's MakeHuman age; given, the built-in brows and facial hair follow the
    wearer (``wearer_looks``): the built-in scalp hair's colour, greying with age; the
    built-in scalp hair greys too unless a colour option was picked for it."""
    options = options or {}
    loaded = [
        g if isinstance(g, Garment)
        else load_garment(g, folders, model=body.model, options=options.get(str(g)))
        for g in garments
    ]
    names = [str(g) if not isinstance(g, Garment) else g.name for g in garments]
    loaded = under_headwear(loaded, names, body.model)
    if age is not None:
        loaded = wearer_looks(loaded, names, options, age)
    return fitting.dress(body, loaded, exact)


def under_headwear(loaded: list[Garment], names: list[str],
                   model: BodyModel | None = None) -> list[Garment]:  # fmt: skip
    """``loaded`` with the built-in scalp hair pressed under a built-in cap when one is worn
    (``headwear.pressed_hair``), so the cap sits on the head and the hair shows below its
    band; anything else as it is."""
    capped = any(builtin.BY_NAME[n].category == "headwear" for n in names if n in builtin.BY_NAME)
    if not capped:
        return loaded
    out = []
    for garment, name in zip(loaded, names, strict=True):
        spec = builtin.BY_NAME.get(name)
        out.append(_pressed(garment, name, model) if spec and spec.category == "hair"
                   else garment)  # fmt: skip
    return out


_PRESSED: dict[int, tuple[Garment, Garment]] = {}


def _pressed(garment: Garment, name: str, model: BodyModel | None) -> Garment:
    """A built-in hair garment (its variant's material kept) with the pressed geometry,
    made once per garment record (its fitting anchors then stay cached with it)."""
    hit = _PRESSED.get(id(garment))
    if hit is not None and hit[0] is garment:
        return hit[1]
    piece = _pressed_piece(name, model)
    out = replace(garment, mesh=piece.mesh, binding=piece.binding)
    if len(_PRESSED) > 32:
        _PRESSED.clear()
    _PRESSED[id(garment)] = (garment, out)
    return out


@lru_cache(maxsize=8)
def _pressed_piece(name: str, model: BodyModel | None):
    from avatar.clothes import headwear

    def build():
        return headwear.pressed_hair(authoring_body(model), _piece(name, model))

    return disk_cache.fetch(("pressed", name, _assets_key(model)), build)


# Built-ins that follow their wearer's hair colour and age, and how (``for_wearer``'s kind);
# the named brow colours (eyebrows-blond, -black) keep their colour but still grey.
FOLLOWS_HAIR = {"eyebrows": "brows", "beard-short": "cards", "moustache": "cards",
                "stubble": "stubble"}  # fmt: skip
KEEPS_COLOUR = {"eyebrows-blond": "brows", "eyebrows-black": "brows"}


def wearer_looks(
    loaded: list[Garment], names: list[str], options: Mapping[str, Mapping[str, object]],
    age: float,
) -> list[Garment]:
    """``loaded`` with the built-in brows and facial hair recoloured for the wearer: the
    colour of the built-in scalp hair worn (its variant's, else its own) unless the item
    has a colour option of its own, greying with ``age`` (``facial_hair.for_wearer``);
    the built-in scalp hair itself greys on the same curve (salt and pepper in the
    sixties, mostly grey at 90) unless a colour was picked for it."""
    hair = None
    for name in names:
        spec = builtin.BY_NAME.get(name)
        if spec is not None and spec.category == "hair":
            hair = str(options.get(name, {}).get("colour", spec.colour))
    out = []
    for garment, name in zip(loaded, names, strict=True):
        own = options.get(name, {}).get("colour")
        kind = FOLLOWS_HAIR.get(name) or KEEPS_COLOUR.get(name)
        scalp = kind is None and _greys(name, own, age)
        if scalp:
            kind = "cards"  # built-in scalp hair: its own colour, greying with age
        if kind is None:
            out.append(garment)
            continue
        colour = None if (own or name in KEEPS_COLOUR or scalp) else hair
        out.append(_wearer_garment(garment, kind, round(float(age), 2), colour))
    return out


def _greys(name: str, own_colour: object, age: float) -> bool:
    """Whether a worn item is built-in scalp hair that greys at ``age``: not when the user
    picked its colour (a dyed grey-free head is a choice), nor before greying starts."""
    from avatar.looks import facial_hair

    spec = builtin.BY_NAME.get(name)
    return (spec is not None and spec.category == "hair" and not own_colour
            and facial_hair.grey_share(age) > 0)  # fmt: skip


_WEARER: dict[tuple, tuple[Garment, Garment]] = {}


def _wearer_garment(garment: Garment, kind: str, age: float, colour: str | None) -> Garment:
    """The garment with ``facial_hair.for_wearer`` of its material, remembered (a few
    dozen): the same record for the same wearer, so its fitting anchors are found once."""
    from avatar.looks import facial_hair

    if garment.material is None:
        return garment
    key = (id(garment), kind, age, colour)
    hit = _WEARER.get(key)
    if hit is not None and hit[0] is garment:
        return hit[1]
    if len(_WEARER) > 64:
        _WEARER.clear()
    look = facial_hair.for_wearer(garment.material, kind, age, colour)
    out = replace(garment, material=look)
    _WEARER[key] = (garment, out)
    return out


def parts(outfit: Outfit) -> list[MeshPart]:
    """MeshParts of an outfit's garments (skin indices into the body's skeleton)."""
    return [garment_part(g) for g in outfit.garments]


def garment_part(g: FittedGarment) -> MeshPart:
    """One fitted garment as a MeshPart for exporters and the Blender bridge."""
    return MeshPart(g.name, g.mesh, g.material, (g.weights.indices, g.weights.weights),
                    normals=garment_normals(g, g.mesh.vertices))  # fmt: skip


def garment_normals(g: FittedGarment, vertices: np.ndarray) -> np.ndarray | None:
    """(M, 3) float32 shading normals of a fitted garment at ``vertices`` (M, 3) (its rest
    or a posed frame): a shell's from its cloth layers alone (``shell.layer_normals``), so
    its hems read as edges, not as a roll; None (the renderer's own) without a shell."""
    shell = g.garment.shell
    return None if shell is None else layer_normals(shell, vertices)


__all__ = [
    "DEFAULT_OUTFIT",
    "FittedGarment",
    "Garment",
    "LibraryEntry",
    "Outfit",
    "dress",
    "entry_of",
    "find_garment",
    "find_reference",
    "garment_normals",
    "garment_part",
    "list_garments",
    "load_garment",
    "mhm_kind",
    "parts",
    "user_folders",
]
