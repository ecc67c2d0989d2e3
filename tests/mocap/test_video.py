"""avatar mocap video: errors, hip-centred keypoints on a floor, and ground truth end to end
(a dressed character rendered performing a fixture clip, MediaPipe on the video, the solved
motion compared with the clip). Skipped without OpenCV and MediaPipe (the ``mocap`` extra)."""

from __future__ import annotations

import importlib.util
import os
import tempfile

import numpy as np
import pytest

from avatar.cli import main
from avatar.mocap import filters, keypoints, solver

needs_video = pytest.mark.skipif(
    importlib.util.find_spec("cv2") is None or importlib.util.find_spec("mediapipe") is None,
    reason="the mocap extra (opencv-python-headless, mediapipe) is not installed",
)


def test_hip_centred_keypoints_stand_on_the_floor(fixtures, rig_skeleton, clip_on):
    """World landmarks are centred between the hips: with ``floor="auto"`` and an automatic
    scale the solved pose matches the clip's (root-relative) within a centimetre, and the
    feet stand on the floor (the keypoints are moved into the rig's space after the root
    fit; before, the spine bent to reach shoulders left below the lifted hips)."""
    clip = clip_on("default", fixtures / "bvh/cmu_motionbuilder/02_01_walk.bvh", 90)
    rig = keypoints.bind("mediapipe33", rig_skeleton("default"))
    truth = rig.positions(clip)
    names = rig.keypoints.names
    hips = [names.index("left_hip"), names.index("right_hip")]
    centred = truth - truth[:, hips].mean(axis=1, keepdims=True)
    settings = solver.SolverSettings(smoothing=filters.OneEuro.off(), floor="auto",
                                     plant_feet=False)  # fmt: skip
    got = rig.positions(solver.solve(rig, centred, None, clip.fps, settings))
    got_centred = got - got[:, hips].mean(axis=1, keepdims=True)
    body = [names.index(n) for n in ("left_shoulder", "right_shoulder", "left_elbow",
                                      "right_wrist", "left_knee", "right_ankle")]  # fmt: skip
    err = np.linalg.norm(got_centred[:, body] - centred[:, body], axis=-1)
    assert err.max() < 0.01, err.max()
    ankles = [names.index("left_ankle"), names.index("right_ankle")]
    lowest = np.nanmin(got[:, ankles, 2])
    assert 0.0 < lowest < 0.15, lowest  # the rig's ankle height, not the hips' -0.9 m


@needs_video
def test_missing_or_unreadable_video_is_one_line(tmp_path, capsys):
    out = tmp_path / "out.bvh"
    assert main(["mocap", "video", str(tmp_path / "none.mp4"), "-o", str(out)]) == 1
    err = capsys.readouterr().err
    assert "no such file" in err and err.count("\n") == 1
    bad = tmp_path / "bad.mp4"
    bad.write_bytes(b"not a video at all" * 100)
    assert main(["mocap", "video", str(bad), "-o", str(out)]) == 1
    err = capsys.readouterr().err
    assert "not a video OpenCV can read" in err and err.count("\n") == 1
    assert not out.exists()
    assert main(["mocap", "video", str(bad), "-o", str(tmp_path / "out.xyz")]) == 1
    assert "unknown output format" in capsys.readouterr().err


@needs_video
def test_a_video_without_a_person_fails_cleanly(model, tmp_path, capsys):
    import cv2

    movie = tmp_path / "empty.mp4"
    writer = cv2.VideoWriter(str(movie), cv2.VideoWriter_fourcc(*"mp4v"), 30.0, (128, 128))
    for i in range(10):
        writer.write(np.full((128, 128, 3), 20 * i, np.uint8))
    writer.release()
    out = tmp_path / "out.glb"
    assert main(["mocap", "video", str(movie), "-o", str(out)]) == 1
    assert "found no person" in capsys.readouterr().err
    assert not out.exists()


@needs_video
def test_rendered_walk_is_recovered_from_video(fixtures, model, tmp_path, capsys):
    """Ground truth end to end, short: 24 frames (30 fps) of a CMU walk on a dressed
    character, rendered (Workbench, 256x320), then ``avatar mocap video`` -> BVH. Measured
    on 40 frames at 320x400: PA-MPJPE 57 mm, MPJPE 73 mm; the bounds leave room for the
    smaller picture and MediaPipe's start-up."""
    os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="avatar-test-"))
    pytest.importorskip("bpy")
    import avatar
    from avatar import export
    from avatar.io import bvh
    from avatar.mocap import groundtruth, video
    from avatar.motion import load_bvh, retarget
    from avatar.motion.timing import resample, select

    human = avatar.Human().dressed("tshirt", "jeans")
    source, clip = load_bvh(fixtures / "bvh/cmu_motionbuilder/02_01_walk.bvh")
    clip = select(resample(clip, 30.0), slice(0, 24))
    clip, _ = retarget(source, clip, human.skeleton, measure=False)
    truth = groundtruth.in_place(human.skeleton, clip)
    movie = tmp_path / "walk.mp4"
    character = export.character(human, truth, resolve_garments=False)
    _, camera = groundtruth.render_video(character, movie, truth.fps, (256, 320))
    out = tmp_path / "walk.bvh"
    assert main(["mocap", "video", str(movie), "-o", str(out)]) == 0
    assert "a person found in 24 of 24 frames" in capsys.readouterr().out
    skeleton, written = bvh.load(out)
    assert written.frames == 24 and written.fps == pytest.approx(30.0, rel=1e-3)
    assert "spine05" in skeleton.names  # the default rig
    rest = human.skeleton
    solved = video.solve(video.estimate(movie), rest)
    result = groundtruth.compare(rest, truth, solved, groundtruth.camera_axes(camera))
    print(result.summary())
    assert result.pa_mpjpe < 90.0, result.summary()
    assert result.mpjpe < 120.0, result.summary()
    assert max(result.bones.values()) < 35.0, result.bones
    # smoothed over time without lag: no jerkier than twice the clip (2.8x unsmoothed on
    # the 360-frame forward jumps)
    assert result.jerk[0] < 2.0 * result.jerk[1], result.summary()
    # the comparison sees a wrong turn: the clip turned a quarter more is far off
    quarter = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    axes = groundtruth.camera_axes(camera)
    wrong = groundtruth.compare(rest, truth, solved, quarter @ axes)
    assert wrong.mpjpe > result.mpjpe + 40.0, (wrong.mpjpe, result.mpjpe)
    assert wrong.pa_mpjpe == pytest.approx(result.pa_mpjpe, rel=1e-6)  # Procrustes undoes it


def test_ground_puts_each_frame_on_its_lowest_ankle(fixtures, rig_skeleton, clip_on):
    """Hips-centred keypoints of the forward jumps (crouches before each jump): with
    ``floor="ground"`` the lowest ankle of every frame stands at the rig's ankle height and,
    where the clip has a foot on the floor, the hip joints go up and down with the clip's (a
    crouch lowers them); with one floor for the clip ("auto") the hips stay at standing
    height and the crouching feet float."""
    skeleton = rig_skeleton("default")
    clip = clip_on("default", fixtures / "bvh/cmu_motionbuilder/01_01_forward_jumps.bvh", 640)
    rig = keypoints.bind("mediapipe33", skeleton)
    truth = rig.positions(clip)[::4]  # 30 frames/s
    names = rig.keypoints.names
    hips = [names.index("left_hip"), names.index("right_hip")]
    ankles = [names.index("left_ankle"), names.index("right_ankle")]
    centred = truth - truth[:, hips].mean(axis=1, keepdims=True)
    hip_truth = truth[:, hips, 2].mean(axis=1)
    standing = truth[:, ankles, 2].min(axis=1) < truth[:, ankles, 2].min() + 0.01
    assert np.ptp(hip_truth[standing]) > 0.08  # the clip crouches: hips 8+ cm lower
    rest_ankle = float(np.mean([skeleton.heads[skeleton.index(n), 2]
                                for n in ("foot.L", "foot.R")]))  # fmt: skip
    got = {}
    for floor in ("ground", "auto"):
        settings = solver.SolverSettings(smoothing=filters.OneEuro.off(), floor=floor,
                                         scale=1.0, plant_feet=False)  # fmt: skip
        points = rig.positions(solver.solve(rig, centred, None, 30.0, settings))
        got[floor] = (points[:, ankles, 2].min(axis=1), points[:, hips, 2].mean(axis=1))
    lowest, hip_height = got["ground"]
    np.testing.assert_allclose(lowest, rest_ankle, atol=0.01)
    # the hips follow the clip's up and down (the offset: the clip's standing ankle is not
    # quite at the rig's rest ankle height)
    offset = hip_height[standing] - hip_truth[standing]
    assert np.ptp(offset) < 0.02 and abs(offset.mean()) < 0.03, (np.ptp(offset), offset.mean())
    lowest_auto, _ = got["auto"]
    assert (lowest_auto[standing] - rest_ankle).max() > 0.04  # floating feet, before


def test_a_floor_that_is_not_one_is_a_clear_error(rig_skeleton):
    from avatar.errors import ParameterError

    rig = keypoints.bind("coco17", rig_skeleton("default"))
    for bad in ("floor", float("nan"), [0.0]):
        with pytest.raises(ParameterError, match="floor must be"):
            solver.PoseSolver(rig, solver.SolverSettings(floor=bad))  # type: ignore[arg-type]
