"""Retargeting properties: identity, invariance to naming/units/orders/up axis/rest pose,
and the quality targets on every fixture clip."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from avatar.io import bvh
from avatar.motion import bonemap, geometry
from avatar.motion.retarget import retarget
from avatar.rig import quaternion
from avatar.rig.kinematics import forward

FIXTURES = Path(__file__).resolve().parents[2] / ".." / "shared" / "fixtures" / "bvh"
CLIPS = (
    sorted(p for p in FIXTURES.glob("*/*.bvh") if "face" not in p.name) if FIXTURES.is_dir() else []
)
needs_fixtures = pytest.mark.skipif(not CLIPS, reason="../shared/fixtures/bvh is absent")
WALK = FIXTURES / "cmu_motionbuilder" / "02_01_walk.bvh"


def _clip(frames: slice = slice(0, 120)) -> bvh.BvhData:
    data = bvh.read(WALK)
    return bvh.BvhData(data.names, data.parents, data.offsets, data.channels, data.end_sites,
                       data.motion[frames], data.frame_time)  # fmt: skip


@pytest.fixture(scope="module")
def target():
    from avatar.human import Human

    return Human().skeleton


@pytest.fixture(scope="module")
def reference(target):
    sk, an = bvh.to_animation(_clip())
    out, report = retarget(sk, an, target)
    return out, report


def _compare(target, a, b, limit_deg: float, path_cm: float = 1.0) -> None:
    """Same world direction (within ``limit_deg``) of every body segment between mapped
    joints of the target (fingers excluded), and the same hips path."""
    tmap = bonemap.detect(target)
    segs = [(tmap.bones[r], tmap.bones[n]) for r, n in bonemap.NEXT.items()
            if r in bonemap.CORE and n in tmap.bones and r in tmap.bones]  # fmt: skip
    heads = [forward(target, x.rotations, x.translations)[..., :3, 3] for x in (a, b)]
    idx = np.array(segs)
    da = heads[0][:, idx[:, 1]] - heads[0][:, idx[:, 0]]
    db = heads[1][:, idx[:, 1]] - heads[1][:, idx[:, 0]]
    err = geometry.angle(da, db)
    worst = target.names[segs[int(err.max(axis=0).argmax())][0]]
    assert err.max() < limit_deg, (err.max(), worst)
    assert np.abs(heads[0][:, 0] - heads[1][:, 0]).max() * 100 < path_cm


@needs_fixtures
def test_retarget_onto_own_skeleton_is_identity():
    sk, an = bvh.to_animation(_clip())
    out, report = retarget(sk, an, sk, fix_feet=False)
    src = forward(sk, an.rotations, an.translations)
    dst = forward(sk, out.rotations, out.translations)
    rel = np.swapaxes(src[..., :3, :3], -1, -2) @ dst[..., :3, :3]
    angle = np.degrees(np.arccos(np.clip((np.trace(rel, axis1=-2, axis2=-1) - 1) / 2, -1, 1)))
    assert angle.max() < 0.1
    assert report.scale == pytest.approx(1.0)
    drift = dst[:, 0, :3, 3] - src[:, 0, :3, 3]
    assert np.abs(drift - drift.mean(axis=0)).max() < 1e-6  # same path up to a floor shift


@needs_fixtures
def test_renamed_to_another_convention_gives_the_same_result(target, reference):
    data = _clip()
    cmu = bonemap.conventions()["cmu_motionbuilder"]
    mixamo = bonemap.conventions()["mixamo"]
    rename = {cmu[r][0]: "mixamorig:" + mixamo[r][0] for r in cmu if r in mixamo}
    names = tuple(rename.get(n, "extra:" + n) for n in data.names)
    renamed = bvh.BvhData(names, data.parents, data.offsets, data.channels, data.end_sites,
                          data.motion, data.frame_time)  # fmt: skip
    sk, an = bvh.to_animation(bvh.loads(bvh.dumps(renamed)))
    out, report = retarget(sk, an, target)
    assert report.source_convention == "mixamo"
    _compare(target, reference[0], out, 1.0)


FILE_FORMS = [("mm", "y", "ZYX"), ("m", "z", "XYZ"), ("in", "-y", "YZX"), ("dm", "x", "ZXY")]


@needs_fixtures
@pytest.mark.parametrize(("unit", "up", "order"), FILE_FORMS)
def test_units_up_axes_and_rotation_orders_do_not_change_the_result(
    target, reference, unit, up, order
):
    sk, an = bvh.to_animation(_clip())
    text = bvh.dumps(bvh.from_animation(sk, an, unit=unit, up=up, order=order), precision=8)
    sk2, an2 = bvh.to_animation(bvh.loads(text))
    assert sk2.extra == {"bvh_unit": unit, "bvh_up": up}
    out, _ = retarget(sk2, an2, target)
    _compare(target, reference[0], out, 1.0)


def _bake_rest(data: bvh.BvhData, joint: str, turn: np.ndarray) -> bvh.BvhData:
    """Change the rest pose: the subtree below ``joint`` rests turned by ``turn`` (quat,
    file axes); the motion is rewritten so every joint stays where it was."""
    j0 = data.names.index(joint)
    inside = np.zeros(len(data.names), dtype=bool)
    for j, p in enumerate(data.parents):
        inside[j] = j != j0 and (p == j0 or (p >= 0 and inside[p]))
    m = quaternion.to_matrix(turn)
    offsets = np.where(inside[:, None], data.offsets @ m.T, data.offsets)
    ends = np.where(inside[:, None], data.end_sites @ m.T, data.end_sites)
    q = bvh.local_rotations(data)
    inv = quaternion.conjugate(turn)
    q[:, j0] = quaternion.multiply(q[:, j0], inv)
    q[:, inside] = quaternion.multiply(quaternion.multiply(turn, q[:, inside]), inv)
    motion = data.motion.copy()
    starts = data.channel_starts()
    for j, chans in enumerate(data.channels):
        rot = [k for k, c in enumerate(chans) if c.endswith("rotation")]
        order = "".join(chans[k][0] for k in rot)
        angles = np.degrees(quaternion.to_euler(q[:, j], order[::-1])[..., ::-1])
        motion[:, starts[j] + np.array(rot)] = angles
    return bvh.BvhData(data.names, data.parents, offsets, data.channels, ends, motion,
                       data.frame_time)  # fmt: skip


@needs_fixtures
def test_a_different_rest_pose_with_baked_motion_gives_the_same_result(target, reference):
    data = _clip()
    down = quaternion.from_axis_angle(np.array([0.0, 0.0, 1.0]), np.radians(-50.0))
    up = quaternion.from_axis_angle(np.array([0.0, 0.0, 1.0]), np.radians(50.0))
    twist = quaternion.from_axis_angle(np.array([1.0, 0.0, 0.0]), np.radians(30.0))
    baked = _bake_rest(_bake_rest(data, "LeftArm", down), "RightArm", up)
    baked = _bake_rest(baked, "LeftUpLeg", twist)
    a = bvh.world_positions(data)
    b = bvh.world_positions(baked)
    assert np.abs(a - b).max() < 1e-6  # same motion, different rest
    sk, an = bvh.to_animation(baked)
    out, _ = retarget(sk, an, target)
    _compare(target, reference[0], out, 1.0)


@needs_fixtures
@pytest.mark.parametrize("clip", CLIPS, ids=lambda p: f"{p.parent.name}/{p.name}")
def test_quality_targets_on_every_fixture_clip(target, clip):
    sk, an = bvh.load(clip)
    _, report = retarget(sk, an, target)
    q = report.quality
    assert q.direction_median < 2.0 and q.direction_p95 < 5.0, q.summary()
    assert q.skating_cm < 1.0, q.summary()


@needs_fixtures
def test_hand_and_finger_base_starting_at_the_wrist_both_follow_the_source(reference):
    """CMU's finger base starts at the wrist: the hand's segment runs over the finger bone,
    which has its own pair. Both segments land on the source's directions."""
    per_bone = reference[1].quality.per_bone
    for side in "LR":
        assert per_bone[f"hand.{side}"] < 0.05 and per_bone[f"middle1.{side}"] < 0.05, per_bone
