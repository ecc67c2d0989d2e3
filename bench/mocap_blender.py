"""The Blender Mocap panel's timer step: what one 60 Hz tick costs, and the latency from a
VMC sender to the evaluated skin.

    .venv/bin/python bench/mocap_blender.py [--frames 240] [--rig default]

A character is made with the bridge (``avatar.blender.live.create``; pip bpy), a session
listens on loopback (``avatar.mocap.session.LiveSession``), and the fixture walk is sent as
VMC one frame at a time. Per frame, timed separately:

1. ``step``: the newest frame taken and turned into the rig's pose (VMC -> rig);
2. ``write``: the pose written into the pose bones (``mocap_drive.PoseWriter``: two
   ``foreach_set`` calls), against the anchor measured in the same run: the same pose
   written bone by bone (``pose_bone.rotation_quaternion = ...``, the usual add-on way);
3. ``evaluate``: the depsgraph update that deforms the skin (what Blender does after a
   tick anyway; the viewport redraw is not counted);
4. latency: the frame's send -> its pose in hand (the receiver thread, the conversion),
   and end to end -> the evaluated skin showing it (goal: under one 60 Hz frame, 16.7 ms).

Ratios against the 16.7 ms frame budget and against the per-bone anchor are printed, so
the numbers travel between machines.
"""

from __future__ import annotations

import argparse
import os
import statistics
import tempfile
import time
from pathlib import Path

os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="avatar-bpy-"))

import bpy  # noqa: E402, TID251 - a Blender benchmark
import numpy as np  # noqa: E402

import avatar  # noqa: E402
from avatar.blender import live, mocap_drive  # noqa: E402
from avatar.blender.scene import clear_scene  # noqa: E402
from avatar.mocap import unity, vmc  # noqa: E402
from avatar.mocap.session import LiveSession, LiveSettings  # noqa: E402
from avatar.motion import load_bvh, retarget  # noqa: E402
from avatar.motion.timing import select  # noqa: E402

FIXTURE = (
    Path(__file__).resolve().parents[2] / "shared/fixtures/bvh/cmu_motionbuilder/02_01_walk.bvh"
)
BUDGET_MS = 1000.0 / 60.0


def per_bone_write(arm, names, rotations, translations) -> None:
    """The anchor: one RNA assignment per bone and channel."""
    bones = arm.pose.bones
    for j, name in enumerate(names):
        bone = bones.get(name)
        if bone is not None:
            bone.rotation_quaternion = rotations[j]
            bone.location = translations[j]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=240)
    parser.add_argument("--rig", default="default")
    args = parser.parse_args()

    clear_scene()
    human = avatar.Human(rig=args.rig)
    built = live.create(human.recipe, "Bench")
    arm = built.root
    body = next(o for o in built.parts if o.get(live.PART_KEY) == "body")
    source, clip = load_bvh(FIXTURE)
    clip, _ = retarget(source, select(clip, slice(0, args.frames)), human.skeleton, measure=False)
    rig = unity.UnityRig(human.skeleton)
    poses = [rig.to_unity(clip.rotations[i], clip.translations[i]) for i in range(clip.frames)]
    session = LiveSession(human.skeleton, LiveSettings("vmc", "127.0.0.1", 0))
    writer = mocap_drive.PoseWriter(arm, human.skeleton.names)
    sender = vmc.VmcSender(*session.address)
    depsgraph = bpy.context.evaluated_depsgraph_get()
    keys = ("step", "receive", "write", "anchor", "evaluate", "e2e")
    times: dict[str, list[float]] = {k: [] for k in keys}
    try:
        for i, pose in enumerate(poses):
            sent = time.perf_counter()
            sender.send(pose, i / clip.fps)
            got = None
            while got is None and time.perf_counter() - sent < 1.0:
                time.sleep(0.0005)  # a timer's main thread idles between ticks
                t0 = time.perf_counter()
                got = session.step()
            times["step"].append(time.perf_counter() - t0)
            if got is None:
                continue
            times["receive"].append(time.perf_counter() - sent)
            t0 = time.perf_counter()
            writer.write(arm, got.rotations, got.translations)
            times["write"].append(time.perf_counter() - t0)
            t0 = time.perf_counter()
            depsgraph.update()
            body.evaluated_get(depsgraph)
            end = time.perf_counter()
            times["evaluate"].append(end - t0)
            times["e2e"].append(end - sent)
            t0 = time.perf_counter()  # the anchor, after the frame is done
            per_bone_write(arm, human.skeleton.names, got.rotations, got.translations)
            times["anchor"].append(time.perf_counter() - t0)
    finally:
        sender.close()
        session.close()
    ms = {k: 1000.0 * statistics.median(v) for k, v in times.items() if v}
    p95 = {k: 1000.0 * float(np.percentile(v, 95)) for k, v in times.items() if v}
    bones = len(arm.pose.bones)
    print(f"{len(times['e2e'])} frames of {FIXTURE.name} on the {args.rig} rig ({bones} bones)")
    for key, label in (("step", "step (VMC -> rig pose)"), ("receive", "sent -> pose in hand"),
                       ("write", "write (foreach_set)"),
                       ("anchor", "anchor: per-bone write"), ("evaluate", "evaluate (skin)"),
                       ("e2e", "end to end")):  # fmt: skip
        print(f"  {label:24s} median {ms[key]:7.3f} ms  p95 {p95[key]:7.3f} ms  "
              f"= {ms[key] / BUDGET_MS:6.3f} of a 60 Hz frame")  # fmt: skip
    print(f"  write is {ms['anchor'] / ms['write']:.1f}x faster than the per-bone anchor")
    tick = ms["step"] + ms["write"]
    print(f"  a tick (step + write) {tick:.3f} ms = {tick / BUDGET_MS:.3f} of a frame")


if __name__ == "__main__":
    main()
