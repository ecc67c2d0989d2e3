"""glTF/GLB: write -> read is lossless; glTF skinning equals Avatar's; Khronos-valid; bad input."""

from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pygltflib
import pytest
from gltf_fixtures import box, chain, many_influences, scene, skeleton

from avatar.errors import FormatError, ParameterError
from avatar.io import gltf
from avatar.io import gltf_accessors as acc
from avatar.io.gltf_weights import pack_weights
from avatar.material import Material
from avatar.part import MeshPart
from avatar.rig import kinematics, quaternion
from avatar.rig.skeleton import Animation

ROOT = Path(__file__).resolve().parents[2]
HERE = Path(__file__).resolve().parent
VALIDATORS = [ROOT / ".cache/node/node_modules/gltf-validator",
              Path.home() / ".cache/avatar-node/node_modules/gltf-validator"]  # fmt: skip
SUFFIXES = ["t.glb", "t.gltf", "embedded.gltf"]


def _write(tmp_path: Path, name: str, parts, sk=None, animations=()) -> Path:
    path = tmp_path / name
    gltf.write(path, parts, sk, animations, embed=name.startswith("embedded"))
    return path


def _triangles(faces: np.ndarray) -> set[tuple[int, ...]]:
    """Triangles of (F, 3|4) faces as rotation-normalised tuples (quads split 0-2)."""
    tris = faces if faces.shape[1] == 3 else np.concatenate([faces[:, :3], faces[:, [0, 2, 3]]])
    return {tuple(np.roll(t, -int(np.argmin(t)))) for t in tris.tolist()}


@pytest.mark.parametrize("name", SUFFIXES)
def test_write_read_is_lossless(tmp_path, name):
    parts, sk, anim = scene()
    back = gltf.read(_write(tmp_path, name, parts, sk, {"bend": anim}))
    assert [p.name for p in back.parts] == ["limb", "crate"]
    for src, got in zip(parts, back.parts, strict=True):
        np.testing.assert_array_equal(got.mesh.vertices, src.mesh.vertices)
        assert _triangles(got.mesh.faces) == _triangles(src.mesh.faces)
        # The UV of every triangle corner survives (matched through the face order).
        src_corner_uv = src.mesh.uvs[src.mesh.face_uvs[:, [0, 1, 2]]]
        got_corner_uv = got.mesh.uvs[got.mesh.face_uvs[: len(src.mesh.faces)]]
        np.testing.assert_allclose(got_corner_uv, src_corner_uv, atol=1e-7)
    limb = back.parts[0]
    assert list(limb.morphs) == ["bulge", "poke", "nothing"]
    for key, delta in parts[0].morphs.items():
        np.testing.assert_array_equal(limb.morphs[key], delta.astype(np.float32))
    idx, w = limb.skin
    dense_src = _dense(*parts[0].skin, 3)
    np.testing.assert_allclose(_dense(idx, w, 3), dense_src / dense_src.sum(1, keepdims=True),
                               atol=1e-7)  # fmt: skip
    assert back.parts[1].skin is None


@pytest.mark.parametrize("name", SUFFIXES)
def test_skeleton_and_animation_round_trip(tmp_path, name):
    parts, sk, anim = scene()
    back = gltf.read(_write(tmp_path, name, parts, sk, {"bend": anim}))
    assert back.skeleton.names == sk.names
    np.testing.assert_array_equal(back.skeleton.parents, sk.parents)
    np.testing.assert_allclose(back.skeleton.rest, sk.rest, atol=1e-6)
    np.testing.assert_allclose(back.skeleton.tails, sk.tails, atol=1e-6)
    assert back.skeleton.extra["name"] == "Rig"
    clip = back.animations["bend"]
    assert clip.fps == anim.fps and clip.frames == anim.frames and clip.bone_names == sk.names
    assert np.any(anim.rotations[..., 0] < 0)  # signs must survive, not just rotations
    np.testing.assert_allclose(clip.rotations, anim.rotations, atol=3e-7)
    np.testing.assert_allclose(clip.translations, anim.translations, atol=1e-6)


def test_materials_and_textures_round_trip(tmp_path):
    parts, sk, anim = scene()
    back = gltf.read(_write(tmp_path, "t.glb", parts, sk))
    for src, got in zip(parts, back.parts, strict=True):
        a, b = src.material, got.material
        assert (b.name, b.alpha_mode, b.double_sided) == (a.name, a.alpha_mode, a.double_sided)
        np.testing.assert_allclose(b.base_color, a.base_color)
        assert (b.roughness, b.metallic, b.extras) == (a.roughness, a.metallic, a.extras)
        for key, image in a.textures().items():
            np.testing.assert_array_equal(getattr(b, key), image)


def test_identical_images_are_stored_once(tmp_path):
    parts, _, _ = scene()
    twin = MeshPart("twin", parts[1].mesh, parts[1].material)
    path = _write(tmp_path, "t.glb", [parts[1], twin])
    doc = pygltflib.GLTF2().load(str(path))
    assert len(doc.images) == 2 and len(doc.materials) == 1  # colour + normal map, one material


def test_parallel_texture_encoding_writes_the_same_bytes(tmp_path, monkeypatch):
    """Textures are PNG-encoded on all cores before the file is laid out; the file is the
    same byte for byte as encoding each image when it is first used."""
    from avatar.io import gltf_materials

    parts, sk, _ = scene()
    fast = _write(tmp_path, "fast.glb", parts, sk).read_bytes()
    monkeypatch.setattr(gltf_materials.Materials, "encode_all", lambda self, materials: None)
    assert _write(tmp_path, "plain.glb", parts, sk).read_bytes() == fast


def test_more_than_four_influences_use_joints_1(tmp_path):
    mesh = box([-0.1, -0.1, 0], [0.1, 0.1, 2])
    sk = chain(10)
    idx = np.stack([np.random.default_rng(v).permutation(10)[:7] for v in range(8)])
    w = np.random.default_rng(0).random((8, 7)) + 0.05
    path = _write(tmp_path, "t.glb", [MeshPart("wide", mesh, skin=(idx, w))], sk)
    attrs = pygltflib.GLTF2().load(str(path)).meshes[0].primitives[0].attributes
    assert getattr(attrs, "JOINTS_1", None) is not None
    back_idx, back_w = gltf.read(path).parts[0].skin
    assert back_idx.shape == (8, 8)
    np.testing.assert_allclose(_dense(back_idx, back_w, 10), _dense(idx, w / w.sum(1)[:, None], 10),
                               atol=1e-6)  # fmt: skip
    # Seven influences over three joints merge to three: one JOINTS set is enough.
    narrow = MeshPart("narrow", mesh, skin=many_influences(8, k=7, joints=3))
    path = _write(tmp_path, "n.glb", [narrow], skeleton())
    attrs = pygltflib.GLTF2().load(str(path)).meshes[0].primitives[0].attributes
    assert getattr(attrs, "JOINTS_1", None) is None


def test_pack_weights_edge_cases():
    idx = np.array([[2, 2, 1, 0], [0, 1, 2, 3], [1, 0, 0, 0]])
    w = np.array([[0.25, 0.25, 0.5, 0.0], [0.0, 0.0, 0.0, 0.0], [-1.0, 0.0, 0.0, 0.0]])
    joints, weights = pack_weights(idx, w, joint_count=4)
    assert joints.shape == (3, 4)
    idx, w = np.tile(np.arange(9), (2, 1)), np.linspace(1, 2, 18).reshape(2, 9)
    wide_joints, wide_weights = pack_weights(idx, w, joint_count=300)
    assert wide_joints.shape == (2, 8) and wide_joints.dtype == np.uint16
    np.testing.assert_allclose(wide_weights.sum(axis=1), 1.0, atol=2.5e-7)
    assert set(wide_joints[0].tolist()) == set(range(1, 9))  # the 8 largest kept
    np.testing.assert_allclose(_dense(joints, weights, 4)[0], [0, 0.5, 0.5, 0])  # merged
    np.testing.assert_allclose(_dense(joints, weights, 4)[1:], [[1, 0, 0, 0]] * 2)  # to root
    with pytest.raises(ValueError, match="out of range"):
        pack_weights(np.array([[5]]), np.array([[1.0]]), joint_count=4)


def test_gltf_skinning_matches_avatar_skinning(tmp_path):
    """A viewer evaluating the file (nodes, IBMs, weights) poses vertices as Avatar does."""
    parts, sk, anim = scene()
    path = _write(tmp_path, "t.glb", parts, sk, [anim])
    world = kinematics.forward(sk, anim.rotations, anim.translations)
    skinning = kinematics.skinning_matrices(sk, world)  # (T, J, 4, 4)
    idx, w = parts[0].skin
    w = w / w.sum(axis=1, keepdims=True)
    rest = np.concatenate([parts[0].mesh.vertices, np.ones((len(w), 1))], axis=1)
    expected = np.einsum("vk,tvkab,vb->tva", w, skinning[:, idx], rest)[..., :3]
    got = _viewer_skinning(path)
    np.testing.assert_allclose(got, expected, atol=2e-5)


def _viewer_skinning(path: Path) -> np.ndarray:
    """(T, V, 3) skinned limb vertices by the glTF spec's own rules, back in Avatar's frame."""
    doc = pygltflib.GLTF2().load(str(path))
    blobs = [acc.buffer_bytes(doc, 0, path.parent)]
    get = lambda i: acc.unpack(doc, blobs, i)  # noqa: E731
    prim = doc.meshes[0].primitives[0]
    pos, ids = get(prim.attributes.POSITION), get(prim.attributes._AVATAR_VERTEX).astype(int)
    joints, weights = get(prim.attributes.JOINTS_0), get(prim.attributes.WEIGHTS_0)
    skin = doc.skins[0]
    ibm = get(skin.inverseBindMatrices)
    channels = {(c.target.node, c.target.path): get(doc.animations[0].samplers[c.sampler].output)
                for c in doc.animations[0].channels}  # fmt: skip
    frames = len(next(iter(channels.values())))
    parent = {c: i for i, n in enumerate(doc.nodes) for c in (n.children or [])}
    out = []
    for t in range(frames):

        def local(n: int, t: int = t) -> np.ndarray:
            node = doc.nodes[n]
            m = np.eye(4)
            q = channels.get((n, "rotation"), [node.rotation or [0, 0, 0, 1]] * frames)[t]
            m[:3, :3] = quaternion.to_matrix(np.roll(np.asarray(q, float), 1))
            m[:3, 3] = channels.get((n, "translation"), [node.translation or [0, 0, 0]] * frames)[t]
            return m

        def world(n: int) -> np.ndarray:
            return local(n) if n not in parent else world(parent[n]) @ local(n)

        jm = np.stack([world(n) for n in skin.joints]) @ ibm
        p = np.concatenate([pos, np.ones((len(pos), 1))], axis=1)
        skinned = np.einsum("vk,vkab,vb->va", weights, jm[joints.astype(int)], p)[:, :3]
        avatar = np.stack([skinned[:, 0], -skinned[:, 2], skinned[:, 1]], axis=1)
        merged = np.zeros((ids.max() + 1, 3))
        merged[ids] = avatar
        out.append(merged)
    return np.stack(out)


def _dense(idx: np.ndarray, w: np.ndarray, joints: int) -> np.ndarray:
    out = np.zeros((len(idx), joints))
    np.add.at(out, (np.repeat(np.arange(len(idx)), idx.shape[1]), idx.reshape(-1)), w.reshape(-1))
    return out


def test_seams_split_vertices_and_map_back():
    mesh = box([0, 0, 0], [1, 1, 1])
    source, uv, tris = gltf.split_vertices(mesh)
    assert len(source) == 24 and set(source.tolist()) == set(range(8))  # every corner a seam
    assert tris.shape == (12, 3) and uv is not None
    np.testing.assert_array_equal(np.sort(source), source)  # glTF order follows Avatar's


def test_bad_input(tmp_path):
    parts, sk, anim = scene()
    with pytest.raises(ValueError, match="skeleton"):
        gltf.write(tmp_path / "a.glb", parts)
    with pytest.raises(ValueError, match=r"\.glb or \.gltf"):
        gltf.write(tmp_path / "a.fbx", parts, sk)
    stranger = Animation(anim.rotations[:, :1], anim.translations[:, :1], 24.0, ("rot",))
    with pytest.raises(ParameterError, match="root"):
        gltf.write(tmp_path / "a.glb", parts, sk, [stranger])
    (tmp_path / "bad.glb").write_bytes(b"glTF\x02\x00\x00\x00garbage")
    with pytest.raises(FormatError):
        gltf.read(tmp_path / "bad.glb")
    (tmp_path / "bad.gltf").write_text("{not json")
    with pytest.raises(FormatError):
        gltf.read(tmp_path / "bad.gltf")
    with pytest.raises(ValueError):
        Material("m", alpha_mode="CLIP")
    with pytest.raises(ValueError, match="morph"):
        MeshPart("p", parts[0].mesh, morphs={"m": np.zeros((3, 3))})


def _validator() -> Path | None:
    if shutil.which("node") is None:
        return None
    return next((v for v in VALIDATORS if v.is_dir()), None)


@pytest.mark.skipif(
    _validator() is None,
    reason="Khronos validator missing: npm install --prefix .cache/node "
    "gltf-validator@2.0.0-dev.3.10 (scripts/setup.sh does it)",
)
@pytest.mark.parametrize("name", SUFFIXES)
def test_khronos_validator_reports_no_issue(tmp_path, name):
    parts, sk, anim = scene()
    path = _write(tmp_path, name, parts, sk, {"bend": anim, "copy": anim})
    done = subprocess.run(["node", str(HERE / "validate_gltf.cjs"), str(_validator()), str(path)],
                          capture_output=True, text=True, check=True, timeout=120)  # fmt: skip
    issues = json.loads(done.stdout)["issues"]
    assert issues["numErrors"] == 0 and issues["numWarnings"] == 0, issues["messages"][:5]


def test_keyed_morph_weights_round_trip_and_validate(tmp_path):
    """A ``weights`` channel (STEP, sparse output) is read back per part; bad shapes fail."""
    parts, sk, anim = scene()
    weights = np.zeros((anim.frames, 3), dtype=np.float32)
    weights[1, 0], weights[-1, 1] = 1.0, 0.25
    path = tmp_path / "t.glb"
    gltf.write(path, parts, sk, {"bend": anim}, morph_weights={"bend": {"limb": weights}})
    back = gltf.read(path)
    np.testing.assert_array_equal(back.morph_weights["bend"]["limb"], weights)
    assert "crate" not in back.morph_weights["bend"]
    if _validator() is not None:
        done = subprocess.run(["node", str(HERE / "validate_gltf.cjs"), str(_validator()),
                               str(path)], capture_output=True, text=True, check=True)  # fmt: skip
        issues = json.loads(done.stdout)["issues"]
        assert issues["numErrors"] == 0 and issues["numWarnings"] == 0, issues["messages"][:5]
    for bad in ({"bend": {"limb": weights[:, :2]}}, {"bend": {"nope": weights}},
                {"walk": {"limb": weights}}):  # fmt: skip
        with pytest.raises(ValueError):
            gltf.write(tmp_path / "bad.glb", parts, sk, {"bend": anim}, morph_weights=bad)
    assert not (tmp_path / "bad.glb").exists()


@pytest.mark.parametrize("name", SUFFIXES)
def test_interrupted_write_leaves_the_old_file_and_no_partial_one(tmp_path, name, monkeypatch):
    parts, sk, anim = scene()
    _write(tmp_path, name, parts, sk, {"bend": anim})
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir()}

    def interrupt(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(pygltflib.GLTF2, "save_to_bytes", interrupt)
    monkeypatch.setattr(pygltflib.GLTF2, "gltf_to_json", interrupt)
    with pytest.raises(KeyboardInterrupt):  # a different file, interrupted while saving
        _write(tmp_path, name, parts[1:], sk, {"bend": anim})
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == before
