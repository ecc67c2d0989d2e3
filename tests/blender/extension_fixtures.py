"""Fixtures shared by the tests of the installed extension (registered in conftest.py):
the zip built once from this checkout, installed per test module into Blender's private
user folder, the MakeHuman assets (skip without them) and a new human made by the
operator."""

from __future__ import annotations

import importlib.util
import os
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
FIXTURES = Path(os.environ.get("AVATAR_FIXTURES", ROOT.parent / "shared" / "fixtures"))
ADDON = "bl_ext.user_default.avatar_addon"


def load_build_script():
    """addon/build.py as a module (registered in sys.modules while it loads: its
    dataclasses look their module up)."""
    spec = importlib.util.spec_from_file_location("avatar_addon_build", ROOT / "addon/build.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    try:
        spec.loader.exec_module(module)
    except BaseException:
        sys.modules.pop(spec.name, None)
        raise
    return module


@pytest.fixture(scope="session")
def extension_zip(tmp_path_factory):
    """The zip built from this checkout once per run (``--no-wheel``: the tests import
    ``avatar`` from ``src``; the wheel step is pip's job)."""
    out = tmp_path_factory.mktemp("dist")
    return load_build_script().main(["--output", str(out), "--no-wheel"])


@pytest.fixture(scope="module")
def installed(extension_zip):
    """The zip installed and enabled for one test module, disabled after it."""
    import bpy

    result = bpy.ops.extensions.package_install_files(
        filepath=str(extension_zip), repo="user_default", enable_on_install=True
    )
    assert result == {"FINISHED"}
    yield
    bpy.ops.preferences.addon_disable(module=ADDON)


@pytest.fixture
def human(installed, assets, empty_scene):
    """A new rigged human (hair, brows, lashes) made by the operator, active, settled."""
    import bpy

    assert bpy.ops.avatar.create_human() == {"FINISHED"}
    root = bpy.context.view_layer.objects.active
    assert bpy.ops.avatar.settle() == {"FINISHED"}
    return root
