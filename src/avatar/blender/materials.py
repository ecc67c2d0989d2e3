"""Material record -> Principled BSDF node tree, with image textures made from numpy arrays.

The record is ``avatar.material.Material``; fields are read by name with ``getattr`` so this
module needs nothing else from it. Fields used (all optional): ``name``, ``base_color``
(3 or 4 floats, linear), ``roughness``, ``metallic``, ``alpha``, ``subsurface``,
``subsurface_radius`` (3 floats, metres), ``base_color_texture`` (H, W, 3|4),
``normal_texture`` (H, W, 3, tangent space, OpenGL +Y), ``roughness_texture`` (H, W) or
(H, W, 3|4) glTF metallic-roughness (G = roughness, B = metallic), ``normal_strength``.
Textures are uint8 0..255 or float 0..1, row 0 at the top (as PNG and glTF store them).
"""

from __future__ import annotations

from collections.abc import Sequence

import bpy
import numpy as np

_GREY = (0.55, 0.55, 0.55)


def material(record: object | None, fallback_name: str = "Material") -> bpy.types.Material:
    """A new node material from a Material record (or a plain grey one for None)."""
    if record is None:
        return plain(fallback_name, _GREY)
    name = getattr(record, "name", None) or fallback_name
    mat, bsdf = _principled(name)
    _set_scalars(bsdf, record)
    _link_textures(mat, bsdf, record, name)
    return mat


def plain(name: str, colour: Sequence[float], roughness: float = 0.6) -> bpy.types.Material:
    """A Principled material of one linear RGB colour."""
    mat, bsdf = _principled(name)
    bsdf.inputs["Base Color"].default_value = (*colour[:3], 1.0)
    bsdf.inputs["Roughness"].default_value = roughness
    mat.diffuse_color = (*colour[:3], 1.0)  # Workbench's material colour
    return mat


def _principled(name: str) -> tuple[bpy.types.Material, bpy.types.Node]:
    mat = bpy.data.materials.new(name)
    if bpy.app.version < (5, 0):  # always node-based from 5.0 (use_nodes deprecated)
        mat.use_nodes = True
    bsdf = mat.node_tree.nodes.get("Principled BSDF")
    if bsdf is None:  # a future default tree without one
        bsdf = mat.node_tree.nodes.new("ShaderNodeBsdfPrincipled")
        output = mat.node_tree.nodes.get("Material Output") or mat.node_tree.nodes.new(
            "ShaderNodeOutputMaterial"
        )
        mat.node_tree.links.new(bsdf.outputs["BSDF"], output.inputs["Surface"])
    return mat, bsdf


def _set_scalars(bsdf: bpy.types.Node, record: object) -> None:
    colour = getattr(record, "base_color", None)
    if colour is not None:
        rgba = (*[float(c) for c in colour][:3], 1.0)
        bsdf.inputs["Base Color"].default_value = rgba
    for field, socket in (("roughness", "Roughness"), ("metallic", "Metallic"),
                          ("alpha", "Alpha"), ("subsurface", "Subsurface Weight")):  # fmt: skip
        value = getattr(record, field, None)
        if value is not None and socket in bsdf.inputs:
            bsdf.inputs[socket].default_value = float(value)
    radius = getattr(record, "subsurface_radius", None)
    if radius is not None and "Subsurface Radius" in bsdf.inputs:
        bsdf.inputs["Subsurface Radius"].default_value = [float(r) for r in radius][:3]


def _link_textures(mat: bpy.types.Material, bsdf: bpy.types.Node, record, name: str) -> None:
    tree = mat.node_tree
    colour = getattr(record, "base_color_texture", None)
    if colour is not None:
        node = _image_node(tree, image_from_array(f"{name} colour", colour), (-500, 300))
        tree.links.new(node.outputs["Color"], bsdf.inputs["Base Color"])
        if np.shape(colour)[-1] == 4 and np.ndim(colour) == 3:
            tree.links.new(node.outputs["Alpha"], bsdf.inputs["Alpha"])
    else:
        base = getattr(record, "base_color", None) or _GREY
        mat.diffuse_color = (*[float(c) for c in base][:3], 1.0)
    rough = getattr(record, "roughness_texture", None)
    if rough is not None:
        _link_roughness(tree, bsdf, rough, name)
    normal = getattr(record, "normal_texture", None)
    if normal is not None:
        _link_normal(tree, bsdf, normal, name, getattr(record, "normal_strength", None))


def _link_roughness(tree, bsdf, rough: np.ndarray, name: str) -> None:
    image = image_from_array(f"{name} roughness", rough, non_color=True)
    node = _image_node(tree, image, (-500, 0))
    if np.ndim(rough) == 3 and np.shape(rough)[-1] >= 3:
        split = tree.nodes.new("ShaderNodeSeparateColor")
        split.location = (-220, 0)
        tree.links.new(node.outputs["Color"], split.inputs["Color"])
        tree.links.new(split.outputs["Green"], bsdf.inputs["Roughness"])
        tree.links.new(split.outputs["Blue"], bsdf.inputs["Metallic"])
    else:
        tree.links.new(node.outputs["Color"], bsdf.inputs["Roughness"])


def _link_normal(tree, bsdf, normal: np.ndarray, name: str, strength) -> None:
    image = image_from_array(f"{name} normal", normal, non_color=True)
    node = _image_node(tree, image, (-500, -300))
    normal_map = tree.nodes.new("ShaderNodeNormalMap")
    normal_map.location = (-220, -300)
    if strength is not None:
        normal_map.inputs["Strength"].default_value = float(strength)
    tree.links.new(node.outputs["Color"], normal_map.inputs["Color"])
    tree.links.new(normal_map.outputs["Normal"], bsdf.inputs["Normal"])


def _image_node(tree, image: bpy.types.Image, location) -> bpy.types.Node:
    node = tree.nodes.new("ShaderNodeTexImage")
    node.image = image
    node.location = location
    return node


def image_from_array(name: str, array: np.ndarray, non_color: bool = False) -> bpy.types.Image:
    """A packed Blender image from (H, W), (H, W, 1|3|4) uint8 or float 0..1, row 0 on top.

    non_color: data textures (normal, roughness) that must not be colour-managed.
    The image is packed into the .blend so saving or exporting keeps it.
    """
    rgba = to_rgba(array)
    height, width = rgba.shape[:2]
    image = bpy.data.images.new(name, width, height, alpha=True)
    # Blender stores rows bottom-up.
    image.pixels.foreach_set(np.ascontiguousarray(rgba[::-1]).ravel())
    if non_color:
        image.colorspace_settings.name = "Non-Color"
    image.pack()
    return image


def to_rgba(array: np.ndarray) -> np.ndarray:
    """(H, W[, C]) uint8 or float -> (H, W, 4) float32 in 0..1 (grey and RGB get alpha 1)."""
    a = np.asarray(array)
    a = a.astype(np.float32) / 255.0 if a.dtype == np.uint8 else a.astype(np.float32)
    if a.ndim == 2:
        a = a[..., None]
    channels = a.shape[-1]
    if channels == 1:
        a = np.repeat(a, 3, axis=-1)
    if channels == 2:  # grey + alpha
        a = np.concatenate([np.repeat(a[..., :1], 3, axis=-1), a[..., 1:]], axis=-1)
    if a.shape[-1] == 3:
        a = np.concatenate([a, np.ones(a.shape[:2] + (1,), np.float32)], axis=-1)
    return np.clip(a, 0.0, 1.0)
