"""Names the panels offer (local targets, garments), read from the library once per session.

Panels redraw often; these lists come from the compiled assets, so they are cached here.
Failures give empty lists: the operators report the real error when the user acts.
"""

from __future__ import annotations

import logging
from functools import lru_cache

log = logging.getLogger(__name__)


@lru_cache(maxsize=1)
def local_targets() -> tuple[str, ...]:
    """MakeHuman modifier names usable as local-target sliders (``torso/torso-scale-...``)."""
    try:
        from avatar.body.model import BodyModel

        model = BodyModel.load()
        return tuple(sorted(n for n, p in model.parameters.items() if p.kind == "modifier"))
    except Exception as exc:  # noqa: BLE001 - a panel must draw even without assets
        log.warning("Avatar: no local targets (%s)", exc)
        return ()


def garments() -> list[tuple[str, str, str]]:
    """(name, category, recipe entry) of every garment in the clothes library; the entry is
    the name of a built-in garment or the ``.mhclo`` path of a user's."""
    from avatar.clothes.library import list_garments

    return [(e.name, e.category, e.name if e.source == "builtin" else e.source)
            for e in list_garments()]  # fmt: skip
