"""Standing on shoes: how far a body rises when it wears built-in footwear.

A shaped body stands with its feet on z = 0 (``body.shaped.rest_vertices``). A shoe's sole
lies under the foot, so a shod body must stand up by the sole's depth, or the sole sinks
into the floor. ``sole_height`` measures that depth on the body itself: the footwear's
surface fitted on it (``fitting.fitted_surface``, what ``fitting`` does first) and the
shell's outer layer grown by its ``worn_thickness`` along the shoe's own normals, as
``fitting`` grows it; the lowest of those points is how far the floor is below the
soles. The composition root (``Human``) lifts the body, and so its rig and every garment,
by that much, and lifts settled poses by it too.
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Sequence

import numpy as np

from avatar.body.model import BODY_VERTICES, BodyModel
from avatar.clothes import builtin
from avatar.clothes.fitting import fitted_surface, shell_directions, worn_thickness
from avatar.geometry import collision

FOOTWEAR = "footwear"


def worn_footwear(clothes: Sequence[str]) -> list[str]:
    """The built-in footwear among garment names (MakeHuman assets are fitted as MakeHuman
    fits them, on feet at z = 0)."""
    return [c for c in clothes if c in builtin.BY_NAME and builtin.BY_NAME[c].category == FOOTWEAR]


def sole_height(
    vertices: np.ndarray,
    clothes: Sequence[str],
    folders: Iterable[str | os.PathLike[str]] = (),
    model: BodyModel | None = None,
) -> float:
    """Metres the body of ``vertices`` ((19158, 3), feet on z = 0) must rise for the lowest
    point of its built-in footwear to touch z = 0; 0.0 barefoot.

    clothes: garment names of the recipe; folders, model: as ``library.load_garment``.
    """
    from avatar.clothes import library  # library imports this module's callers

    names = worn_footwear(clothes)
    if not names:
        return 0.0
    model = model or BodyModel.shared()
    surface = collision.skin_surface(model.base.faces[model.base.face_groups["body"]])
    skin = np.asarray(vertices[:BODY_VERTICES], np.float32)
    lowest = np.inf
    for name in names:
        garment = library.load_garment(name, folders, model=model)
        points = fitted_surface(garment, vertices)
        # Only the bottom matters: the points within 2 cm of the lowest.
        low = np.flatnonzero(points[:, 2] < points[:, 2].min() + 0.02)
        q = collision.query(skin, surface, points[low], k=4)
        grown = shell_directions(garment, points, _skin_side(q.normal, low, len(points)))[low]
        outer = points[low] + np.float32(worn_thickness(garment, vertices)) * grown
        lowest = min(lowest, float(points[low, 2].min()), float(outer[:, 2].min()))
    return max(0.0, -lowest)


def _skin_side(normal: np.ndarray, rows: np.ndarray, count: int) -> np.ndarray:
    """(count, 3) the skin's normals at ``rows``, straight down elsewhere (only the bottom
    rows' shell is grown: the others' side is never read)."""
    side = np.tile(np.array([0, 0, -1], np.float32), (count, 1))
    side[rows] = normal
    return side


__all__ = ["sole_height", "worn_footwear"]
