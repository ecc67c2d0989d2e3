"""Property changes -> the library's in-place updates (``avatar.blender.live``).

A slider (or a script) setting ``object.avatar.weight`` calls ``apply_params``: the body,
skeleton and garments move at once, fitted the real-time way, as a drag step
(``avatar.blender.live.set_params(drag=True)``: the new joints shown through the pose, no
edit-mode trip, so Blender re-evaluates this character only); a timer then settles the
character (true rest bones, garments exact, skin texture of the new ethnicity/age/gender,
measurements) once no change came for ``SETTLE_DELAY`` seconds. Headless scripts, where
timers do not run, call ``settle_now`` (``bpy.ops.avatar.settle``). A character caught
mid-drag by an undo, redo or file load is settled again; one is never saved mid-drag
(handlers installed with the first change, ``install_handlers``).

Errors inside a property callback cannot reach the status bar: they are logged and kept
on the object (``ERROR_KEY``) for the Body panel to show; the character is left unchanged.
"""

import logging
import time
from contextlib import contextmanager

import bpy

log = logging.getLogger(__name__)

SETTLE_DELAY = 0.3  # s of no change before the exact pass
ERROR_KEY = "avatar_error"
_SUSPENDED: set = set()  # roots whose callbacks are off (while many properties are set)
_PENDING: dict = {}  # root name -> time of its last change, waiting to settle


@contextmanager
def suspended(root):
    """Set many properties of ``root.avatar`` with one update at most (by the caller)."""
    _SUSPENDED.add(root.name_full)
    try:
        yield
    finally:
        _SUSPENDED.discard(root.name_full)


def apply_params(root) -> bool:
    """Write ``root.avatar``'s parameters into its character; True when it changed."""
    if root.name_full in _SUSPENDED:
        return False
    from avatar.blender import live
    from avatar.errors import AvatarError

    try:
        live.set_params(root, root.avatar.params(), drag=True)
    except AvatarError as exc:
        root[ERROR_KEY] = str(exc)
        log.error("Avatar: %s", exc)
        return False
    if ERROR_KEY in root.keys():
        del root[ERROR_KEY]
    schedule_settle(root)
    return True


def schedule_settle(root) -> None:
    """Settle ``root``'s character once it has had no change for ``SETTLE_DELAY`` s."""
    _PENDING[root.name_full] = time.monotonic()
    install_handlers()
    if not bpy.app.timers.is_registered(_settle_pending):
        bpy.app.timers.register(_settle_pending, first_interval=SETTLE_DELAY)


def _dragging_roots() -> list:
    """Characters whose pose stands in for their rest (a drag not settled yet)."""
    from avatar.blender import live

    return [o for o in bpy.data.objects if o.type == "ARMATURE" and live.is_dragging(o)]


@bpy.app.handlers.persistent
def _resume_settling(*_args) -> None:
    """After an undo, redo or file load: a character caught mid-drag settles again (the
    step restored may be one Blender pushed at the end of a drag, before its settle)."""
    if not _registered():
        return
    for root in _dragging_roots():
        schedule_settle(root)


@bpy.app.handlers.persistent
def _settle_before_save(*_args) -> None:
    """A file is never written mid-drag: such characters settle first."""
    if not _registered():
        return
    for root in _dragging_roots():
        try:
            settle_now(root)
        except Exception as exc:  # noqa: BLE001 - a save handler must never raise into Blender
            log.error("Avatar: settling %s before saving failed: %s", root.name, exc)


_HANDLERS = (("undo_post", _resume_settling), ("redo_post", _resume_settling),
             ("load_post", _resume_settling), ("save_pre", _settle_before_save))  # fmt: skip


def _registered() -> bool:
    """Whether the add-on is registered: a disabled one's handlers do nothing (they are
    not taken off here, while Blender walks their list; ``release`` does that)."""
    return hasattr(bpy.types.Object, "avatar")


_INSTALLED = {"done": False}  # install_handlers ran (every change asks: keep it cheap)


def install_handlers() -> None:
    """The undo/redo/load and save handlers above, once (replacing those of an earlier
    load of this module, e.g. after the add-on was disabled and enabled again)."""
    if _INSTALLED["done"]:
        return
    _INSTALLED["done"] = True
    for kind, handler in _HANDLERS:
        handlers = getattr(bpy.app.handlers, kind)
        if handler in handlers:
            continue
        for old in [h for h in handlers if _same(h, handler)]:
            handlers.remove(old)
        handlers.append(handler)


def release() -> None:
    """Take this module's handlers off (unregister)."""
    _INSTALLED["done"] = False
    for kind, handler in _HANDLERS:
        handlers = getattr(bpy.app.handlers, kind)
        for old in [h for h in handlers if _same(h, handler)]:
            handlers.remove(old)


def _same(a, b) -> bool:
    return getattr(a, "__module__", None) == b.__module__ and a.__name__ == b.__name__


def _settle_pending():
    now = time.monotonic()
    for name, when in list(_PENDING.items()):
        if now - when < SETTLE_DELAY:
            continue
        del _PENDING[name]
        root = bpy.data.objects.get(name)
        if root is not None:
            try:
                settle_now(root)
            except Exception as exc:  # noqa: BLE001 - a timer must never raise into Blender
                log.error("Avatar: settling %s failed: %s", name, exc)
    return SETTLE_DELAY if _PENDING else None


def settle_now(root) -> None:
    """The exact pass on ``root``'s character now; measurements refreshed."""
    from avatar.blender import live
    from avatar.body import measures

    _PENDING.pop(root.name_full, None)
    geo = live.settle(root)
    got = measures.measure(geo.body.vertices, geo.body.model.base)
    with suspended(root):
        for name, value in got.items():
            setattr(root.avatar, f"measured_{name}", value * 100.0)


def normalise_races(props, changed: str) -> None:
    """MakeHuman's ethnicity mix: the other two races share what ``changed`` leaves, in
    their current proportion (equally when both are 0), so the three sum to 1."""
    root = props.id_data
    if root.name_full in _SUSPENDED:
        return
    from .properties import RACES

    others = [r for r in RACES if r != changed]
    left = max(0.0, 1.0 - getattr(props, changed))
    total = sum(getattr(props, r) for r in others)
    with suspended(root):
        for r in others:
            share = getattr(props, r) / total if total > 1e-9 else 0.5
            setattr(props, r, left * share)


def change_rig(root, rig: str) -> None:
    """A new rig is a new armature: rebuild the character (the operator path)."""
    if root.name_full in _SUSPENDED:
        return
    from avatar.blender import character
    from avatar.errors import AvatarError

    recipe = character.recipe_of(root)
    if recipe.get("rig") == rig:
        return
    recipe["rig"] = rig
    try:
        built = character.update(root, recipe)
    except AvatarError as exc:
        root[ERROR_KEY] = str(exc)
        log.error("Avatar: %s", exc)
        return
    sync_from_recipe(built.root)


def change_eyes(root, colour: str) -> None:
    """Another iris colour: only the eyes' material changes (``character.set_looks``)."""
    if root.name_full in _SUSPENDED:
        return
    from avatar.blender import character
    from avatar.errors import AvatarError

    try:
        character.set_looks(root, eye_material=f"eyes/materials/{colour}.mhmat")
    except AvatarError as exc:
        root[ERROR_KEY] = str(exc)
        log.error("Avatar: %s", exc)


def _eye_colour(eye_material) -> str:
    """The Eyes menu's entry for a recipe's eye material (MakeHuman's names mapped)."""
    from pathlib import Path

    from avatar.human import EYE_COLOURS

    from .properties import EYES

    stem = Path(eye_material or "brown").stem.lower()
    colour = EYE_COLOURS.get(stem, "brown")
    return colour if colour in EYES else "brown"


def sync_from_recipe(root) -> None:
    """Set ``root.avatar`` from the stored recipe (no update runs): after a create, a
    rebuild, a preset or an undo of something the properties do not hold."""
    from avatar.blender import character

    from . import catalogue
    from .properties import ATTRIBUTES, MACROS, RACES

    recipe = character.recipe_of(root)
    params = recipe.get("params") or {}
    props = root.avatar
    with suspended(root):
        for m in (*MACROS, *RACES):
            setattr(props, m, params.get(m, 1 / 3 if m in RACES else 0.5))
        for a in ATTRIBUTES:
            setattr(props, f"pca_{a}", params.get(f"pca/{a}", 0.0))
        if recipe.get("rig") and recipe["rig"] != props.rig:
            props.rig = recipe["rig"]
        eyes = _eye_colour(recipe.get("eye_material"))
        if eyes != props.eyes:
            props.eyes = eyes
        if len(props.modifiers) == 0:
            for name, label, group, minimum in catalogue.modifier_rows():
                item = props.modifiers.add()
                item.name, item.label, item.group, item.minimum = name, label, group, minimum
        for item in props.modifiers:
            value = params.get(item.name, 0.0)
            if item.value != value:
                item.value = value
