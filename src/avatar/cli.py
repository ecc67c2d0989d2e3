"""The ``avatar`` command: one small function per subcommand."""

from __future__ import annotations

import argparse
import logging
import sys
from collections.abc import Sequence

from avatar.errors import AvatarError, ParameterError

log = logging.getLogger("avatar")


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point; returns the exit status (0 ok, 1 Avatar error, 2 usage error)."""
    parser = build_parser()
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.DEBUG if args.verbose else logging.INFO,
                        format="%(levelname)s: %(message)s")  # fmt: skip
    if not hasattr(args, "run"):
        parser.print_help()
        return 2
    try:
        return int(args.run(args) or 0)
    except AvatarError as exc:
        print(f"avatar: error: {exc}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("avatar: interrupted", file=sys.stderr)
        return 130


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="avatar",
        description="Create realistic, rigged, dressed and animated 3D humans "
        "(MakeHuman body model).",
    )
    parser.add_argument("-v", "--verbose", action="store_true", help="debug logging")
    sub = parser.add_subparsers(title="commands", metavar="COMMAND")
    _add_create(sub)
    _add_info(sub)
    _add_optional(sub)
    return parser


def _add_create(sub: argparse._SubParsersAction) -> None:
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
    p.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="set a parameter (see `avatar info --params`); repeatable",
    )
    p.add_argument(
        "--measure",
        action="append",
        default=[],
        metavar="NAME=CM",
        help="solve the body for a measurement in cm: height, chest, waist, hips; "
        "repeatable (e.g. --measure height=180 --measure waist=85)",
    )
    p.add_argument(
        "--rig",
        help="skeleton: default, default_no_toes, game_engine, "
        "game_engine_with_breast, cmu_mb, mixamo (default: default)",
    )
    p.add_argument(
        "--pose",
        metavar="NAME|FILE",
        help="static pose: rest, a-pose, t-pose (any rig), a pose of the library "
        "(see `avatar poses list`), or a .bvh (first frame) or MPFB .json pose file",
    )
    p.add_argument("--pose-folder", action="append", default=[], metavar="DIR",
                   help="also look for poses in this folder; repeatable")  # fmt: skip
    p.add_argument(
        "--wear",
        action="append",
        default=[],
        metavar="NAME|PATH",
        help="garment from the library or a .mhclo file; repeatable",
    )
    p.add_argument(
        "--motion", metavar="CLIP.bvh", help="BVH clip to retarget onto the human, or: walk"
    )
    from avatar.motion.cli import add_motion_arguments

    add_motion_arguments(p)
    p.add_argument(
        "--hide-covered",
        action="store_true",
        help="glTF: leave out skin that garments cover entirely (default: keep it)",
    )
    p.add_argument(
        "--expressions",
        action="store_true",
        help="glTF: include the 52 ARKit face units as morph targets",
    )
    p.add_argument(
        "--no-resolve-garments",
        dest="resolve_garments",
        action="store_false",
        help="glTF/FBX/USD/.blend: skin garments plainly instead of baking each frame's "
        "penetration resolve into morph targets / shape keys (faster, smaller; garments may "
        "clip into the body)",
    )
    p.add_argument("--render", metavar="PNG", help="also render a picture (needs bpy)")
    p.add_argument("-o", "--output", required=True, help="output file (.glb .gltf .obj .mhm ...)")
    p.set_defaults(run=run_create)


def _add_info(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "info",
        help="list parameters, rigs and assets",
        description="List parameters (name, range, default), rigs and assets.",
    )
    p.add_argument("--params", action="store_true", help="list every parameter")
    p.add_argument("--search", metavar="TEXT", help="only parameters whose name contains TEXT")
    p.set_defaults(run=run_info)


def _add_optional(sub: argparse._SubParsersAction) -> None:
    """Subcommands of the clothes and motion packages."""
    from avatar.motion.cli import add_retarget_arguments, cli_retarget

    p = sub.add_parser("retarget", help="retarget BVH clips (files or folders) onto an Avatar rig",
                       description="Retarget BVH motion capture from any common skeleton onto "
                       "an Avatar rig; writes one BVH per clip and reports quality.")  # fmt: skip
    add_retarget_arguments(p)
    p.set_defaults(run=cli_retarget)
    from avatar.motion.cli import cli_poses_list

    poses = sub.add_parser("poses", help="the pose library",
                           description="List built-in poses and the poses in user folders "
                           "(single-frame .bvh, MPFB .json; also $AVATAR_POSES_PATH).")  # fmt: skip
    poses_sub = poses.add_subparsers(title="commands", metavar="COMMAND")
    p = poses_sub.add_parser("list", help="list poses (built-in and user folders)")
    p.add_argument("--search", metavar="TEXT", help="only poses matching every word")
    p.add_argument("--folder", action="append", default=[], metavar="DIR",
                   help="also scan this folder (MakeHuman data/poses); repeatable")  # fmt: skip
    p.set_defaults(run=cli_poses_list)
    from avatar.clothes.library import cli_clothes_list

    clothes = sub.add_parser("clothes", help="the clothes library",
                             description="List and search the clothes library.")  # fmt: skip
    clothes_sub = clothes.add_subparsers(title="commands", metavar="COMMAND")
    p = clothes_sub.add_parser("list", help="list garments (built-in and user folders)")
    p.add_argument("--search", metavar="TEXT", help="only garments matching every word")
    p.add_argument("--folder", action="append", metavar="DIR",
                   help="also scan this MakeHuman/MPFB asset folder; repeatable")  # fmt: skip
    p.set_defaults(run=cli_clothes_list)
    from avatar.clothes.binder import FRAMES, cli_clothes_bind

    p = clothes_sub.add_parser(
        "bind", help="bind a garment OBJ modelled on an Avatar body, so it fits every body",
        description="Bind a garment mesh (OBJ) to the body it was modelled on and save it as "
        "MakeHuman .mhclo + .obj + .mhmat; from then on it fits every body (--wear PATH).",
    )  # fmt: skip
    p.add_argument("garment", metavar="GARMENT.obj")
    p.add_argument("-o", "--output", required=True, metavar="DIR", help="folder to write into")
    body = p.add_mutually_exclusive_group()
    body.add_argument("--set", action="append", metavar="NAME=VALUE",
                      help="the body it was modelled on (as for create); repeatable")  # fmt: skip
    body.add_argument("--mhm", metavar="FILE", help="the body it was modelled on, as a .mhm file")
    p.add_argument("--name", help="garment name (default: the file's stem)")
    p.add_argument("--frame", default="auto", choices=["auto", *FRAMES],
                   help="the OBJ's axes and units (default: whichever fits the body)")  # fmt: skip
    p.add_argument("--tag", action="append", help="library tag; repeatable")
    p.add_argument("--z-depth", type=int, default=50, help="layer: higher goes over lower")
    p.add_argument("--texture", metavar="IMAGE", help="diffuse texture to copy beside it")
    p.set_defaults(run=cli_clothes_bind)


def parse_assignments(items: Sequence[str]) -> dict[str, float]:
    """["gender=1", "pca/belly=1.5"] -> {"gender": 1.0, "pca/belly": 1.5}."""
    out: dict[str, float] = {}
    for item in items:
        name, sep, value = item.partition("=")
        if not sep or not name:
            raise ParameterError(f"--set expects NAME=VALUE, got {item!r}")
        try:
            out[name.strip()] = float(value)
        except ValueError:
            raise ParameterError(f"--set {name}: {value!r} is not a number") from None
    return out


def run_create(args: argparse.Namespace) -> int:
    from avatar.body import assets
    from avatar.body.model import BodyModel
    from avatar.export import save
    from avatar.human import Human

    model = BodyModel(assets.load(progress=True))
    params = parse_assignments(args.set)
    if args.character:
        base = Human.from_mhm(args.character, model, args.rig)
        human = Human(base.params | params, args.rig or base.recipe.rig, model, base.recipe)
    else:
        human = Human(params, args.rig or "default", model)
    if args.measure:
        from avatar.body import measures

        wanted = {k: v / 100.0 for k, v in parse_assignments(args.measure).items()}
        solved, got = measures.fit(model, wanted, human.params)
        log.info("measurements: %s", ", ".join(f"{k} {v * 100:.1f} cm" for k, v in got.items()))
        human = Human(solved, human.recipe.rig, model, human.recipe)
    human = _dress(human, args.wear)
    animation, name = _animation(human, args)
    path = save(human, args.output, animation, args.expressions, args.hide_covered, name,
                args.rest, resolve_garments=args.resolve_garments, progress=True)  # fmt: skip
    log.info("wrote %s", path)
    if args.render:
        from avatar.blender.picture import render_human

        log.info("rendered %s", render_human(human, args.render, animation))
    return 0


def _dress(human, wear: list[str]):
    if not wear:
        return human
    from avatar.clothes import library

    for name in wear:  # fail early, naming the unknown garment, before any fitting
        library.load_garment(name)
    return human.dressed(*wear)


def _animation(human, args: argparse.Namespace):
    """(the Animation or None, its name for the file: the clip's stem, the motion or pose)."""
    from avatar.motion.procedural import MOTIONS

    if args.motion in MOTIONS:
        return MOTIONS[args.motion](human, fps=args.fps or 30.0), args.motion
    if args.motion:
        from pathlib import Path

        from avatar.motion.cli import motion_for, on_floor

        animation, report = motion_for(human.skeleton, args.motion, args)
        log.info("%s", report.summary())
        animation, _ = on_floor(human, animation, args)
        return animation, Path(args.motion).stem
    if args.pose:
        from pathlib import Path

        return human.pose(args.pose, args.pose_folder), Path(args.pose).stem  # on the floor
    return None, None


def run_info(args: argparse.Namespace) -> int:
    from avatar.body import assets
    from avatar.body.model import BodyModel

    compiled = assets.load(progress=True)
    model = BodyModel(compiled)
    params = model.parameters.values()
    print(f"assets: {compiled.meta['source']}\ncache:  {compiled.folder}")
    print(f"rigs:   {', '.join(assets.RIG_NAMES)}")
    kinds: dict[str, int] = {}
    for p in params:
        kinds[p.kind] = kinds.get(p.kind, 0) + 1
    print("parameters: " + ", ".join(f"{n} {k}s" for k, n in kinds.items()))
    if args.params or args.search:
        for p in params:
            if args.search and args.search.lower() not in p.name.lower():
                continue
            print(
                f"  {p.name:60s} {p.kind:10s} [{p.minimum:g}, {p.maximum:g}] default {p.default:g}"
            )
    return 0


if __name__ == "__main__":
    sys.exit(main())
