"""Keypoints -> pose: round trips on fixture clips, missing joints, limits, filter, feet."""

from __future__ import annotations

import numpy as np
import pytest
from tests.mocap.conftest import clips

from avatar.mocap import filters, keypoints, solver

BODY = ("left_shoulder", "right_shoulder", "left_elbow", "right_elbow", "left_wrist",
        "right_wrist", "left_hip", "right_hip", "left_knee", "right_knee", "left_ankle",
        "right_ankle")  # fmt: skip
EXACT = solver.SolverSettings(smoothing=filters.OneEuro.off(), plant_feet=False, scale=1.0)


def _errors(rig, animation, settings=EXACT, points=None, confidence=None):
    truth = rig.positions(animation)
    solved = solver.solve(rig, truth if points is None else points, confidence,
                          animation.fps, settings)  # fmt: skip
    return np.linalg.norm(rig.positions(solved) - truth, axis=-1)  # (T, K) metres


def test_every_fixture_clip_round_trips_within_a_centimetre(fixtures, rig_skeleton, clip_on):
    """Keypoints computed from each fixture clip on the Avatar skeleton, solved back: every
    body joint within 1 cm on every frame (noise-free); the face within 3 cm."""
    rig = keypoints.bind("coco17", rig_skeleton("default"))
    body = [rig.keypoints.index(n) for n in BODY]
    face = [
        rig.keypoints.index(n) for n in ("nose", "left_eye", "right_eye", "left_ear", "right_ear")
    ]
    found = clips(fixtures)
    assert len(found) >= 8
    for path in found:
        err = _errors(rig, clip_on("default", path, 150))
        assert err[:, body].max() < 0.01, (path.name, err[:, body].max())
        assert err[:, face].max() < 0.03, (path.name, err[:, face].max())


@pytest.mark.parametrize("name", ["mediapipe33", "coco17", "h36m17", "openpose25"])
@pytest.mark.parametrize("rig_name", ["default", "game_engine", "mixamo"])
def test_every_keypoint_set_on_every_kind_of_rig(fixtures, rig_skeleton, clip_on, name, rig_name):
    clip = clip_on(rig_name, fixtures / "bvh/cmu_motionbuilder/02_01_walk.bvh", 120)
    rig = keypoints.bind(name, rig_skeleton(rig_name))
    err = _errors(rig, clip)
    body = [rig.keypoints.index(n) for n in BODY if n in rig.keypoints.names]
    assert len(body) == 12
    assert err[:, body].max() < 0.01, err[:, body].max()
    assert np.nanmedian(err[:, rig.solve]) < 0.01


def test_noise_and_dropout_degrade_gracefully(fixtures, rig_skeleton, clip_on):
    """20 mm Gaussian noise: mean joint error well under the noise (the filter and the
    rig's fixed bone lengths absorb it); 20 % of the joints dropped: the held and decayed
    bones keep the error within a few cm, and nothing is NaN."""
    clip = clip_on("default", fixtures / "bvh/cmu_motionbuilder/02_01_walk.bvh", 240)
    rig = keypoints.bind("coco17", rig_skeleton("default"))
    truth = rig.positions(clip)
    rng = np.random.default_rng(0)
    noisy = truth + rng.normal(0, 0.02, truth.shape)
    body = [rig.keypoints.index(n) for n in BODY]
    settings = solver.SolverSettings(plant_feet=False, scale=1.0)
    err = _errors(rig, clip, settings, noisy)
    assert np.isfinite(err).all()
    assert err[:, body].mean() < 0.03
    conf = (rng.random(truth.shape[:2]) > 0.2).astype(float)
    err = _errors(rig, clip, settings, truth, conf)
    assert np.isfinite(err).all()
    assert err[:, body].mean() < 0.05


def test_missing_joints_hold_then_decay_to_rest(fixtures, rig_skeleton, clip_on):
    clip = clip_on("default", fixtures / "bvh/cmu_motionbuilder/02_01_walk.bvh", 60)
    rig = keypoints.bind("coco17", rig_skeleton("default"))
    truth = rig.positions(clip)
    s = solver.PoseSolver(rig, solver.SolverSettings(smoothing=filters.OneEuro.off(), hold=0.5))
    arm = rig.skeleton.index("lowerarm01.L")
    for t in range(30):
        last = s(truth[t], None, t / 30)
    conf = np.ones(len(truth[0]))
    conf[rig.keypoints.index("left_wrist")] = 0.1  # below the threshold: missing
    held = s(truth[30], conf, 30 / 30)
    assert not held.solved[s.plan.index[arm]]
    np.testing.assert_allclose(held.rotations[arm], last.rotations[arm], atol=0.06)
    angles = []
    for t in range(31, 60):
        frame = s(truth[t], conf, t / 30)
        angles.append(2 * np.degrees(np.arccos(min(1.0, abs(frame.rotations[arm, 0])))))
    assert angles[-1] < 0.5 * angles[0] + 0.5  # after ~1 s (two time constants): near rest
    assert all(b <= a + 1e-6 for a, b in zip(angles, angles[1:], strict=False))  # monotone decay


def test_joint_limits_stop_a_knee_folding_through_itself(rig_skeleton):
    rig = keypoints.bind("coco17", rig_skeleton("default"))
    rest = rig.rest.copy()
    knee, ankle = rig.keypoints.index("left_knee"), rig.keypoints.index("left_ankle")
    folded = rest.copy()
    folded[ankle] = 2 * rest[knee] - rest[ankle]  # the shin turned straight up
    s = solver.PoseSolver(rig, solver.SolverSettings(smoothing=filters.OneEuro.off()))
    frame = s(folded, None, 0.0)
    shin = rig.skeleton.index("lowerleg01.L")
    angle = 2 * np.degrees(np.arccos(min(1.0, abs(frame.rotations[shin, 0]))))
    assert angle <= 170.0 + 1e-3
    free = solver.PoseSolver(
        rig, solver.SolverSettings(smoothing=filters.OneEuro.off(), limits=False)
    )
    unlimited = free(folded, None, 0.0).rotations[shin]
    assert 2 * np.degrees(np.arccos(min(1.0, abs(unlimited[0])))) > 170.5


def test_one_euro_lag_matches_its_documented_latency():
    """A point moving steadily at v trails by 1 / (2 pi (min_cutoff + beta v)) seconds."""
    params = filters.OneEuro()
    for speed in (0.2, 1.0, 3.0):
        f = filters.PointFilter(1, params)
        dt = 1 / 240
        for i in range(2400):
            t = i * dt
            out = f(np.array([[speed * t, 0.0, 0.0]]), t)
        lag = (speed * t - out[0, 0]) / speed
        assert abs(lag - params.lag(speed)) < 0.05 * params.lag(speed) + dt, (speed, lag)
    assert filters.OneEuro.off().lag(1.0) == 0.0


def test_one_euro_smooths_jitter_and_passes_missing_points():
    f = filters.PointFilter(2)
    rng = np.random.default_rng(1)
    outs = []
    for i in range(300):
        p = np.array([[0.0, 0.0, 1.0], [np.nan, np.nan, np.nan]]) + rng.normal(0, 0.01, (2, 3))
        outs.append(f(p, i / 30))
    outs = np.array(outs)
    assert np.isnan(outs[:, 1]).all()
    assert outs[100:, 0].std(axis=0).max() < 0.5 * 0.01


def test_planted_feet_hold_still_under_jitter(fixtures, rig_skeleton):
    """A still, standing subject seen with 5 mm jitter: planted ankles move a fraction of
    what the unplanted ones do."""
    import avatar
    from avatar.rig.kinematics import world_pose

    rig = keypoints.bind("coco17", rig_skeleton("default"))
    rest = avatar.Human().pose("t-pose")
    truth = np.repeat(rig.positions(rest), 90, axis=0)
    rng = np.random.default_rng(2)
    noisy = truth + rng.normal(0, 0.005, truth.shape)
    foot = rig.skeleton.index("foot.L")
    paths = {}
    for plant in (False, True):
        settings = solver.SolverSettings(smoothing=filters.OneEuro.off(), plant_feet=plant)
        anim = solver.solve(rig, noisy, None, 30.0, settings)
        paths[plant] = world_pose(rig.skeleton, anim.rotations, anim.translations)[1][:, foot]
    jitter = {k: np.linalg.norm(np.diff(v[10:], axis=0), axis=1).mean() for k, v in paths.items()}
    assert jitter[True] < 0.3 * jitter[False], jitter


def test_bad_input_is_one_clear_error(rig_skeleton):
    from avatar.errors import FormatError, ParameterError

    rig = keypoints.bind("coco17", rig_skeleton("default"))
    s = solver.PoseSolver(rig)
    with pytest.raises(ParameterError, match=r"expected \(17, 3\)"):
        s(np.zeros((16, 3)))
    with pytest.raises(ParameterError, match="unknown keypoint set"):
        keypoints.load("coco18")
    with pytest.raises(FormatError, match="needs 'at' or 'on'"):
        keypoints.parse('{"keypoints": [{"name": "x"}]}', "bad.json")
    with pytest.raises(FormatError, match="unknown role"):
        keypoints.parse('{"keypoints": [{"name": "x", "on": "tail"}]}', "bad.json")
    nothing = s(np.full((17, 3), np.nan))  # all missing: the rest pose, no NaN
    assert np.isfinite(nothing.rotations).all()


def test_axes_conversions_are_rotations():
    for name, m in keypoints.AXES.items():
        np.testing.assert_allclose(m @ m.T, np.eye(3), atol=1e-12, err_msg=name)
        assert np.linalg.det(m) == pytest.approx(1.0)
    # MediaPipe world landmarks: y down, z away from the camera; the head is up, the
    # subject faces the camera (-z), and image-right is the subject's left (+X in Avatar)
    up = keypoints.to_avatar(np.array([0.0, -1.0, 0.0]), "camera")
    facing = keypoints.to_avatar(np.array([0.0, 0.0, -1.0]), "camera")
    np.testing.assert_allclose(up, [0, 0, 1])
    np.testing.assert_allclose(facing, [0, -1, 0])
