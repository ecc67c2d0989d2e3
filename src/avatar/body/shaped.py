"""The shaped body record: what clothes, motion and the Blender bridge take.

``avatar.human.Human`` realises one from a recipe; nothing below it builds a ``Human``.

    body = human.body
    body.vertices            # (19158, 3) float32, helpers included, feet on z = 0
    body.skin_vertices       # (13380, 3) the skin alone
    body.skeleton, body.weights, body.model, body.rig
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from functools import cached_property, lru_cache

import numpy as np

from avatar.body.assets import RIG_NAMES
from avatar.body.model import BODY_VERTICES, BodyModel
from avatar.errors import unknown_name
from avatar.rig.placement import RigDefinition
from avatar.rig.skeleton import Skeleton
from avatar.rig.skinning import SkinWeights

# Renderable parts of the base mesh by their face groups (other helpers excluded). Teeth
# and tongue sit inside the mouth: the lower teeth are weighted to the jaw and the tongue
# to its bones, and the face units (``expression/jawOpen``) move them with the jaw.
PART_GROUPS = {
    "body": ("body",),
    "eyes": ("helper-l-eye", "helper-r-eye"),
    "teeth": ("helper-upper-teeth", "helper-lower-teeth"),
    "tongue": ("helper-tongue",),
}


@dataclass(frozen=True, eq=False)
class Body:
    """A shaped body on its rig, at rest.

    vertices: (19158, 3) float32 every base-mesh vertex (skin 0..13379, then helpers),
        metres, Z-up, facing -Y, feet on z = 0.
    skeleton: the rig placed on this body, rest pose.
    weights: skin weights of all 19,158 vertices over ``skeleton``'s bones.
    model: the BodyModel the body came from (its topology: ``model.base``).
    rig: the rig's name (``avatar.body.assets.RIG_NAMES``).
    """

    vertices: np.ndarray
    skeleton: Skeleton
    weights: SkinWeights
    model: BodyModel
    rig: str

    @property
    def faces(self) -> np.ndarray:
        """(F, 4) int32 the base mesh's faces (every body of a model shares them)."""
        return self.model.base.faces

    @property
    def skin_vertices(self) -> np.ndarray:
        """(13380, 3) float32 the skin's vertices (a view)."""
        return self.vertices[:BODY_VERTICES]

    @cached_property
    def skin_index(self) -> np.ndarray:
        """Indices into ``vertices`` of the skin part's vertices, in its mesh's order."""
        return part_vertices(self.model, "body")

    @cached_property
    def skin_weights(self) -> SkinWeights:
        """The weights of the skin part's vertices (``skin_index``)."""
        return self.weights.subset(self.skin_index)


def rest_vertices(model: BodyModel, values: Mapping[str, float]) -> np.ndarray:
    """(19158, 3) float32 the body of resolved parameter ``values``, feet on z = 0 (the
    mean of MakeHuman's ``joint-ground`` helper)."""
    v = model.shape(values)
    ground = v[model.base.groups["joint-ground"], 2].mean()
    return (v - np.array([0.0, 0.0, ground], dtype=np.float32)).astype(np.float32)


@lru_cache(maxsize=4)
def default_vertices(model: BodyModel) -> np.ndarray:
    """``rest_vertices`` of the model's default body (every parameter at its default),
    computed once per model: garments find their anchor triangles on it."""
    v = rest_vertices(model, {})
    v.setflags(write=False)
    return v


def rig_definition(model: BodyModel, rig: str) -> RigDefinition:
    """A rig's definition (how its joints sit on the mesh) over the model's topology.
    Raises ParameterError naming close matches for an unknown rig."""
    if rig not in RIG_NAMES:
        raise unknown_name("rig", rig, RIG_NAMES)
    return RigDefinition.from_json(rig, model.assets.rig(rig), model.base.groups)


def realise(model: BodyModel, vertices: np.ndarray, rig: str) -> Body:
    """The Body of ``vertices`` (19158, 3) (``rest_vertices``) with ``rig`` placed on it."""
    skeleton = rig_definition(model, rig).skeleton(vertices)
    return Body(vertices, skeleton, model.skin_weights(rig, tuple(skeleton.names)), model, rig)


@lru_cache(maxsize=8)
def default_body(model: BodyModel, rig: str = "default") -> Body:
    """The model's default body (every parameter at its default) on ``rig``, made once
    per model: the body built-in garments are cut from."""
    return realise(model, default_vertices(model), rig)


def part_vertices(model: BodyModel, name: str) -> np.ndarray:
    """Indices into the base mesh's vertices of a renderable part (``PART_GROUPS``)."""
    base = model.base
    faces = np.concatenate([base.face_groups[g] for g in PART_GROUPS[name]])
    return np.unique(base.faces[faces])
