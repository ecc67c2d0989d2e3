"""Fixtures for tests on the pip ``bpy`` module.

Blender writes user config at import; point it at a temporary folder first. Every test here
is marked ``blender`` and skipped when ``bpy`` cannot be imported.
"""

from __future__ import annotations

import importlib.util
import os
import sys
import tempfile
from pathlib import Path

import numpy as np
import pytest

HAVE_BPY = importlib.util.find_spec("bpy") is not None

if importlib.util.find_spec("avatar") is None:  # a checkout without `pip install -e .`
    sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "src"))

if HAVE_BPY:
    os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="avatar-bpy-"))

sys.path.insert(0, str(Path(__file__).resolve().parent))  # this folder's helper modules
from extension_fixtures import extension_zip, human, installed  # noqa: E402,F401


def pytest_collection_modifyitems(config, items):
    here = os.path.dirname(__file__)
    skip = pytest.mark.skip(reason="bpy (pip install bpy==5.0.1) is not importable")
    for item in items:
        if str(item.fspath).startswith(here):
            item.add_marker(pytest.mark.blender)
            if not HAVE_BPY:
                item.add_marker(skip)


@pytest.fixture
def empty_scene():
    """A factory-empty scene (objects, meshes, armatures, actions, materials, images)."""
    from avatar.blender import scene

    scene.clear_scene()
    yield
    scene.clear_scene()


@pytest.fixture
def rng():
    return np.random.default_rng(7)
