"""Live motion capture: solve time, end-to-end latency on loopback, error under noise.

    .venv/bin/python bench/mocap.py [--frames 240] [--clip PATH.bvh] [--runs 5]
        [--reference REV] [--no-errors] [--video CLIP.mp4 | --no-video]

1. Solve time per frame (keypoints -> pose, streaming ``PoseSolver``) for COCO-17 and
   MediaPipe-33 on the default rig (goal < 1 ms), CPU time of this process (the machine is
   shared), each number the median of --runs runs. Two anchors measured in the same runs,
   interleaved with the solver: forward kinematics of the same rig for the same frames
   (``world_pose``, one frame per call: a fixed numpy workload), and the reference solver:
   ``avatar.mocap`` (rotations, filters, feet, plan, solver) as it was at git revision
   --reference (default 9d87694: before the spine-pass reuse and the VMC decoder), imported
   under another name. Then the VMC receive path alone (datagram -> frame -> rotations on
   the rig, CPU ms per frame), against ``avatar.mocap.vmc``/``unity`` at that revision
   (python-osc's parser, a quaternion product of 36 numpy calls per tree level).
2. End to end on loopback (goal < 16.7 ms, one 60 Hz frame), wall time from the send to
   the posed skin mesh (13,380 vertices, linear blend skinning) in this process:
   (a) VMC: bundles built and sent with python-osc alone (not Avatar's sender) -> Avatar's
       VMC receiver -> HumanBodyBones onto the rig -> forward kinematics -> skinning;
   (b) keypoints: JSON datagrams written with ``json`` alone -> Avatar's keypoint receiver
       -> ``PoseSolver`` -> forward kinematics -> skinning.
   Median and 95th percentile per run; the median over runs is reported.
3. Error against Gaussian keypoint noise (0-30 mm) and random joint dropout (0-30 %):
   mean and 95th percentile of the 12 body joints' error, fixture walk on the default rig,
   unfiltered and with the default One Euro filter (whose lag shows as error on a walk).
4. MediaPipe Pose frames/s on this CPU (full model, tracking mode) on --video, or on a short
   Workbench render of the fixture walk (needs the mocap extra and bpy).
"""

from __future__ import annotations

import argparse
import functools
import importlib
import json
import os
import socket
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from pythonosc.osc_bundle_builder import IMMEDIATELY, OscBundleBuilder
from pythonosc.osc_message_builder import OscMessageBuilder
from pythonosc.udp_client import UDPClient

import avatar
from avatar.mocap import filters, keypoints, live, solver, unity
from avatar.motion import load_bvh, retarget
from avatar.motion.timing import select
from avatar.rig import kinematics, skinning
from avatar.rig.kinematics import world_pose

FIXTURE = (
    Path(__file__).resolve().parents[2] / "shared/fixtures/bvh/cmu_motionbuilder/02_01_walk.bvh"
)
BODY = ("left_shoulder", "right_shoulder", "left_elbow", "right_elbow", "left_wrist",
        "right_wrist", "left_hip", "right_hip", "left_knee", "right_knee", "left_ankle",
        "right_ankle")  # fmt: skip
# The solver before this round of speed-ups (plain floats, 0.66-1.2 ms/frame on the 2-core
# container; 4a19b57 is the numpy-per-level one before it); results pinned by
# tests/mocap/test_solver_regression.py. Also the VMC receive path at that revision
# (python-osc's parser, Unity -> rig a product per tree level of 36 numpy calls).
REFERENCE = "9d87694"
MODULES = ("rotations", "filters", "feet", "plan", "solver")
VMC_MODULES = ("stream", "unity", "osc", "vmc")
FRAME_MS = 1000.0 / 60.0


# -- 1. solve time -----------------------------------------------------------------------


def reference_solver(rev: str):
    """``avatar.mocap.solver`` with the modules it leans on as they were at git revision
    ``rev``, imported as a private package (None when git or the revision is missing)."""
    package = _reference_package(rev, MODULES, "solver")
    return None if package is None else importlib.import_module(f"{package}.solver")


def reference_vmc(rev: str):
    """``avatar.mocap.vmc`` (and ``unity``, ``stream``, ``osc`` where it existed) as at git
    revision ``rev``, as a private package: (vmc, unity) modules, or None."""
    package = _reference_package(rev, VMC_MODULES, "vmc")
    if package is None:
        return None
    return (importlib.import_module(f"{package}.vmc"), importlib.import_module(f"{package}.unity"))


def _reference_package(rev: str, modules: tuple[str, ...], kind: str) -> str | None:
    root = Path(__file__).resolve().parents[1]
    package = f"avatar_mocap_{kind}_" + "".join(c if c.isalnum() else "_" for c in rev)
    folder = Path(tempfile.mkdtemp(prefix="avatar-bench-")) / package
    folder.mkdir()
    (folder / "__init__.py").write_text("")
    texts = {}
    for name in modules:
        try:
            texts[name] = subprocess.run(["git", "show", f"{rev}:src/avatar/mocap/{name}.py"],
                                         cwd=root, check=True, capture_output=True,
                                         text=True).stdout  # fmt: skip
        except (OSError, subprocess.CalledProcessError):
            continue  # a module the revision did not have (nothing there imports it)
    if kind not in texts:
        return None
    for name, text in texts.items():
        for other in texts:
            text = text.replace(
                f"from avatar.mocap import {other}", f"from {package} import {other}"
            )
            text = text.replace(f"avatar.mocap.{other}", f"{package}.{other}")
        (folder / f"{name}.py").write_text(text)
    sys.path.insert(0, str(folder.parent))
    return package


def solve_ms(module, rig, truth) -> float:
    """CPU ms per frame of one streaming solve of ``truth`` (10 frames of warm-up first)."""
    s = module.PoseSolver(rig, module.SolverSettings())
    for i in range(10):
        s(truth[i], None, i / 30)
    t = time.process_time()
    for i in range(len(truth)):
        s(truth[i], None, (i + 10) / 30)
    return (time.process_time() - t) / len(truth) * 1e3


def fk_ms(skeleton, clip) -> float:
    """CPU ms per frame of forward kinematics of the rig, one frame per call (the anchor)."""
    rotations, translations = clip.rotations, clip.translations
    t = time.process_time()
    for i in range(clip.frames):
        world_pose(skeleton, rotations[i], translations[i])
    return (time.process_time() - t) / clip.frames * 1e3


def solve_times(human, clip, runs: int, reference) -> None:
    """Print solve ms/frame per keypoint set: medians over runs, ratios to the anchors."""
    modules = {"solver": solver} | ({"reference": reference} if reference else {})
    for name in ("coco17", "mediapipe33"):
        rig = keypoints.bind(name, human.skeleton)
        truth = rig.positions(clip)
        got: dict[str, list[float]] = {k: [] for k in [*modules, "fk"]}
        for _ in range(runs):  # interleaved, so load changes hit every column alike
            for label, module in modules.items():
                got[label].append(solve_ms(module, rig, truth))
            got["fk"].append(fk_ms(human.skeleton, clip))
        ms, fk = statistics.median(got["solver"]), statistics.median(got["fk"])
        per_run = [a / b for a, b in zip(got["solver"], got["fk"], strict=True)]
        line = (f"solve {name:12s} {ms:6.3f} ms/frame (runs {min(got['solver']):.3f}-"
                f"{max(got['solver']):.3f}; goal 1 ms) = {statistics.median(per_run):4.2f} x FK "
                f"of the rig ({fk:.3f} ms)")  # fmt: skip
        if reference:
            old = statistics.median(got["reference"])
            speed = [a / b for a, b in zip(got["reference"], got["solver"], strict=True)]
            line += f"; reference {old:6.3f} ms: {statistics.median(speed):4.2f}x faster"
        print(line)


def vmc_receive_ms(vmc_module, unity_module, skeleton, datagrams: list[bytes]) -> float:
    """CPU ms per frame of the VMC receive path without sockets: datagram -> frame
    (``VmcAssembler``) -> rotations on the rig (``UnityRig.from_unity``)."""
    from avatar.mocap.stream import Counters

    rig = unity_module.UnityRig(skeleton)
    assembler = vmc_module.VmcAssembler(Counters())
    t = time.process_time()
    for data in datagrams:
        for frame in assembler.feed(data, 0.0):
            rig.from_unity(frame.data)
    return (time.process_time() - t) / len(datagrams) * 1e3


def vmc_receive_times(human, clip, runs: int, reference) -> None:
    """Print the VMC receive path's CPU ms per frame, against the reference revision's."""
    from avatar.mocap import vmc

    datagrams = [b.dgram for b in vmc_bundles(human.skeleton, clip, min(clip.frames, 120))]
    got: dict[str, list[float]] = {"now": [], "reference": []}
    for _ in range(runs):
        got["now"].append(vmc_receive_ms(vmc, unity, human.skeleton, datagrams))
        if reference:
            got["reference"].append(vmc_receive_ms(*reference, human.skeleton, datagrams))
    ms = statistics.median(got["now"])
    line = (f"VMC receive (decode {len(datagrams[0])}-byte bundles of 55 bones + onto the rig) "
            f"{ms:6.3f} ms/frame CPU (runs {min(got['now']):.3f}-{max(got['now']):.3f})")
    if reference:
        old = statistics.median(got["reference"])
        speed = [a / b for a, b in zip(got["reference"], got["now"], strict=True)]
        line += f"; reference {old:6.3f} ms: {statistics.median(speed):4.2f}x faster"
    print(line)


# -- 2. end to end ------------------------------------------------------------------------


class PosedMesh:
    """Pose -> the body's skin vertices (V, 3): forward kinematics (Blender's pose-bone
    evaluation, as ``kinematics.forward``) and linear blend skinning, with what depends only
    on the rig (local rest matrices, inverse rest matrices, hierarchy levels) computed once,
    as a live consumer would."""

    def __init__(self, human):
        sk = human.skeleton
        self.skeleton = sk
        self.local_rest = sk.local_rest()
        self.inverse_rest = np.linalg.inv(sk.rest)
        self.levels = [(g, sk.parents[g]) for g in kinematics.levels(sk.parents)]
        self.vertices = human.body.skin_vertices
        self.weights = human.body.skin_weights

    def __call__(self, rotations: np.ndarray, translations: np.ndarray) -> np.ndarray:
        local = self.local_rest @ kinematics.pose_matrices(rotations, translations)
        world = np.empty_like(local)
        for group, parents in self.levels:
            world[group] = local[group] if parents[0] < 0 else world[parents] @ local[group]
        return skinning.linear_blend(self.vertices, self.weights, world @ self.inverse_rest)

    def check(self, rotations: np.ndarray, translations: np.ndarray) -> None:
        """Same vertices as the library's own path (``Human.posed``'s steps)."""
        world = kinematics.forward(self.skeleton, rotations, translations)
        matrices = kinematics.skinning_matrices(self.skeleton, world)
        expected = skinning.linear_blend(self.vertices, self.weights, matrices)
        assert np.allclose(self(rotations, translations), expected, atol=1e-5)


def vmc_bundles(skeleton, clip, count: int) -> list:
    """``count`` VMC frames of the clip as python-osc bundles, built from the spec's
    messages directly (Root/Pos, Bone/Pos per HumanBodyBones bone, OK, T); the clip's poses
    in Unity's axes from ``unity.UnityRig`` (before any timing)."""
    rig = unity.UnityRig(skeleton)
    out = []
    for i in range(count):
        pose = rig.to_unity(clip.rotations[i % clip.frames], clip.translations[i % clip.frames])
        bundle = OscBundleBuilder(IMMEDIATELY)
        messages = [("/VMC/Ext/Root/Pos", ["root", *pose.root[0], *pose.root[1]])]
        messages += [("/VMC/Ext/Bone/Pos", [bone, *p, *q]) for bone, (p, q) in pose.bones.items()]
        messages += [("/VMC/Ext/OK", [1]), ("/VMC/Ext/T", [i / 60])]
        for address, args in messages:
            m = OscMessageBuilder(address)
            for a in args:
                if isinstance(a, str | int):
                    m.add_arg(a, "s" if isinstance(a, str) else "i")
                else:
                    m.add_arg(float(a), "f")
            bundle.add_content(m.build())
        out.append(bundle.build())
    return out


def keypoint_datagrams(truth: np.ndarray, count: int) -> list[bytes]:
    """``count`` frames of keypoints as the stream's documented JSON, written by hand."""
    return [json.dumps({"seq": i, "t": i / 60, "axes": "avatar",
                        "points": [[round(v, 6) for v in p] for p in truth[i % len(truth)].tolist()]
                        }).encode()
            for i in range(count)]  # fmt: skip


def round_trips(source, send, frames: list, mesh: PosedMesh) -> tuple[list, list]:
    """Wall ms from each send to its posed mesh, and of the posing alone."""
    total, posing = [], []
    for data in frames:
        t0 = time.perf_counter()
        send(data)
        pose = None
        while pose is None:
            time.sleep(0.0002)  # yield the interpreter to the receiving thread
            pose = source.poll()
        t1 = time.perf_counter()
        vertices = mesh(pose.rotations, pose.translations)
        t2 = time.perf_counter()
        assert np.isfinite(vertices).all()
        total.append((t2 - t0) * 1e3)
        posing.append((t2 - t1) * 1e3)
        time.sleep(0.002)
    return total, posing


def _send_to(sock: socket.socket, address: tuple[str, int], data: bytes) -> None:
    sock.sendto(data, address)


def latencies(human, clip, runs: int, count: int = 150) -> None:
    mesh = PosedMesh(human)
    mesh.check(clip.rotations[0], clip.translations[0])
    rig = keypoints.bind("coco17", human.skeleton)
    paths = {
        "VMC (python-osc) -> posed mesh": (lambda: live.open_vmc(human.skeleton, "127.0.0.1", 0),
                                           vmc_bundles(human.skeleton, clip, count)),
        "keypoints JSON -> solved -> posed mesh": (
            lambda: live.open_keypoints(rig, "127.0.0.1", 0),
            keypoint_datagrams(rig.positions(clip), count)),
    }  # fmt: skip
    for label, (open_source, frames) in paths.items():
        medians, p95s, worst, posing = [], [], [], []
        for _ in range(runs):
            with open_source() as source, socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as tx:
                if "VMC" in label:
                    send = UDPClient(*source.address).send  # python-osc's own client
                else:
                    send = functools.partial(_send_to, tx, source.address)
                total, pose_ms = round_trips(source, send, frames, mesh)
            medians.append(float(np.median(total)))
            p95s.append(float(np.percentile(total, 95)))
            worst.append(max(total))
            posing.append(float(np.median(pose_ms)))
        med, p95 = statistics.median(medians), statistics.median(p95s)
        skin = statistics.median(posing)
        print(f"latency {label:38s} median {med:5.2f} ms, 95% {p95:5.2f} ms, "
              f"worst {max(worst):5.2f} ms ({med / FRAME_MS:.2f} / {p95 / FRAME_MS:.2f} of a "
              f"60 Hz frame; posing and skinning {skin:.2f} ms of it; 95% per run "
              f"{', '.join(f'{v:.1f}' for v in p95s)}; load {os.getloadavg()[0]:.1f})")  # fmt: skip


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
    parser.add_argument("--runs", type=int, default=5, help="runs per measurement (medians)")
    parser.add_argument("--reference", metavar="REV", default=REFERENCE,
                        help="time the solver at git REV too ('' : not)")  # fmt: skip
    parser.add_argument("--no-errors", action="store_true", help="skip the error curve")
    parser.add_argument("--video", help="MediaPipe frames/s on this video")
    parser.add_argument("--no-video", action="store_true", help="skip MediaPipe")
    args = parser.parse_args()
    human = avatar.Human()
    source, clip = load_bvh(args.clip)
    clip, _ = retarget(source, select(clip, slice(0, args.frames)), human.skeleton, measure=False)
    print(f"clip: {Path(args.clip).name}, {clip.frames} frames at {clip.fps:g} fps, default "
          f"rig; {os.cpu_count()} CPUs, load {os.getloadavg()[0]:.1f}; medians of {args.runs} "
          "runs")  # fmt: skip
    reference = reference_solver(args.reference) if args.reference else None
    if args.reference and reference is None:
        print(f"reference solver at {args.reference}: not available (no git or no such revision)")
    solve_times(human, clip, args.runs, reference)
    vmc_reference = reference_vmc(args.reference) if args.reference else None
    vmc_receive_times(human, clip, args.runs, vmc_reference)
    latencies(human, clip, args.runs)
    if not args.no_errors:
        rig = keypoints.bind("coco17", human.skeleton)
        truth = rig.positions(clip)
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
