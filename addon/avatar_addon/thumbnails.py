"""Dress panel thumbnails (``bpy.utils.previews``): MakeHuman assets' own ``.thumb`` files,
and for built-in garments a picture of the item as worn (``avatar.clothes.thumbnail``),
cached as PNG in Avatar's cache folder.

Drawing all built-ins' pictures takes about a minute (each item is built and fitted), too
long to hold Blender's interface, and garment building must not run in a thread inside
Blender (a k-d tree thread crashed it). So the first time the grid is shown without them,
a separate Python process draws the missing ones (``python -m avatar.clothes.thumbnail``)
while the grid shows each item's fabric swatch; a timer swaps each picture in as it lands.
"""

from __future__ import annotations

import logging
import os
import subprocess
import sys

import bpy
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
_SWATCHED: set[str] = set()  # built-ins showing a swatch until their picture lands
_DRAWER: list[subprocess.Popen] = []  # the process drawing the missing pictures
POLL_S = 1.0


def release() -> None:
    """Close the icons, stop the drawing process and its timer (unregister)."""
    _DRESS.release()
    _SWATCHED.clear()
    if bpy.app.timers.is_registered(_swap_pictures):
        bpy.app.timers.unregister(_swap_pictures)
    for process in _DRAWER:
        if process.poll() is None:
            process.terminate()
    _DRAWER.clear()


def icon(entry: str, thumbnail: str) -> int:
    """The preview icon id of a library entry (0: none, the panel shows a plain button)."""
    previews = _DRESS.get()
    if entry in previews:
        return previews[entry].icon_id
    path = thumbnail if thumbnail and os.path.isfile(thumbnail) else _builtin_picture(entry)
    if not path:
        path = _builtin_swatch(entry)
        if path:
            _SWATCHED.add(entry)
            _draw_pictures()
    if not path:
        return 0
    return previews.load(entry, path, "IMAGE").icon_id


def _builtin_picture(name: str) -> str:
    """The cached picture of a built-in item ("" while it is not drawn, or not a built-in)."""
    try:
        from avatar.clothes import builtin, thumbnail

        if name not in builtin.BY_NAME:
            return ""
        path = thumbnail.picture_path(name)
        return str(path) if path.is_file() else ""
    except Exception as exc:  # noqa: BLE001 - a missing picture must not break the panel
        log.warning("Avatar: no picture for %s (%s)", name, exc)
        return ""


def _draw_pictures() -> None:
    """Start, once a session, the process that draws the missing built-in pictures, and the
    timer that swaps them in. Nothing happens without a Python interpreter to run it."""
    if _DRAWER:
        return
    python = sys.executable or ""
    if "python" not in os.path.basename(python).lower():  # Blender itself: no interpreter
        log.info("Avatar: garment pictures need a Python interpreter; showing swatches")
        return
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(p for p in sys.path if p))
    command = [python, "-m", "avatar.clothes.thumbnail"]  # not the CLI: no extras needed
    try:
        _DRAWER.append(subprocess.Popen(command, env=env, stdin=subprocess.DEVNULL,
                                        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
    except OSError as exc:
        log.warning("Avatar: garment pictures not drawn (%s); showing swatches", exc)
        return
    if not bpy.app.timers.is_registered(_swap_pictures):
        bpy.app.timers.register(_swap_pictures, first_interval=POLL_S, persistent=True)


def _swap_pictures() -> float | None:
    """Timer: reload the icons of items whose picture has landed and redraw the sidebar;
    stops once every swatch is replaced or the drawing process has ended."""
    previews = _DRESS.get()
    landed = [name for name in _SWATCHED if _builtin_picture(name)]
    for name in landed:
        if name in previews:
            del previews[name]  # the grid's next draw loads the picture (``icon``)
        _SWATCHED.discard(name)
    if landed:
        _redraw_sidebars()
    process = _DRAWER[0] if _DRAWER else None
    if process is None or not _SWATCHED:
        return None
    if process.poll() is not None:
        if process.returncode:
            log.warning("Avatar: garment pictures stopped (exit %d); `avatar clothes "
                        "thumbnails` shows why", process.returncode)  # fmt: skip
        if not [name for name in _SWATCHED if _builtin_picture(name)]:
            return None
    return POLL_S


def _redraw_sidebars() -> None:
    for window in getattr(bpy.context.window_manager, "windows", ()):
        for area in window.screen.areas:
            if area.type == "VIEW_3D":
                area.tag_redraw()


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
