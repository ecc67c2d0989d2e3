"""What the Motion panel reads often, read once: clips (by file version), the active
character's skeleton and roles (by recipe), and pose thumbnails (``bpy.utils.previews``).

Pose thumbnails: a pose file's MakeHuman ``.thumb`` beside it when there is one, else a
picture of the default body in that pose (``avatar.motion.thumbnail``), drawn once and
cached as PNG in Avatar's cache folder (``$AVATAR_CACHE`` or ``~/.cache/avatar``).
"""

from __future__ import annotations

import hashlib
import json
import logging
import os
from functools import lru_cache

from . import thumbnails

log = logging.getLogger(__name__)

THUMB_SIZE = 96
THUMB_VERSION = 1  # bump when the picture changes: cached files are keyed by it
_POSES = thumbnails.Previews()  # the pose library's icons


@lru_cache(maxsize=4)
def _clip(path: str, stamp: float):
    from avatar.motion import load_bvh

    return load_bvh(path)


def clip(path: str):
    """(Skeleton, Animation) of a BVH file, read once per file version."""
    return _clip(os.path.abspath(path), os.path.getmtime(path))


@lru_cache(maxsize=4)
def _human(recipe_json: str):
    from avatar.human import Human

    return Human.from_recipe(json.loads(recipe_json))


def human(root):
    """The ``Human`` a character's stored recipe realises (cached per recipe)."""
    from avatar.blender import character

    return _human(root[character.RECIPE_KEY])


@lru_cache(maxsize=4)
def _roles(recipe_json: str) -> tuple[tuple[str, str], ...]:
    from avatar.motion import mapping

    return tuple(mapping.roles_of(_human(recipe_json).skeleton).items())


def roles(root) -> dict[str, str]:
    """Avatar bone -> canonical role, for the character's rig."""
    from avatar.blender import character

    return dict(_roles(root[character.RECIPE_KEY]))


# ------------------------------------------------------------------ pose thumbnails


previews = _POSES.get
release = _POSES.release


def pose_icon(name: str, path: str) -> int:
    """The preview icon id of a pose (0: none; the panel then shows a plain button)."""
    key = f"{name}|{path}"
    collection = previews()
    if key in collection:
        return collection[key].icon_id
    image = thumbnail_path(name, path)
    if not image:
        return 0
    return collection.load(key, image, "IMAGE").icon_id


def thumbnail_path(name: str, path: str) -> str:
    """A pose's thumbnail file: its ``.thumb`` beside it, else the cached picture (drawn
    now if missing); "" when it cannot be made (logged)."""
    if path:
        thumb = os.path.splitext(path)[0] + ".thumb"
        if os.path.isfile(thumb):
            return thumb
    try:
        from avatar.body import assets

        stamp = f"{path}:{os.path.getmtime(path)}" if path and os.path.isfile(path) else ""
        digest = hashlib.blake2b(f"{THUMB_VERSION}|{name}|{stamp}".encode(),
                                 digest_size=6).hexdigest()  # fmt: skip
        safe = "".join(c if c.isalnum() or c in "-_" else "_" for c in name)
        target = assets.cache_root() / "thumbnails" / f"pose-{safe}-{digest}.png"
        if not target.is_file():
            draw_thumbnail(path or name, target)
        return str(target)
    except Exception as exc:  # noqa: BLE001 - a missing thumbnail must not break the panel
        log.warning("Avatar: no thumbnail for pose %s (%s)", name, exc)
        return ""


def draw_thumbnail(pose: str, target) -> None:
    """Draw the default body in ``pose`` (a name or a pose file) into the PNG ``target``."""
    from avatar.io import png
    from avatar.motion import thumbnail

    body = _default_human()
    target.parent.mkdir(parents=True, exist_ok=True)
    png.write(target, thumbnail.picture(body.body, body.pose(pose), THUMB_SIZE))


@lru_cache(maxsize=1)
def _default_human():
    from avatar.human import Human

    return Human({})
