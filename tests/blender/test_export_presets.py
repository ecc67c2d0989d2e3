"""Engine presets round-trip: a dressed, animated character exported as GLB, FBX and USD for
Blender, Unity, Unreal and Godot, each file re-imported into an empty scene by Blender's own
importer: meshes (vertex counts), bones (renamed as the preset says; Unreal's root bone at
the origin), animation length, textured materials (an image on Base Color with real
pixels), shape keys (kept or baked), height (1.66 m, or 166 in Unreal's centimetres), the
character facing -Y, at most 4 bone weights per vertex for the engines. Also: the user's
character is unchanged by an export, bad paths fail with one line and write nothing.
Skipped without the MakeHuman assets."""

from __future__ import annotations

import re
import struct

import numpy as np
import pytest

FRAMES = 5
PRESETS = ("BLENDER", "UNITY", "UNREAL", "GODOT")
FORMATS = ("GLB", "FBX", "USD")


def _identifier(name: str) -> str:
    return re.sub(r"[^A-Za-z0-9_]", "_", name)


@pytest.fixture(scope="module")
def walker(tmp_path_factory):
    """The character staged in an empty scene, what to expect of it, and every preset x
    format exported once (before any test re-imports into a cleared scene)."""
    import bpy

    from avatar import export as front
    from avatar.blender import export, mesh, scene
    from avatar.errors import AssetError
    from avatar.human import Human

    try:
        human = Human({"weight": 0.6}).dressed("tshirt")
    except AssetError as exc:
        pytest.skip(f"MakeHuman assets not installed: {exc}")
    walk = human.walk(seconds=FRAMES / 30, fps=30)
    scene.clear_scene()
    built = scene.build_character(front.character(human, walk, name="Walker"))
    built.root.location = (2.0, 1.0, 0.0)  # engines get it at the origin
    bpy.context.view_layer.update()
    root = built.root
    expect = {
        "counts": {o.name: len(o.data.vertices) for o in built.parts},
        "distinct": {o.name: _distinct(o) for o in built.parts},
        "bones": [b.name for b in root.data.bones],
        "height": float(np.ptp(mesh.read_vertices(built.parts[0])[:, 2])),
        "keys": {
            o.name: [k.name for k in o.data.shape_keys.key_blocks[1:]]
            for o in built.parts
            if o.data.shape_keys
        },  # fmt: skip
        "influences": max(_influences(o) for o in built.parts),
        "snapshot": _snapshot(root),
    }
    expect["data_before"] = _data_counts()
    out = tmp_path_factory.mktemp("exports")
    files = {(p, f): export.export_character(root, out / f"walker_{p.lower()}", p, f)
             for p in PRESETS for f in FORMATS}  # fmt: skip
    files["baked"] = export.export_character(root, out / "baked.fbx", "UNITY", shape_keys="BAKE")
    expect["after"] = _snapshot(root)
    expect["data"] = _data_counts()
    expect["objects"] = sorted(o.name for o in bpy.data.objects)
    return expect, files


def _data_counts() -> list[int]:
    import bpy

    d = bpy.data
    return [len(p) for p in (d.meshes, d.armatures, d.actions, d.shape_keys, d.collections)]


def _snapshot(root):
    """Names, bones, vertex groups, action curves and placement of a character."""
    from avatar.blender import action

    parts = sorted(root.children_recursive, key=lambda o: o.name)
    curves = sorted(c.data_path for c in action.action_curves(root.animation_data.action))
    keys = [len(o.data.shape_keys.key_blocks) if o.data.shape_keys else 0 for o in parts]
    groups = [(o.name, o.data.name, [g.name for g in o.vertex_groups]) for o in parts]
    return (root.name, tuple(root.location), [b.name for b in root.data.bones], curves,
            groups, keys)  # fmt: skip


def _distinct(obj) -> int:
    """How many distinct vertex positions (0.01 mm) ``obj`` has: glTF splits a vertex where
    its normals or UVs differ, and its importer merges only those equal in every attribute."""
    from avatar.blender import mesh

    return len(np.unique(np.round(mesh.read_vertices(obj) * 1e5).astype(np.int64), axis=0))


def _influences(obj) -> int:
    """The most bone weights (> 0) any vertex of ``obj`` has."""
    bones = {g.index for g in obj.vertex_groups}
    return max((sum(1 for g in v.groups if g.group in bones and g.weight > 1e-6)
                for v in obj.data.vertices), default=0)  # fmt: skip


def _import(path, unit_scale=1.0):
    import bpy

    from avatar.blender import scene

    scene.clear_scene()
    bpy.context.scene.unit_settings.system = "METRIC"
    bpy.context.scene.unit_settings.scale_length = unit_scale
    suffix = path.suffix.lower()
    if suffix == ".fbx":
        bpy.ops.import_scene.fbx(filepath=str(path))
    elif suffix == ".glb":
        bpy.ops.import_scene.gltf(filepath=str(path), merge_vertices=True)
    else:
        bpy.ops.wm.usd_import(filepath=str(path))
    bpy.context.scene.unit_settings.scale_length = 1.0
    bpy.context.view_layer.update()


def _mesh(name):
    import bpy

    found = [o for o in bpy.data.objects if o.type == "MESH" and o.name.split(".")[0] == name]
    assert found, f"no mesh {name!r} among {[o.name for o in bpy.data.objects]}"
    return found[0]


def _frames(armature) -> int:
    from avatar.blender import action

    anim = armature.animation_data
    if anim is None or anim.action is None:
        return 0
    keys = {round(p.co[0]) for c in action.action_curves(anim.action) for p in c.keyframe_points}
    return len(keys)


def _world(obj) -> np.ndarray:
    from avatar.blender import mesh

    matrix = np.array(obj.matrix_world)
    return mesh.read_vertices(obj) @ matrix[:3, :3].T + matrix[:3, 3]


def _centre(obj) -> np.ndarray:
    """(3,) the centre of ``obj``'s world bounding box."""
    world = _world(obj)
    return (world.min(0) + world.max(0)) / 2


def _base_colour_image(obj):
    material = obj.active_material
    assert material is not None, obj.name
    bsdf = next(n for n in material.node_tree.nodes if n.type == "BSDF_PRINCIPLED")
    links = bsdf.inputs["Base Color"].links
    assert links, f"{obj.name}: no texture on Base Color (a flat colour)"
    node = links[0].from_node
    if node.type == "MIX":  # glTF's importer: texture x baseColorFactor
        node = next(s.links[0].from_node for s in node.inputs if s.is_linked)
    assert node.type == "TEX_IMAGE", f"{obj.name}: Base Color from {node.type}"
    return node.image


def _expected_bones(preset: str, names: list[str], fmt: str) -> set[str]:
    out = list(names)
    if preset in ("UNREAL", "GODOT"):
        out = [_identifier(n) for n in out]
    if preset == "UNREAL":
        out = [f"{n}_0" if n.lower() == "root" else n for n in out] + ["root"]
    if fmt == "USD":  # USD prim names are identifiers whatever the preset
        out = [_identifier(n) for n in out]
    return set(out)


def _fbx_unit_scale(path) -> float:
    """The FBX file's UnitScaleFactor (centimetres per file unit), read from its bytes."""
    data = path.read_bytes()
    found = re.search(rb"UnitScaleFactorS\x06\x00\x00\x00doubleS\x06\x00\x00\x00Number"
                      rb"S\x00\x00\x00\x00D(.{8})", data, re.S)  # fmt: skip
    assert found, "no UnitScaleFactor"
    return struct.unpack("<d", found.group(1))[0]


def test_the_users_character_is_unchanged(walker):
    expect, _ = walker
    assert expect["after"] == expect["snapshot"]
    assert expect["data"] == expect["data_before"]  # every copy and its data went
    assert expect["objects"] == sorted([expect["snapshot"][0], *expect["counts"]])


@pytest.mark.parametrize("fmt", FORMATS)
@pytest.mark.parametrize("preset", PRESETS)
def test_reimport(walker, preset, fmt):
    import bpy

    expect, files = walker
    path = files[preset, fmt]
    assert path.suffix == {"GLB": ".glb", "FBX": ".fbx", "USD": ".usdz"}[fmt]
    assert not [p for p in path.parent.iterdir() if p.name.startswith(".")]  # no leftovers
    scale = 100.0 if (preset, fmt) == ("UNREAL", "FBX") else 1.0
    if scale != 1.0:
        assert _fbx_unit_scale(path) == pytest.approx(1.0)  # the file says centimetres
    _import(path, unit_scale=1.0 / scale)
    armatures = [o for o in bpy.data.objects if o.type == "ARMATURE"]
    assert len(armatures) == 1
    armature = armatures[0]
    bones = {b.name for b in armature.data.bones}
    want = _expected_bones(preset, expect["bones"], fmt)
    assert bones == want, (sorted(want - bones)[:5], sorted(bones - want)[:5])
    if preset == "UNREAL":
        root = armature.data.bones["root"]
        assert root.parent is None and root.head_local.length < 1e-3
        assert len([b for b in armature.data.bones if b.parent is None]) == 1
        if fmt == "FBX":
            assert armature.name.split(".")[0] == "Armature"
    assert _frames(armature) == FRAMES
    for name, count in expect["counts"].items():
        obj = _mesh(name)
        if fmt == "GLB":
            assert _distinct(obj) == expect["distinct"][name], name
        else:
            assert len(obj.data.vertices) == count, (name, len(obj.data.vertices), count)
        if name in ("body", "tshirt", "eyes"):
            image = _base_colour_image(obj)
            assert image.size[0] > 0
            pixels = np.empty(image.size[0] * image.size[1] * 4, np.float32)
            image.pixels.foreach_get(pixels)
            # A lost texture is one flat colour (std 0); a white cotton tee's colour varies
            # little (~0.006: its weave is in the normal map since the band-limited cotton).
            assert pixels.reshape(-1, 4)[:, :3].std() > 0.003, f"{name}: a flat image"
        keys = obj.data.shape_keys
        got = [k.name for k in keys.key_blocks[1:]] if keys else []
        assert got == expect["keys"].get(name, []), name
        limit = expect["influences"] if preset == "BLENDER" else 4
        assert _influences(obj) <= limit, name
    body = _mesh("body")
    assert float(np.ptp(_world(body)[:, 2])) == pytest.approx(expect["height"] * scale, rel=0.01)
    eyes = _mesh("eyes")  # the face looks down -Y, as in Blender
    head = _world(body)
    head = head[np.abs(head[:, 2] - _centre(eyes)[2]) < 0.05 * scale]  # a slice at eye level
    assert _centre(eyes)[1] < head[:, 1].mean() - 0.01 * scale  # eyes ahead of the head
    if preset != "BLENDER":  # engines get the character at the origin
        assert abs(_centre(body)[0]) < 0.05 * scale


def test_more_than_four_weights_before_the_limit(walker):
    expect, _ = walker
    assert expect["influences"] > 4  # else the engine presets' limit would test nothing


def test_baked_shape_keys_leave_none(walker):
    import bpy

    expect, files = walker
    _import(files["baked"])
    for name, count in expect["counts"].items():
        obj = _mesh(name)
        assert obj.data.shape_keys is None, name
        assert len(obj.data.vertices) == count
    assert len([o for o in bpy.data.objects if o.type == "ARMATURE"]) == 1


@pytest.fixture
def small_character(empty_scene):
    """A bare, unanimated character (for the failure cases)."""
    from avatar import export as front
    from avatar.blender import scene
    from avatar.errors import AssetError
    from avatar.human import Human

    try:
        human = Human()
    except AssetError as exc:
        pytest.skip(f"MakeHuman assets not installed: {exc}")
    return scene.build_character(front.character(human, None, name="Bare")).root


@pytest.mark.parametrize("case", ["under_a_file", "a_folder", "unwritable", "preset", "format"])
def test_bad_requests_fail_in_one_line_and_write_nothing(small_character, tmp_path, case):
    import bpy

    from avatar.blender import export
    from avatar.errors import AvatarError

    (tmp_path / "file.txt").write_text("x")
    (tmp_path / "folder.glb").mkdir()
    before = sorted(p.name for p in tmp_path.rglob("*"))
    objects = sorted(o.name for o in bpy.data.objects)
    path, options = {
        "under_a_file": (tmp_path / "file.txt" / "out.glb", {}),
        "a_folder": (tmp_path / "folder.glb", {}),
        "unwritable": ("/proc/avatar-export/out.fbx", {}),
        "preset": (tmp_path / "out.glb", {"preset": "CRYENGINE"}),
        "format": (tmp_path / "out.glb", {"file_format": "OBJ"}),
    }[case]
    with pytest.raises(AvatarError) as raised:
        export.export_character(small_character, path, **options)
    assert "\n" not in str(raised.value) and str(raised.value)
    assert sorted(p.name for p in tmp_path.rglob("*")) == before
    assert sorted(o.name for o in bpy.data.objects) == objects


def test_exporter_failure_leaves_no_file(small_character, tmp_path, monkeypatch):
    from avatar.blender import export
    from avatar.errors import AvatarError

    def broken(path, spec, staged):
        open(path, "wb").write(b"half")  # the exporter got part way, then failed
        raise RuntimeError("Error: something went wrong\nin the exporter")

    monkeypatch.setitem(export._CHARACTER_WRITERS, "GLB", broken)
    with pytest.raises(AvatarError, match="in the exporter"):
        export.export_character(small_character, tmp_path / "out.glb")
    assert list(tmp_path.iterdir()) == []
