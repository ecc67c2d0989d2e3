"""The composition root: a serialisable recipe and the human it realises.

human = Human({"gender": 1.0, "age": 0.4, "pca/belly": 1.5}, rig="game_engine")
human.mesh, human.skeleton, human.weights, human.posed(animation)
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from functools import cached_property
from typing import Any

import numpy as np

from avatar.body.assets import RIG_NAMES
from avatar.body.model import BodyModel
from avatar.errors import ParameterError, unknown_name
from avatar.mesh import Mesh
from avatar.rig import kinematics, skinning
from avatar.rig.placement import RigDefinition
from avatar.rig.skeleton import Animation, Skeleton
from avatar.rig.skinning import SkinWeights

RECIPE_VERSION = 1
BODY_PART_GROUPS = {"body": ("body",), "eyes": ("helper-l-eye", "helper-r-eye")}


@dataclass(frozen=True)
class Recipe:
    """Everything that defines a character; plain data, JSON-serialisable."""

    params: dict[str, float] = field(default_factory=dict)
    rig: str = "default"
    pose: str | None = None
    clothes: tuple[str, ...] = ()
    motion: str | None = None

    def to_dict(self) -> dict[str, Any]:
        return {
            "version": RECIPE_VERSION,
            "params": dict(self.params),
            "rig": self.rig,
            "pose": self.pose,
            "clothes": list(self.clothes),
            "motion": self.motion,
        }

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> Recipe:
        unknown = set(data) - {"version", "params", "rig", "pose", "clothes", "motion"}
        if unknown:
            raise ParameterError(f"unknown recipe fields: {', '.join(sorted(unknown))}")
        return cls(
            params={str(k): float(v) for k, v in (data.get("params") or {}).items()},
            rig=str(data.get("rig", "default")),
            pose=data.get("pose"),
            clothes=tuple(data.get("clothes") or ()),
            motion=data.get("motion"),
        )


class Human:
    """A shaped, rigged human realised from a recipe. Arrays are computed lazily, once.

    model: the body model; by default the one this thread shares (``BodyModel.shared``),
    so making many humans costs ~1 ms each, not a model load each.
    """

    def __init__(
        self,
        params: Mapping[str, float] | None = None,
        rig: str = "default",
        model: BodyModel | None = None,
        recipe: Recipe | None = None,
    ):
        if rig not in RIG_NAMES:
            raise unknown_name("rig", rig, RIG_NAMES)
        self.model = model or BodyModel.shared()
        values = self.model.resolve(params)  # validates names and ranges up front
        self.recipe = replace(recipe or Recipe(), params=values, rig=rig)

    @classmethod
    def from_recipe(
        cls, recipe: Recipe | Mapping[str, Any], model: BodyModel | None = None
    ) -> Human:
        r = recipe if isinstance(recipe, Recipe) else Recipe.from_dict(recipe)
        return cls(r.params, r.rig, model, r)

    def to_recipe(self) -> dict[str, Any]:
        return self.recipe.to_dict()

    @property
    def params(self) -> dict[str, float]:
        return dict(self.recipe.params)

    # ------------------------------------------------------------------ geometry
    @cached_property
    def vertices(self) -> np.ndarray:
        """(19158, 3) float32 all vertices incl. helpers, metres, Z-up, feet on z = 0."""
        v = self.model.shape(self.recipe.params)
        ground = v[self.model.base.groups["joint-ground"], 2].mean()
        return (v - np.array([0.0, 0.0, ground], dtype=np.float32)).astype(np.float32)

    def part(self, name: str) -> Mesh:
        """A renderable part ("body", "eyes") as its own Mesh (helpers excluded)."""
        base = self.model.base
        faces = np.sort(np.concatenate([base.face_groups[g] for g in BODY_PART_GROUPS[name]]))
        mesh = base.with_vertices(self.vertices).subset(faces)
        return _eye_uvs(mesh, faces, base) if name == "eyes" else mesh

    def part_vertices(self, name: str) -> np.ndarray:
        """Indices into ``vertices`` of a part's vertices, in the part mesh's order."""
        base = self.model.base
        faces = np.concatenate([base.face_groups[g] for g in BODY_PART_GROUPS[name]])
        return np.unique(base.faces[faces])

    @property
    def mesh(self) -> Mesh:
        """The skin mesh (13,380 vertices), the part most users want."""
        return self.part("body")

    # ------------------------------------------------------------------ rig
    @cached_property
    def rig(self) -> RigDefinition:
        return RigDefinition.from_json(
            self.recipe.rig, self.model.assets.rig(self.recipe.rig), self.model.base.groups
        )

    @cached_property
    def skeleton(self) -> Skeleton:
        """The rig placed on this body, in rest pose."""
        return self.rig.skeleton(self.vertices)

    @cached_property
    def weights(self) -> SkinWeights:
        """Skin weights of all 19,158 vertices over ``skeleton``'s bones (shared by every
        body of the rig: weights do not depend on the shape)."""
        return self.model.skin_weights(self.recipe.rig, tuple(self.skeleton.names))

    def pose(self, name: str, folders: Sequence[str] = ()) -> Animation:
        """A pose for this rig (1 frame): "rest", "a-pose", "t-pose" (any rig, from its
        geometry), a pose of the library (``folders``, ``$AVATAR_POSES_PATH``), or a
        ``.bvh``/MPFB ``.json`` pose file; all but "rest" stood on the floor (lowest skin
        vertex at z = 0, ``motion.floor.settle``). See ``avatar.motion.poselib``."""
        from avatar.motion import floor, poselib

        def reference() -> Skeleton:  # MPFB pose files name the MakeHuman default rig's bones
            return Human(self.params, "default", self.model).skeleton

        pose = poselib.load(name, self.skeleton, folders, reference)
        return pose if name.lower() == "rest" else floor.settle_human(self, pose)[0]

    def posed(
        self, animation: Animation, frames: slice | None = None, method: str = "lbs"
    ) -> np.ndarray:
        """(T, 19158, 3) posed vertices for an animation on this skeleton (LBS or DQS)."""
        rot = animation.rotations[frames or slice(None)]
        trans = animation.translations[frames or slice(None)]
        world = kinematics.forward(self.skeleton, rot, trans)
        mats = kinematics.skinning_matrices(self.skeleton, world)
        skin = skinning.dual_quaternion if method == "dqs" else skinning.linear_blend
        return skin(self.vertices, self.weights, mats)

    # ------------------------------------------------------------------ export
    def parts(self, expressions: bool = False, hide_covered: bool = False) -> list:
        """MeshParts ready for exporters and the Blender bridge: body, eyes (+ garments).

        expressions: attach the 52 ARKit face units to the body as morph targets.
        hide_covered: drop body faces that the garments cover entirely (their
            ``delete_verts``); by default the whole body is kept, e.g. for cloth simulation.
        """
        from avatar.part import MeshPart

        out = []
        for name in BODY_PART_GROUPS:
            mesh, index = self.part(name), self.part_vertices(name)
            if name == "body" and hide_covered and self.recipe.clothes:
                mesh, index = self._uncovered_body()
            morphs = self.expression_morphs(index) if expressions and name == "body" else {}
            skin = self.weights.subset(index)
            out.append(MeshPart(name, mesh, self.material(name), (skin.indices, skin.weights),
                                morphs))  # fmt: skip
        if self.recipe.clothes:
            from avatar.clothes import library

            out += library.parts(self.outfit)
        return out

    def _uncovered_body(self) -> tuple[Mesh, np.ndarray]:
        """The skin without faces every corner of which some garment covers."""
        base = self.model.base
        covered = np.zeros(len(self.vertices), dtype=bool)
        for g in self.outfit.garments:
            covered[g.delete_verts] = True
        faces = base.face_groups["body"]
        keep = np.sort(faces[~covered[base.faces[faces]].all(axis=1)])
        return base.with_vertices(self.vertices).subset(keep), np.unique(base.faces[keep])

    def expression_morphs(self, vertices: np.ndarray | None = None) -> dict[str, np.ndarray]:
        """ARKit face unit name -> (n, 3) float32 deltas (metres) of ``vertices``
        (default: the skin's 13,380 vertices)."""
        index = self.part_vertices("body") if vertices is None else vertices
        out = {}
        for name in self.model.target_names:
            if name.startswith("faceunits/"):
                delta = self.model.displacement({"expression/" + name[10:]: 1.0})
                out[name[10:]] = delta[index]
        return out

    @cached_property
    def outfit(self):
        """The recipe's garments fitted on this body (``avatar.clothes.fitting.Outfit``),
        every vertex outside the body (``exact``: this is what exports and renders use)."""
        from avatar.clothes import library

        return library.dress(self, list(self.recipe.clothes), exact=True)

    def dressed(self, *garments: str) -> Human:
        """A copy of this human also wearing ``garments`` (library names or .mhclo paths)."""
        clothes = tuple(dict.fromkeys(self.recipe.clothes + tuple(str(g) for g in garments)))
        return Human(self.recipe.params, self.recipe.rig, self.model,
                     replace(self.recipe, clothes=clothes))  # fmt: skip

    def material(self, part: str):
        """The generated material of a body part (procedural skin or eye)."""
        from avatar.looks import skin

        p = self.model.defaults() | self.recipe.params
        if part == "eyes":
            return skin.eye_material()
        return skin.skin_material(
            african=p["african"], asian=p["asian"], caucasian=p["caucasian"], age=p["age"]
        )

    # ------------------------------------------------------------------ MakeHuman files
    @classmethod
    def from_mhm(cls, path: str, model: BodyModel | None = None, rig: str | None = None) -> Human:
        """A human from a MakeHuman ``.mhm`` character file (modifiers, skeleton, clothes)."""
        from avatar.io import mhm

        character = mhm.read(path)
        params = {**character.modifiers, **character.avatar_params}
        recipe = Recipe(clothes=tuple(c.split()[0] for c in character.clothes))
        return cls(params, rig or character.rig or "default", model, recipe)

    def to_mhm(self, name: str = "avatar"):
        """This human as a MakeHuman character file record (``avatar.io.mhm``)."""
        from avatar.io import mhm

        out = mhm.CharacterFile(name=name, skeleton=f"{self.recipe.rig}.mhskel")
        values = self.model.defaults() | self.recipe.params
        for key, value in values.items():
            p = self.model.parameters[key]
            if p.mhm_name:
                out.modifiers[p.mhm_name] = value
            else:
                out.avatar_params[key] = value
        out.clothes = list(self.recipe.clothes)
        return out


def _eye_uvs(mesh: Mesh, faces: np.ndarray, base: Mesh) -> Mesh:
    """The eyes with UVs spread over the procedural eye texture (one texture, both eyes)."""
    from avatar.looks import skin

    assert mesh.uvs is not None and mesh.face_uvs is not None
    left = np.isin(faces, base.face_groups["helper-l-eye"])
    corners = mesh.uvs[mesh.face_uvs]  # (F, 4, 2) UV per face corner
    out = np.empty_like(corners)
    for side, rows in (("l", left), ("r", ~left)):
        out[rows] = skin.eye_uvs(corners[rows].reshape(-1, 2), side).reshape(-1, 4, 2)
    face_uvs = np.arange(out.shape[0] * out.shape[1], dtype=np.int32).reshape(out.shape[:2])
    return replace(mesh, uvs=out.reshape(-1, 2), face_uvs=face_uvs)
