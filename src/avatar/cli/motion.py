"""``avatar retarget`` (batch), ``avatar poses list``, and the motion options of ``create``."""

from __future__ import annotations

import argparse
import json
import logging
import sys
from pathlib import Path

import numpy as np

from avatar.body.shaped import Body
from avatar.cli import paths
from avatar.errors import AvatarError, ParameterError
from avatar.human import Human
from avatar.io import atomic, bvh
from avatar.motion import floor, poselib, timing
from avatar.motion.retarget import RetargetReport, retarget, with_stretch
from avatar.rig.skeleton import Animation, Skeleton

log = logging.getLogger(__name__)


def add_parsers(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("retarget", help="retarget BVH clips (files or folders) onto an Avatar rig",
                       description="Retarget BVH motion capture from any common skeleton onto "
                       "an Avatar rig; writes one BVH per clip and reports quality.")  # fmt: skip
    add_retarget_arguments(p)
    p.set_defaults(run=run_retarget)
    poses = sub.add_parser("poses", help="the pose library",
                           description="List built-in poses and the poses in user folders "
                           "(single-frame .bvh, MPFB .json; also $AVATAR_POSES_PATH).")  # fmt: skip
    poses_sub = poses.add_subparsers(title="commands", metavar="COMMAND")
    p = poses_sub.add_parser("list", help="list poses (built-in and user folders)")
    p.add_argument("--search", metavar="TEXT", help="only poses matching every word")
    p.add_argument("--folder", action="append", default=[], metavar="DIR",
                   help="also scan this folder (MakeHuman data/poses); repeatable")  # fmt: skip
    p.set_defaults(run=run_poses_list)


def add_motion_arguments(parser: argparse.ArgumentParser) -> None:
    """Options shared by ``create --motion`` and ``retarget``."""
    parser.add_argument("--frames", metavar="A:B", help="source frames to keep (B exclusive)")
    parser.add_argument(
        "--fps", type=paths.positive_number, help="output frame rate (default: the clip's)"
    )
    parser.add_argument("--in-place", action="store_true", help="remove horizontal root motion")
    parser.add_argument("--no-foot-fix", action="store_true", help="skip contact planting (IK)")
    parser.add_argument("--rest", metavar="POSE",
                        help="BVH output: rest the skeleton in this pose (t-pose, a-pose, a "
                        "pose file), the motion re-expressed on it")  # fmt: skip
    parser.add_argument("--keep-height", action="store_true",
                        help="keep the retargeted height (default: raise or lower the motion "
                        "so planted feet touch the floor with the body mesh)")  # fmt: skip
    parser.add_argument("--source-map", default="auto", metavar="NAME|FILE.json",
                        help="source bone map: convention name, JSON file or topology "
                        "(default: by names, the hierarchy where they fail)")  # fmt: skip


def add_retarget_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``avatar retarget``."""
    parser.add_argument("clips", nargs="+", help="BVH files or folders of them")
    parser.add_argument("--rig", default="default", help="Avatar rig to retarget onto")
    parser.add_argument("--out", default="retargeted", help="output folder (BVH per clip)")
    parser.add_argument("--report", metavar="FILE.json", help="write per-clip quality as JSON")
    add_motion_arguments(parser)


def clip_paths(inputs: list[str]) -> list[Path]:
    """Files as given, folders expanded to their ``*.bvh`` files (sorted, recursive).
    Raises ParameterError for a missing path or a folder without any ``.bvh`` file."""
    out: list[Path] = []
    for item in inputs:
        path = Path(item)
        if path.is_dir():
            found = sorted(p for p in path.rglob("*") if p.suffix.lower() == ".bvh")
            if not found:
                raise ParameterError(f"no .bvh clips in folder {item!r}")
            out.extend(found)
        elif path.exists():
            out.append(path)
        else:
            raise ParameterError(f"no such clip or folder: {item}")
    return out


def motion_for(target: Skeleton, clip: str | Path, args: argparse.Namespace,
               body: Body | None = None) -> tuple[Animation, RetargetReport]:  # fmt: skip
    """Retarget one clip onto ``target`` with the options of ``add_motion_arguments``; with
    the ``body`` on it, the report also says how the motion stretches its skin."""
    source, animation = bvh.load(paths.input_file(clip, "clip"))
    animation, report = retarget(
        source,
        animation,
        target,
        source_map=args.source_map,
        frames=timing.parse_frames(args.frames),
        fps=args.fps,
        in_place=args.in_place,
        fix_feet=not args.no_foot_fix,
    )
    return animation, report if body is None else with_stretch(report, body, animation)


def run_retarget(args: argparse.Namespace) -> int:
    """Every clip onto one rig: a BVH per clip plus a quality line (and a JSON report).

    A clip that fails (a broken file, a skeleton that is not a human) is reported on one
    line and skipped; the others are written and reported. Exit status 1 when any failed.
    """
    clips = clip_paths(args.clips)
    out = paths.output_folder(args.out)
    if args.report:
        paths.output_file(args.report, "report")
    timing.parse_frames(args.frames)  # a bad range fails once, not once per clip
    human = Human(rig=args.rig)
    target = human.skeleton
    out.mkdir(parents=True, exist_ok=True)
    table: dict[str, dict] = {}
    for clip in clips:
        try:
            row = _retarget_one(human, target, clip, out, args)
        except AvatarError as exc:
            print(f"avatar: error: {clip}: {exc}", file=sys.stderr)
            table[str(clip)] = {"error": str(exc)}
            continue
        table[str(clip)] = row
    if args.report:
        atomic.write_text(args.report, json.dumps(table, indent=1) + "\n")
    failed = sum("error" in row for row in table.values())
    if failed:
        print(f"avatar: error: {failed} of {len(table)} clips failed", file=sys.stderr)
    return 1 if failed else 0


def _retarget_one(human: Human, target: Skeleton, clip: Path, out: Path,
                  args: argparse.Namespace) -> dict:  # fmt: skip
    """One clip of ``run_retarget``: its BVH written, its line printed; its report row."""
    animation, report = motion_for(target, clip, args, human.body)
    animation, ground = on_floor(human.body, animation, args.keep_height)
    skeleton = target
    if args.rest:
        skeleton, animation = poselib.switch_rest(target, animation, args.rest)
    bvh.save(out / clip.name, skeleton, animation)
    print(f"{clip.name}: {report.summary()}\n{ground.summary()}")
    return _row(report) | {"floor": ground.as_dict()}


def _row(report: RetargetReport) -> dict:
    row = {"source": report.source_convention, "frames": report.frames, "fps": report.fps,
           "scale": report.scale}  # fmt: skip
    if report.quality is not None:
        row.update(report.quality.as_dict())
    return row


def on_floor(body: Body, animation: Animation, keep_height: bool = False,
             most_frames: int = 3000) -> tuple[Animation, floor.FloorReport]:  # fmt: skip
    """Unless ``keep_height``: the motion moved up or down as a whole so planted feet
    touch the floor (``floor.settle``, logged). Returns it and its ``floor.FloorReport``."""
    report = floor.measure_body(body, animation, most_frames)
    if not keep_height:
        animation, shift = floor.settle_body(body, animation, most_frames, report=report)
        report = report.shifted(shift)
        log.info("moved the motion to the floor: %+.1f cm (median; %+.1f to %+.1f cm)",
                 np.median(shift) * 100, shift.min() * 100, shift.max() * 100)  # fmt: skip
    log.info("%s", report.summary())
    return animation, report


def run_poses_list(args: argparse.Namespace) -> int:
    """Built-in poses and pose files in user folders."""
    words = (args.search or "").lower().split()
    for entry in poselib.list_poses(args.folder):
        text = f"{entry.name} {entry.source} {entry.description}".lower()
        if all(w in text for w in words):
            where = f"  {entry.path}" if entry.path else ""
            print(f"{entry.name:24s} {entry.source:9s} {entry.description}{where}")
    return 0
