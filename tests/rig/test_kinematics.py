"""Quaternion helpers and forward kinematics: the fast paths equal the plain definitions."""

import numpy as np
import pytest

from avatar.rig import kinematics, quaternion
from avatar.rig.placement import rest_matrices
from avatar.rig.skeleton import Skeleton


def _unit(rng, shape):
    q = rng.normal(size=shape + (4,))
    return q / np.linalg.norm(q, axis=-1, keepdims=True)


def test_rotate_and_products_match_matrices():
    rng = np.random.default_rng(0)
    q, p, v = _unit(rng, (50,)), _unit(rng, (50,)), rng.normal(size=(50, 3))
    m = quaternion.to_matrix(q)
    np.testing.assert_allclose(quaternion.rotate(q, v), np.einsum("nij,nj->ni", m, v), atol=1e-12)
    inverse = np.einsum("nji,nj->ni", m, v)
    np.testing.assert_allclose(quaternion.rotate(q, v, inverse=True), inverse, atol=1e-12)
    qp = quaternion.multiply(q, p)
    np.testing.assert_allclose(quaternion.to_matrix(qp), m @ quaternion.to_matrix(p), atol=1e-12)
    rows = q[:, None, :]
    np.testing.assert_allclose((rows @ quaternion.right_matrix(p))[:, 0], qp, atol=1e-12)
    np.testing.assert_allclose((p[:, None, :] @ quaternion.left_matrix(q))[:, 0], qp, atol=1e-12)


def test_between_is_the_shortest_arc():
    rng = np.random.default_rng(1)
    a, b = rng.normal(size=(2, 200, 3))
    a[0], b[0] = [1.0, 0.0, 0.0], [-2.0, 0.0, 0.0]  # opposite: half a turn
    a[1], b[1] = 0.0, [0.0, 0.0, 1.0]  # zero vector: identity
    q = quaternion.between(a, b)
    turned = quaternion.rotate(q, a)
    lengths = np.linalg.norm(a, axis=-1, keepdims=True) / np.maximum(
        np.linalg.norm(b, axis=-1, keepdims=True), 1e-300
    )
    np.testing.assert_allclose(turned[2:], b[2:] * lengths[2:], atol=1e-12)
    np.testing.assert_allclose(turned[0], [-1.0, 0.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(q[1], [1.0, 0.0, 0.0, 0.0])
    # shortest: the axis is perpendicular to both directions
    axis = q[2:, 1:]
    assert np.abs(np.sum(axis * a[2:], -1)).max() < 1e-12
    assert np.abs(np.sum(axis * b[2:], -1)).max() < 1e-12


def _chain_skeleton(rng, count=12) -> Skeleton:
    """A random tree (parents precede children) with rolled rest frames."""
    parents = np.array([-1] + [int(rng.integers(0, j)) for j in range(1, count)], np.int32)
    heads = rng.normal(size=(count, 3))
    tails = heads + rng.normal(size=(count, 3)) * 0.3
    rest = rest_matrices(heads, tails, rng.uniform(-3, 3, count))
    return Skeleton(tuple(f"b{j}" for j in range(count)), parents, rest, tails)


@pytest.mark.parametrize("batch", [(), (7,), (3, 5)])
def test_world_pose_equals_forward(batch):
    rng = np.random.default_rng(2)
    sk = _chain_skeleton(rng)
    rot = _unit(rng, batch + (12,))
    trans = rng.normal(size=batch + (12, 3)) * (rng.random(12) < 0.3)[:, None]
    world = kinematics.forward(sk, rot, trans)
    q, heads = kinematics.world_pose(sk, rot, trans)
    np.testing.assert_allclose(quaternion.to_matrix(q), world[..., :3, :3], atol=1e-9)
    np.testing.assert_allclose(heads, world[..., :3, 3], atol=1e-9)
    q1, h1 = kinematics.world_pose(sk, rot, trans, bones_first=True, dtype=np.float32)
    assert q1.dtype == np.float32 and q1.shape == (12,) + batch + (4,)
    np.testing.assert_allclose(np.moveaxis(h1, 0, -2), heads, atol=1e-5)
