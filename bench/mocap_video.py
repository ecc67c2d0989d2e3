"""Motion capture from video against ground truth, end to end.

    .venv/bin/python bench/mocap_video.py [--clip PATH.bvh] [--frames 240]
        [--wear tshirt --wear jeans] [--strip docs/images/mocap_video.png]
        [--keep DIR [--reuse]]

A dressed Avatar character performs a fixture clip (travel removed: a camera tracking the
pelvis), rendered with Blender's Workbench into an MP4 (OpenCV); ``avatar mocap video``
turns the video back into motion on the same rig; the two are compared on the 17 COCO
joints (MPJPE, PA-MPJPE in mm, direction error per bone; ``avatar.mocap.groundtruth``).
Anchor: HybrIK reports PA-MPJPE 44.5 mm on 3DPW (real videos; a different, harder test).
Also prints MediaPipe's frames/s on this CPU. With --strip, writes a side-by-side picture
(top: rendered input; bottom: the solved motion on the same character and camera).
--keep DIR keeps the video and its camera there; --reuse then skips the render (the clip,
frame count and clothes must be the same) to re-run the estimate, the solve and the strip.
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

import numpy as np

os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="avatar-bench-"))

import avatar  # noqa: E402
from avatar import export  # noqa: E402
from avatar.cli import main as cli  # noqa: E402
from avatar.mocap import groundtruth, video  # noqa: E402
from avatar.motion import load_bvh, retarget  # noqa: E402
from avatar.motion.timing import resample, select  # noqa: E402

FIXTURE = (
    Path(__file__).resolve().parents[2] / "shared/fixtures/bvh/cmu_motionbuilder/02_01_walk.bvh"
)


def run(clip_path: Path, frames: int, wear: list[str], resolution: tuple[int, int],
        folder: Path, strip: Path | None, every: int,
        reuse: bool = False) -> groundtruth.Comparison:  # fmt: skip
    human = avatar.Human()
    if wear:
        human = human.dressed(*wear)
    source, clip = load_bvh(clip_path)
    clip = select(resample(clip, 30.0), slice(0, frames))  # a 30 fps camera
    clip, _ = retarget(source, clip, human.skeleton, measure=False)
    truth = groundtruth.in_place(human.skeleton, clip)
    character = export.character(human, truth, resolve_garments=False)
    movie, saved = folder / "input.mp4", folder / "camera.npy"
    print(f"clip {clip_path.name}: {truth.frames} frames at {truth.fps:g} fps")
    if reuse and movie.is_file() and saved.is_file():
        camera = np.load(saved)
        pictures = np.array(list(video.frames(movie)[2]))
        print(f"reusing {movie} ({len(pictures)} frames)")
    else:
        t = time.perf_counter()
        pictures, camera = groundtruth.render_video(character, movie, truth.fps, resolution)
        np.save(saved, camera)
        print(f"rendered {len(pictures)} frames {resolution[0]}x{resolution[1]} (Workbench) "
              f"in {time.perf_counter() - t:.1f} s -> {movie}")  # fmt: skip
    out = folder / "solved.bvh"
    t = time.perf_counter()
    assert cli(["mocap", "video", str(movie), "-o", str(out)]) == 0
    print(f"avatar mocap video: {time.perf_counter() - t:.1f} s")
    t = time.perf_counter()
    pose = video.estimate(movie)
    seconds = time.perf_counter() - t
    print(f"MediaPipe Pose (full model) on this CPU: {len(pose.points) / seconds:.1f} frames/s "
          f"at {resolution[0]}x{resolution[1]} ({os.cpu_count()} cores, shared)")  # fmt: skip
    solved = video.solve(pose, human.skeleton)
    axes = groundtruth.camera_axes(camera)
    result = groundtruth.compare(human.skeleton, truth, solved, axes)
    print(result.summary())
    for name, deg in result.bones.items():
        print(f"  {name:12s} {deg:5.1f} deg")
    print("anchor: HybrIK PA-MPJPE 44.5 mm on 3DPW")
    if strip is not None:
        _strip(human, truth, solved, camera, axes, pictures, strip, every, resolution)
    return result


def _strip(human, truth, solved, camera, axes, pictures, path, every, resolution) -> None:
    """Top row: rendered input frames; bottom row: the solved motion turned back into the
    world, rendered from the same camera."""
    import cv2

    back = groundtruth.upright(solved, human.skeleton, axes)
    character = export.character(human, back, resolve_garments=False, name="Solved")
    picks = list(range(0, len(pictures), every))
    with tempfile.TemporaryDirectory() as tmp:
        got, _ = groundtruth.render_video(character, Path(tmp) / "solved.mp4", truth.fps,
                                          resolution, camera=camera, only=picks)  # fmt: skip
    top = np.concatenate([pictures[i] for i in picks], axis=1)
    bottom = np.concatenate(list(got), axis=1)
    path.parent.mkdir(parents=True, exist_ok=True)
    cv2.imwrite(str(path), cv2.cvtColor(np.concatenate([top, bottom], axis=0), cv2.COLOR_RGB2BGR))
    print(f"strip: {path} (frames {picks})")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--clip", default=str(FIXTURE))
    parser.add_argument("--frames", type=int, default=240)
    parser.add_argument("--wear", action="append", default=[])
    parser.add_argument("--size", default="320x400", help="WIDTHxHEIGHT pixels")
    parser.add_argument("--strip", type=Path, default=None)
    parser.add_argument("--every", type=int, default=30, help="strip: every N-th frame")
    parser.add_argument("--keep", type=Path, default=None, help="keep the video here")
    parser.add_argument("--reuse", action="store_true", help="--keep's video, not rendered again")
    args = parser.parse_args()
    width, height = (int(v) for v in args.size.split("x"))
    wear = args.wear or ["tshirt", "jeans"]
    if args.keep:
        args.keep.mkdir(parents=True, exist_ok=True)
        run(Path(args.clip), args.frames, wear, (width, height), args.keep, args.strip, args.every,
            args.reuse)  # fmt: skip
        return
    with tempfile.TemporaryDirectory(prefix="avatar-mocap-video-") as tmp:
        run(Path(args.clip), args.frames, wear, (width, height), Path(tmp), args.strip,
            args.every)  # fmt: skip


if __name__ == "__main__":
    main()
