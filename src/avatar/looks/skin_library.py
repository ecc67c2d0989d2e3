"""MakeHuman and MPFB skins a user has: every ``.mhmat`` under a ``skins`` folder of their
asset folders whose diffuse texture is there (MakeHuman's ``skins/<name>/<name>.mhmat``,
its ``.thumb`` beside it). A recipe names one as ``skin_material``; without one, Avatar's
procedural skin follows ethnicity, age and gender.

    for skin in list_skins(["~/makehuman/v1py3/data"]):
        print(skin.name, skin.path, skin.thumbnail)

Untextured materials (MakeHuman's ``default.mhmat``, litsphere-only skins) are left out:
Avatar's own skin is better than a flat colour. A broken file is left out with a warning,
so one bad asset does not hide the others.
"""

from __future__ import annotations

import logging
import os
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

from avatar.errors import AvatarError, ParameterError, unknown_name
from avatar.io import mhmat

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class SkinEntry:
    """One skin: its name (the material's ``name`` line, else the file's stem), its
    ``.mhmat`` path and its thumbnail: a ``.thumb`` or ``.png`` beside it, else its diffuse
    texture (an unwrapped skin, shrunk to an icon, still shows its tone: a plain button for
    every user skin without a picture gave nothing to choose by)."""

    name: str
    path: str
    thumbnail: str


def list_skins(folders: Iterable[str | os.PathLike[str]]) -> list[SkinEntry]:
    """The textured skins under ``folders`` (each searched for ``skins`` folders, the
    folder itself included when it is one; a ``clothes`` folder's sibling ``skins`` too,
    as MakeHuman's data folder has them), sorted by name, each path once."""
    found: dict[str, SkinEntry] = {}
    roots = [Path(f).expanduser() for f in folders]
    roots += [r.parent / "skins" for r in roots if r.name.lower() == "clothes"]
    for root in roots:
        for path in _skin_files(root):
            key = str(path.resolve())
            if key not in found:
                entry = _entry(path)
                if entry is not None:
                    found[key] = entry
    return sorted(found.values(), key=lambda e: (e.name.lower(), e.path))


def _skin_files(root: Path) -> list[Path]:
    if not root.is_dir():
        return []
    tops = [root] if root.name.lower() == "skins" else []
    tops += [p for p in root.rglob("*") if p.is_dir() and p.name.lower() == "skins"]
    return sorted({p for top in tops for p in top.rglob("*.mhmat")})


def _entry(path: Path) -> SkinEntry | None:
    try:
        material = mhmat.read(path)
        textures = mhmat.texture_paths(material, path.parent, path)
    except (AvatarError, OSError) as exc:
        log.warning("skin %s left out: %s", path, exc)
        return None
    if "diffuseTexture" not in textures:
        return None
    beside = (path.with_suffix(".thumb"), path.with_suffix(".png"))
    thumbnail = next((t for t in beside if t.is_file()), textures["diffuseTexture"])
    return SkinEntry(material.name or path.stem, str(path), str(thumbnail))


def find_skin(name_or_path: str, folders: Iterable[str | os.PathLike[str]]) -> str:
    """The ``.mhmat`` of a skin named by path or by name (a ``list_skins`` entry's name or
    file stem). Raises ParameterError (close matches named) for an unknown name, and
    AvatarError for a file that is missing or has no diffuse texture."""
    path = Path(name_or_path).expanduser()
    if path.suffix.lower() == ".mhmat" or path.is_file():
        if not path.is_file():
            raise ParameterError(f"{name_or_path}: no such skin material file")
        material = mhmat.read(path)
        if "diffuseTexture" not in mhmat.texture_paths(material, path.parent, path):
            raise ParameterError(f"{name_or_path}: the skin has no diffuse texture")
        return str(path)
    skins = list_skins(folders)
    for skin in skins:
        if name_or_path in (skin.name, Path(skin.path).stem):
            return skin.path
    if not skins:
        raise ParameterError(f"unknown skin {name_or_path!r}: no textured skins in the asset "
                             "folders (--folder, $AVATAR_CLOTHES_PATH); give a .mhmat path")
    raise unknown_name("skin", name_or_path, [s.name for s in skins])
