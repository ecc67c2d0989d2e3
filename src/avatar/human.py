"""The composition root: a serialisable recipe and the human it realises.

human = Human({"gender": 1.0, "age": 0.4, "pca/belly": 1.5}, rig="game_engine")
human.mesh, human.skeleton, human.weights, human.posed(animation)
human.body     # the shaped body record (``avatar.body.shaped.Body``) the layers below take

Names are checked here, where they enter the library: parameters (``BodyModel.resolve``),
the rig, garments (``dressed``), each with close matches in the error.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field, replace
from functools import cached_property
from typing import Any

import numpy as np

from avatar.body import shaped
from avatar.body.assets import RIG_NAMES
from avatar.body.model import BodyModel
from avatar.body.shaped import PART_GROUPS, Body
from avatar.clothes import library
from avatar.clothes.outfit import Outfit
from avatar.errors import ParameterError, unknown_name
from avatar.io import mhm
from avatar.looks import skin
from avatar.material import Material
from avatar.mesh import Mesh
from avatar.motion import floor, poselib, procedural
from avatar.motion.retarget import RetargetReport, retarget
from avatar.part import MeshPart
from avatar.rig import kinematics, skinning
from avatar.rig.placement import RigDefinition
from avatar.rig.skeleton import Animation, Skeleton
from avatar.rig.skinning import SkinWeights

RECIPE_VERSION = 1
BODY_PART_GROUPS = PART_GROUPS


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

    @classmethod
    def from_mhm(cls, path: str | os.PathLike[str], rig: str | None = None) -> Recipe:
        """The recipe of a MakeHuman ``.mhm`` character file (modifiers, skeleton, clothes);
        ``rig`` overrides the file's skeleton."""
        character = mhm.read(path)
        return cls(params={**character.modifiers, **character.avatar_params},
                   rig=rig or character.rig or "default",
                   clothes=tuple(c.split()[0] for c in character.clothes))  # fmt: skip


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
        for garment in self.recipe.clothes:  # names, without building the garments
            library.find_garment(garment)

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
        return shaped.rest_vertices(self.model, self.recipe.params)

    @cached_property
    def body(self) -> Body:
        """The shaped body on its rig: the record clothes, motion and Blender take."""
        return Body(self.vertices, self.skeleton, self.weights, self.model, self.recipe.rig)

    def part(self, name: str) -> Mesh:
        """A renderable part ("body", "eyes") as its own Mesh (helpers excluded)."""
        base = self.model.base
        faces = np.sort(np.concatenate([base.face_groups[g] for g in BODY_PART_GROUPS[name]]))
        mesh = base.with_vertices(self.vertices).subset(faces)
        return _eye_uvs(mesh, faces, base) if name == "eyes" else mesh

    def part_vertices(self, name: str) -> np.ndarray:
        """Indices into ``vertices`` of a part's vertices, in the part mesh's order."""
        return shaped.part_vertices(self.model, name)

    @property
    def mesh(self) -> Mesh:
        """The skin mesh (13,380 vertices), the part most users want."""
        return self.part("body")

    # ------------------------------------------------------------------ rig
    @cached_property
    def rig(self) -> RigDefinition:
        return shaped.rig_definition(self.model, self.recipe.rig)

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

        def reference() -> Skeleton:  # MPFB pose files name the MakeHuman default rig's bones
            if self.recipe.rig == "default":
                return self.skeleton
            return shaped.rig_definition(self.model, "default").skeleton(self.vertices)

        pose = poselib.load(name, self.skeleton, folders, reference)
        return pose if name.lower() == "rest" else floor.settle_body(self.body, pose)[0]

    def walk(self, seconds: float = 2.0, fps: float = 30.0, cadence: float = 1.0) -> Animation:
        """The built-in walk on this human's rig, arms hung clear of its own torso
        (``avatar.motion.procedural.walk``)."""
        return procedural.walk(self.skeleton, seconds, fps, cadence, body=self.body)

    def retarget(
        self, source: Skeleton, animation: Animation, **options: Any
    ) -> tuple[Animation, RetargetReport]:
        """A clip on ``source`` retargeted onto this human and settled on its skin (planted
        feet on the floor); options as ``avatar.motion.retarget``."""
        return retarget(source, animation, self.skeleton, body=self.body, **options)

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
    def parts(self, expressions: bool = False, hide_covered: bool = False) -> list[MeshPart]:
        """MeshParts ready for exporters and the Blender bridge: body, eyes (+ garments).

        expressions: attach the 52 ARKit face units to the body as morph targets.
        hide_covered: drop body faces that the garments cover entirely (their
            ``delete_verts``); by default the whole body is kept, e.g. for cloth simulation.
        """
        # The procedural skin and eye textures (~0.3 s each, numpy that frees the GIL) are
        # drawn on other cores while the garments are made and fitted.
        with ThreadPoolExecutor(max_workers=len(BODY_PART_GROUPS)) as pool:
            materials = {name: pool.submit(self.material, name) for name in BODY_PART_GROUPS}
            garments = library.parts(self.outfit) if self.recipe.clothes else []
            out = []
            for name in BODY_PART_GROUPS:
                mesh, index = self.part(name), self.part_vertices(name)
                if name == "body" and hide_covered and self.recipe.clothes:
                    mesh, index = self._uncovered_body()
                morphs = self.expression_morphs(index) if expressions and name == "body" else {}
                skin = self.weights.subset(index)
                out.append(MeshPart(name, mesh, materials[name].result(),
                                    (skin.indices, skin.weights), morphs))  # fmt: skip
        return out + garments

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
    def outfit(self) -> Outfit:
        """The recipe's garments fitted on this body (``avatar.clothes.outfit.Outfit``),
        every vertex outside the body (``exact``: this is what exports and renders use)."""
        return library.dress(self.body, list(self.recipe.clothes), exact=True)

    def dressed(self, *garments: str) -> Human:
        """A copy of this human also wearing ``garments`` (library names or .mhclo paths).

        Raises ParameterError naming close matches for an unknown garment (checked here,
        without building it), AvatarError for a missing ``.mhclo`` file.
        """
        clothes = tuple(dict.fromkeys(self.recipe.clothes + tuple(str(g) for g in garments)))
        return Human(self.recipe.params, self.recipe.rig, self.model,
                     replace(self.recipe, clothes=clothes))  # fmt: skip

    def material(self, part: str) -> Material:
        """The generated material of a body part (procedural skin or eye)."""
        p = self.model.defaults() | self.recipe.params
        if part == "eyes":
            return skin.eye_material()
        return skin.skin_material(
            african=p["african"], asian=p["asian"], caucasian=p["caucasian"], age=p["age"]
        )

    # ------------------------------------------------------------------ MakeHuman files
    @classmethod
    def from_mhm(
        cls, path: str | os.PathLike[str], model: BodyModel | None = None, rig: str | None = None
    ) -> Human:
        """A human from a MakeHuman ``.mhm`` character file (modifiers, skeleton, clothes)."""
        return cls.from_recipe(Recipe.from_mhm(path, rig), model)

    def to_mhm(self, name: str = "avatar") -> mhm.CharacterFile:
        """This human as a MakeHuman character file record (``avatar.io.mhm``)."""
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
    assert mesh.uvs is not None and mesh.face_uvs is not None
    left = np.isin(faces, base.face_groups["helper-l-eye"])
    corners = mesh.uvs[mesh.face_uvs]  # (F, 4, 2) UV per face corner
    out = np.empty_like(corners)
    for side, rows in (("l", left), ("r", ~left)):
        out[rows] = skin.eye_uvs(corners[rows].reshape(-1, 2), side).reshape(-1, 4, 2)
    face_uvs = np.arange(out.shape[0] * out.shape[1], dtype=np.int32).reshape(out.shape[:2])
    return replace(mesh, uvs=out.reshape(-1, 2), face_uvs=face_uvs)
