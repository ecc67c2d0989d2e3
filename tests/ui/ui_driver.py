"""Runs inside a real Blender window for run_ui_smoke.sh (Blender 3.4+ API only).

Opens the 3D view's sidebar, then serves requests the shell script makes through files
in $AVATAR_UI_OUT, polling on a timer so Blender's UI stays live between them:

- ``geometry.json`` (written at start): window size and the sidebar region's rectangle in X
  screen coordinates (origin top-left), for xdotool.
- ``request-shot-NAME`` -> ``NAME.png`` (Blender's screenshot operator) and ``state.json``
  (the characters in the scene, with their stored recipes).
- ``request-undo`` -> Edit > Undo in the window (``bpy.ops.ed.undo``).
- ``request-bvh`` -> the Motion panel's BVH set to ``$AVATAR_UI_BVH`` (30 frames), as
  typing a path would.
- ``request-search-TEXT`` -> the Dress grid's search set to TEXT ("" clears it).
- ``request-quit`` -> quit Blender.
"""

import json
import os

import bpy

OUT = os.environ["AVATAR_UI_OUT"]


def _view3d():
    window = bpy.context.window_manager.windows[0]
    area = next(a for a in window.screen.areas if a.type == "VIEW_3D")
    return window, area


def open_sidebar():
    window, area = _view3d()
    area.spaces.active.show_region_ui = True
    cube = bpy.data.objects.get("Cube")  # the factory scene's; the character stands there
    if cube is not None:
        bpy.data.objects.remove(cube)
    # Keep an active object, so the sidebar keeps its Item tab and the tab positions the
    # shell script clicks stay those of the factory layout.
    bpy.context.view_layer.objects.active = bpy.data.objects.get("Camera")
    return None


def write_geometry():
    window, area = _view3d()
    ui = next(r for r in area.regions if r.type == "UI")
    top = window.height - (ui.y + ui.height)  # Blender counts y from the bottom
    geometry = {
        "window": [window.width, window.height],
        "sidebar": {"left": ui.x, "top": top, "width": ui.width, "height": ui.height},
    }
    _write("geometry.json", geometry)
    return None


def serve():
    for name in sorted(os.listdir(OUT)):
        if not name.startswith("request-"):
            continue
        os.remove(os.path.join(OUT, name))
        if name == "request-quit":
            bpy.ops.wm.quit_blender()
            return None
        if name.startswith("request-shot-"):
            _screenshot(name[len("request-shot-") :])
        if name == "request-undo":
            window, area = _view3d()
            with bpy.context.temp_override(window=window, area=area):
                bpy.ops.ed.undo()
        if name.startswith("request-search-"):
            bpy.context.scene.avatar.garment_search = name[len("request-search-") :]
            _view3d()[1].tag_redraw()  # a property set from a timer redraws nothing
        if name == "request-bvh":
            bpy.context.scene.avatar_motion.bvh_path = os.environ.get("AVATAR_UI_BVH", "")
            bpy.context.scene.avatar_motion.frame_end = 30
    return 0.25


def _screenshot(name):
    window, area = _view3d()
    if bpy.context.selected_objects:  # zoom the viewport onto a new character
        region = next(r for r in area.regions if r.type == "WINDOW")
        with bpy.context.temp_override(window=window, area=area, region=region):
            bpy.ops.view3d.view_selected()
    # Let the smooth-view animation finish and the window redraw before capturing.
    bpy.app.timers.register(lambda: _capture(name), first_interval=1.0)


def _capture(name):
    window, area = _view3d()
    with bpy.context.temp_override(window=window, area=area):
        bpy.ops.screen.screenshot(filepath=os.path.join(OUT, f"{name}.png"))
    characters = {
        o.name: json.loads(o["avatar_recipe"])
        for o in bpy.data.objects
        if "avatar_recipe" in o.keys()
    }
    meshes = {o.name: len(o.data.vertices) for o in bpy.data.objects if o.type == "MESH"}
    # What the viewport shows of each part: the sum of its evaluated vertex coordinates.
    depsgraph = bpy.context.evaluated_depsgraph_get()
    shown = {}
    for o in bpy.data.objects:
        if o.type == "MESH" and "avatar_part" in o.keys():
            data = o.evaluated_get(depsgraph).data
            shown[o["avatar_part"]] = round(sum(abs(c) for v in data.vertices for c in v.co), 3)
    actions = {
        o.name: [round(f) for f in o.animation_data.action.frame_range]
        for o in bpy.data.objects
        if o.animation_data and o.animation_data.action
    }
    reports = {
        o.name: o.get("avatar_motion_report", "")
        for o in bpy.data.objects
        if "avatar_recipe" in o.keys()
    }
    _write(
        "state.json",
        {
            "characters": characters,
            "meshes": meshes,
            "shown": shown,
            "actions": actions,
            "reports": reports,
            "panel": hasattr(bpy.types, "AVATAR_PT_body"),
        },
    )
    _write(f"done-{name}", {})


def _write(name, data):
    tmp = os.path.join(OUT, name + ".tmp")
    with open(tmp, "w") as f:
        json.dump(data, f)
    os.replace(tmp, os.path.join(OUT, name))  # the shell never reads a half-written file


bpy.app.timers.register(open_sidebar, first_interval=0.5)
bpy.app.timers.register(write_geometry, first_interval=1.5)
bpy.app.timers.register(serve, first_interval=2.0)
