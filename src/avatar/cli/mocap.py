"""``avatar mocap record|send|serve``: live motion capture streams (``avatar.mocap``)."""

from __future__ import annotations

import argparse
import time

from avatar.cli import paths
from avatar.errors import ParameterError
from avatar.human import Human
from avatar.io import bvh
from avatar.mocap import keypoints, live, record, vmc
from avatar.mocap.bvhstream import BvhStreamReceiver
from avatar.motion.retarget import retarget


def add_parsers(sub: argparse._SubParsersAction) -> None:
    mocap = sub.add_parser("mocap", help="live motion capture (VMC, BVH over TCP, keypoints)",
                           description="Record, send and serve live motion capture streams "
                           "on Avatar rigs.")  # fmt: skip
    cmds = mocap.add_subparsers(title="commands", metavar="COMMAND")
    p = cmds.add_parser("record", help="record a VMC stream onto a rig as BVH",
                        description="Listen for VMC (OSC over UDP) and write what arrived, "
                        "retargeted onto the rig, as BVH: one frame per /VMC/Ext/OK or bundle, "
                        "at the sender's rate.")  # fmt: skip
    p.add_argument("--vmc", required=True, metavar="HOST:PORT",
                   help="address to listen on (':39539' = every interface)")  # fmt: skip
    p.add_argument("--seconds", type=paths.positive_number, required=True)
    p.add_argument("--rig", default="default", help="Avatar rig to record onto")
    p.add_argument("-o", "--output", required=True, metavar="TAKE.bvh")
    p.set_defaults(run=run_record)
    p = cmds.add_parser("send", help="replay a BVH clip as VMC",
                        description="Send a BVH clip (any humanoid skeleton) as VMC frames "
                        "at its own rate.")  # fmt: skip
    p.add_argument("clip", metavar="CLIP.bvh")
    p.add_argument("--vmc", required=True, metavar="HOST:PORT", help="receiver address")
    p.add_argument("--speed", type=paths.positive_number, default=1.0, help="playback speed")
    p.add_argument("--fast", action="store_true", help="send as fast as possible")
    p.set_defaults(run=run_send)
    p = cmds.add_parser("serve", help="receive a stream, print its statistics, record it",
                        description="Receive one live source and print packet rate, dropped "
                        "packets and latency once a second; with -o, write what arrived onto "
                        "the rig as BVH.")  # fmt: skip
    src = p.add_mutually_exclusive_group(required=True)
    src.add_argument("--vmc", metavar="HOST:PORT", help="listen for VMC")
    src.add_argument("--keypoints", metavar="HOST:PORT",
                     help="listen for the JSON keypoints stream (docs/mocap.md)")  # fmt: skip
    src.add_argument("--bvh-tcp", metavar="HOST:PORT", help="connect to a BVH-over-TCP server")
    p.add_argument(
        "--set", default="mediapipe33", help=f"keypoint set ({', '.join(keypoints.shipped())})"
    )
    p.add_argument("--bvh-header", metavar="FILE.bvh",
                   help="skeleton of a BVH stream that sends no header")  # fmt: skip
    p.add_argument("--seconds", type=paths.positive_number, default=None,
                   help="stop after this long (default: Ctrl-C)")  # fmt: skip
    p.add_argument("--rig", default="default", help="Avatar rig to drive")
    p.add_argument("-o", "--output", metavar="TAKE.bvh", help="record onto the rig as BVH")
    p.set_defaults(run=run_serve)
    p = cmds.add_parser("video", help="motion from a video (MediaPipe Pose) onto a character",
                        description="Estimate the body's motion in a video with MediaPipe Pose "
                        "(pip install 'avatar[mocap]'), solve it onto an Avatar rig and write "
                        "the animated (dressed) character as GLB/glTF/FBX/... or the motion "
                        "as BVH. World landmarks have no travel: the character moves on the "
                        "spot.")  # fmt: skip
    p.add_argument("clip", metavar="CLIP.mp4", help="a video file OpenCV can read")
    p.add_argument("--rig", default="default", help="Avatar rig to drive")
    p.add_argument("--wear", action="append", default=[], metavar="NAME|PATH",
                   help="a garment to wear (avatar clothes list); repeatable")  # fmt: skip
    p.add_argument("--frames", type=paths.positive_number, default=None,
                   help="use at most this many frames")  # fmt: skip
    p.add_argument("-o", "--output", required=True, metavar="OUT.glb|OUT.bvh")
    p.set_defaults(run=run_video)


def run_record(args: argparse.Namespace) -> int:
    paths.output_file(args.output, "take")
    host, port = vmc.parse_address(args.vmc, "0.0.0.0")
    skeleton = Human(rig=args.rig).skeleton
    take = record.record_vmc(skeleton, host, port, args.seconds)
    bvh.save(args.output, skeleton, take)
    print(f"{args.output}: {take.frames} frames at {take.fps:g} fps on the {args.rig} rig")
    return 0


def run_send(args: argparse.Namespace) -> int:
    clip = paths.input_file(args.clip, "clip")
    host, port = vmc.parse_address(args.vmc)
    sent = record.send_clip(clip, host, port, realtime=not args.fast, speed=args.speed)
    print(f"sent {sent} frames to {host}:{port}")
    return 0


def run_serve(args: argparse.Namespace) -> int:
    if args.output:
        paths.output_file(args.output, "take")
    human = Human(rig=args.rig)
    if args.bvh_tcp:
        return _serve_bvh(args, human)
    if args.vmc:
        host, port = vmc.parse_address(args.vmc, "0.0.0.0")
        source = live.open_vmc(human.skeleton, host, port)
    else:
        host, port = vmc.parse_address(args.keypoints, "0.0.0.0")
        source = live.open_keypoints(keypoints.bind(args.set, human.skeleton), host, port)
    poses: list[live.LivePose] = []
    print(f"listening on {source.address[0]}:{source.address[1]}")
    with source:
        _loop(args.seconds, lambda: poses.extend(source.take()), source.stats)
    if args.output:
        take = record.to_animation(poses, human.skeleton)
        bvh.save(args.output, human.skeleton, take)
        print(f"{args.output}: {take.frames} frames at {take.fps:g} fps")
    return 0


def run_video(args: argparse.Namespace) -> int:
    from avatar import export
    from avatar.clothes import library
    from avatar.mocap import video

    clip = paths.input_file(args.clip, "video")
    out = paths.output_file(args.output)
    if out.suffix.lower() not in export.WRITERS:
        raise ParameterError(f"{args.output}: unknown output format; use one of "
                             f"{', '.join(export.WRITERS)}")  # fmt: skip
    for name in args.wear:  # fail early, naming the unknown garment
        library.find_garment(name)
    human = Human(rig=args.rig)
    if args.wear:
        human = human.dressed(*args.wear)
    most = None if args.frames is None else int(args.frames)
    pose = video.estimate(clip, most)
    animation = video.solve(pose, human.skeleton)
    found = int(pose.found.sum())
    export.save(human, out, animation, animation_name=clip.stem)
    print(f"{out}: {animation.frames} frames at {animation.fps:g} fps on the {args.rig} rig "
          f"(a person found in {found} of {len(pose.points)} frames)")  # fmt: skip
    return 0


def _serve_bvh(args: argparse.Namespace, human: Human) -> int:
    host, port = vmc.parse_address(args.bvh_tcp)
    header = None
    if args.bvh_header:
        header = paths.input_file(args.bvh_header, "BVH header").read_text(encoding="utf-8")
    frames: list = []
    with BvhStreamReceiver(host, port, header) as source:
        _loop(args.seconds, lambda: frames.extend(f.data for f in source.take()), source.stats)
        if args.output:
            if not frames:
                raise ParameterError("nothing was received")
            skeleton, clip = source.to_animation(frames)
            take, report = retarget(skeleton, clip, human.skeleton)
            bvh.save(args.output, human.skeleton, take)
            print(f"{args.output}: {take.frames} frames; {report.summary()}")
    return 0


def _loop(seconds: float | None, collect, stats) -> None:
    end = None if seconds is None else time.perf_counter() + seconds
    next_print = time.perf_counter() + 1.0
    try:
        while end is None or time.perf_counter() < end:
            time.sleep(0.05)
            collect()
            if time.perf_counter() >= next_print:
                print(stats().summary(), flush=True)
                next_print += 1.0
    except KeyboardInterrupt:
        pass
    collect()
    print(stats().summary())
