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


def garments() -> list[tuple[str, str]]:
    """(name, category) of every garment in the clothes library."""
    try:
        from avatar.clothes import library
    except ImportError as exc:
        log.warning("Avatar: no clothes library (%s)", exc)
        return []
    return [(g.name, getattr(g, "category", "")) for g in library.catalogue()]
