"""The Export panel of the installed extension: export_character, studio and export_camera
from a script and from the panel's settings, and their one-line error reports (no
character, a path under a file, an unwritable folder, no camera) that write nothing."""

from __future__ import annotations

import json

import pytest


def test_the_panel_registers_after_the_others(installed):  # noqa: F811
    import bpy

    assert bpy.types.AVATAR_PT_export.bl_order == 10
    for op in ("export_character", "studio", "export_camera"):
        assert hasattr(bpy.ops.avatar, op), op
    assert bpy.context.scene.avatar_export.preset == "UNITY"


def test_export_from_a_script_and_from_the_panel(human, tmp_path):  # noqa: F811
    import bpy

    from avatar.blender import live

    counts = {n: len(o.data.vertices) for n, o in live.part_objects(human).items()}
    path = tmp_path / "hero.fbx"
    assert bpy.ops.avatar.export_character(filepath=str(path), preset="UNITY") == {"FINISHED"}
    assert path.is_file()
    settings = bpy.context.scene.avatar_export
    settings.filepath, settings.preset = str(tmp_path / "hero_godot"), "GODOT"
    assert bpy.ops.avatar.export_character(use_panel=True) == {"FINISHED"}
    glb = tmp_path / "hero_godot.glb"  # the preset's format picked the suffix
    assert glb.is_file()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["hero.fbx", "hero_godot.glb"]
    from avatar.blender import scene

    scene.clear_scene()
    bpy.ops.import_scene.fbx(filepath=str(path))
    meshes = {o.name.split(".")[0]: len(o.data.vertices) for o in bpy.data.objects
              if o.type == "MESH"}  # fmt: skip
    assert meshes == counts


@pytest.mark.parametrize("case", ["no_character", "under_a_file", "unwritable", "empty"])
def test_export_errors_are_one_line_and_write_nothing(human, tmp_path, case):  # noqa: F811
    import bpy

    (tmp_path / "file.txt").write_text("x")
    path = {"no_character": tmp_path / "a.glb", "under_a_file": tmp_path / "file.txt" / "a.glb",
            "unwritable": "/proc/avatar-panel/a.glb", "empty": ""}[case]  # fmt: skip
    if case == "no_character":
        bpy.context.view_layer.objects.active = None
    with pytest.raises(RuntimeError) as raised:
        bpy.ops.avatar.export_character(filepath=str(path), preset="GODOT")
    message = str(raised.value).strip()
    assert message.startswith("Error:") and "\n" not in message and "Traceback" not in message
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file.txt"]


def test_studio_twice_and_camera_json(human, tmp_path):  # noqa: F811
    import bpy

    from avatar.blender import studio

    for _ in range(2):
        assert bpy.ops.avatar.studio(engine="CYCLES", samples=8) == {"FINISHED"}
    roles = sorted(o[studio.ROLE_KEY] for o in bpy.data.objects if studio.ROLE_KEY in o)
    assert roles == ["backdrop", "camera", "fill", "key", "rim"]
    assert bpy.context.scene.cycles.samples == 8
    path = tmp_path / "camera.json"
    assert bpy.ops.avatar.export_camera(filepath=str(path)) == {"FINISHED"}
    record = json.loads(path.read_text())
    assert record["camera"] == bpy.context.scene.camera.name and len(record["K"]) == 3
    bpy.context.view_layer.objects.active = None
    with pytest.raises(RuntimeError, match="select an Avatar character"):
        bpy.ops.avatar.studio()
    bpy.context.scene.camera = None
    with pytest.raises(RuntimeError, match="no camera"):
        bpy.ops.avatar.export_camera(filepath=str(tmp_path / "none.json"))
    assert not (tmp_path / "none.json").exists()
