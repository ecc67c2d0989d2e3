"""Pose library: built-in T/A poses on any rig, pose files, rest-pose switching, CLI."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from avatar.errors import ParameterError
from avatar.io import bvh
from avatar.motion import bonemap, geometry, poselib
from avatar.motion.retarget import retarget
from avatar.rig import poses
from avatar.rig.kinematics import forward

FIXTURES = Path(__file__).resolve().parents[2] / ".." / "shared" / "fixtures" / "bvh"
MH_POSES = FIXTURES / "makehuman_default"
WALK = FIXTURES / "cmu_motionbuilder" / "02_01_walk.bvh"
needs_poses = pytest.mark.skipif(not MH_POSES.is_dir(), reason="../shared/fixtures is absent")
needs_walk = pytest.mark.skipif(not WALK.exists(), reason="../shared/fixtures is absent")
RIGS = ("default", "default_no_toes", "game_engine", "game_engine_with_breast", "cmu_mb", "mixamo")


@pytest.fixture(scope="module")
def skeletons(model):
    from avatar.human import Human

    return {rig: Human(rig=rig, model=model).skeleton for rig in RIGS}


def _heads(skeleton, pose):
    return forward(skeleton, pose.rotations, pose.translations)[..., :3, 3]


def _arm_drop(skeleton, pose) -> np.ndarray:
    """(T, 4) degrees below horizontal of upper arm and forearm, left and right."""
    m = bonemap.detect(skeleton)
    h = _heads(skeleton, pose)
    out = []
    for side in "LR":
        for a, b in (("upperarm", "forearm"), ("forearm", "hand")):
            v = h[:, m.bones[f"{b}.{side}"]] - h[:, m.bones[f"{a}.{side}"]]
            out.append(np.degrees(np.arcsin(-v[:, 2] / np.linalg.norm(v, axis=-1))))
    return np.stack(out, axis=-1)


@pytest.mark.parametrize("rig", RIGS)
def test_built_in_t_and_a_poses_on_every_rig(skeletons, rig):
    skeleton = skeletons[rig]
    m = bonemap.detect(skeleton)
    for name, drop in (("t-pose", 0.0), ("a-pose", 45.0)):
        pose = poselib.built_in(skeleton, name)
        np.testing.assert_allclose(_arm_drop(skeleton, pose), drop, atol=0.5)
        h = _heads(skeleton, pose)[0]
        for side, sign in (("L", 1), ("R", -1)):
            hand = h[m.bones[f"hand.{side}"]] - h[m.bones[f"upperarm.{side}"]]
            assert sign * hand[0] > 0.25  # out sideways, on its own side
            thigh, shin = (h[m.bones[f"{b}.{side}"]] - h[m.bones[f"{a}.{side}"]]
                           for a, b in (("thigh", "shin"), ("shin", "foot")))  # fmt: skip
            assert geometry.angle(thigh, shin) < 0.5  # straight knee
            assert geometry.angle(thigh, [0, 0, -1]) < 10  # legs down
        # Feet and trunk keep their rest place (only arms and legs turn).
        np.testing.assert_allclose(h[m.bones["head"]], skeleton.heads[m.bones["head"]], atol=1e-9)
    assert np.all(poselib.built_in(skeleton, "rest").rotations[..., 0] == 1.0)


def test_human_pose_names(skeletons, model):
    from avatar.human import Human

    human = Human(rig="mixamo", model=model)  # MPFB has no T-pose file for this rig
    np.testing.assert_allclose(_arm_drop(human.skeleton, human.pose("t-pose")), 0.0, atol=0.5)
    with pytest.raises(ParameterError, match="t-pose"):
        human.pose("t-pos")
    from avatar.motion import floor

    lowest = floor.measure_body(human.body, human.pose("a-pose")).lowest_cm
    assert abs(lowest[0]) < 0.05  # stood on the floor
    if MH_POSES.is_dir():  # a sitting pose file: feet on the floor, nothing under it
        sit = floor.measure_body(human.body, human.pose(str(MH_POSES / "sit01.bvh")))
        assert abs(sit.lowest_cm[0]) < 0.05


def test_rebase_keeps_the_world_motion_and_inverse_undoes_it(skeletons):
    from avatar.motion.procedural import MOTIONS

    skeleton = skeletons["default"]
    walk = MOTIONS["walk"](skeleton, fps=30.0)
    t_rest, moved = poselib.switch_rest(skeleton, walk, "t-pose")
    before = forward(skeleton, walk.rotations, walk.translations)
    after = forward(t_rest, moved.rotations, moved.translations)
    np.testing.assert_allclose(after, before, atol=1e-9)
    # The new rest is the T-pose: arms horizontal with identity pose rotations.
    np.testing.assert_allclose(_arm_drop(t_rest, poses.rest_pose(t_rest)), 0.0, atol=0.5)
    np.testing.assert_allclose(t_rest.lengths, skeleton.lengths, atol=1e-9)
    back_rest, back = poses.rebase(
        t_rest, moved, poses.inverse(poselib.built_in(skeleton, "t-pose"))
    )
    np.testing.assert_allclose(back_rest.rest, skeleton.rest, atol=1e-9)
    np.testing.assert_allclose(back_rest.tails, skeleton.tails, atol=1e-9)
    dots = np.abs(np.sum(back.rotations * walk.rotations, axis=-1))
    np.testing.assert_allclose(dots, 1.0, atol=1e-9)
    np.testing.assert_allclose(back.translations, walk.translations, atol=1e-9)


@needs_walk
def test_clip_with_t_pose_rest_retargets_the_same(skeletons):
    """A CMU clip re-expressed over a T-pose rest (motion baked) retargets within 1 degree."""
    source, clip = bvh.load(WALK)
    t_rest, moved = poselib.switch_rest(source, clip, "t-pose")
    assert np.abs(_arm_drop(t_rest, poses.rest_pose(t_rest))).max() < 0.5
    target = skeletons["default"]
    a, _ = retarget(source, clip, target, frames=slice(0, 120))
    b, _ = retarget(t_rest, moved, target, frames=slice(0, 120))
    m = bonemap.detect(target)
    segs = np.array([(m.bones[r], m.bones[n]) for r, n in bonemap.NEXT.items()
                     if r in bonemap.CORE and n in bonemap.CORE])  # fmt: skip
    ha, hb = _heads(target, a), _heads(target, b)
    err = geometry.angle(
        ha[:, segs[:, 1]] - ha[:, segs[:, 0]], hb[:, segs[:, 1]] - hb[:, segs[:, 0]]
    )
    assert err.max() < 1.0


@needs_poses
@pytest.mark.parametrize("rig", ["default", "game_engine", "mixamo", "cmu_mb"])
def test_fixture_t_pose_retargets_with_horizontal_arms(skeletons, rig):
    pose = poselib.load(MH_POSES / "tpose.bvh", skeletons[rig])
    assert pose.frames == 1
    assert np.abs(_arm_drop(skeletons[rig], pose)).max() < 3.0


@needs_poses
def test_fixture_poses_change_the_body_as_named(skeletons):
    skeleton = skeletons["game_engine"]
    m = bonemap.detect(skeleton)
    sit = _heads(skeleton, poselib.load(MH_POSES / "sit01.bvh", skeleton))[0]
    stand = _heads(skeleton, poselib.load(MH_POSES / "standing01.bvh", skeleton))[0]
    # Sitting: thighs about horizontal; standing: about vertical.
    for side in "LR":
        knee, hip = m.bones[f"shin.{side}"], m.bones[f"thigh.{side}"]
        assert geometry.angle(sit[knee] - sit[hip], [0, 0, -1]) > 50
        assert geometry.angle(stand[knee] - stand[hip], [0, 0, -1]) < 35


@needs_poses
def test_library_folders_names_and_env(tmp_path, monkeypatch, skeletons):
    shutil.copy(MH_POSES / "sit01.bvh", tmp_path / "sit01.bvh")
    shutil.copy(MH_POSES / "sit01.meta", tmp_path / "sit01.meta")
    raise_arm = {"bone_rotations": {"upperarm01.L": [0.0, 0.0, 0.8]}}
    (tmp_path / "mpfb").mkdir()
    (tmp_path / "mpfb" / "wave.json").write_text(json.dumps(raise_arm))
    (tmp_path / "mpfb" / "t-pose.json").write_text(json.dumps(raise_arm))  # built-in's name
    (tmp_path / "notes.json").write_text('{"other": 1}')
    names = {e.name: e for e in poselib.list_poses([tmp_path])}
    assert list(names)[:3] == ["rest", "a-pose", "t-pose"]
    assert names["sit01"].source == "bvh" and "Sitting" in names["sit01"].description
    assert names["wave"].source == "mpfb" and "notes" not in names
    assert names["t-pose"].source == "built-in" and names["mpfb/t-pose"].source == "mpfb"
    monkeypatch.setenv(poselib.ENV_PATH, str(tmp_path))
    assert "sit01" in {e.name for e in poselib.list_poses()}
    skeleton = skeletons["default"]
    wave = poselib.load("wave", skeleton)
    j = skeleton.index("upperarm01.L")
    assert np.count_nonzero(np.abs(wave.rotations[0, :, 0] - 1) > 1e-9) == 1
    assert wave.rotations[0, j, 0] == pytest.approx(np.cos(0.4))
    np.testing.assert_allclose(poselib.load("mpfb/t-pose", skeleton).rotations, wave.rotations)
    with pytest.raises(ParameterError, match="sit01"):
        poselib.load("sit0", skeleton)


def test_mpfb_pose_onto_another_rig_through_the_reference(skeletons):
    """MPFB's T-pose names the default rig's bones; on mixamo it goes through the
    retargeter and still raises the arms."""
    from avatar.body import assets

    meta = assets.load().meta["poses"]
    if "default" not in meta:
        pytest.skip("MPFB poses not installed")
    root = Path(assets.load().meta["source"])
    path = root / "poses" / "default_fk" / "t-pose.json"
    if not path.is_file():
        pytest.skip("MPFB pose file not found")
    direct = poselib.load(path, skeletons["default"])
    via = poselib.load(path, skeletons["mixamo"], reference=lambda: skeletons["default"])
    a = _arm_drop(skeletons["default"], direct)
    b = _arm_drop(skeletons["mixamo"], via)
    assert np.abs(a).max() < 15  # MPFB's T-pose is near horizontal ...
    assert np.abs(a - b).max() < 3  # ... and mixamo's arms follow it


def test_cli_pose_and_clip_names_in_the_glb(tmp_path, model, capsys):
    from avatar import cli
    from avatar.io import gltf

    out = tmp_path / "t.glb"
    assert cli.main(["create", "--pose", "t-pose", "-o", str(out)]) == 0
    assert list(gltf.read(out).animations) == ["t-pose"]
    assert cli.main(["create", "--motion", "walk", "--fps", "10", "-o", str(out)]) == 0
    assert list(gltf.read(out).animations) == ["walk"]
    assert cli.main(["poses", "list", "--search", "sideways"]) == 0
    assert capsys.readouterr().out.split()[0] == "t-pose"


@needs_walk
def test_cli_clip_named_and_floor_reported(tmp_path, model, caplog):
    import logging

    from avatar import cli
    from avatar.io import gltf

    out = tmp_path / "walk.glb"
    with caplog.at_level(logging.INFO):
        assert cli.main(["create", "--motion", str(WALK), "--frames", "0:40", "-o", str(out)]) == 0
    assert list(gltf.read(out).animations) == [WALK.stem]
    assert "mesh on floor: penetration" in caplog.text


def test_glb_animation_named_by_save(tmp_path, model):
    from avatar.export import save
    from avatar.human import Human
    from avatar.io import gltf

    human = Human(model=model)
    pose = human.pose("t-pose")
    save(human, tmp_path / "a.glb", pose, animation_name="jump")
    assert list(gltf.read(tmp_path / "a.glb").animations) == ["jump"]
    save(human, tmp_path / "b.glb", pose)
    assert list(gltf.read(tmp_path / "b.glb").animations) == ["animation"]
    save(human, tmp_path / "c.glb")
    assert gltf.read(tmp_path / "c.glb").animations == {}
