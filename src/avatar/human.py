"""The composition root: a serialisable recipe and the human it realises.

human = Human({"gender": 1.0, "age": 0.4, "pca/belly": 1.5}, rig="game_engine")
human.mesh, human.skeleton, human.weights, human.posed(animation)
human.body     # the shaped body record (``avatar.body.shaped.Body``) the layers below take

Names are checked here, where they enter the library: parameters (``BodyModel.resolve``),
the rig, garments (``dressed``), each with close matches in the error.
"""

from __future__ import annotations

import json
import logging
import os
from collections.abc import Mapping, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field, replace
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np

from avatar.body import shaped
from avatar.body.assets import RIG_NAMES
from avatar.body.model import BodyModel
from avatar.body.shaped import PART_GROUPS, Body
from avatar.clothes import face, footing, library, variants
from avatar.clothes.asset import material_from_file
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

log = logging.getLogger(__name__)

RECIPE_VERSION = 3  # 2: MakeHuman looks (eyes, skin, expression, ...), hide_covered, folders
# 3: garment_options (fabric/colour variants of built-ins)
MHM_GARMENT = "avatar-garment"  # .mhm line: avatar-garment <entry> <options as JSON>
BODY_PART_GROUPS = PART_GROUPS
# MakeHuman's eye materials (eyes/materials/<stem>.mhmat) -> Avatar's iris colours.
EYE_COLOURS = {"brown": "brown", "brownlight": "hazel", "lightbrown": "hazel", "hazel": "hazel",
               "darkbrown": "dark_brown", "dark_brown": "dark_brown", "green": "green",
               "bluegreen": "green", "blue": "blue", "lightblue": "blue", "darkblue": "blue",
               "deepblue": "blue", "ice": "grey", "grey": "grey", "gray": "grey"}  # fmt: skip
DEFAULT_EYE_MATERIAL = "eyes/materials/brown.mhmat"
DEFAULT_SKIN_MATERIAL = "skins/default.mhmat"  # MakeHuman's untextured default skin
WEARABLE = ("clothes", "hair", "eyebrows", "eyelashes")  # .mhm proxies Avatar dresses in
_FIELDS = ("version", "params", "rig", "pose", "clothes", "motion", "name", "eye_material",
           "skin_material", "expression", "hide_covered", "subdivide", "folders",
           "mhm", "garment_options")  # fmt: skip


@dataclass(frozen=True)
class Recipe:
    """Everything that defines a character; plain data, JSON-serialisable (``to_dict``).

    params: body parameters; rig: the skeleton; pose: a pose name or file (MakeHuman's
        ``pose`` line), the character's static pose; clothes: garments, hair, eyebrows and
        eyelashes worn (built-in names or ``.mhclo`` paths); motion: a motion name or file.
    name: the character's name. eye_material: a MakeHuman eye material file
        (``eyes/materials/blue.mhmat``), whose stem picks the iris colour (``EYE_COLOURS``);
        None: brown. skin_material: a MakeHuman skin ``.mhmat`` (used when it is found and
        has a texture; else Avatar's procedural skin). expression: a MakeHuman expression
        (``.mhpose``), kept for the file (Avatar's faces are the ``expression/*`` params).
    hide_covered: leave out body faces the garments cover (their ``delete_verts``), as
        MakeHuman's ``clothesHideFaces``: None (default) for MakeHuman garments only (built-ins
        keep the body, e.g. for cloth simulation), True for every garment, False for none.
    subdivide: MakeHuman's smoothing flag (kept for the file).
    folders: asset folders (MakeHuman/MPFB data, user garments) searched besides
        ``$AVATAR_CLOTHES_PATH`` for the garments and materials named here.
    mhm: other ``.mhm`` statements kept verbatim as (key, rest of line): camera, tags, the
        eyes proxy, proxies and materials Avatar does not use, assets not found.
    garment_options: {clothes entry: its variant} for worn built-ins in another colour or
        fabric, e.g. {"tshirt": {"colour": "navy"}} (``avatar.clothes.variants``).
    """

    params: dict[str, float] = field(default_factory=dict)
    rig: str = "default"
    pose: str | None = None
    clothes: tuple[str, ...] = ()
    motion: str | None = None
    name: str = ""
    eye_material: str | None = None
    skin_material: str | None = None
    expression: str | None = None
    hide_covered: bool | None = None
    subdivide: bool = False
    folders: tuple[str, ...] = ()
    mhm: tuple[tuple[str, str], ...] = ()
    garment_options: dict[str, dict[str, str]] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        return {
            "version": RECIPE_VERSION,
            "params": dict(self.params),
            "rig": self.rig,
            "pose": self.pose,
            "clothes": list(self.clothes),
            "motion": self.motion,
            "name": self.name,
            "eye_material": self.eye_material,
            "skin_material": self.skin_material,
            "expression": self.expression,
            "hide_covered": self.hide_covered,
            "subdivide": self.subdivide,
            "folders": list(self.folders),
            "mhm": [list(kv) for kv in self.mhm],
            "garment_options": self.worn_options(),
        }

    def worn_options(self) -> dict[str, dict[str, str]]:
        """``garment_options`` of the garments worn (a garment taken off forgets its own)."""
        return {k: dict(v) for k, v in self.garment_options.items() if k in self.clothes and v}

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> Recipe:
        """A recipe from ``to_dict``'s output (any version up to ``RECIPE_VERSION``)."""
        unknown = set(data) - set(_FIELDS)
        if unknown:
            raise ParameterError(f"unknown recipe fields: {', '.join(sorted(unknown))}")
        version = data.get("version", 1)
        if not isinstance(version, int) or not 1 <= version <= RECIPE_VERSION:
            raise ParameterError(f"recipe version {version!r} is not one this Avatar reads "
                                 f"(1..{RECIPE_VERSION})")  # fmt: skip
        hide = data.get("hide_covered")
        return cls(
            params={str(k): float(v) for k, v in (data.get("params") or {}).items()},
            rig=str(data.get("rig", "default")),
            pose=_text(data.get("pose")),
            clothes=tuple(str(c) for c in data.get("clothes") or ()),
            motion=_text(data.get("motion")),
            name=str(data.get("name") or ""),
            eye_material=_text(data.get("eye_material")),
            skin_material=_text(data.get("skin_material")),
            expression=_text(data.get("expression")),
            hide_covered=None if hide is None else bool(hide),
            subdivide=bool(data.get("subdivide", False)),
            folders=tuple(str(f) for f in data.get("folders") or ()),
            mhm=tuple(_statement(kv) for kv in data.get("mhm") or ()),
            garment_options=_options(data.get("garment_options")),
        )

    @classmethod
    def from_mhm(
        cls,
        path: str | os.PathLike[str],
        rig: str | None = None,
        folders: Sequence[str | os.PathLike[str]] = (),
    ) -> Recipe:
        """The recipe of a MakeHuman ``.mhm`` character file: modifiers, skeleton (``rig``
        overrides it), clothes, hair, eyebrows and eyelashes (found by uuid, else by name,
        in the library, ``folders`` and ``$AVATAR_CLOTHES_PATH``), eyes and skin materials,
        pose, expression, clothesHideFaces, subdivide; every other line is kept for re-saving.
        An asset that is not found is logged and kept in the file, not worn (as MakeHuman does).
        """
        character = mhm.read(path)
        names = tuple(str(f) for f in folders)
        clothes, kept = [], []
        for ref in character.proxies:
            if ref.kind in WEARABLE:
                found = library.find_reference(ref.name, ref.uuid, names)
                if found is not None:
                    clothes.append(found)
                    continue
                log.warning("%s: %s %r (uuid %s) is not in the clothes library or its "
                            "folders: kept in the file, not worn", path, ref.kind, ref.name,
                            ref.uuid or "-")  # fmt: skip
            kept.append((ref.kind, ref.line()[len(ref.kind) + 1 :]))
        eyes = character.proxy("eyes")
        eye_material = None
        for m in character.materials:
            of_eyes = eyes is not None and (m.uuid == eyes.uuid or m.proxy == eyes.name)
            if of_eyes and eye_material is None:
                eye_material = m.file
            else:
                kept.append(("material", f"{m.proxy} {m.uuid} {m.file}"))
        text = dict(character.text)
        kept += [(k, text.pop(k)) for k in ("uuid", "tags", "camera") if k in text]
        if "expression" in text:
            log.info("%s: MakeHuman expression %s kept for the file (not applied; Avatar's "
                     "faces are the expression/* parameters)", path,
                     text["expression"])  # fmt: skip
        hide = character.flags.get("clothesHideFaces")
        options = {}
        for key, rest in list(character.other):
            if key == MHM_GARMENT:
                worn, _, payload = rest.partition(" ")
                try:
                    options[worn] = json.loads(payload)
                except ValueError:
                    log.warning("%s: bad %s line %r: ignored", path, MHM_GARMENT, rest)
                character.other.remove((key, rest))
        return cls(params={**character.modifiers, **character.avatar_params},
                   rig=rig or character.rig or "default", pose=text.get("pose"),
                   clothes=tuple(dict.fromkeys(clothes)), name=text.get("name", ""),
                   eye_material=eye_material, skin_material=text.get("skinMaterial"),
                   expression=text.get("expression"), hide_covered=hide,
                   subdivide=character.flags.get("subdivide", False), folders=names,
                   mhm=tuple(kept + list(character.other)),
                   garment_options=_options(options))  # fmt: skip


def _options(data: Any) -> dict[str, dict[str, str]]:
    """A recipe's ``garment_options`` as plain text mappings (checked by ``Human``)."""
    if not data:
        return {}
    if not isinstance(data, Mapping) or not all(isinstance(v, Mapping) for v in data.values()):
        raise ParameterError(f"garment_options must map garments to options, not {data!r}")
    return {str(k): {str(o): v for o, v in opts.items()} for k, opts in data.items()}


def _text(value: Any) -> str | None:
    return None if value is None else str(value)


def _statement(kv: Any) -> tuple[str, str]:
    if not isinstance(kv, (list, tuple)) or len(kv) != 2:
        raise ParameterError(f"recipe 'mhm' entries are [key, text] pairs, got {kv!r}")
    return str(kv[0]), str(kv[1])


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
            source = library.find_garment(garment, self.recipe.folders)
            variants.check(source, self.recipe.garment_options.get(garment))

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
        """(19158, 3) float32 all vertices incl. helpers, metres, Z-up, feet on z = 0 (or,
        wearing built-in shoes, raised by ``sole_height`` so their soles are on it)."""
        rest = shaped.rest_vertices(self.model, self.recipe.params)
        rest[:, 2] += np.float32(self._sole_height(rest))
        return rest

    @property
    def sole_height(self) -> float:
        """Metres the body stands up on its built-in shoes' soles (0 barefoot)."""
        return self._sole_height(shaped.rest_vertices(self.model, self.recipe.params))

    def _sole_height(self, rest: np.ndarray) -> float:
        if "sole_height" not in self.__dict__:
            self.__dict__["sole_height"] = footing.sole_height(
                rest, self.recipe.clothes, self.recipe.folders, self.model)
        return self.__dict__["sole_height"]

    @cached_property
    def body(self) -> Body:
        """The shaped body on its rig: the record clothes, motion and Blender take."""
        return Body(self.vertices, self.skeleton, self.weights, self.model, self.recipe.rig)

    def part(self, name: str) -> Mesh:
        """A renderable part ("body", "eyes", "teeth", "tongue") as its own Mesh."""
        base = self.model.base
        faces = np.sort(np.concatenate([base.face_groups[g] for g in BODY_PART_GROUPS[name]]))
        mesh = base.with_vertices(self.vertices).subset(faces)
        if name == "teeth":  # spread over the teeth-and-gums texture (looks.skin)
            return face.teeth(mesh, np.isin(faces, base.face_groups["helper-upper-teeth"]),
                              self.model)  # fmt: skip
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
        if name.lower() == "rest":
            return pose
        return self._on_soles(floor.settle_body(self.body, pose)[0])

    def _on_soles(self, animation: Animation) -> Animation:
        """A motion settled on the skin (feet on z = 0) raised onto the shoes' soles."""
        if not self.sole_height:
            return animation
        return floor.raise_by(self.skeleton, animation, self.sole_height)

    def walk(self, seconds: float = 2.0, fps: float = 30.0, cadence: float = 1.0) -> Animation:
        """The built-in walk on this human's rig, arms hung clear of its own torso
        (``avatar.motion.procedural.walk``)."""
        return procedural.walk(self.skeleton, seconds, fps, cadence, body=self.body)

    def retarget(
        self, source: Skeleton, animation: Animation, **options: Any
    ) -> tuple[Animation, RetargetReport]:
        """A clip on ``source`` retargeted onto this human and settled on its skin (planted
        feet on the floor); options as ``avatar.motion.retarget``."""
        moved, report = retarget(source, animation, self.skeleton, body=self.body, **options)
        return self._on_soles(moved), report

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
    def parts(self, expressions: bool = False, hide_covered: bool | None = None) -> list[MeshPart]:
        """MeshParts ready for exporters and the Blender bridge: body, eyes, teeth, tongue
        (``BODY_PART_GROUPS``), then the garments.

        expressions: attach the 52 ARKit face units to the body, teeth and tongue as morph
            targets.
        hide_covered: drop body faces that garments cover entirely (their ``delete_verts``,
            MakeHuman's ``clothesHideFaces``): True for every garment, False for none (the
            whole body, e.g. for cloth simulation); None: the recipe's ``hide_covered``,
            by default MakeHuman garments only (``hidden_by``).
        """
        # The procedural skin and eye textures (~0.3 s each, numpy that frees the GIL) are
        # drawn on other cores while the garments are made and fitted.
        with ThreadPoolExecutor(max_workers=len(BODY_PART_GROUPS)) as pool:
            materials = {name: pool.submit(self.material, name) for name in BODY_PART_GROUPS}
            garments = library.parts(self.outfit) if self.recipe.clothes else []
            hiding = self.hidden_by(hide_covered) if self.recipe.clothes else []
            out = []
            for name in BODY_PART_GROUPS:
                mesh, index = self.part(name), self.part_vertices(name)
                if name == "body" and hiding:
                    mesh, index = self._uncovered_body(hiding)
                # Teeth and tongue follow the jaw in the face units too (a mouth, not a hole).
                morphs = self.expression_morphs(index) if expressions and name != "eyes" else {}
                skin = self.weights.subset(index)
                out.append(MeshPart(name, mesh, materials[name].result(),
                                    (skin.indices, skin.weights), morphs))  # fmt: skip
        return out + garments

    def hidden_by(self, hide_covered: bool | None = None) -> list[str]:
        """Names of the garments whose covered body faces are left out of the body part:
        every garment (True), none (False), or by default (None, then the recipe's
        ``hide_covered``) those that are MakeHuman assets (``.mhclo`` files), as MakeHuman
        shows them; built-ins keep the body under them unless asked."""
        hide = self.recipe.hide_covered if hide_covered is None else hide_covered
        if hide is False or not self.recipe.clothes:
            return []
        return [g.name for g in self.outfit.garments if hide or g.garment.source != "builtin"]

    def _uncovered_body(self, garments: Sequence[str]) -> tuple[Mesh, np.ndarray]:
        """The skin without faces every corner of which one of ``garments`` covers."""
        base = self.model.base
        covered = np.zeros(len(self.vertices), dtype=bool)
        for g in self.outfit.garments:
            if g.name in garments:
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
        every vertex outside the body (``exact``: this is what exports and renders use);
        brows and facial hair follow the hair worn and grey with age."""
        age = (self.model.defaults() | self.recipe.params)["age"]
        return library.dress(self.body, list(self.recipe.clothes), exact=True,
                             folders=self.recipe.folders,
                             options=self.recipe.garment_options, age=age)  # fmt: skip

    def dressed(self, *garments: str) -> Human:
        """A copy of this human also wearing ``garments`` (library names or .mhclo paths).

        Raises ParameterError naming close matches for an unknown garment (checked here,
        without building it), AvatarError for a missing ``.mhclo`` file.
        """
        clothes = tuple(dict.fromkeys(self.recipe.clothes + tuple(str(g) for g in garments)))
        return Human(self.recipe.params, self.recipe.rig, self.model,
                     replace(self.recipe, clothes=clothes))  # fmt: skip

    def material(self, part: str) -> Material:
        """The material of a body part: the eyes' iris from the recipe's eye material, the
        skin from its MakeHuman skin ``.mhmat`` when one is found with a texture, else
        Avatar's procedural skin for this body's ethnicity and age."""
        if part == "eyes":
            return skin.eye_material(self.eye_colour)
        if part in ("teeth", "tongue"):
            age = (self.model.defaults() | self.recipe.params)["age"]
            return skin.mouth_material(part, age=age)
        found = self.skin_file()
        if found is not None:
            loaded = material_from_file(found)
            if loaded.base_color_texture is not None:
                return loaded
            log.info("%s has no texture: Avatar's procedural skin is used", found)
        p = self.model.defaults() | self.recipe.params
        return skin.skin_material(
            african=p["african"], asian=p["asian"], caucasian=p["caucasian"], age=p["age"]
        )

    @property
    def eye_colour(self) -> str:
        """Avatar's iris colour (``looks.skin.IRIS_SRGB``) for the recipe's eye material."""
        stem = Path(self.recipe.eye_material or DEFAULT_EYE_MATERIAL).stem.lower()
        if stem not in EYE_COLOURS:
            log.warning("eye material %s: unknown colour, brown eyes", self.recipe.eye_material)
        return EYE_COLOURS.get(stem, "brown")

    def skin_file(self) -> Path | None:
        """The recipe's skin ``.mhmat``: as given, or under an asset folder (also without
        MakeHuman's ``skins/`` prefix); None for the default skin or when not found."""
        name = self.recipe.skin_material
        if not name or name == DEFAULT_SKIN_MATERIAL:
            return None
        relative = Path(name)
        tails = [relative, *([Path(*relative.parts[1:])] if len(relative.parts) > 1 else [])]
        folders = [Path(), *library.user_folders(self.recipe.folders)]
        for folder in folders:
            for tail in tails:
                for candidate in (folder / tail, folder / "skins" / tail):
                    if candidate.is_file():
                        return candidate
        log.warning("skin material %s not found in %s: Avatar's procedural skin is used", name,
                    ", ".join(str(f) for f in folders))  # fmt: skip
        return None

    # ------------------------------------------------------------------ MakeHuman files
    @classmethod
    def from_mhm(
        cls,
        path: str | os.PathLike[str],
        model: BodyModel | None = None,
        rig: str | None = None,
        folders: Sequence[str | os.PathLike[str]] = (),
    ) -> Human:
        """A human from a MakeHuman ``.mhm`` character file (``Recipe.from_mhm``)."""
        return cls.from_recipe(Recipe.from_mhm(path, rig, folders), model)

    def to_mhm(self, name: str = "avatar") -> mhm.CharacterFile:
        """This human as a MakeHuman character file record (``avatar.io.mhm``): what a
        ``.mhm`` read into it held, line for line, with the body, rig and garments as now.

        Garments are written as MakeHuman writes its assets (``hair <name> <uuid>``,
        ``clothes <name> <uuid>``, ...), built-ins under their fixed uuids.
        """
        r = self.recipe
        out = mhm.loads("\n".join(f"{k} {v}" for k, v in r.mhm))  # the kept statements
        out.text["name"] = r.name or name
        out.skeleton = f"{r.rig}.mhskel"
        missing = {k: v for k, v in self.model.defaults().items() if k not in r.params}
        for key, value in (missing | r.params).items():
            p = self.model.parameters[key]
            if p.mhm_name:
                out.modifiers[p.mhm_name] = value
            else:
                out.avatar_params[key] = value
        worn = []
        for garment in r.clothes:
            entry = library.entry_of(garment, r.folders)
            kind = library.mhm_kind(entry)
            if kind != "clothes" and out.proxy(kind) is not None:
                kind = "clothes"  # MakeHuman has one hair/eyebrows/eyelashes: the rest are clothes
            ref = mhm.ProxyRef(kind, entry.name.replace(" ", "_"), entry.uuid)
            out.proxies.append(ref)
            worn.append(ref)
        # Worn clothes first, in the recipe's order, then those kept from the file.
        out.proxies = worn + [p for p in out.proxies if p not in worn]
        eyes = out.proxy("eyes")
        if eyes is None:
            eyes = mhm.ProxyRef("eyes", *mhm.DEFAULT_EYES)
            out.proxies.append(eyes)
        eye_material = r.eye_material or DEFAULT_EYE_MATERIAL
        out.materials.insert(0, mhm.MaterialRef(eyes.name, eyes.uuid, eye_material))
        out.text["skinMaterial"] = r.skin_material or DEFAULT_SKIN_MATERIAL
        for key, text in (("pose", r.pose), ("expression", r.expression)):
            if text:
                out.text[key] = text
        for worn_entry, options in r.worn_options().items():
            out.other.append((MHM_GARMENT, f"{worn_entry} {json.dumps(options, sort_keys=True)}"))
        if r.hide_covered is not None:
            out.flags["clothesHideFaces"] = r.hide_covered
        out.flags["subdivide"] = r.subdivide
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
