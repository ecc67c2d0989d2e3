"""Export presets, studio and camera JSON in a fresh Blender Python (run by
test_export_envs.py under pip bpy 4.2): every preset x format re-imported (vertex counts,
animation length, shape keys), the studio twice (EEVEE's id of this Blender), a camera JSON.
Prints one line per step; exits non-zero on the first failure."""

from __future__ import annotations

import json
import os
import sys
import tempfile


def main() -> int:
    os.environ["BLENDER_USER_RESOURCES"] = tempfile.mkdtemp(prefix="avatar-export-")
    import bpy
    import numpy as np

    from avatar import export as front
    from avatar.blender import action, export, scene, studio
    from avatar.human import Human

    print("blender", bpy.app.version_string)
    human = Human({"weight": 0.6}).dressed("tshirt")
    scene.clear_scene()
    built = scene.build_character(front.character(human, human.walk(5 / 30, fps=30), name="W"))

    def distinct(obj):
        co = np.empty(len(obj.data.vertices) * 3, np.float32)
        obj.data.vertices.foreach_get("co", co)
        return len(np.unique(np.round(co.reshape(-1, 3) * 1e5).astype(np.int64), axis=0))

    # glTF splits vertices on seams: distinct positions there (metres), counts elsewhere
    want = {o.name: distinct(o) for o in built.parts}
    counts = {o.name: len(o.data.vertices) for o in built.parts}
    keys = len(built.parts[-1].data.shape_keys.key_blocks)
    out = tempfile.mkdtemp()
    presets, formats = ("BLENDER", "UNITY", "UNREAL", "GODOT"), ("GLB", "FBX", "USD")
    files = {(p, f): export.export_character(built.root, os.path.join(out, p), p, f)
             for p in presets for f in formats}  # fmt: skip
    for (preset, fmt), path in files.items():
        scene.clear_scene()
        if fmt == "FBX":
            bpy.ops.import_scene.fbx(filepath=str(path))
        elif fmt == "GLB":
            bpy.ops.import_scene.gltf(filepath=str(path), merge_vertices=True)
        else:
            bpy.ops.wm.usd_import(filepath=str(path))
        arm = next(o for o in bpy.data.objects if o.type == "ARMATURE")
        curves = action.action_curves(arm.animation_data.action)
        frames = {round(k.co[0]) for c in curves for k in c.keyframe_points}
        meshes = {o.name.split(".")[0]: o for o in bpy.data.objects if o.type == "MESH"}
        if fmt == "GLB":
            got, expected = {n: distinct(meshes[n]) for n in want}, want
        else:
            got, expected = {n: len(meshes[n].data.vertices) for n in want}, counts
        assert got == expected and len(frames) == 5, (preset, fmt, got, len(frames))
        assert len(meshes["tshirt"].data.shape_keys.key_blocks) == keys, (preset, fmt)
        print(f"{preset} {fmt} ok")
    scene.clear_scene()
    built = scene.build_character(front.character(Human(), None, name="M"))
    for engine in ("CYCLES", "EEVEE"):
        for _ in range(2):
            studio.setup(built.parts, engine=engine, samples=4, resolution=(48, 64))
        roles = sorted(o[studio.ROLE_KEY] for o in bpy.data.objects if studio.ROLE_KEY in o)
        assert roles == ["backdrop", "camera", "fill", "key", "rim"], roles
        print(f"studio {engine} ok: {bpy.context.scene.render.engine}")
    record = json.loads(export.export_camera(os.path.join(out, "cam")).read_text())
    assert record["width"] == 48 and len(record["world_to_camera"]) == 4
    print("camera ok")
    return 0


if __name__ == "__main__":
    code = main()
    sys.stdout.flush()
    os._exit(code)  # bpy 4.2's module crashes tearing itself down at exit
