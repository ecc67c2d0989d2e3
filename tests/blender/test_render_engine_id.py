"""EEVEE's engine id differs between Blender 4.2-4.5 (BLENDER_EEVEE_NEXT) and 5.x
(BLENDER_EEVEE): ``render.engine_id`` gives the one this Blender takes, from either name.
Blender 4.2 runs the same check through tests/blender/extension_smoke.py."""

from __future__ import annotations

import pytest


@pytest.mark.parametrize("name", ["BLENDER_EEVEE", "BLENDER_EEVEE_NEXT"])
def test_either_eevee_id_sets_eevee(name, empty_scene):
    import bpy

    from avatar.blender import render

    scene = bpy.context.scene
    scene.render.engine = render.engine_id(name)
    want = "BLENDER_EEVEE" if bpy.app.version >= (5, 0) else "BLENDER_EEVEE_NEXT"
    assert scene.render.engine == want


def test_other_engines_pass_through_and_configure_sets_eevee(empty_scene):
    import bpy

    from avatar.blender import render

    assert render.engine_id("CYCLES") == "CYCLES"
    assert render.engine_id("BLENDER_WORKBENCH") == "BLENDER_WORKBENCH"
    render.configure(bpy.context.scene, engine="BLENDER_EEVEE_NEXT", resolution=32)
    assert bpy.context.scene.render.engine.startswith("BLENDER_EEVEE")
