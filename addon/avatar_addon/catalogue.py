"""Names the panels offer (local modifiers, face units, garments, thumbnails), read from the
library once per session.

Panels redraw often; these lists come from the compiled assets, so they are cached here.
Failures give empty lists: the operators report the real error when the user acts.
"""

from __future__ import annotations

import logging
from functools import lru_cache

log = logging.getLogger(__name__)

_ENUM_CACHE: list = []  # Blender needs enum item strings kept alive by Python


@lru_cache(maxsize=1)
def local_targets() -> tuple[str, ...]:
    """MakeHuman modifier names usable as local-target sliders (``torso/torso-scale-...``)."""
    return tuple(name for name, _, group, _ in modifier_rows() if group != "expression")


@lru_cache(maxsize=1)
def modifier_rows() -> tuple[tuple[str, str, str, float], ...]:
    """(name, label, group, minimum) of every local modifier (grouped as MakeHuman groups
    them: armslegs, torso, head, ...) and face unit (group "expression"), sorted."""
    try:
        from avatar.body.model import BodyModel

        params = BodyModel.shared().parameters.values()
    except Exception as exc:  # noqa: BLE001 - a panel must draw even without assets
        log.warning("Avatar: no local modifiers (%s)", exc)
        return ()
    rows = []
    for p in params:
        if p.kind == "modifier":
            group, _, short = p.name.partition("/")
            rows.append((p.name, short.replace("-decr|incr", "").replace("|", " / "), group,
                         p.minimum))  # fmt: skip
        elif p.kind == "expression":
            rows.append((p.name, p.name.split("/", 1)[1], "expression", 0.0))
    return tuple(sorted(rows, key=lambda r: (r[2], r[1])))


@lru_cache(maxsize=1)
def groups() -> tuple[str, ...]:
    """The local modifier groups, in order."""
    return tuple(dict.fromkeys(r[2] for r in modifier_rows() if r[2] != "expression"))


def garments() -> list[tuple[str, str, str, str]]:
    """(name, category, recipe entry, thumbnail path or "") of every garment in the clothes
    library; the entry is a built-in's name or a user garment's ``.mhclo`` path."""
    from avatar.clothes.library import list_garments

    return [(e.name, e.category, e.name if e.source == "builtin" else e.source,
             e.thumbnail or "") for e in list_garments()]  # fmt: skip


@lru_cache(maxsize=1)
def skins() -> tuple[tuple[str, str, str], ...]:
    """(name, .mhmat path, picture path) of every textured MakeHuman/MPFB skin in
    the user's asset folders (``looks.skin_library``); ``refresh`` reads them again."""
    try:
        from avatar.clothes.library import user_folders
        from avatar.looks.skin_library import list_skins

        return tuple((s.name, s.path, s.thumbnail) for s in list_skins(user_folders()))
    except Exception as exc:  # noqa: BLE001 - a panel must draw even without assets
        log.warning("Avatar: no skins listed (%s)", exc)
        return ()


def enum_items(names) -> list[tuple[str, str, str]]:
    items = [(n, n.replace("_", " ").title(), "") for n in names]
    _ENUM_CACHE[:] = items
    return items
