"""Rig properties: identity pose, weights, LBS/DQS agreement, Blender-exact rest matrices."""

import numpy as np
import pytest

from avatar.human import Human
from avatar.rig import kinematics, quaternion, skinning
from avatar.rig.placement import rest_matrices, roll_from_matrix


@pytest.fixture(scope="module")
def human(model):
    return Human({"gender": 0.8, "age": 0.6}, model=model)


@pytest.mark.parametrize("rig", ["default", "game_engine", "cmu_mb", "mixamo", "default_no_toes"])
def test_every_rig_is_placed_and_weighted(model, rig):
    h = Human({}, rig=rig, model=model)
    sk = h.skeleton
    assert np.isfinite(sk.rest).all() and (sk.lengths > 1e-4).all()
    w = h.weights.weights
    np.testing.assert_allclose(w.sum(axis=1), 1.0, atol=1e-5)
    assert (w >= 0).all() and h.weights.indices.max() < len(sk.names)
    # every skin vertex is influenced by some bone (no fallback-only vertices on the body)
    assert np.all(np.diff(h.model.assets.weights(rig)[1]) >= 0)


def test_a_rig_without_toes_gives_toe_weights_to_the_feet(model):
    """default_no_toes uses the default rig's weights: those of toes it lacks go to their
    nearest ancestor it has (the foot, or its one toe bone), not to the root."""
    toes = Human({}, rig="default_no_toes", model=model)
    full = Human({}, rig="default", model=model)
    dense = toes.weights.dense(len(toes.skeleton.names))
    names = full.skeleton.names
    on_toes = full.weights.dense(len(names))[:, [j for j, n in enumerate(names)
                                                  if n.startswith("toe")]].sum(axis=1)  # fmt: skip
    tips = on_toes > 0.99
    assert tips.sum() > 100
    feet = [j for j, n in enumerate(toes.skeleton.names) if n.startswith(("foot", "toe"))]
    assert len(feet) < len([n for n in names if n.startswith(("foot", "toe"))])
    np.testing.assert_allclose(dense[tips][:, feet].sum(axis=1), 1.0, atol=0.01)
    assert dense[tips, toes.skeleton.names.index("root")].max() == 0.0


def test_identity_pose_returns_the_rest_mesh(human):
    for method in ("lbs", "dqs"):
        posed = human.posed(human.pose("rest"), method=method)[0]
        np.testing.assert_allclose(posed, human.vertices, atol=1e-5)


def test_lbs_equals_dqs_for_pure_translations(human):
    j = len(human.skeleton.names)
    mats = np.tile(np.eye(4), (j, 1, 1))
    mats[:, :3, 3] = np.random.default_rng(0).normal(size=(j, 3)) * 0.1
    a = skinning.linear_blend(human.vertices, human.weights, mats)
    b = skinning.dual_quaternion(human.vertices, human.weights, mats)
    np.testing.assert_allclose(a, b, atol=1e-5)


def test_dqs_preserves_volume_under_twist_better_than_lbs(human):
    sk = human.skeleton
    rot = np.tile([1.0, 0, 0, 0], (1, len(sk.names), 1))
    rot[0, sk.index("lowerarm01.L")] = quaternion.from_axis_angle(
        np.array([0, 1.0, 0]), np.pi * 0.8
    )
    world = kinematics.forward(sk, rot)
    mats = kinematics.skinning_matrices(sk, world)
    wrist = human.weights.dense(len(sk.names))[:, sk.index("lowerarm01.L")] > 0.3
    lbs = skinning.linear_blend(human.vertices, human.weights, mats)[0, wrist]
    dqs = skinning.dual_quaternion(human.vertices, human.weights, mats)[0, wrist]
    spread = lambda p: np.linalg.norm(p - p.mean(0), axis=1).mean()  # noqa: E731
    assert spread(dqs) > spread(lbs)


def test_rest_matrices_match_blender_conventions():
    heads = np.zeros((4, 3))
    tails = np.array([[0, 1.0, 0], [0, 0, 1.0], [1.0, 0, 0], [0, -1.0, 0]])
    m = rest_matrices(heads, tails, np.array([0.0, 0.3, -1.0, 0.0]))
    np.testing.assert_allclose(m[0, :3, :3], np.eye(3), atol=1e-12)
    # Blender: a bone pointing +Z with roll 0 has X = +X, Z = -Y
    m0 = rest_matrices(heads[1:2], tails[1:2], np.zeros(1))[0]
    np.testing.assert_allclose(m0[:3, 0], [1, 0, 0], atol=1e-12)
    np.testing.assert_allclose(m0[:3, 2], [0, -1, 0], atol=1e-12)
    for r in m:
        np.testing.assert_allclose(r[:3, :3] @ r[:3, :3].T, np.eye(3), atol=1e-12)
    np.testing.assert_allclose(roll_from_matrix(m[:3]), [0.0, 0.3, -1.0], atol=1e-9)


def test_t_pose_raises_the_arms(human):
    posed = human.posed(human.pose("t-pose"))[0]
    hand = human.skeleton.index("wrist.L")
    wrist = human.weights.dense(len(human.skeleton.names))[:, hand] > 0.5
    assert posed[wrist, 2].mean() > human.vertices[wrist, 2].mean() + 0.15


def test_quaternion_round_trips():
    rng = np.random.default_rng(3)
    q = rng.normal(size=(100, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    q[q[:, 0] < 0] *= -1
    np.testing.assert_allclose(quaternion.from_matrix(quaternion.to_matrix(q)), q, atol=1e-9)
    for order in ("XYZ", "ZYX", "YXZ", "ZXY"):
        e = rng.uniform(-1.2, 1.2, size=(50, 3))
        back = quaternion.to_euler(quaternion.from_euler(e, order), order)
        np.testing.assert_allclose(back, e, atol=1e-9)
