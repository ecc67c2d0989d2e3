"""Sidebar panels (View3D > Sidebar > Avatar): Body, Dress, Motion."""

import bpy

from .properties import ATTRIBUTES, MACROS


class _AvatarPanel:
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Avatar"


class AVATAR_PT_body(_AvatarPanel, bpy.types.Panel):
    bl_label = "Body"
    bl_idname = "AVATAR_PT_body"

    def draw(self, context):
        settings = context.scene.avatar
        layout = self.layout
        column = layout.column(align=True)
        for name in MACROS:
            column.prop(settings, name, slider=True)
        layout.label(text="Attributes")
        column = layout.column(align=True)
        for name in ATTRIBUTES:
            column.prop(settings, f"pca_{name}", slider=True)
        self._draw_targets(layout, settings)
        layout.prop(settings, "rig")
        row = layout.row(align=True)
        row.scale_y = 1.4
        row.operator("avatar.create_human", icon="OUTLINER_OB_ARMATURE")
        row.operator("avatar.update_human", icon="FILE_REFRESH")
        layout.operator("avatar.load_recipe", icon="IMPORT")

    @staticmethod
    def _draw_targets(layout, settings):
        layout.label(text="Local targets")
        row = layout.row(align=True)
        row.prop(settings, "target_search", text="", icon="VIEWZOOM")
        row.operator("avatar.add_target", text="", icon="ADD")
        column = layout.column(align=True)
        for target in settings.targets:
            row = column.row(align=True)
            row.prop(target, "value", text=target.name, slider=True)
            row.operator("avatar.remove_target", text="", icon="X").name = target.name


class AVATAR_UL_garments(bpy.types.UIList):
    bl_idname = "AVATAR_UL_garments"

    def draw_item(self, context, layout, data, item, icon, active_data, active_prop, index=0):
        row = layout.row()
        row.label(text=item.name, icon="MOD_CLOTH")
        row.label(text=item.category)


class AVATAR_PT_dress(_AvatarPanel, bpy.types.Panel):
    bl_label = "Dress"
    bl_idname = "AVATAR_PT_dress"

    def draw(self, context):
        settings = context.scene.avatar
        layout = self.layout
        layout.template_list("AVATAR_UL_garments", "", settings, "garments",
                             settings, "garment_index", rows=5)  # fmt: skip
        row = layout.row(align=True)
        row.operator("avatar.refresh_library", icon="FILE_REFRESH")
        row.operator("avatar.wear", icon="ADD")
        row.operator("avatar.take_off", icon="REMOVE")
        layout.operator("avatar.bind_garment", icon="MOD_CLOTH")


class AVATAR_PT_motion(_AvatarPanel, bpy.types.Panel):
    bl_label = "Motion"
    bl_idname = "AVATAR_PT_motion"

    def draw(self, context):
        settings = context.scene.avatar
        layout = self.layout
        layout.prop(settings, "bvh_path")
        row = layout.row(align=True)
        row.prop(settings, "frame_start")
        row.prop(settings, "frame_end")
        layout.prop(settings, "fps")
        layout.prop(settings, "in_place")
        layout.operator("avatar.apply_motion", icon="PLAY")
