"""Files in and out: ``save`` writes a human, ``load`` reads a file; the suffix picks the
format, through the one registry of formats (``WRITERS``, ``READERS``).

    avatar.save(human, "out.glb", animation)       # .glb .gltf .obj .mhm .bvh .fbx .usd .blend
    avatar.load("out.glb")                         # GltfFile: parts, skeleton, animations
    avatar.load("me.mhm")                          # Human
    avatar.load("clip.bvh")                        # (Skeleton, Animation)
    avatar.load("body.obj")                        # Mesh

Formats that go through Blender (FBX, USD, .blend, pictures) stage a ``Character`` record
with the bridge (``avatar.blender``); ``character`` builds it from a human.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from avatar.clothes import bake, library
from avatar.errors import AvatarError, ParameterError
from avatar.geometry.decimate import decimate
from avatar.human import Human
from avatar.io import bvh, mhm, obj, texture_size
from avatar.io.gltf_weights import INFLUENCE_LIMITS, MAX_INFLUENCES
from avatar.motion import poselib
from avatar.part import MeshPart
from avatar.rig import kinematics, skinning
from avatar.rig.poses import rest_pose
from avatar.rig.skeleton import Animation

if TYPE_CHECKING:  # the bridge imports bpy: loaded only when a Blender format is used
    from avatar.blender.scene import Character

Writer = Callable[..., None]  # (human, path, animation, **options)


def _mhm(human: Human, path: Path, animation: Animation | None, **options: Any) -> None:
    mhm.write(path, human.to_mhm(path.stem))


def _obj(
    human: Human,
    path: Path,
    animation: Animation | None,
    *,
    hide_covered: bool | None = None,
    texture_size: int | None = None,
    **_: Any,
) -> None:
    """Every part (body, eyes, garments) as one OBJ with its .mtl and PNG textures, posed at
    the animation's first frame (garments resolved out of the body) when one is given."""
    parts = _posed(human, human.parts(hide_covered=hide_covered), animation)
    obj.write_parts(path, texture_size_of(parts, texture_size))


def _posed(human: Human, parts: list[MeshPart], animation: Animation | None) -> list[MeshPart]:
    """The parts at the animation's first frame: body and eyes by their skin (LBS, as
    ``Human.posed``), garments by ``Outfit.frame(exact=True)``; unchanged without one."""
    if animation is None:
        return parts
    world = kinematics.forward(human.skeleton, animation.rotations[:1],
                               animation.translations[:1])  # fmt: skip
    matrices = kinematics.skinning_matrices(human.skeleton, world)[0]
    garments = len(human.outfit.garments) if human.recipe.clothes else 0
    resolved: list = []
    if garments:
        body = skinning.linear_blend(human.vertices, human.weights, matrices)
        resolved = human.outfit.frame(body, matrices, exact=True)
    out = []
    for i, part in enumerate(parts):
        k = i - (len(parts) - garments)
        normals = None
        if k >= 0:
            vertices = resolved[k]
            normals = library.garment_normals(human.outfit.garments[k], vertices)
        elif part.skin is not None:
            skin = skinning.SkinWeights(part.skin[0].astype(np.int32), part.skin[1])
            vertices = skinning.linear_blend(part.mesh.vertices, skin, matrices)
        else:
            vertices = part.mesh.vertices
        out.append(replace(part, mesh=part.mesh.with_vertices(vertices), normals=normals))
    return out


def texture_size_of(parts: list[MeshPart], size: int | None) -> list[MeshPart]:
    """``io.texture_size.sized`` with the user's size checked (ParameterError)."""
    if size is not None and not 16 <= size <= 8192:
        raise ParameterError(f"texture size {size} px: use 16 to 8192 (e.g. 512, 1024, 2048)")
    return texture_size.sized(parts, size)


def levels_of_detail(
    parts: list[MeshPart], lods: int, weights: dict[str, np.ndarray] | None = None
) -> tuple[list[MeshPart], dict[str, np.ndarray]]:
    """LOD parts ``<name>_LOD1`` .. ``_LOD<lods>`` of the body and the garments, each level
    with about half the triangles of the one before (``geometry.decimate``), keeping the
    skin, the morphs (expressions, garment corrections) and their keyed ``weights``.
    Returns (the LOD parts, their morph weights by part name)."""
    if not 0 <= lods <= 6:
        raise ParameterError(f"{lods} levels of detail: use 0 to 6 (each halves the triangles)")
    out: list[MeshPart] = []
    keyed: dict[str, np.ndarray] = {}
    for part in parts:
        if part.name in ("eyes", "teeth", "tongue"):  # a few hundred triangles: no gain
            continue
        for level in range(1, lods + 1):
            mesh, source = decimate(part.mesh, 0.5**level)
            skin = None if part.skin is None else (part.skin[0][source], part.skin[1][source])
            morphs = {k: np.asarray(d)[source] for k, d in part.morphs.items()}
            name = f"{part.name}_LOD{level}"
            out.append(MeshPart(name, mesh, part.material, skin, morphs))
            if weights and part.name in weights:
                keyed[name] = weights[part.name]
    return out, keyed


def _gltf(
    human: Human,
    path: Path,
    animation: Animation | None,
    *,
    expressions: bool = False,
    hide_covered: bool | None = None,
    animation_name: str | None = None,
    resolve_garments: bool = True,
    progress: bool = False,
    max_influences: int = MAX_INFLUENCES,
    texture_size: int | None = None,
    lods: int = 0,
    bake_segment: int = bake.SEGMENT,
    **_: Any,
) -> None:
    from avatar.io import gltf  # pygltflib: not in every Blender's Python, only glTF needs it

    if max_influences not in INFLUENCE_LIMITS:
        raise ParameterError(f"max influences {max_influences}: use 4 or 8")
    clips = {animation_name or "animation": animation} if animation is not None else {}
    parts = human.parts(expressions, hide_covered)
    weights: dict[str, np.ndarray] = {}
    if resolve_garments and animation is not None and human.recipe.clothes:
        parts, weights = bake.bake(human.body, human.outfit, animation, parts, progress,
                                   max_influences=max_influences,
                                   segment=bake_segment)  # fmt: skip
    parts = texture_size_of(parts, texture_size)
    lod_parts, lod_weights = levels_of_detail(parts, lods, weights)
    keyed = {animation_name or "animation": weights | lod_weights} if weights else {}
    gltf.write(path, parts + lod_parts, human.skeleton, clips, morph_weights=keyed,
               max_influences=max_influences)  # fmt: skip


def _bvh(
    human: Human, path: Path, animation: Animation | None, *, rest: str | None = None, **_: Any
) -> None:
    skeleton = human.skeleton
    motion = animation if animation is not None else rest_pose(skeleton)
    if rest:  # e.g. a T-pose rest for pipelines that expect one
        skeleton, motion = poselib.switch_rest(skeleton, motion, rest)
    bvh.save(path, skeleton, motion)


def _blender(
    human: Human,
    path: Path,
    animation: Animation | None,
    *,
    resolve_garments: bool = True,
    progress: bool = False,
    hide_covered: bool | None = None,
    expressions: bool = False,
    bake_segment: int = bake.SEGMENT,
    **_: Any,
) -> None:
    from avatar.blender import export as blender_export
    from avatar.blender import scene

    staged = character(human, animation, resolve_garments=resolve_garments, progress=progress,
                       hide_covered=hide_covered, expressions=expressions,
                       bake_segment=bake_segment)  # fmt: skip
    scene.clear_scene()
    built = scene.build_character(staged)
    blender_export.export(path, [built.root, *built.parts])


WRITERS: dict[str, Writer] = {
    ".mhm": _mhm,
    ".obj": _obj,
    ".bvh": _bvh,
    ".glb": _gltf,
    ".gltf": _gltf,
    ".fbx": _blender,
    ".usd": _blender,
    ".usdc": _blender,
    ".usda": _blender,
    ".blend": _blender,
}


def _read_gltf(path: Path) -> Any:
    from avatar.io import gltf  # see _gltf

    return gltf.read(path)


READERS: dict[str, Callable[[Path], Any]] = {
    ".glb": _read_gltf,
    ".gltf": _read_gltf,
    ".obj": obj.read,
    ".mhm": Human.from_mhm,
    ".bvh": bvh.load,
}


def save(
    human: Human,
    path: str | os.PathLike[str],
    animation: Animation | None = None,
    *,
    expressions: bool = False,
    hide_covered: bool | None = None,
    animation_name: str | None = None,
    rest: str | None = None,
    resolve_garments: bool = True,
    progress: bool = False,
    max_influences: int = MAX_INFLUENCES,
    texture_size: int | None = None,
    lods: int = 0,
    bake_segment: int = bake.SEGMENT,
) -> Path:
    """Write ``human`` (posed/animated by ``animation`` when given) to ``path``.

    expressions: include the 52 ARKit face units as morph targets (glTF only).
    hide_covered: leave out skin that garments cover entirely (their ``delete_verts``, as
        MakeHuman does): True for every garment, False for none (the whole body, e.g. for
        cloth simulation); None: the recipe's choice, by default MakeHuman garments only.
    animation_name: the glTF animation's name, e.g. the clip's file stem (default
        "animation"); players and Blender's importer show it as the clip/action name.
    rest: BVH only: write the skeleton resting in this pose ("t-pose", "a-pose", a pose
        file) with the motion re-expressed on it (``poselib.switch_rest``).
    resolve_garments: glTF/FBX/USD/.blend with garments and an animation: bake each frame's
        penetration resolve (``Outfit.frame(..., exact=True)``) into a small basis of
        correction morph targets (shape keys) per garment driven by per-frame weights (a
        weights channel; a shape-key action in Blender's formats), so viewers show garments
        out of the body (``avatar.clothes.bake``). False: plain skinned garments.
    bake_segment: the most frames one set of correction shapes holds (default 300); a
        longer clip is cut into equal segments with their own shapes, so the file grows
        linearly with the clip. Longer segments: fewer, fuller sets of shapes.
    progress: show a progress bar over long work (the garment bake).
    max_influences: glTF: joints per vertex, 8 or 4 (three.js and engines reading JOINTS_0).
    texture_size: glTF/OBJ: the longest texture side in px (e.g. 512, 1024, 2048); default:
        each part's textures sized to its surface (``io.texture_size``), never enlarged.
    lods: glTF: that many decimated levels of the body and garments, each with half the
        triangles of the one before, as parts ``<name>_LOD1``, ``_LOD2``, ...
    Formats by suffix: .glb/.gltf (mesh, UVs, skeleton, skin, materials, animation), .obj
    (every part, posed at the first frame, with its .mtl and PNG textures), .mhm
    (MakeHuman character file), .bvh (the skeleton and its motion, or its rest pose),
    .fbx/.usd/.blend (through Blender).
    """
    path = Path(path)
    writer = WRITERS.get(path.suffix.lower())
    if writer is None:
        raise AvatarError(f"{path}: unknown output format; use one of {', '.join(WRITERS)}")
    if bake_segment < 1:  # checked before any work, not deep inside the bake
        raise ParameterError(f"bake segment of {bake_segment} frames: use at least 1")
    path.parent.mkdir(parents=True, exist_ok=True)
    writer(human, path, animation, expressions=expressions, hide_covered=hide_covered,
           animation_name=animation_name, rest=rest, resolve_garments=resolve_garments,
           progress=progress, max_influences=max_influences, texture_size=texture_size,
           lods=lods, bake_segment=bake_segment)  # fmt: skip
    return path


def load(path: str | os.PathLike[str]) -> Any:
    """Read a file by its suffix: .glb/.gltf -> ``avatar.io.gltf.GltfFile`` (parts,
    skeleton, animations, morph weights); .obj -> ``Mesh``; .mhm -> ``Human``; .bvh ->
    ``(Skeleton, Animation)`` in Avatar's frame. Raises FormatError for a malformed file,
    AvatarError for an unknown suffix or a missing file."""
    path = Path(path)
    reader = READERS.get(path.suffix.lower())
    if reader is None:
        raise AvatarError(f"{path}: unknown input format; use one of {', '.join(READERS)}")
    if not path.is_file():
        raise AvatarError(f"{path}: no such file")
    return reader(path)


def character(
    human: Human,
    animation: Animation | None = None,
    *,
    name: str = "Avatar",
    location: tuple[float, float, float] = (0.0, 0.0, 0.0),
    resolve_garments: bool = True,
    progress: bool = False,
    hide_covered: bool | None = None,
    expressions: bool = False,
    bake_segment: int = bake.SEGMENT,
) -> Character:
    """The Blender bridge's record of ``human``: its parts (body, eyes, garments), skeleton,
    animation and recipe (stored on the character so the extension can regenerate it).

    resolve_garments: when the human wears garments and an animation is given, bake each
    frame's penetration resolve into each garment's few correction shape keys driven by
    per-frame values (``avatar.clothes.bake`` with Blender's Armature-modifier skinning), so
    garments stay out of the body; ``progress`` shows a bar over those frames.
    hide_covered, expressions, bake_segment: as ``save`` (the same parts as the files).
    """
    from avatar.blender.scene import Character

    x, y, z = location
    staged = Character(name, human.parts(expressions, hide_covered), human.skeleton, animation,
                       (x, y, z), human.to_recipe())  # fmt: skip
    if resolve_garments and animation is not None and human.recipe.clothes:
        parts, weights = bake.bake(human.body, human.outfit, animation, list(staged.parts),
                                   progress, skin=bake.vertex_group_skin,
                                   segment=bake_segment)  # fmt: skip
        staged = replace(staged, parts=parts, morph_weights=weights)
    return staged


def render(
    human: Human,
    path: str | os.PathLike[str],
    animation: Animation | None = None,
    **options: Any,
) -> Path:
    """A PNG of ``human`` (at the middle frame of ``animation``, if any) through Blender;
    options as ``avatar.blender.picture.render_character``; ``hide_covered`` and
    ``expressions`` as ``save`` (so a picture shows what the file holds). What
    ``create --render`` does."""
    from avatar.blender import picture

    parts = {k: options.pop(k) for k in ("hide_covered", "expressions") if k in options}

    if animation is not None:  # one picture: stage that frame only (its garments bake once)
        middle = slice(animation.frames // 2, animation.frames // 2 + 1)
        animation = replace(animation, rotations=animation.rotations[middle],
                            translations=animation.translations[middle])  # fmt: skip
    return picture.render_character(character(human, animation, **parts), path, **options)
