"""Exported files come back whole: a dressed, animated human written as FBX, USD, .blend
and GLB, re-imported by Blender's own importers, has its meshes (vertex counts), bones,
animation length and textured materials (image -> Base Color, nothing in between; the
skin's alpha not linked). Skipped without the MakeHuman assets."""

from __future__ import annotations

import re

import pytest

FRAMES = 5
GARMENTS = ("tshirt", "hair-short")


@pytest.fixture(scope="module")
def walker():
    from avatar.errors import AssetError
    from avatar.human import Human

    try:
        human = Human({"weight": 0.6}).dressed(*GARMENTS)
        walk = human.walk(seconds=FRAMES / 30, fps=30)
        parts = {p.name: (len(p.mesh.vertices), p.material) for p in human.parts()}
    except AssetError as exc:
        pytest.skip(f"MakeHuman assets not installed: {exc}")
    return human, walk, parts


def _import(path):
    import bpy

    from avatar.blender import scene

    scene.clear_scene()
    suffix = path.suffix.lower()
    if suffix == ".fbx":
        bpy.ops.import_scene.fbx(filepath=str(path))
    elif suffix == ".glb":
        bpy.ops.import_scene.gltf(filepath=str(path))
    elif suffix.startswith(".usd"):
        bpy.ops.wm.usd_import(filepath=str(path))
    else:  # .blend: append its objects
        with bpy.data.libraries.load(str(path), link=False) as (source, target):
            target.objects = list(source.objects)
        for obj in target.objects:
            bpy.context.scene.collection.objects.link(obj)
    bpy.context.view_layer.update()


def _mesh(name):
    """The imported mesh object of an exported part (importers may add suffixes; USD's
    names are identifiers)."""
    import bpy

    wanted = {name, re.sub(r"[^A-Za-z0-9_]", "_", name)}
    found = [o for o in bpy.data.objects if o.type == "MESH" and o.name.split(".")[0] in wanted]
    assert found, f"no mesh {name!r} among {[o.name for o in bpy.data.objects]}"
    return found[0]


def _frames(armature) -> int:
    from avatar.blender import action

    anim = armature.animation_data
    if anim is None or anim.action is None:  # USD import puts it on the armature too
        return 0
    keys = {round(p.co[0]) for c in action.action_curves(anim.action) for p in c.keyframe_points}
    return len(keys)


def _base_colour_image(obj, through_mix: bool):
    """The image feeding the Base Color of ``obj``'s material, and the BSDF. Only glTF's
    importer may put its own Mix node (texture x baseColorFactor) in between."""
    material = obj.active_material
    assert material is not None, obj.name
    bsdf = next(n for n in material.node_tree.nodes if n.type == "BSDF_PRINCIPLED")
    links = bsdf.inputs["Base Color"].links
    assert links, f"{obj.name}: no texture on Base Color"
    node = links[0].from_node
    if through_mix and node.type == "MIX":
        node = next(s.links[0].from_node for s in node.inputs if s.is_linked)
    assert node.type == "TEX_IMAGE", f"{obj.name}: Base Color from {node.type}"
    return node.image, bsdf


@pytest.mark.parametrize("suffix", [".fbx", ".usdc", ".blend", ".glb"])
def test_reimport_keeps_meshes_bones_animation_and_textures(empty_scene, walker, tmp_path, suffix):
    import bpy

    import avatar

    human, walk, parts = walker
    path = avatar.save(human, tmp_path / f"walker{suffix}", walk)
    _import(path)
    armatures = [o for o in bpy.data.objects if o.type == "ARMATURE"]
    assert len(armatures) == 1
    bones = {b.name for b in armatures[0].data.bones}
    names = set(human.skeleton.names)
    if suffix.startswith(".usd"):  # USD prim names are identifiers: '.', '-' become '_'
        names = {re.sub(r"[^A-Za-z0-9_]", "_", n) for n in names}
    assert names <= bones, sorted(names - bones)[:5]
    assert _frames(armatures[0]) == walk.frames
    for name, (count, material) in parts.items():
        obj = _mesh(name)
        if suffix != ".glb":  # glTF splits vertices on UV seams; its own test checks counts
            assert len(obj.data.vertices) == count, (name, len(obj.data.vertices), count)
        if material.base_color_texture is None:  # a plain colour (teeth, tongue) stays one
            bsdf = next(n for n in obj.active_material.node_tree.nodes
                        if n.type == "BSDF_PRINCIPLED")  # fmt: skip
            got = bsdf.inputs["Base Color"].default_value[:3]
            assert got == pytest.approx(material.base_color[:3], abs=0.02), name
            continue
        image, bsdf = _base_colour_image(obj, through_mix=suffix == ".glb")
        assert image.size[0] > 0 and image.size[1] > 0, name
        if name == "body":
            assert not bsdf.inputs["Alpha"].is_linked  # an opaque skin, not a cut-out
