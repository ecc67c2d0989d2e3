"""Live motion capture: solve time, end-to-end latency on loopback, error under noise.

    .venv/bin/python bench/mocap.py [--frames 240] [--clip PATH.bvh] [--baseline REV]
        [--video CLIP.mp4 | --no-video]

1. Solve time per frame (keypoints -> pose, streaming ``PoseSolver``) for COCO-17 and
   MediaPipe-33 on the default rig (goal < 1 ms), with the anchor: one 3x3 numpy matrix
   product timed in the same run (the machine is shared; the ratio travels).
2. End to end on loopback (goal < 16.7 ms, one 60 Hz frame): a VMC bundle sent ->
   received, assembled, turned into the rig's pose and its joints posed (forward
   kinematics); and a JSON keypoints datagram sent -> received and solved.
3. Error against Gaussian keypoint noise (0-30 mm) and random joint dropout (0-30 %):
   mean and 95th percentile of the 12 body joints' error, fixture walk on the default rig,
   unfiltered and with the default One Euro filter (whose lag shows as error on a walk).
4. MediaPipe Pose frames/s on this CPU (full model, tracking mode) on --video, or on a short
   Workbench render of the fixture walk (needs the mocap extra and bpy).

--baseline REV also times ``src/avatar/mocap/solver.py`` as it was at git revision REV (e.g.
the commit before a speed-up) in the same run, interleaved with the current one.
"""

from __future__ import annotations

import argparse
import importlib.util
import os
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import avatar
from avatar.mocap import filters, keypoint_stream, keypoints, live, solver, unity, vmc
from avatar.motion import load_bvh, retarget
from avatar.motion.timing import select
from avatar.rig.kinematics import world_pose

FIXTURE = (
    Path(__file__).resolve().parents[2] / "shared/fixtures/bvh/cmu_motionbuilder/02_01_walk.bvh"
)
BODY = ("left_shoulder", "right_shoulder", "left_elbow", "right_elbow", "left_wrist",
        "right_wrist", "left_hip", "right_hip", "left_knee", "right_knee", "left_ankle",
        "right_ankle")  # fmt: skip


def anchor_us() -> float:
    a = np.eye(3)
    t = time.process_time()
    for _ in range(20000):
        a @ a
    return (time.process_time() - t) / 20000 * 1e6


def solve_time(rig, truth, module=solver, repeats: int = 3) -> float:
    """Best of ``repeats`` runs over the clip, ms per frame (CPU time of this process: the
    machine is shared)."""
    best = []
    for _ in range(repeats):
        s = module.PoseSolver(rig, module.SolverSettings())
        for i in range(10):
            s(truth[i], None, i / 30)
        t = time.process_time()
        for i in range(len(truth)):
            s(truth[i], None, (i + 10) / 30)
        best.append((time.process_time() - t) / len(truth) * 1e3)
    return min(best)


def baseline_solver(rev: str):
    """``avatar.mocap.solver`` as it was at git revision ``rev``, imported under another name."""
    root = Path(__file__).resolve().parents[1]
    text = subprocess.run(["git", "show", f"{rev}:src/avatar/mocap/solver.py"], cwd=root,
                          check=True, capture_output=True, text=True).stdout  # fmt: skip
    path = Path(tempfile.mkdtemp(prefix="avatar-bench-")) / "baseline_solver.py"
    path.write_text(text)
    spec = importlib.util.spec_from_file_location("baseline_solver", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules["baseline_solver"] = module
    spec.loader.exec_module(module)
    return module


def mediapipe_rate(video_path: str | None) -> str:
    """MediaPipe Pose frames/s on a video (or a short render of the fixture walk)."""
    try:
        from avatar.mocap import video
    except ImportError as exc:
        return f"MediaPipe: not measured ({exc})"
    if video_path is None:
        os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="avatar-bench-"))
        from avatar import export
        from avatar.mocap import groundtruth
        from avatar.motion.timing import resample

        human = avatar.Human().dressed("tshirt", "jeans")
        source, clip = load_bvh(FIXTURE)
        clip = select(resample(clip, 30.0), slice(0, 30))
        clip, _ = retarget(source, clip, human.skeleton, measure=False)
        clip = groundtruth.in_place(human.skeleton, clip)
        video_path = str(Path(tempfile.mkdtemp(prefix="avatar-bench-")) / "walk.mp4")
        groundtruth.render_video(export.character(human, clip, resolve_garments=False),
                                 video_path, clip.fps, (320, 400))  # fmt: skip
    video.estimate(video_path, most=5)  # start-up: graph, models, XNNPACK
    t = time.perf_counter()
    pose = video.estimate(video_path)
    rate = len(pose.points) / (time.perf_counter() - t)
    w, h = pose.size
    return (f"MediaPipe Pose (full model, tracking) {rate:6.1f} frames/s at {w}x{h} on this "
            f"CPU ({os.cpu_count()} cores, shared), decoding included; "
            f"person found in {int(pose.found.sum())}/{len(pose.points)} frames")  # fmt: skip


def vmc_latency(skeleton, clip, count=200) -> np.ndarray:
    rig = unity.UnityRig(skeleton)
    out = []
    with live.open_vmc(skeleton, "127.0.0.1", 0) as source, vmc.VmcSender(*source.address) as tx:
        for i in range(count):
            pose = rig.to_unity(clip.rotations[i % clip.frames], clip.translations[i % clip.frames])
            t0 = time.perf_counter()
            tx.send(pose, i / 60)
            got = None
            while got is None:
                time.sleep(0.0002)  # yield the interpreter to the receiving thread
                got = source.poll()
            world_pose(skeleton, got.rotations, got.translations)  # the posed joints
            out.append(time.perf_counter() - t0)
            time.sleep(0.002)
    return np.array(out) * 1e3


def keypoint_latency(rig, truth, count=200) -> np.ndarray:
    out = []
    with live.open_keypoints(rig, "127.0.0.1", 0) as source:
        sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        for i in range(count):
            data = keypoint_stream.encode(i, truth[i % len(truth)], None, i / 60, axes="avatar")
            t0 = time.perf_counter()
            sock.sendto(data, source.address)
            got = None
            while got is None:
                time.sleep(0.0002)  # yield the interpreter to the receiving thread
                got = source.poll()
            out.append(time.perf_counter() - t0)
            time.sleep(0.002)
        sock.close()
    return np.array(out) * 1e3


def error_curve(rig, clip, truth, smoothing) -> list[tuple[float, float, float, float]]:
    body = [rig.keypoints.index(n) for n in BODY]
    rows = []
    for noise in (0.0, 0.005, 0.01, 0.02, 0.03):
        for drop in (0.0, 0.1, 0.2, 0.3):
            rng = np.random.default_rng([int(noise * 1000), int(drop * 100)])
            points = truth + rng.normal(0, noise, truth.shape) if noise else truth
            conf = (rng.random(truth.shape[:2]) >= drop).astype(float)
            settings = solver.SolverSettings(scale=1.0, smoothing=smoothing)
            anim = solver.solve(rig, points, conf, clip.fps, settings)
            err = np.linalg.norm(rig.positions(anim)[:, body] - truth[:, body], axis=-1) * 1000
            rows.append(
                (noise * 1000, drop * 100, float(err.mean()), float(np.percentile(err, 95)))
            )
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=240)
    parser.add_argument("--clip", default=str(FIXTURE))
    parser.add_argument("--baseline", metavar="REV", help="also time the solver at git REV")
    parser.add_argument("--video", help="MediaPipe frames/s on this video")
    parser.add_argument("--no-video", action="store_true", help="skip MediaPipe")
    args = parser.parse_args()
    human = avatar.Human()
    source, clip = load_bvh(args.clip)
    clip, _ = retarget(source, select(clip, slice(0, args.frames)), human.skeleton, measure=False)
    print(f"clip: {Path(args.clip).name}, {clip.frames} frames at {clip.fps:g} fps, default rig")
    anchor = anchor_us()
    print(f"anchor: one 3x3 matrix product {anchor:.2f} us")
    old = baseline_solver(args.baseline) if args.baseline else None
    for name in ("coco17", "mediapipe33"):
        rig = keypoints.bind(name, human.skeleton)
        truth = rig.positions(clip)
        if old is not None:
            ms = solve_time(rig, truth, old)
            print(f"solve {name:12s} {ms:6.3f} ms/frame  (= {ms * 1000 / anchor:5.0f} anchors) "
                  f"at {args.baseline}")  # fmt: skip
        ms = solve_time(rig, truth)
        print(f"solve {name:12s} {ms:6.3f} ms/frame  (= {ms * 1000 / anchor:5.0f} anchors; "
              f"goal 1 ms)")  # fmt: skip
    rig = keypoints.bind("coco17", human.skeleton)
    truth = rig.positions(clip)
    for label, lat in (("VMC -> posed joints", vmc_latency(human.skeleton, clip)),
                       ("keypoints UDP -> solved", keypoint_latency(rig, truth))):  # fmt: skip
        p95 = np.percentile(lat, 95)
        print(f"latency {label:24s} median {np.median(lat):6.2f} ms, 95% {p95:6.2f} ms,"
              f" max {lat.max():6.2f} ms  (goal 16.7 ms)")  # fmt: skip
    print("body joint error, mm (12 joints): mean / 95th percentile")
    print("noise mm  dropout %   unfiltered     One Euro (defaults)")
    off = error_curve(rig, clip, truth, filters.OneEuro.off())
    on = error_curve(rig, clip, truth, filters.OneEuro())
    for (noise, drop, m0, p0), (_, _, m1, p1) in zip(off, on, strict=True):
        print(f"{noise:8.0f}  {drop:9.0f}  {m0:6.1f} / {p0:5.1f}   {m1:6.1f} / {p1:5.1f}")
    if not args.no_video:
        print(mediapipe_rate(args.video))


if __name__ == "__main__":
    main()
