"""Baked garment corrections: a viewer playing the GLB shows the exact frames, none inside."""

from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
from gltf_player import Player

import avatar
from avatar.clothes import bake
from avatar.geometry import collision
from avatar.io import gltf
from avatar.rig import kinematics, skinning

ROOT = Path(__file__).resolve().parents[2]
VALIDATOR = ROOT / ".cache/node/node_modules/gltf-validator"
GARMENTS = ("tshirt", "jeans")


@pytest.fixture(scope="module")
def dressed(heavy_walker):
    return heavy_walker(0.5)


@pytest.fixture(scope="module")
def files(dressed, tmp_path_factory):
    human, walk = dressed
    folder = tmp_path_factory.mktemp("bake")
    return (avatar.save(human, folder / "baked.glb", walk),
            avatar.save(human, folder / "plain.glb", walk, resolve_garments=False))  # fmt: skip


def _names(human) -> list[str]:
    return [g.name for g in human.outfit]  # layer order (z_depth), as exported


def _exact_frames(human, walk):
    world = kinematics.forward(human.skeleton, walk.rotations, walk.translations)
    matrices = kinematics.skinning_matrices(human.skeleton, world)
    for t in range(walk.frames):
        body = skinning.linear_blend(human.vertices, human.weights, matrices[t])
        yield t, human.outfit.frame(body, matrices[t], exact=True)


def test_baked_glb_plays_the_exact_frames_with_no_garment_inside(dressed, files, model):
    human, walk = dressed
    baked, plain = Player(files[0]), Player(files[1])
    triangles = collision.skin_surface(model.base.faces).triangles
    plain_inside = 0
    for t, exact in _exact_frames(human, walk):
        body = baked.positions("body", t)
        np.testing.assert_allclose(body, human.posed(walk, slice(t, t + 1))[0][:13380], atol=1e-5)
        for name, want in zip(_names(human), exact, strict=True):
            got = baked.positions(name, t)
            np.testing.assert_allclose(got, want, atol=1e-4, err_msg=f"{name} frame {t}")
            assert not np.any(collision.winding_number(got, body, triangles) > 0), (name, t)
            plain_inside += np.count_nonzero(
                collision.winding_number(plain.positions(name, t), body, triangles) > 0
            )
    assert plain_inside > 0  # plain skinning does clip: the bake is what fixes it


def test_round_trip_reads_the_targets_and_their_weights(dressed, files):
    human, walk = dressed
    back = gltf.read(files[0])
    assert [p.name for p in back.parts] == ["body", "eyes", *_names(human)]
    assert next(iter(back.animations.values())).frames == walk.frames
    keyed = back.morph_weights["animation"]
    assert set(keyed) <= set(GARMENTS) and keyed
    for part in back.parts[2:]:
        if part.name not in keyed:
            assert not part.morphs
            continue
        w = keyed[part.name]
        assert w.shape == (walk.frames, len(part.morphs))
        frames = [int(n.split("_")[1]) for n in part.morphs]
        assert all(name.startswith("frame_") for name in part.morphs)
        # Frame t's own target is on at frame t, every other one off.
        expect = np.zeros_like(w)
        expect[frames, np.arange(len(frames))] = 1.0
        np.testing.assert_array_equal(w, expect)
        rest = human.outfit[_names(human).index(part.name)].mesh.vertices
        np.testing.assert_allclose(part.mesh.vertices, rest, atol=1e-6)


def test_plain_export_writes_no_garment_morphs(files):
    plain = Player(files[1])
    assert all(plain.morph_count(name) == 0 for name in GARMENTS)
    assert not gltf.read(files[1]).morph_weights
    assert files[0].stat().st_size > files[1].stat().st_size


@pytest.mark.skipif(not VALIDATOR.is_dir() or shutil.which("node") is None,
                    reason="Khronos gltf-validator not installed (scripts/setup.sh)")  # fmt: skip
def test_baked_glb_passes_the_khronos_validator(files):
    done = subprocess.run(["node", str(ROOT / "tests/io/validate_gltf.cjs"), str(VALIDATOR),
                           str(files[0])], capture_output=True, text=True, check=True)  # fmt: skip
    issues = json.loads(done.stdout)["issues"]
    assert issues["numErrors"] == 0 and issues["numWarnings"] == 0, issues["messages"][:5]


def test_bind_correction_lands_skinning_on_the_wanted_points():
    """LBS(rest + d) = wanted for random rigid bones and weights; tiny moves are dropped."""
    rng = np.random.default_rng(3)
    joints, count = 5, 200
    q = rng.normal(size=(joints, 4))
    matrices = kinematics.pose_matrices(q / np.linalg.norm(q, axis=1, keepdims=True),
                                        rng.normal(size=(joints, 3)))  # fmt: skip
    idx = rng.integers(0, joints, size=(count, 3)).astype(np.int32)
    w = rng.random((count, 3)).astype(np.float32)
    skin = skinning.SkinWeights(idx, (w / w.sum(axis=1, keepdims=True)).astype(np.float32))
    rest = rng.normal(size=(count, 3)).astype(np.float32)
    posed = skinning.linear_blend(rest, skin, matrices).astype(np.float64)
    wanted = posed + rng.normal(scale=0.01, size=posed.shape)
    wanted[:50] = posed[:50] + 1e-5  # under TOLERANCE: no delta
    delta = bake.bind_correction(rest, skin, matrices, wanted)
    assert delta is not None and not delta[:50].any() and np.all(delta[50:] != 0)
    got = skinning.linear_blend(rest + delta, skin, matrices)
    np.testing.assert_allclose(got[50:], wanted[50:], atol=2e-5)
    assert bake.bind_correction(rest, skin, matrices, posed) is None


def test_vertex_group_skin_keeps_every_influence_renormalised():
    """Blender's Armature modifier blends all vertex groups (no cap at 8), over their sum."""
    from avatar.mesh import Mesh
    from avatar.part import MeshPart

    rng = np.random.default_rng(5)
    idx = np.tile(np.arange(10, dtype=np.int32), (4, 1))
    w = rng.random((4, 10))
    w[1, 3], w[2] = -0.2, 0.0  # a negative weight is dropped; vertex 2 has none at all
    mesh = Mesh(rng.normal(size=(4, 3)).astype(np.float32), np.array([[0, 1, 2]]))
    skin = bake.vertex_group_skin(MeshPart("cape", mesh, skin=(idx, w)), 12)
    np.testing.assert_allclose(skin.weights.sum(axis=1), 1.0, atol=1e-6)
    assert np.count_nonzero(skin.weights[0]) == 10 and skin.weights[1, 3] == 0
    assert skin.indices[2, 0] == 0 and skin.weights[2, 0] == 1.0  # follows the root
    np.testing.assert_allclose(skin.weights[0], w[0] / w[0].sum(), rtol=1e-6)
