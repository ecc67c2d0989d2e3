"""Dress panel thumbnails (``bpy.utils.previews``): MakeHuman assets' own ``.thumb`` files,
and for built-in garments and user garments without one a picture of the item as worn
(``avatar.clothes.thumbnail``), cached as PNG in Avatar's cache folder.

Drawing all built-ins' pictures takes about a minute (each item is built and fitted), too
long to hold Blender's interface, and garment building must not run in a thread inside
Blender (a k-d tree thread crashed it). So the first time the grid is shown without them,
a separate Python process draws the missing ones (``python -m avatar.clothes.thumbnail``)
while the grid shows each built-in's fabric swatch (a user garment's plain button); a
timer swaps each picture in as it lands.
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
_SKINS = Previews()  # the Body panel's skin icons (their own .thumb files)
_WAITING: set[str] = set()  # entries whose picture is being drawn (a swatch or no icon)
_QUEUE: list[str] = []  # entries to draw, started together by ``draw_queued``
_DRAWER: list[subprocess.Popen] = []  # the processes drawing the missing pictures
POLL_S = 1.0


def release() -> None:
    """Close the icons, stop the drawing processes and their timer (unregister)."""
    _DRESS.release()
    _SKINS.release()
    _WAITING.clear()
    _QUEUE.clear()
    if bpy.app.timers.is_registered(_swap_pictures):
        bpy.app.timers.unregister(_swap_pictures)
    for process in _DRAWER:
        if process.poll() is None:
            process.terminate()
    _DRAWER.clear()


def icon(entry: str, thumbnail: str) -> int:
    """The preview icon id of a library entry (a built-in's name or a user garment's file;
    0: none, the panel shows a plain button). An entry with neither its own ``.thumb`` nor
    a drawn picture is queued for drawing (``draw_queued``): a built-in shows its fabric
    swatch meanwhile, a user garment a plain button."""
    previews = _DRESS.get()
    if entry in previews:
        return previews[entry].icon_id
    if entry in _WAITING:
        return 0
    path = thumbnail if thumbnail and os.path.isfile(thumbnail) else _picture(entry)
    if not path:
        _WAITING.add(entry)
        _QUEUE.append(entry)
        path = _builtin_swatch(entry)
    if not path:
        return 0
    return previews.load(entry, path, "IMAGE").icon_id


def skin_icon(path: str, thumbnail: str) -> int:
    """The preview icon id of a skin's picture (its ``.thumb``, else its texture; 0 when it
    cannot be read)."""
    previews = _SKINS.get()
    if path not in previews:
        if not os.path.isfile(thumbnail):
            return 0
        previews.load(path, thumbnail, "IMAGE")
    return previews[path].icon_id


def _picture(entry: str) -> str:
    """The cached picture of a library entry ("" while it is not drawn)."""
    try:
        from avatar.clothes import thumbnail

        path = thumbnail.picture_path(entry)
        return str(path) if path.is_file() else ""
    except Exception as exc:  # noqa: BLE001 - a missing picture must not break the panel
        log.warning("Avatar: no picture for %s (%s)", entry, exc)
        return ""


def draw_queued() -> None:
    """Start one process drawing the pictures ``icon`` queued (the grid calls it after its
    items), and the timer that swaps them in. Nothing happens without a Python
    interpreter to run it: the swatches and buttons stay."""
    if not _QUEUE:
        return
    items = list(dict.fromkeys(_QUEUE))
    _QUEUE.clear()
    python = sys.executable or ""
    if "python" not in os.path.basename(python).lower():  # Blender itself: no interpreter
        log.info("Avatar: garment pictures need a Python interpreter; showing swatches")
        return
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(p for p in sys.path if p))
    command = [python, "-m", "avatar.clothes.thumbnail", *items]  # not the CLI: no extras
    try:
        with open(_drawing_log(), "a", encoding="utf-8") as log_file:  # why one failed
            _DRAWER.append(subprocess.Popen(command, env=env, stdin=subprocess.DEVNULL,
                                            stdout=subprocess.DEVNULL, stderr=log_file))
    except OSError as exc:
        log.warning("Avatar: garment pictures not drawn (%s); showing swatches", exc)
        return
    if not bpy.app.timers.is_registered(_swap_pictures):
        bpy.app.timers.register(_swap_pictures, first_interval=POLL_S, persistent=True)


def _swap_pictures() -> float | None:
    """Timer: reload the icons of entries whose picture has landed and redraw the sidebar;
    stops once nothing waits or every drawing process has ended (an entry it could not
    draw keeps its swatch or button)."""
    previews = _DRESS.get()
    landed = [entry for entry in _WAITING if _picture(entry)]
    for entry in landed:
        if entry in previews:
            del previews[entry]  # the grid's next draw loads the picture (``icon``)
        _WAITING.discard(entry)
    if landed:
        _redraw_sidebars()
    if not _WAITING:
        return None
    running = [process for process in _DRAWER if process.poll() is None]
    for process in _DRAWER:
        if process not in running and process.returncode:
            log.warning("Avatar: some garment pictures not drawn (exit %d); %s says why",
                        process.returncode, _drawing_log())  # fmt: skip
    _DRAWER[:] = running
    return POLL_S if running else None


def _drawing_log() -> str:
    """The file the drawing processes write their errors to (one line per item)."""
    from avatar.body import assets

    folder = assets.cache_root() / "thumbnails"
    folder.mkdir(parents=True, exist_ok=True)
    return str(folder / "drawing.log")


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
