"""MPFB2 driven in this bpy process through its own operators and services, for
``bench/blender.py --mpfb``: nothing of MPFB2 is copied here (it is GPL), only called.

What each call does is what an MPFB2 user's click does (2.0.17's code paths):

- ``create``: ``bpy.ops.mpfb.create_human()`` (New human > Create, panel defaults);
- ``dress``: ``bpy.ops.mpfb.add_standard_rig()`` with the rig set to ``default`` (MakeHuman's
  163-bone rig, Avatar's default; MPFB2's panel default is ``default_no_toes``), then one
  ``bpy.ops.mpfb.load_library_clothes(filepath=..., object_type=...)`` per asset, as the
  asset library's Load button does with its default settings (fit to body, delete group,
  rigging with interpolated weights, a subdivision modifier at viewport level 0);
- ``change``: the Model panel's macro slider, ``scene.mpfb_macropanel_<macro> = v`` with the
  basemesh active (``TargetService.reapply_macro_details`` with shape-key pruning, the panel
  default), then, for a dressed human, ``HumanService.refit(basemesh)``: what the panel's
  "Auto refit assets" option calls after the macros (clothes, body parts and rig refitted).

The MakeHuman assets are found by MPFB2 itself through its "second root" preference (a user
asset folder), because its refit looks garments up by name in its asset roots.
"""

from __future__ import annotations

import importlib
import os
import time
from pathlib import Path

import addon_utils  # noqa: TID251 (Blender's add-on loader: bench only)
import bpy  # noqa: TID251 (this file drives MPFB2 inside Blender: bench only)

from mpfb_source import MpfbError, Source

MODULE = "bl_ext.user_default.mpfb"  # the name Blender gives the extension in its user repo
# MPFB2's object_type for an asset folder's category (MakeHuman's library layout).
KINDS = {"clothes": "Clothes", "hair": "Hair", "eyebrows": "Eyebrows", "eyelashes": "Eyelashes",
         "eyes": "Eyes", "teeth": "Teeth", "tongue": "Tongue"}  # fmt: skip


class Mpfb:
    """MPFB2 registered in this process (``register`` once), with handles on the services and
    panel settings its operators read."""

    def __init__(self, source: Source, assets: Path | None) -> None:
        self.source = source
        repo = Path(bpy.utils.user_resource("EXTENSIONS", path="user_default", create=True))
        link = repo / "mpfb"
        if not link.exists():
            os.symlink(source.package, link)  # installed as a user extension, not copied
        bpy.ops.extensions.repo_refresh_all()
        # register() builds MPFB2's panels, properties and services (about a second).
        if addon_utils.enable(MODULE, default_set=True, handle_error=_raise) is None:
            raise MpfbError(f"{source.package}: MPFB2 did not register")
        self.services = importlib.import_module(MODULE + ".services")
        self.rig_settings = importlib.import_module(
            MODULE + ".ui.rigging.standardrig.standardrigpanel").STANDARD_RIG_PROPERTIES
        self.model_settings = importlib.import_module(
            MODULE + ".ui.model.modelpanel").MODEL_PROPERTIES
        scene = bpy.context.scene
        self.rig_settings.set_value("standard_rig", "default", entity_reference=scene)
        self.model_settings.set_value("refit", False, entity_reference=scene)  # refit: ours
        if assets is not None:
            bpy.context.preferences.addons[MODULE].preferences.mpfb_second_root = str(assets)
            self.services.LocationService.update_second_root()

    def create(self) -> bpy.types.Object:
        """A new default human (MPFB2's basemesh), made the active object."""
        _check(bpy.ops.mpfb.create_human(), "create_human")
        return bpy.context.active_object

    def dress(self, basemesh: bpy.types.Object, assets: list[Path]) -> None:
        """Give ``basemesh`` the default rig, then each ``.mhclo`` of ``assets`` in order."""
        _activate(basemesh)
        _check(bpy.ops.mpfb.add_standard_rig(), "add_standard_rig")
        for path in assets:
            _activate(basemesh)
            kind = KINDS.get(path.parent.parent.name.lower(), "Clothes")
            _check(bpy.ops.mpfb.load_library_clothes(filepath=str(path), object_type=kind),
                   f"load_library_clothes {path.name}")  # fmt: skip

    def change(self, basemesh: bpy.types.Object, macro: str, value: float,
               refit: bool) -> tuple[float, float]:  # fmt: skip
        """Move the Model panel's ``macro`` slider of ``basemesh`` to ``value``; ``refit``:
        then refit its clothes and rig as Auto refit does. Seconds of (slider, refit)."""
        _activate(basemesh)
        start = time.perf_counter()
        setattr(bpy.context.scene, "mpfb_macropanel_" + macro, value)
        middle = time.perf_counter()
        if refit:
            self.services.HumanService.refit(basemesh)
        end = time.perf_counter()
        now = getattr(bpy.context.scene, "mpfb_macropanel_" + macro)  # read from the basemesh
        if abs(now - value) > 1e-4:
            raise MpfbError(f"MPFB2's {macro} slider reads {now}, not {value}, after the change")
        return middle - start, end - middle


def remove(basemesh: bpy.types.Object) -> None:
    """Delete an MPFB2 human: its root (rig or basemesh), everything under it, and their
    meshes, armature, materials and images once nothing else uses them."""
    root = basemesh.parent or basemesh
    objects = [root, *root.children_recursive]
    datas = [o.data for o in objects if o.data is not None]
    materials = {m for d in datas for m in getattr(d, "materials", []) if m is not None}
    images = {n.image for m in materials if m.node_tree for n in m.node_tree.nodes
              if n.type == "TEX_IMAGE" and n.image is not None}  # fmt: skip
    for obj in objects:
        bpy.data.objects.remove(obj)
    meshes = [d for d in datas if isinstance(d, bpy.types.Mesh)]
    armatures = [d for d in datas if isinstance(d, bpy.types.Armature)]
    for pool, blocks in ((bpy.data.meshes, meshes), (bpy.data.armatures, armatures),
                         (bpy.data.materials, materials), (bpy.data.images, images)):  # fmt: skip
        for block in blocks:  # each once, in an order where users drop to 0 before
            if block.users == 0:
                pool.remove(block)


def _activate(obj: bpy.types.Object) -> None:
    for other in bpy.context.selected_objects:
        other.select_set(False)
    bpy.context.view_layer.objects.active = obj
    obj.select_set(True)


def _check(result: set[str], what: str) -> None:
    if result != {"FINISHED"}:
        raise MpfbError(f"MPFB2's {what} returned {sorted(result)}")


def _raise(exc: BaseException) -> None:
    raise MpfbError(f"MPFB2 failed to register: {exc}") from exc
