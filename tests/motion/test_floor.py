"""Floor contact of the skinned body: penetration and hover measured on the mesh."""

from __future__ import annotations

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
    report = floor.measure_human(human, _shifted(human, np.zeros(12)))
    assert report.frames == 12 and report.total_frames == 12
    assert np.abs(report.lowest_cm).max() < 0.2
    assert report.penetration_cm < 0.1 and report.penetrating == 0.0
    # Both feet still all along: every frame is a contact, with the soles on the floor.
    assert report.contact_frames == 12 and report.hover_cm < 0.2


def test_sinking_and_hovering_are_measured(human):
    sunk = floor.measure_human(human, _shifted(human, np.full(10, -0.03)))
    assert sunk.penetration_cm == pytest.approx(3.0, abs=0.2)
    assert sunk.penetrating == 1.0
    raised = floor.measure_human(human, _shifted(human, np.full(10, 0.05)))
    assert raised.penetration_cm == 0.0 and raised.penetrating == 0.0
    assert raised.hover_cm == pytest.approx(5.0, abs=0.2)
    half = floor.measure_human(human, _shifted(human, np.r_[np.zeros(5), np.full(5, -0.02)]))
    assert half.penetrating == pytest.approx(0.5)
    assert "penetration" in half.summary() and "hover" in half.summary()
    assert set(half.as_dict()) >= {"penetration_cm", "penetrating", "hover_cm"}


def test_long_clips_are_subsampled(human):
    heights = np.zeros(700)
    heights[350] = -0.04  # one sunk frame in the middle: picked by the even subsample
    report = floor.measure_human(human, _shifted(human, heights), most_frames=101)
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
    settled, shift = floor.settle_human(human, lifted)
    np.testing.assert_allclose(shift, -bob, atol=0.003)
    report = floor.measure_human(human, settled)
    assert report.penetration_cm < 0.1 and report.hover_cm < 0.1
    # The report after a shift follows from the one before, without skinning again.
    guess = floor.measure_human(human, lifted).shifted(shift)
    np.testing.assert_allclose(guess.lowest_cm, report.lowest_cm, atol=1e-3)
    assert guess.hover_cm == pytest.approx(report.hover_cm, abs=1e-3)
    _, one = floor.settle_human(human, lifted, per_frame=False)
    np.testing.assert_allclose(one, -np.median(bob), atol=0.003)
    sunk, up = floor.settle_human(human, _shifted(human, [-0.05]))  # one frame: no contacts
    assert up[0] == pytest.approx(0.05, abs=0.002)
    assert floor.measure_human(human, sunk).penetration_cm < 0.1
    # The whole body moved straight up or down, nothing else.
    from avatar.rig.kinematics import forward

    a = forward(human.skeleton, lifted.rotations, lifted.translations)[..., :3, 3]
    b = forward(human.skeleton, settled.rotations, settled.translations)[..., :3, 3]
    np.testing.assert_allclose(b[..., :2], a[..., :2], atol=1e-6)
    np.testing.assert_allclose(b[..., 2] - a[..., 2], np.broadcast_to(shift[:, None], b.shape[:2]),
                               atol=1e-6)  # fmt: skip
