"""Body presets: a few built-in bodies and the user's own, saved as JSON parameter sets in
Blender's user config folder (``avatar/presets/<name>.json``)."""

from __future__ import annotations

import json
import os
import re

import bpy

BUILTIN = {
    "default": {},
    "child": {"age": 0.12, "height": 0.4, "proportions": 0.3},
    "old_man": {"gender": 1.0, "age": 0.95, "weight": 0.6, "muscle": 0.35, "pca/belly": 1.0},
    "athletic_woman": {
        "gender": 0.0,
        "age": 0.45,
        "muscle": 0.8,
        "weight": 0.4,
        "proportions": 0.8,
        "pca/strength": 1.0,
    },
    "heavy_man": {"gender": 1.0, "age": 0.6, "weight": 0.95, "muscle": 0.4, "pca/belly": 2.0},
    "tall_woman": {"gender": 0.0, "height": 0.9, "proportions": 0.9, "weight": 0.45},
}


def folder() -> str:
    return bpy.utils.user_resource("CONFIG", path=os.path.join("avatar", "presets"))


def names() -> list[str]:
    user = []
    if os.path.isdir(folder()):
        user = sorted(f[:-5] for f in os.listdir(folder()) if f.endswith(".json"))
    return list(BUILTIN) + [n for n in user if n not in BUILTIN]


def load(name: str) -> dict[str, float]:
    """A preset's parameters. Raises KeyError for an unknown name, ValueError for a bad file."""
    if name in BUILTIN:
        return dict(BUILTIN[name])
    path = os.path.join(folder(), f"{name}.json")
    if not os.path.isfile(path):
        raise KeyError(name)
    with open(path) as f:
        data = json.load(f)
    if not isinstance(data, dict) or not all(isinstance(v, (int, float)) for v in data.values()):
        raise ValueError(f"{path}: not a parameter preset")
    return {str(k): float(v) for k, v in data.items()}


def save(name: str, params: dict[str, float]) -> str:
    """Save a user preset (written to a temporary file, then renamed); returns its path."""
    clean = re.sub(r"[^A-Za-z0-9_-]+", "_", name.strip()).strip("_").lower()
    if not clean or clean in BUILTIN:
        raise ValueError(f"choose another preset name than {name!r}")
    os.makedirs(folder(), exist_ok=True)
    path = os.path.join(folder(), f"{clean}.json")
    with open(path + ".tmp", "w") as f:
        json.dump(params, f, indent=1, sort_keys=True)
    os.replace(path + ".tmp", path)
    return path
