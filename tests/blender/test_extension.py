"""The extension zip builds, validates, installs into Blender and its operators work."""

from __future__ import annotations

import importlib.util
import tomllib
import zipfile
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]


def load_build_script():
    spec = importlib.util.spec_from_file_location("avatar_addon_build", ROOT / "addon/build.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def extension_zip(tmp_path_factory):
    # --no-wheel: the tests import `avatar` from this checkout; the wheel step is pip's job.
    out = tmp_path_factory.mktemp("dist")
    return load_build_script().main(["--output", str(out), "--no-wheel"])


@pytest.fixture(scope="module")
def installed(extension_zip):
    import bpy

    result = bpy.ops.extensions.package_install_files(
        filepath=str(extension_zip), repo="user_default", enable_on_install=True
    )
    assert result == {"FINISHED"}
    yield
    bpy.ops.preferences.addon_disable(module="bl_ext.user_default.avatar_addon")


def test_zip_manifest_is_stamped_from_pyproject(extension_zip):
    with open(ROOT / "pyproject.toml", "rb") as f:
        version = tomllib.load(f)["project"]["version"]
    with zipfile.ZipFile(extension_zip) as z:
        manifest = tomllib.loads(z.read("blender_manifest.toml").decode())
        assert {"__init__.py", "operators.py", "panels.py"} <= set(z.namelist())
    assert manifest["version"] == version
    assert manifest["id"] == "avatar_addon"


def test_panels_and_operators_register(installed):
    import bpy

    for panel in ("AVATAR_PT_body", "AVATAR_PT_dress", "AVATAR_PT_motion"):
        assert hasattr(bpy.types, panel)
    for op in ("create_human", "update_human", "wear", "take_off", "apply_motion"):
        assert hasattr(bpy.ops.avatar, op)


def test_create_and_update_through_operators(installed, empty_scene, monkeypatch):
    import bpy
    from bridge_fixtures import box_mesh, skeleton

    from avatar.blender import character
    from avatar.errors import ParameterError

    def fake_realise(recipe):
        if recipe["params"]["height"] > 0.9:
            raise ParameterError("height too tall for this test")
        mesh = box_mesh((0, 0, 0), (0.4, 0.3, 1 + recipe["params"]["height"]))
        return _Fake(mesh, skeleton(np.random.default_rng(0)), recipe)

    monkeypatch.setattr(character, "realise", fake_realise)
    settings = bpy.context.scene.avatar
    settings.height = 0.25
    assert bpy.ops.avatar.create_human() == {"FINISHED"}
    root = bpy.context.view_layer.objects.active
    assert character.recipe_of(root)["params"]["height"] == pytest.approx(0.25)
    settings.height = 0.75
    assert bpy.ops.avatar.update_human() == {"FINISHED"}
    root = bpy.context.view_layer.objects.active
    assert character.recipe_of(root)["params"]["height"] == pytest.approx(0.75)
    settings.height = 0.95
    with pytest.raises(RuntimeError, match="too tall"):  # AvatarError -> an error report
        bpy.ops.avatar.update_human()


class _Fake:
    def __init__(self, mesh, skel, recipe):
        self.mesh, self.skeleton, self._recipe = mesh, skel, recipe
        self.weights = (np.zeros((8, 1), np.int32), np.ones((8, 1)))

    def to_recipe(self):
        return self._recipe


def test_dress_library_lists_the_builtin_garments(installed):
    import bpy

    assert bpy.ops.avatar.refresh_library() == {"FINISHED"}
    garments = bpy.context.scene.avatar.garments
    assert len(garments) >= 14
    assert all(g.entry for g in garments)
