"""Write a human to a file; the suffix picks the format (the one suffix registry)."""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path

from avatar.errors import AvatarError
from avatar.human import Human
from avatar.rig.skeleton import Animation


def _mhm(human: Human, path: Path, animation: Animation | None, options: dict) -> None:
    from avatar.io import mhm

    mhm.write(path, human.to_mhm(path.stem))


def _obj(human: Human, path: Path, animation: Animation | None, options: dict) -> None:
    from avatar.io import obj

    mesh = human.mesh
    if animation is not None:  # an OBJ holds one pose: the animation's first frame
        mesh = mesh.with_vertices(
            human.posed(animation, slice(0, 1))[0][human.part_vertices("body")]
        )
    obj.write(path, mesh)


def _gltf(human: Human, path: Path, animation: Animation | None, options: dict) -> None:
    from avatar.io import gltf

    options = dict(options)
    name = options.pop("animation_name", None) or "animation"
    resolve, progress = options.pop("resolve_garments", True), options.pop("progress", False)
    clips = {name: animation} if animation is not None else {}
    parts, keyed = human.parts(**options), {}
    if resolve and animation is not None and human.recipe.clothes:
        from avatar.clothes import bake

        parts, weights = bake.bake(human, animation, parts, progress)
        keyed = {name: weights}
    gltf.write(path, parts, human.skeleton, clips, morph_weights=keyed)


def _bvh(human: Human, path: Path, animation: Animation | None, options: dict) -> None:
    from avatar.io import bvh
    from avatar.motion import poselib
    from avatar.rig.poses import rest_pose

    skeleton = human.skeleton
    motion = animation if animation is not None else rest_pose(skeleton)
    if options.get("rest"):  # e.g. a T-pose rest for pipelines that expect one
        skeleton, motion = poselib.switch_rest(skeleton, motion, options["rest"])
    bvh.save(path, skeleton, motion)


def _blender(human: Human, path: Path, animation: Animation | None, options: dict) -> None:
    from avatar.blender import export, scene

    resolve, progress = options.get("resolve_garments", True), options.get("progress", False)
    scene.clear_scene()
    character = scene.character_from_human(human, animation=animation,
                                           resolve_garments=resolve, progress=progress)  # fmt: skip
    built = scene.build_character(character)
    export.export(path, [built.root, *built.parts])


WRITERS: dict[str, Callable[[Human, Path, Animation | None, dict], None]] = {
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


def save(
    human: Human,
    path: str | os.PathLike[str],
    animation: Animation | None = None,
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
    options = {"expressions": expressions, "hide_covered": hide_covered,
               "animation_name": animation_name}  # fmt: skip
    if writer in (_gltf, _blender):
        options |= {"resolve_garments": resolve_garments, "progress": progress}
    if rest:
        options["rest"] = rest
    writer(human, path, animation, options)
    return path
