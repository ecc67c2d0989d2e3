"""Avatar: realistic, rigged, dressed and animated 3D humans from MakeHuman's body model.

import avatar
human = avatar.Human({"gender": 1.0, "pca/belly": 1.0}).dressed("tshirt", "jeans")
avatar.save(human, "human.glb", human.walk())
skeleton, clip = avatar.load("clip.bvh")
animation, report = human.retarget(skeleton, clip)
"""

from __future__ import annotations

from avatar.body.model import BodyModel
from avatar.body.shaped import Body
from avatar.errors import AssetError, AvatarError, FormatError, ParameterError
from avatar.export import load, save
from avatar.human import Human, Recipe
from avatar.motion import load_bvh, retarget, save_bvh
from avatar.motion.procedural import walk

__version__ = "0.1.0"
__all__ = [
    "AssetError", "AvatarError", "Body", "BodyModel", "FormatError", "Human", "ParameterError",
    "Recipe", "load", "load_bvh", "retarget", "save", "save_bvh", "walk",
]  # fmt: skip
