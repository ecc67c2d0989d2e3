"""Floor contact of the skinned body: penetration and hover measured on the mesh."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from avatar.motion import floor
from avatar.rig.poses import rest_pose
from avatar.rig.skeleton import Animation


@pytest.fixture(scope="module")
def human(model):
    from avatar.human import Human

    return Human(model=model)


def _shifted(human, heights_m) -> Animation:
    """The rest pose moved vertically by ``heights_m`` (T,) metres, one frame each."""
    skeleton = human.skeleton
    base = rest_pose(skeleton)
    t = len(heights_m)
    rot = np.repeat(base.rotations, t, axis=0)
    trans = np.zeros((t, len(skeleton.names), 3))
    root = int(np.flatnonzero(skeleton.parents < 0)[0])
    world = np.zeros((t, 3))
    world[:, 2] = heights_m
    trans[:, root] = world @ skeleton.rest[root, :3, :3]  # into the root's rest frame
    return Animation(rot, trans, 30.0, skeleton.names)


def test_rest_pose_stands_on_the_floor(human):
    report = floor.measure_body(human.body, _shifted(human, np.zeros(12)))
    assert report.frames == 12 and report.total_frames == 12
    assert np.abs(report.lowest_cm).max() < 0.2
    assert report.penetration_cm < 0.1 and report.penetrating == 0.0
    # Both feet still all along: every frame is a contact, with the soles on the floor.
    assert report.contact_frames == 12 and report.hover_cm < 0.2


def test_sinking_and_hovering_are_measured(human):
    sunk = floor.measure_body(human.body, _shifted(human, np.full(10, -0.03)))
    assert sunk.penetration_cm == pytest.approx(3.0, abs=0.2)
    assert sunk.penetrating == 1.0
    raised = floor.measure_body(human.body, _shifted(human, np.full(10, 0.05)))
    assert raised.penetration_cm == 0.0 and raised.penetrating == 0.0
    assert raised.hover_cm == pytest.approx(5.0, abs=0.2)
    half = floor.measure_body(human.body, _shifted(human, np.r_[np.zeros(5), np.full(5, -0.02)]))
    assert half.penetrating == pytest.approx(0.5)
    assert "penetration" in half.summary() and "hover" in half.summary()
    assert set(half.as_dict()) >= {"penetration_cm", "penetrating", "hover_cm"}


def test_long_clips_are_subsampled(human):
    heights = np.zeros(700)
    heights[350] = -0.04  # one sunk frame in the middle: picked by the even subsample
    report = floor.measure_body(human.body, _shifted(human, heights), most_frames=101)
    assert report.frames == 101 and report.total_frames == 700
    assert report.penetration_cm == pytest.approx(4.0, abs=0.2)
    assert report.penetrating == pytest.approx(1 / 101)


def test_pick_frames():
    assert list(floor.pick_frames(5, 10)) == [0, 1, 2, 3, 4]
    picked = floor.pick_frames(1000, 50)
    assert len(picked) == 50 and picked[0] == 0 and picked[-1] == 999
    assert np.all(np.diff(picked) > 0)


def test_settle_puts_planted_feet_on_the_floor(human):
    """A standing body bobbing 4-8 cm above the floor comes down onto it, frame by frame;
    one sunk below it comes up; the shift is vertical only."""
    bob = 0.06 + 0.02 * np.sin(np.linspace(0, 2 * np.pi, 40))
    lifted = _shifted(human, bob)
    settled, shift = floor.settle_body(human.body, lifted)
    np.testing.assert_allclose(shift, -bob, atol=0.003)
    report = floor.measure_body(human.body, settled)
    assert report.penetration_cm < 0.1 and report.hover_cm < 0.1
    # The report after a shift follows from the one before, without skinning again.
    guess = floor.measure_body(human.body, lifted).shifted(shift)
    np.testing.assert_allclose(guess.lowest_cm, report.lowest_cm, atol=1e-3)
    assert guess.hover_cm == pytest.approx(report.hover_cm, abs=1e-3)
    _, one = floor.settle_body(human.body, lifted, per_frame=False)
    np.testing.assert_allclose(one, -np.median(bob), atol=0.003)
    sunk, up = floor.settle_body(human.body, _shifted(human, [-0.05]))  # one frame: no contacts
    assert up[0] == pytest.approx(0.05, abs=0.002)
    assert floor.measure_body(human.body, sunk).penetration_cm < 0.1
    # The whole body moved straight up or down, nothing else.
    from avatar.rig.kinematics import forward

    a = forward(human.skeleton, lifted.rotations, lifted.translations)[..., :3, 3]
    b = forward(human.skeleton, settled.rotations, settled.translations)[..., :3, 3]
    np.testing.assert_allclose(b[..., :2], a[..., :2], atol=1e-6)
    np.testing.assert_allclose(b[..., 2] - a[..., 2], np.broadcast_to(shift[:, None], b.shape[:2]),
                               atol=1e-6)  # fmt: skip


FIXTURES = Path(__file__).resolve().parents[2] / ".." / "shared" / "fixtures" / "bvh"
CLIPS = sorted(p for p in FIXTURES.glob("*/*.bvh") if "face" not in p.name)


@pytest.mark.skipif(not CLIPS, reason="../shared/fixtures/bvh is absent")
@pytest.mark.parametrize("clip", CLIPS, ids=lambda p: f"{p.parent.name}/{p.name}")
def test_retargeted_clips_stand_on_the_floor_before_settling(human, clip):
    """The retargeter's own output (no mesh, no settle): planted feet within 1 cm of the
    floor (median), no skin vertex more than 1 cm under it."""
    from avatar.io import bvh
    from avatar.motion.retarget import retarget

    source, clip_animation = bvh.load(clip)
    out, _ = retarget(source, clip_animation, human.skeleton, measure=False)
    report = floor.measure_body(human.body, out, most_frames=600)
    assert report.hover_cm < 1.0 and report.penetration_cm < 1.0, report.summary()


@pytest.mark.skipif(not CLIPS, reason="../shared/fixtures/bvh is absent")
def test_retarget_onto_a_human_settles_on_its_skin(human):
    from avatar.io import bvh
    from avatar.motion.retarget import retarget

    source, clip_animation = bvh.load(FIXTURES / "cmu_motionbuilder" / "02_01_walk.bvh")
    out, report = retarget(source, clip_animation, human.skeleton, body=human.body)
    assert report.floor is not None and "mesh on floor" in report.summary()
    assert report.floor.penetration_cm < 0.1 and report.floor.hover_cm < 0.1
    bare, plain = retarget(source, clip_animation, human.skeleton)
    assert plain.floor is None
    settled, _ = floor.settle_body(human.body, bare)
    np.testing.assert_allclose(out.translations, settled.translations, atol=1e-9)
    np.testing.assert_allclose(out.rotations, bare.rotations)


def test_sole_points_lie_on_the_floor_under_the_feet(human):
    from avatar.motion import bonemap, contacts

    skeleton = human.skeleton
    tmap = bonemap.detect(skeleton)
    bones, points = contacts.soles(skeleton, tmap)
    assert contacts.floor_height(skeleton, tmap) == 0.0
    assert len(bones) >= 10 and np.all(points[:, 2] >= 0.0)
    tips = points[:, 2] > 0.0  # half way down from the toe tips; the rest on the floor
    assert 0 < tips.sum() < len(points)
    np.testing.assert_allclose(points[tips, 2], skeleton.tails[bones[tips], 2] / 2)
    # Under the feet: each point within a foot's length of its side's ankle.
    for side, sign in (("L", 1), ("R", -1)):
        ankle = skeleton.heads[tmap.bones[f"foot.{side}"]]
        mine = points[np.sign(points[:, 0]) == sign]
        assert len(mine) == len(points) // 2
        assert np.linalg.norm(mine[:, :2] - ankle[:2], axis=1).max() < 0.25
    # The rest pose needs no lift; the same pose sunk 3 cm rises 3 cm.
    rest = np.tile(_rest_rotations(skeleton)[:, None], (1, 2, 1))
    root = np.tile(skeleton.heads[tmap.bones["hips"]], (2, 1))
    root[1, 2] -= 0.03
    up = contacts.lift(skeleton, tmap, rest, root, fps=1.0)  # 0.1 s: no easing
    np.testing.assert_allclose(up, [0.0, 0.03], atol=1e-6)


def _rest_rotations(skeleton) -> np.ndarray:
    """(J, 4) rest world rotations of every bone."""
    from avatar.rig.kinematics import rest_quaternions

    return rest_quaternions(skeleton)[0]
