"""The extension end to end in a fresh Blender Python, as a user's script would drive it.

    python tests/blender/extension_smoke.py ZIP [--block pygltflib,tqdm] [--bvh CLIP]

Installs the zip into a private user folder, then: create_human (hair, brows, lashes),
live property changes checked against a fresh ``Human``, wear by name, error reports that
change nothing, Apply (Motion) with the slotted-action API where Blender has it and the
legacy one where not, unregister. ``--block`` makes those modules unimportable first (the
zip must not need them). Prints one line per step; exits non-zero on the first failure.
Run by tests/blender/test_extension_envs.py under other Blender versions (pip bpy 4.2).
"""

from __future__ import annotations

import argparse
import importlib.abc
import json
import os
import sys
import tempfile


class _Blocker(importlib.abc.MetaPathFinder):
    def __init__(self, names):
        self.names = set(names)

    def find_spec(self, name, path=None, target=None):
        if name.split(".")[0] in self.names:
            raise ImportError(f"{name} is blocked for this test")
        return None


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("zip")
    parser.add_argument("--block", default="")
    parser.add_argument("--bvh", default="")
    args = parser.parse_args()
    if args.block:
        sys.meta_path.insert(0, _Blocker(args.block.split(",")))
    os.environ["BLENDER_USER_RESOURCES"] = tempfile.mkdtemp(prefix="avatar-smoke-")
    import bpy
    import numpy as np

    print("blender", bpy.app.version_string)
    install(bpy, args.zip)
    from avatar.blender import action, armature, live, mesh
    from avatar.body.shaped import PART_GROUPS
    from avatar.human import Human

    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj)
    assert bpy.ops.avatar.create_human() == {"FINISHED"}
    root = bpy.context.view_layer.objects.active
    got = set(live.part_objects(root))
    assert got == {*PART_GROUPS, "hair-short", "eyebrows", "eyelashes"}, (root.name, got)
    print("create ok")
    root.avatar.weight = 0.8
    root.avatar.african = 0.5
    assert bpy.ops.avatar.wear(name="tshirt") == {"FINISHED"}
    bpy.ops.avatar.settle()
    fresh = Human.from_recipe(json.loads(root["avatar_recipe"]))
    parts = live.part_objects(root)
    error = np.abs(mesh.read_vertices(parts["body"]) - fresh.mesh.vertices).max()
    error_rest = np.abs(armature.rest_matrices(root, fresh.skeleton.names) - fresh.skeleton.rest)
    garments = max(np.abs(mesh.read_vertices(parts[g.name]) - g.mesh.vertices).max()
                   for g in fresh.outfit.garments)  # fmt: skip
    print(f"live ok: body {error:.2e} m, rest {error_rest.max():.2e}, garments {garments:.2e} m")
    assert error < 1e-4 and error_rest.max() < 1e-4 and garments < 1e-4
    before = root["avatar_recipe"]
    for call in (lambda: bpy.ops.avatar.wear(name="tshrt"),
                 lambda: bpy.ops.avatar.apply_motion()):  # fmt: skip
        try:
            call()
        except RuntimeError as exc:  # an error report, not a traceback
            assert "Traceback" not in str(exc), exc
        else:
            raise AssertionError("a bad input was accepted")
    assert root["avatar_recipe"] == before
    print("errors ok")
    if args.bvh:
        settings = bpy.context.scene.avatar
        settings.bvh_path, settings.frame_end = args.bvh, 8
        assert bpy.ops.avatar.apply_motion() == {"FINISHED"}
        root = bpy.context.view_layer.objects.active
        curves = action.action_curves(root.animation_data.action)
        frames = {round(p.co[0]) for c in curves for p in c.keyframe_points}
        assert len(frames) == 8, frames
        assert root["avatar_motion_report"]
        print(f"motion ok: slotted actions {action.has_slots()}")
    bpy.ops.preferences.addon_disable(module="bl_ext.user_default.avatar_addon")
    assert not hasattr(bpy.types, "AVATAR_PT_body")
    print("unregister ok")
    return 0


def install(bpy, zip_path: str) -> None:
    result = bpy.ops.extensions.package_install_files(
        filepath=zip_path, repo="user_default", enable_on_install=True
    )
    assert result == {"FINISHED"}, result
    assert hasattr(bpy.types, "AVATAR_PT_body")


if __name__ == "__main__":
    code = main()
    sys.stdout.flush()
    # bpy 4.2's module crashes tearing itself down at interpreter exit (after every check
    # ran): leave without the teardown.
    os._exit(code)
