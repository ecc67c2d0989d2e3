"""Sidebar panels (View3D > Sidebar > Avatar): Body, Dress (Motion: ``panel_motion.py``).

The Body panel shows the active character's own properties (``object.avatar``): moving a
slider changes that character at once. With no character active it offers Create.
"""

import json

import bpy

from . import catalogue, thumbnails
from .operators import root_of
from .properties import ATTRIBUTES, MACROS, RACES


class _AvatarPanel:
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Avatar"


class AVATAR_PT_body(_AvatarPanel, bpy.types.Panel):
    bl_label = "Body"
    bl_idname = "AVATAR_PT_body"
    bl_order = 0  # feature panels (panel_*.py) follow: 3 and up

    def draw(self, context):
        settings = context.scene.avatar
        layout = self.layout
        row = layout.row(align=True)
        row.scale_y = 1.4
        row.operator("avatar.create_human", icon="OUTLINER_OB_ARMATURE")
        row = layout.row(align=True)
        row.prop(settings, "rig", text="")
        row.prop(settings, "rigged", text="", icon="ARMATURE_DATA")
        row.prop(settings, "default_look", text="", icon="USER")
        root = root_of(context.object)
        if root is None:
            layout.label(text="Select a character to edit it", icon="INFO")
            layout.operator("avatar.import_mhm", icon="IMPORT")
            return
        props = root.avatar
        layout.label(text=root.name, icon="OUTLINER_OB_ARMATURE")
        if "avatar_error" in root.keys():
            layout.label(text=root["avatar_error"], icon="ERROR")
        column = layout.column(align=True)
        for name in MACROS:
            column.prop(props, name, slider=True)
        box = layout.box()
        box.label(text="Ethnicity (sums to 1)")
        column = box.column(align=True)
        for name in RACES:
            column.prop(props, name, slider=True)
        _draw_skin_and_eyes(layout, root, props)
        layout.label(text="Attributes (standard deviations)")
        column = layout.column(align=True)
        for name in ATTRIBUTES:
            column.prop(props, f"pca_{name}", slider=True)
        layout.prop(props, "rig")
        _draw_measurements(layout, props, settings)
        _draw_locals(layout, props, settings)
        _draw_expressions(layout, props, settings)
        _draw_body_tools(layout, settings)


def _draw_skin_and_eyes(layout, root, props):
    """Eyes, and the skin: Avatar's own, or one of the user's textured MakeHuman skins,
    each with its ``.thumb``."""
    box = layout.box()
    box.prop(props, "eyes")
    skins = catalogue.skins()
    current = json.loads(root["avatar_recipe"]).get("skin_material") or ""
    if not skins:
        box.label(text="Skin: Avatar's (ethnicity, age)")
        return
    box.label(text="Skin")
    grid = box.grid_flow(row_major=True, columns=0, even_columns=True, align=True)
    for name, path, thumbnail in (("Avatar", "", ""), *skins):
        cell = grid.column(align=True)
        icon = thumbnails.skin_icon(path, thumbnail) if thumbnail else _builtin_icon("USER")
        if icon:
            cell.template_icon(icon_value=icon, scale=2.5)
        op = cell.operator("avatar.set_skin", text=name, depress=path == current)
        op.path = path


def _builtin_icon(name: str) -> int:
    """A Blender icon's id, for ``template_icon`` (a cell without a picture lines up)."""
    icons = bpy.types.UILayout.bl_rna.functions["prop"].parameters["icon"].enum_items
    return icons[name].value if name in icons else 0


def _draw_measurements(layout, props, settings):
    box = layout.box()
    box.label(text="Measurements (cm)")
    grid = box.grid_flow(columns=2, align=True)
    for name in ("height", "chest", "waist", "hips"):
        grid.label(text=f"{name.title()}: {getattr(props, f'measured_{name}'):.1f}")
    column = box.column(align=True)
    for name in ("height", "chest", "waist", "hips"):
        column.prop(settings, f"target_{name}")
    box.operator("avatar.fit_measurements", icon="DRIVER_DISTANCE")


def _draw_locals(layout, props, settings):
    box = layout.box()
    icon = "TRIA_DOWN" if settings.show_locals else "TRIA_RIGHT"
    box.prop(settings, "show_locals", icon=icon, emboss=False)
    if not settings.show_locals:
        return
    box.prop(settings, "modifier_search", text="", icon="VIEWZOOM")
    text = settings.modifier_search.strip().lower()
    items = [m for m in props.modifiers if m.group != "expression"]
    if text:
        column = box.column(align=True)
        for m in [m for m in items if text in m.name.lower()][:60]:
            column.prop(m, "value", text=m.name, slider=True)
        return
    open_groups = set(settings.expanded.split(","))
    for group in catalogue.groups():
        row = box.row()
        opened = group in open_groups
        op = row.operator("avatar.toggle_group", text=group.title(), emboss=False,
                          icon="TRIA_DOWN" if opened else "TRIA_RIGHT")  # fmt: skip
        op.group = group
        if opened:
            column = box.column(align=True)
            for m in items:
                if m.group == group:
                    column.prop(m, "value", text=m.label, slider=True)


def _draw_expressions(layout, props, settings):
    box = layout.box()
    icon = "TRIA_DOWN" if settings.show_expressions else "TRIA_RIGHT"
    box.prop(settings, "show_expressions", icon=icon, emboss=False)
    if settings.show_expressions:
        column = box.column(align=True)
        for m in props.modifiers:
            if m.group == "expression":
                column.prop(m, "value", text=m.label, slider=True)


def _draw_body_tools(layout, settings):
    box = layout.box()
    row = box.row(align=True)
    row.prop(settings, "preset", text="")
    row.operator("avatar.apply_preset", text="", icon="CHECKMARK")
    row.operator("avatar.save_preset", text="", icon="ADD")
    row = box.row(align=True)
    row.prop(settings, "seed")
    row.prop(settings, "realistic", text="", icon="USER")
    row.operator("avatar.randomise", text="", icon="FILE_REFRESH")
    row = box.row(align=True)
    row.operator("avatar.reset_body", icon="LOOP_BACK")
    row.operator("avatar.settle", icon="CHECKMARK")
    row = box.row(align=True)
    row.operator("avatar.import_mhm", icon="IMPORT")
    row.operator("avatar.export_mhm", icon="EXPORT")


class AVATAR_PT_dress(_AvatarPanel, bpy.types.Panel):
    bl_label = "Dress"
    bl_idname = "AVATAR_PT_dress"
    bl_order = 1  # feature panels (panel_*.py) follow: 3 and up

    def draw(self, context):
        settings = context.scene.avatar
        layout = self.layout
        if not len(settings.garments):
            layout.operator("avatar.refresh_library", icon="FILE_REFRESH", text="Load Library")
            return
        row = layout.row(align=True)
        row.prop(settings, "category", text="")
        row.prop(settings, "garment_search", text="", icon="VIEWZOOM")
        row.operator("avatar.refresh_library", text="", icon="FILE_REFRESH")
        root = root_of(context.object)
        worn = set(json.loads(root["avatar_recipe"]).get("clothes") or []) if root else set()
        text = settings.garment_search.strip().lower()
        grid = layout.grid_flow(row_major=True, columns=0, even_columns=True, align=True)
        for item in settings.garments:
            if settings.category not in ("ALL", "", item.category):
                continue
            if text and text not in f"{item.name} {item.category}".lower():
                continue
            cell = grid.column(align=True)
            icon = thumbnails.icon(item.entry, item.thumbnail)
            if icon:
                cell.template_icon(icon_value=icon, scale=3.0)
            op = cell.operator("avatar.toggle_garment", text=item.name,
                               depress=item.entry in worn,
                               icon="CHECKMARK" if item.entry in worn else "NONE")  # fmt: skip
            op.name = item.entry
            cell.enabled = root is not None
        thumbnails.draw_queued()  # one process for every picture this draw found missing
        layout.operator("avatar.bind_garment", icon="MOD_CLOTH")


CLASSES = (AVATAR_PT_body, AVATAR_PT_dress)  # Motion: panel_motion.py
