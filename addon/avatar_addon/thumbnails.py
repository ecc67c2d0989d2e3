"""Dress panel thumbnails (``bpy.utils.previews``): MakeHuman assets' own ``.thumb`` files,
and for built-in garments a swatch of their fabric in their colour, drawn once and cached
as PNG in Avatar's cache folder."""

from __future__ import annotations

import logging
import os

import bpy.utils.previews

log = logging.getLogger(__name__)

SIZE = 96


class Previews:
    """One feature's ``bpy.utils.previews`` collection: made on first use, released at
    unregister (Blender warns about collections left open), so each panel's icons live and
    die together."""

    def __init__(self) -> None:
        self._collection = None

    def get(self):
        if self._collection is None:
            self._collection = bpy.utils.previews.new()
        return self._collection

    def release(self) -> None:
        if self._collection is not None:
            bpy.utils.previews.remove(self._collection)
            self._collection = None


_DRESS = Previews()  # the Dress panel's library icons
release = _DRESS.release


def icon(entry: str, thumbnail: str) -> int:
    """The preview icon id of a library entry (0: none, the panel shows a plain button)."""
    previews = _DRESS.get()
    if entry in previews:
        return previews[entry].icon_id
    path = thumbnail if thumbnail and os.path.isfile(thumbnail) else _builtin_swatch(entry)
    if not path:
        return 0
    return previews.load(entry, path, "IMAGE").icon_id


def _builtin_swatch(name: str) -> str:
    """The cached swatch PNG of a built-in garment ("" for a user garment or on failure)."""
    try:
        from avatar.body import assets
        from avatar.clothes import builtin
        from avatar.io import png
        from avatar.looks import fabrics

        spec = builtin.BY_NAME.get(name)
        if spec is None:
            return ""
        folder = assets.cache_root() / "thumbnails"
        path = folder / f"{name}-{spec.fabric}-{spec.colour}.png".replace(" ", "_")
        if not path.is_file():
            folder.mkdir(parents=True, exist_ok=True)
            png.write(path, fabrics.colour_map(spec.fabric, spec.colour, SIZE))
        return str(path)
    except Exception as exc:  # noqa: BLE001 - a missing thumbnail must not break the panel
        log.warning("Avatar: no thumbnail for %s (%s)", name, exc)
        return ""
