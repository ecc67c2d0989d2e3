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

from avatar.clothes import bake
from avatar.errors import AvatarError
from avatar.human import Human
from avatar.io import bvh, mhm, obj
from avatar.motion import poselib
from avatar.rig.poses import rest_pose
from avatar.rig.skeleton import Animation

if TYPE_CHECKING:  # the bridge imports bpy: loaded only when a Blender format is used
    from avatar.blender.scene import Character

Writer = Callable[..., None]  # (human, path, animation, **options)


def _mhm(human: Human, path: Path, animation: Animation | None, **options: Any) -> None:
    mhm.write(path, human.to_mhm(path.stem))


def _obj(human: Human, path: Path, animation: Animation | None, **options: Any) -> None:
    mesh = human.mesh
    if animation is not None:  # an OBJ holds one pose: the animation's first frame
        mesh = mesh.with_vertices(
            human.posed(animation, slice(0, 1))[0][human.part_vertices("body")]
        )
    obj.write(path, mesh)


def _gltf(
    human: Human,
    path: Path,
    animation: Animation | None,
    *,
    expressions: bool = False,
    hide_covered: bool = False,
    animation_name: str | None = None,
    resolve_garments: bool = True,
    progress: bool = False,
    **_: Any,
) -> None:
    from avatar.io import gltf  # pygltflib: not in every Blender's Python, only glTF needs it

    clips = {animation_name or "animation": animation} if animation is not None else {}
    parts, keyed = human.parts(expressions, hide_covered), {}
    if resolve_garments and animation is not None and human.recipe.clothes:
        parts, weights = bake.bake(human.body, human.outfit, animation, parts, progress)
        keyed = {animation_name or "animation": weights}
    gltf.write(path, parts, human.skeleton, clips, morph_weights=keyed)


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
    **_: Any,
) -> None:
    from avatar.blender import export as blender_export
    from avatar.blender import scene

    staged = character(human, animation, resolve_garments=resolve_garments, progress=progress)
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
    hide_covered: bool = False,
    animation_name: str | None = None,
    rest: str | None = None,
    resolve_garments: bool = True,
    progress: bool = False,
) -> Path:
    """Write ``human`` (posed/animated by ``animation`` when given) to ``path``.

    expressions: include the 52 ARKit face units as morph targets (glTF only).
    hide_covered: leave out skin that garments cover entirely (glTF; default: keep it).
    animation_name: the glTF animation's name, e.g. the clip's file stem (default
        "animation"); players and Blender's importer show it as the clip/action name.
    rest: BVH only: write the skeleton resting in this pose ("t-pose", "a-pose", a pose
        file) with the motion re-expressed on it (``poselib.switch_rest``).
    resolve_garments: glTF/FBX/USD/.blend with garments and an animation: bake each frame's
        penetration resolve (``Outfit.frame(..., exact=True)``) into one morph target
        (shape key) per frame, switched on at its frame only by a weights channel (a
        CONSTANT shape-key action in Blender's formats), so viewers show no garment inside
        the body (``avatar.clothes.bake``; ~0.1-0.3 s a frame). False: plain skinned garments.
    progress: show a progress bar over long work (the garment bake).
    Formats by suffix: .glb/.gltf (mesh, UVs, skeleton, skin, materials, animation), .obj
    (the skin mesh), .mhm (MakeHuman character file), .bvh (the skeleton and its motion,
    or its rest pose), .fbx/.usd/.blend (through Blender).
    """
    path = Path(path)
    writer = WRITERS.get(path.suffix.lower())
    if writer is None:
        raise AvatarError(f"{path}: unknown output format; use one of {', '.join(WRITERS)}")
    path.parent.mkdir(parents=True, exist_ok=True)
    writer(human, path, animation, expressions=expressions, hide_covered=hide_covered,
           animation_name=animation_name, rest=rest, resolve_garments=resolve_garments,
           progress=progress)  # fmt: skip
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
) -> Character:
    """The Blender bridge's record of ``human``: its parts (body, eyes, garments), skeleton,
    animation and recipe (stored on the character so the extension can regenerate it).

    resolve_garments: when the human wears garments and an animation is given, bake each
    frame's penetration resolve into one shape key per frame, keyed 1 at its frame only
    (``avatar.clothes.bake`` with Blender's Armature-modifier skinning, ~0.1-0.3 s a frame),
    so garments never show inside the body; ``progress`` shows a bar over those frames.
    """
    from avatar.blender.scene import Character

    x, y, z = location
    staged = Character(name, human.parts(), human.skeleton, animation, (x, y, z),
                       human.to_recipe())  # fmt: skip
    if resolve_garments and animation is not None and human.recipe.clothes:
        parts, weights = bake.bake(human.body, human.outfit, animation, list(staged.parts),
                                   progress, skin=bake.vertex_group_skin)  # fmt: skip
        staged = replace(staged, parts=parts, morph_weights=weights)
    return staged


def render(
    human: Human,
    path: str | os.PathLike[str],
    animation: Animation | None = None,
    **options: Any,
) -> Path:
    """A PNG of ``human`` (at the middle frame of ``animation``, if any) through Blender;
    options as ``avatar.blender.picture.render_character``. What ``create --render`` does."""
    from avatar.blender import picture

    if animation is not None:  # one picture: stage that frame only (its garments bake once)
        middle = slice(animation.frames // 2, animation.frames // 2 + 1)
        animation = replace(animation, rotations=animation.rotations[middle],
                            translations=animation.translations[middle])  # fmt: skip
    return picture.render_character(character(human, animation), path, **options)
