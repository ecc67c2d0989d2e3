"""``avatar create``: make a human, shape, rig, dress, animate it, write it (and a picture).

The recipe is complete before anything is built: names are checked, measurements solved on
the model, then one ``Human`` is realised, its rig placed once, and it is written.
"""

from __future__ import annotations

import argparse
import logging
from dataclasses import replace
from pathlib import Path

from avatar import export
from avatar.body import measures
from avatar.body.model import BodyModel
from avatar.cli import motion, paths, presets
from avatar.cli.assignments import parse_assignments, parse_measurements
from avatar.clothes import bake, library
from avatar.errors import AvatarError
from avatar.human import Human, Recipe
from avatar.looks import skin_library
from avatar.looks.skin import IRIS_SRGB
from avatar.motion.procedural import MOTIONS
from avatar.rig.skeleton import Animation

log = logging.getLogger("avatar")


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "create",
        help="make a human and write it to a file",
        description="Make a human (optionally from a MakeHuman .mhm file), shape it, rig it, "
        "dress it, animate it, and write it. The output suffix picks the format: "
        ".glb/.gltf, .obj, .mhm, .bvh (the motion on the rig), .fbx/.usd/.blend (via Blender).",
        epilog="examples:\n  avatar create -o human.glb\n"
        "  avatar create --set gender=1 --set age=0.8 --set pca/belly=1.5 --rig game_engine "
        "-o old.glb --render old.png\n  avatar create me.mhm --pose t-pose -o me.obj",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("character", nargs="?", help="a MakeHuman .mhm character file to start from")
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                   help="set a parameter (see `avatar info --params`); repeatable")  # fmt: skip
    p.add_argument("--measure", action="append", default=[], metavar="NAME=CM",
                   help="solve the body for a measurement in cm: height, chest, waist, hips; "
                   "repeatable (e.g. --measure height=180 --measure waist=85)")  # fmt: skip
    p.add_argument("--rig", help="skeleton: default, default_no_toes, game_engine, "
                   "game_engine_with_breast, cmu_mb, mixamo (default: default)")  # fmt: skip
    p.add_argument("--pose", metavar="NAME|FILE",
                   help="static pose: rest, a-pose, t-pose (any rig), a pose of the library "
                   "(see `avatar poses list`), or a .bvh (first frame) or MPFB .json pose "
                   "file")  # fmt: skip
    p.add_argument("--pose-folder", action="append", default=[], metavar="DIR",
                   help="also look for poses in this folder; repeatable")  # fmt: skip
    p.add_argument("--wear", action="append", default=[], metavar="NAME|PATH",
                   help="garment from the library or a .mhclo file; repeatable")  # fmt: skip
    p.add_argument("--eyes", choices=sorted(IRIS_SRGB), help="iris colour (default: brown)")
    p.add_argument("--skin", metavar="NAME|FILE",
                   help="a textured MakeHuman/MPFB skin: a .mhmat, or its name in the asset "
                   "folders (--folder, $AVATAR_CLOTHES_PATH); 'avatar': Avatar's own, by "
                   "ethnicity, age and gender (the default)")  # fmt: skip
    p.add_argument("--motion", metavar="CLIP.bvh",
                   help="BVH clip to retarget onto the human, or: walk")  # fmt: skip
    motion.add_motion_arguments(p)
    p.add_argument("--folder", action="append", default=[], metavar="DIR",
                   help="a MakeHuman/MPFB asset folder (or user garments): its garments, hair, "
                   "eyebrows, eyelashes, skins and poses can be worn, named in the .mhm "
                   "file or found by --wear NAME; repeatable")  # fmt: skip
    p.add_argument("--hide-covered", action="store_true",
                   help="leave out skin that any garment covers entirely, built-ins too "
                   "(MakeHuman garments hide it by default, as in MakeHuman)")  # fmt: skip
    p.add_argument("--keep-body", action="store_true",
                   help="keep the whole body under every garment (e.g. for cloth "
                   "simulation)")  # fmt: skip
    p.add_argument("--preset", choices=sorted(presets.PRESETS), default="full",
                   help="glTF export budget: full (textures as made, 8 joints per vertex) "
                   "or game (4 joints, maps at most 1024 px, 2 LODs); the options below "
                   "override it (default full)")  # fmt: skip
    p.add_argument("--max-influences", type=int, choices=(4, 8),
                   help="glTF: joints per vertex (4 for three.js and engines that read "
                   "one JOINTS set; default 8)")  # fmt: skip
    p.add_argument("--texture-size", type=int, metavar="PX",
                   help="glTF/OBJ: longest texture side, e.g. 512, 1024, 2048 (default: each "
                   "part's textures sized to its surface)")  # fmt: skip
    p.add_argument("--lods", type=int, metavar="N",
                   help="glTF: N decimated levels of the body and garments (<name>_LOD1.., "
                   "each half the triangles of the one before)")  # fmt: skip
    p.add_argument("--expressions", action="store_true",
                   help="glTF: include the 52 ARKit face units as morph targets")  # fmt: skip
    p.add_argument("--no-resolve-garments", dest="resolve_garments", action="store_false",
                   help="glTF/FBX/USD/.blend: skin garments plainly instead of baking each "
                   "frame's penetration resolve into morph targets / shape keys (faster, "
                   "smaller; garments may clip into the body)")  # fmt: skip
    p.add_argument("--bake-segment", type=paths.positive_count, metavar="FRAMES",
                   default=bake.SEGMENT,
                   help="most frames one set of baked garment correction shapes holds; "
                   "longer clips are cut into equal segments with their own shapes "
                   f"(default {bake.SEGMENT})")  # fmt: skip
    p.add_argument("--render", metavar="PNG", help="also render a picture (needs bpy)")
    p.add_argument("-o", "--output", required=True, help="output file (.glb .gltf .obj .mhm ...)")
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    _check_paths(args)
    model = BodyModel.shared(progress=True)
    human = Human.from_recipe(_recipe(args, model), model)
    animation, name = _animation(human, args)
    path = export.save(human, args.output, animation, expressions=args.expressions,
                       hide_covered=_hiding(args), animation_name=name, rest=args.rest,
                       resolve_garments=args.resolve_garments, progress=True,
                       bake_segment=args.bake_segment,
                       **presets.export_options(args.preset, max_influences=args.max_influences,
                                                texture_size=args.texture_size,
                                                lods=args.lods))  # fmt: skip
    log.info("wrote %s", path)
    if args.render:  # the same parts as the file
        picture = export.render(human, args.render, animation, hide_covered=_hiding(args),
                                expressions=args.expressions)  # fmt: skip
        log.info("rendered %s", picture)
    return 0


def _check_paths(args: argparse.Namespace) -> None:
    """Every file named on the command line, before any work: inputs exist, outputs can be
    written (``cli.paths``); raises AvatarError naming the path."""
    paths.output_file(args.output)
    if args.render:
        paths.output_file(args.render, "picture")
    if args.character:
        paths.input_file(args.character, "character file")
    if args.motion and args.motion not in MOTIONS:
        paths.input_file(args.motion, "--motion", f"a .bvh clip or {', '.join(MOTIONS)}")


def _recipe(args: argparse.Namespace, model: BodyModel) -> Recipe:
    """The whole recipe from the options, every name checked, measurements solved."""
    for name in args.wear:  # fail early, naming the unknown garment, before any fitting
        library.find_garment(name, args.folder)
    recipe = Recipe.from_mhm(args.character, folders=args.folder) if args.character else Recipe()
    params = model.resolve(recipe.params | parse_assignments(args.set))
    if args.measure:
        wanted = parse_measurements(args.measure)
        params, got = measures.fit(model, wanted, params)
        log.info("measurements: %s", ", ".join(f"{k} {v * 100:.1f} cm" for k, v in got.items()))
    clothes = tuple(dict.fromkeys(recipe.clothes + tuple(args.wear)))
    hide = recipe.hide_covered if _hiding(args) is None else _hiding(args)
    folders = tuple(dict.fromkeys(recipe.folders + tuple(args.folder)))
    recipe = replace(recipe, **_looks(args, folders))
    return replace(recipe, params=params, rig=args.rig or recipe.rig, clothes=clothes,
                   pose=args.pose or recipe.pose, hide_covered=hide,
                   folders=folders)  # fmt: skip


def _looks(args: argparse.Namespace, folders: tuple[str, ...]) -> dict:
    """--eyes and --skin as recipe fields (only those given)."""
    looks: dict = {}
    if args.eyes:
        looks["eye_material"] = f"eyes/materials/{args.eyes}.mhmat"
    if args.skin:
        wanted = args.skin.strip()
        looks["skin_material"] = (None if wanted.lower() == "avatar" else
                                  skin_library.find_skin(wanted, library.user_folders(folders)))
    return looks


def _hiding(args: argparse.Namespace) -> bool | None:
    """--hide-covered: True, --keep-body: False, neither: None (MakeHuman garments hide)."""
    return True if args.hide_covered else (False if args.keep_body else None)


def _animation(human: Human, args: argparse.Namespace) -> tuple[Animation | None, str | None]:
    """(the Animation or None, its name for the file: the clip's stem, the motion or pose)."""
    if args.motion in MOTIONS:
        clip = MOTIONS[args.motion](human.skeleton, fps=args.fps or 30.0, body=human.body)
        return clip, args.motion
    if args.motion:
        animation, report = motion.motion_for(human.skeleton, args.motion, args, human.body)
        log.info("%s", report.summary())
        animation, _ = motion.on_floor(human.body, animation, args.keep_height)
        return animation, Path(args.motion).stem
    if args.pose:
        return human.pose(args.pose, args.pose_folder + args.folder), Path(args.pose).stem
    if human.recipe.pose:  # a .mhm's pose: MakeHuman names the file (standing01.bvh)
        pose = human.recipe.pose
        pose = pose if Path(pose).is_file() else Path(pose).stem
        try:
            return human.pose(pose, args.pose_folder + args.folder), Path(pose).stem
        except AvatarError as exc:
            log.warning("the character's pose is not applied: %s", exc)
    return None, None
