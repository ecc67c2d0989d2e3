"""Baked garment corrections: a viewer playing the GLB shows the exact frames (within the
documented bound, from a few correction shapes a garment), no vertex 1 mm inside the body."""

from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
from gltf_player import Player

import avatar
from avatar.clothes import bake, correction_basis
from avatar.errors import AvatarError
from avatar.geometry import collision
from avatar.io import gltf
from avatar.rig import kinematics, skinning

ROOT = Path(__file__).resolve().parents[2]
VALIDATOR = ROOT / ".cache/node/node_modules/gltf-validator"
GARMENTS = ("tshirt", "jeans")
JUMPS = "bvh/cmu_motionbuilder/01_01_forward_jumps.bvh"


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
    faces = model.base.faces[model.base.face_groups["body"]]
    plain_inside = 0
    for t, exact in _exact_frames(human, walk):
        body = baked.positions("body", t)
        np.testing.assert_allclose(body, human.posed(walk, slice(t, t + 1))[0][:13380], atol=1e-5)
        for name, want in zip(_names(human), exact, strict=True):
            got = baked.positions(name, t)
            error = np.linalg.norm(got - want, axis=1).max()
            assert error <= bake.ERROR_BOUND + 1e-5, (name, t, error)
            _, depths = collision.penetration(body, faces, got)
            assert depths.max(initial=0.0) <= 1e-3, (name, t, depths.max())
            plain_inside += collision.penetration(body, faces, plain.positions(name, t))[0]
    assert plain_inside > 0  # plain skinning does clip: the bake is what fixes it


def test_round_trip_reads_the_correction_shapes_and_their_weights(dressed, files):
    human, walk = dressed
    back = gltf.read(files[0])
    assert [p.name for p in back.parts] == ["body", "eyes", "teeth", "tongue", *_names(human)]
    assert next(iter(back.animations.values())).frames == walk.frames
    keyed = back.morph_weights["animation"]
    assert set(keyed) <= set(GARMENTS) and keyed
    for part in back.parts[4:]:
        if part.name not in keyed:
            assert not part.morphs
            continue
        w = keyed[part.name]
        assert w.shape == (walk.frames, len(part.morphs))
        assert 1 < len(part.morphs) <= correction_basis.MAX_BASIS + 1
        assert all(name.startswith(bake.BASIS_PREFIX) for name in part.morphs)
        # Weights players keep: within [0, 1], the offset shape held at 1.
        assert w.min() >= 0.0 and w.max() <= 1.0 and np.all(w[:, 0] == 1.0)
        assert list(part.morphs)[0] == f"{bake.BASIS_PREFIX}s00_offset"  # one segment
        rest = human.outfit[_names(human).index(part.name)].mesh.vertices
        np.testing.assert_allclose(part.mesh.vertices, rest, atol=1e-6)


def test_the_file_grows_linearly_with_the_clip(heavy_walker, tmp_path):
    """Twice the frames: the same few shapes a garment, twice the weights, not twice the
    shapes (the per-frame targets grew with the square of the clip's weights)."""
    sizes, shapes = [], []
    for seconds in (0.4, 0.8):
        human, walk = heavy_walker(seconds)
        path = avatar.save(human, tmp_path / f"w{seconds}.glb", walk)
        back = gltf.read(path)
        shapes.append({p.name: len(p.morphs) for p in back.parts[4:]})
        sizes.append(path.stat().st_size)
    assert all(0 < n <= correction_basis.MAX_BASIS + 1 for n in shapes[1].values())
    assert sum(shapes[1].values()) <= 2 * sum(shapes[0].values())
    assert sizes[1] < 1.5 * sizes[0]


@pytest.fixture(scope="module")
def jumps(heavy_walker, fixtures, tmp_path_factory):
    """CMU 01_01 (forward jumps) frames 1000-1400 at every 4th frame on the heavy human,
    baked in segments of 50 frames (2 segments) and written to a GLB: (human, clip, path)."""
    from dataclasses import replace

    human, _ = heavy_walker(0.1)
    clip, _ = human.retarget(*avatar.load_bvh(fixtures / JUMPS))
    clip = replace(clip, rotations=clip.rotations[1000:1400:4],
                   translations=clip.translations[1000:1400:4])  # fmt: skip
    parts, weights = bake.bake(human.body, human.outfit, clip, human.parts(), segment=50)
    path = tmp_path_factory.mktemp("jumps") / "jumps.glb"
    gltf.write(path, parts, human.skeleton, {"jumps": clip}, morph_weights={"jumps": weights})
    return human, clip, path


def test_segmented_bake_of_jumps_plays_back_with_no_garment_inside(jumps, model):
    """Two segments of a jumps excerpt, played back from the file: no garment vertex more
    than 1 mm inside the body on any frame (one basis of 16 shapes over the whole excerpt,
    the bake before segments, left the T-shirt millimetres inside)."""
    human, clip, path = jumps
    player = Player(path)
    faces = model.base.faces[model.base.face_groups["body"]]
    for t in range(clip.frames):
        body = player.positions("body", t)
        for name in _names(human):
            _, depths = collision.penetration(body, faces, player.positions(name, t))
            assert depths.max(initial=0.0) <= 1e-3, (name, t, depths.max())


def test_segment_weights_are_zero_outside_their_frames(jumps):
    """Each segment's targets play on its frames only (at most one segment's shapes a
    frame), and a garment has a segment's few shapes per segment, not one per frame."""
    human, clip, path = jumps
    back = gltf.read(path)
    keyed = back.morph_weights["jumps"]
    windows = bake.segments(clip.frames, 50)
    assert [(w.start, w.stop) for w in windows] == [(0, 50), (50, 100)]
    # a segment: its shapes, offset, grown ones, at most a shape a frame from the last grow
    most = correction_basis.MAX_BASIS + 1 + bake.GROW * (bake.REFINE_PASSES - bake.REFITS - 1) + 50
    for part in back.parts[4:]:
        if part.name not in keyed:
            continue
        names, w = list(part.morphs), keyed[part.name]
        for s, window in enumerate(windows):
            mine = np.array([n.startswith(f"{bake.BASIS_PREFIX}s{s:02d}_") for n in names])
            assert mine.sum() <= most, (part.name, s, mine.sum())
            # Only the principal shapes are dense; those grown for a few frames are sparse.
            dense = [np.count_nonzero(np.any(part.morphs[n] != 0, axis=1)) * 3
                     > len(part.mesh.vertices) for n in np.array(names)[mine]]  # fmt: skip
            assert sum(dense) <= correction_basis.MAX_BASIS + 1, (part.name, s, sum(dense))
            assert mine.sum() > 1 or part.name != "tshirt"  # the T-shirt is corrected in both
            outside = np.ones(clip.frames, bool)
            outside[window.start : window.stop] = False
            assert not w[np.ix_(outside, mine)].any(), (part.name, s)
            assert np.all(w[window.start : window.stop, names.index(
                f"{bake.BASIS_PREFIX}s{s:02d}_offset")] == 1.0)  # fmt: skip
        assert len(names) <= len(windows) * most  # linear in the segments


def test_save_cuts_the_bake_into_the_segments_it_is_given(dressed, tmp_path):
    """``avatar.save(..., bake_segment=n)`` bakes windows of at most n frames, each with its
    own shapes keyed only on its frames; a segment under one frame is refused, nothing written."""
    human, walk = dressed
    n = -(-walk.frames // 2)
    back = gltf.read(avatar.save(human, tmp_path / "two.glb", walk, bake_segment=n))
    keyed = back.morph_weights["animation"]
    windows = bake.segments(walk.frames, n)
    assert len(windows) == 2
    for part in back.parts[4:]:
        if part.name not in keyed:
            continue
        names = list(part.morphs)
        for s, window in enumerate(windows):
            offset = names.index(f"{bake.BASIS_PREFIX}s{s:02d}_offset")
            assert np.all(keyed[part.name][window.start : window.stop, offset] == 1.0)
            assert not keyed[part.name][: window.start, offset].any()
    with pytest.raises(AvatarError, match="bake segment of 0 frames"):
        avatar.save(human, tmp_path / "none.glb", walk, bake_segment=0)
    assert not (tmp_path / "none.glb").exists()


def test_segments_cut_a_clip_into_equal_windows():
    assert bake.segments(300) == [range(0, 300)]
    assert bake.segments(2752) == [range(round(i * 275.2), round((i + 1) * 275.2))
                                   for i in range(10)]  # fmt: skip
    assert bake.segments(7, 3) == [range(0, 2), range(2, 5), range(5, 7)]
    assert bake.segments(0) == [range(0, 0)]
    with pytest.raises(AvatarError, match="segment length 0"):
        bake.segments(10, 0)


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


def test_fit_basis_finds_the_rank_and_meets_the_bound():
    """Deltas of rank 5 (plus noise far under the bound) need 5 shapes; frames without a
    correction get weight 0; every reconstructed vertex is within the bound."""
    rng = np.random.default_rng(7)
    frames, count = 200, 300
    basis = rng.normal(scale=0.01, size=(5, count * 3))
    weights = rng.normal(size=(frames, 5))
    weights[::7] = 0.0  # frames that need no correction
    x = (weights @ basis + rng.normal(scale=1e-6, size=(frames, count * 3))).reshape(
        frames, count, 3
    )
    x[::7] = 0.0
    shapes, w, error = correction_basis.fit_basis(x.astype(np.float32), bound=1e-4)
    assert len(shapes) == 5 and error <= 1e-4
    assert np.all(w[::7] == 0)
    got = np.einsum("tk,kvc->tvc", w, shapes)
    assert np.linalg.norm(got - x, axis=2).max() <= 1e-4 + 1e-6
    tight = correction_basis.fit_basis(x.astype(np.float32), bound=1e-9, limit=8)
    assert len(tight[0]) == 8 and tight[2] > 1e-9  # capped: the error says how far off
    empty = correction_basis.fit_basis(np.zeros((4, 3, 3), np.float32))
    assert empty[0].shape == (0, 3, 3) and empty[1].shape == (4, 0)


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
