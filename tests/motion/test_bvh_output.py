"""BVH output of Avatar rigs: the motion comes back as written, over any rest pose."""

from __future__ import annotations

import numpy as np
import pytest

from avatar.io import bvh
from avatar.motion.procedural import MOTIONS
from avatar.rig.kinematics import forward


@pytest.fixture(scope="module")
def human(model):
    from avatar.human import Human

    return Human(model=model)


def _world_by_name(skeleton, animation, names):
    idx = [skeleton.names.index(n) for n in names]
    return forward(skeleton, animation.rotations, animation.translations)[:, idx]


def test_avatar_rig_round_trips_through_bvh(human, tmp_path):
    """The default rig lists joints in an order the BVH hierarchy (depth first) does not;
    motion columns must follow the hierarchy."""
    skeleton = human.skeleton
    walk = MOTIONS["walk"](skeleton, fps=10.0)
    bvh.save(tmp_path / "walk.bvh", skeleton, walk)
    back_skeleton, back = bvh.load(tmp_path / "walk.bvh")
    assert back_skeleton.names != skeleton.names  # the file's order differs ...
    want = forward(skeleton, walk.rotations, walk.translations)[..., :3, 3]
    got = _world_by_name(back_skeleton, back, skeleton.names)[..., :3, 3]
    np.testing.assert_allclose(got, want, atol=1e-5)  # ... and the motion is the same


@pytest.mark.parametrize("rest", ["t-pose", "a-pose"])
def test_bvh_export_over_another_rest(human, tmp_path, rest):
    from avatar.export import save
    from avatar.motion import bonemap

    walk = MOTIONS["walk"](human.skeleton, fps=10.0)
    save(human, tmp_path / "walk.bvh", walk, rest=rest)
    skeleton, back = bvh.load(tmp_path / "walk.bvh")
    m = bonemap.detect(skeleton)
    arm = skeleton.heads[m.bones["forearm.L"]] - skeleton.heads[m.bones["upperarm.L"]]
    drop = np.degrees(np.arcsin(-arm[2] / np.linalg.norm(arm)))
    assert drop == pytest.approx(0.0 if rest == "t-pose" else 45.0, abs=0.5)
    want = forward(human.skeleton, walk.rotations, walk.translations)[..., :3, 3]
    got = _world_by_name(skeleton, back, human.skeleton.names)[..., :3, 3]
    np.testing.assert_allclose(got, want, atol=1e-5)


def test_cli_writes_bvh_with_a_t_pose_rest(tmp_path, model):
    from avatar import cli

    out = tmp_path / "walk.bvh"
    assert cli.main(["create", "--motion", "walk", "--fps", "10", "--rest", "t-pose",
                     "-o", str(out)]) == 0  # fmt: skip
    skeleton, back = bvh.load(out)
    assert back.frames > 1 and np.isfinite(back.rotations).all()
    i, j = skeleton.names.index("upperarm01.R"), skeleton.names.index("lowerarm01.R")
    assert abs(skeleton.heads[j, 2] - skeleton.heads[i, 2]) < 0.005  # horizontal arm
