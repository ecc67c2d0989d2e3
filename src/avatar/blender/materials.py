"""``avatar.material.Material`` -> Principled BSDF node tree with images from numpy arrays.

Mirrors glTF's metallic-roughness model, as the record does: the colour texture is multiplied
by ``base_color``, the roughness texture by ``roughness``; ``alpha_mode`` MASK thresholds
alpha at ``alpha_cutoff``. Renderer hints in ``extras`` (``subsurface``,
``subsurface_radius``, ``sheen``, ``coat``) go to the matching BSDF inputs.

Every image texture feeds its BSDF input directly: a colour factor is baked into the image's
pixels rather than applied through a Mix node, because the FBX and USD exporters follow
only an image wired straight to Base Color (a Mix node in between exported no colour).

Materials are made once per content and reused: ``material`` tags each one with a digest of
its record (``KEY``) and returns the existing one for an equal record, so rebuilding or
re-creating a character re-packs no image; ``release`` removes those that nothing uses any
more, with their images.
"""

from __future__ import annotations

import hashlib
import weakref
from collections.abc import Iterable, Sequence

import bpy
import numpy as np

_GREY = (0.55, 0.55, 0.55)
_EXTRAS = {  # Material.extras key -> Principled BSDF input (Blender 4.0+ names)
    "subsurface": "Subsurface Weight",
    "subsurface_radius": "Subsurface Radius",
    "subsurface_scale": "Subsurface Scale",
    "sheen": "Sheen Weight",
    "coat": "Coat Weight",
    "specular": "Specular IOR Level",
}


KEY = "avatar_key"  # custom property: the digest of the record a material was made from
# Digests of records already seen (records are frozen and their arrays read-only): a second
# character with the same skin hashes nothing.
_DIGESTS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def material(record: object | None, fallback_name: str = "Material") -> bpy.types.Material:
    """The node material of a Material record (a plain grey one for None): an existing one
    made from an equal record (same name, factors and texture pixels) when there is one,
    else a new one tagged with the record's digest."""
    if record is None:
        return plain(fallback_name, _GREY)
    key = digest(record)
    found = next((m for m in bpy.data.materials if m.get(KEY) == key), None)
    if found is not None:
        return found
    mat = _new_material(record, fallback_name)
    mat[KEY] = key
    return mat


def digest(record) -> str:
    """A hex digest of everything a Material record draws with (name, factors, pixels)."""
    known = _DIGESTS.get(record)
    if known is not None:
        return known
    h = hashlib.blake2b(digest_size=16)
    h.update(repr((record.name, tuple(record.base_color), record.roughness, record.metallic,
                   record.normal_scale, record.alpha_mode, record.alpha_cutoff,
                   record.double_sided, sorted((k, repr(v)) for k, v in
                                               record.extras.items()))).encode())  # fmt: skip
    for name, image in sorted(record.textures().items()):
        h.update(f"{name}{image.shape}{image.dtype}".encode())
        h.update(np.ascontiguousarray(image).data)
    _DIGESTS[record] = out = h.hexdigest()
    return out


def release(materials: Iterable[bpy.types.Material]) -> None:
    """Remove the Avatar-made materials among ``materials`` that no object uses any more,
    and their images that nothing else uses (a rebuilt or deleted character's)."""
    for mat in {m for m in materials if m is not None}:
        if KEY not in mat.keys() or mat.users > 0:
            continue
        images = [n.image for n in mat.node_tree.nodes if n.type == "TEX_IMAGE" and n.image]
        bpy.data.materials.remove(mat)
        for image in images:
            if image.users == 0:
                bpy.data.images.remove(image)


def _new_material(record, fallback_name: str) -> bpy.types.Material:
    mat, bsdf = _principled(record.name or fallback_name)
    rgba = tuple(float(c) for c in record.base_color)
    bsdf.inputs["Base Color"].default_value = rgba
    bsdf.inputs["Alpha"].default_value = rgba[3]
    bsdf.inputs["Roughness"].default_value = float(record.roughness)
    bsdf.inputs["Metallic"].default_value = float(record.metallic)
    mat.diffuse_color = rgba  # what Workbench and the viewport's solid mode show
    mat.use_backface_culling = not record.double_sided
    _set_extras(bsdf, record.extras)
    _link_colour(mat, bsdf, record)
    _link_roughness(mat.node_tree, bsdf, record)
    _link_normal(mat.node_tree, bsdf, record)
    if is_hair(record):
        hair_shading(mat.node_tree, bsdf, record)
    if record.alpha_mode == "BLEND" and hasattr(mat, "surface_render_method"):
        mat.surface_render_method = "BLENDED"  # EEVEE; Cycles blends regardless
    if record.alpha_mode != "OPAQUE":
        allow_transparent_layers(bpy.context.scene)
    return mat


# Hair: strands run along the texture's v axis on every Avatar hair surface (cards from root
# v = 0.5 to tip v = 0, scalp caps bottom to top, lashes lid to tip; ``looks.textures``).
HAIR_ANISOTROPY = 0.8  # how stretched the highlight is across the strands (0..1)
HAIR_SHEEN = 0.25  # the soft fibre rim seen at grazing angles
# Light a hair card passes through to its far side (a Translucent BSDF added, in Cycles):
# hair is a bundle of thin fibres, not a sheet, and lit from behind or through the layers
# above it glows in its own colour. Opaque cards shadowed each other: long hair hanging
# below the ears rendered darker than short hair of the same colour. The share of the
# light the hair does not reflect (``translucency``): never more light out than in.
HAIR_TRANSLUCENCY = 0.6  # a ``translucency`` hint in a record's extras overrides it
HAIR_TINT_GAMMA = 0.25  # the highlight's tint: the hair's colour ** this (0.03 -> 0.42)
HAIR_THROUGH_GAMMA = 0.5  # the colour of light through hair: the hair's colour ** this
UV_MAP = "UVMap"  # the layer ``blender.mesh`` makes


def is_hair(record) -> bool:
    """Whether a Material record is hair (scalp hair, lashes; an ``anisotropy`` hint or
    Avatar's ``hair`` fabric), so it gets the anisotropic fibre shading. Eyebrows are not:
    their hairs run every way across the texture."""
    if "anisotropy" in record.extras:
        return float(record.extras["anisotropy"]) > 0
    return record.extras.get("fabric") == "hair" and not record.name.startswith("eyebrows")


def hair_shading(tree, bsdf: bpy.types.Node, record) -> None:
    """Anisotropic fibre shading on a hair material's Principled BSDF (for meshes: the
    Principled Hair BSDF shades curves only).

    The highlight is stretched across the strands: the tangent comes from the UV map (its
    u direction) rotated a quarter turn (``Anisotropic Rotation`` 0.25) onto v, along which
    the strands run. The specular is tinted by a light version of the hair's own colour
    (the coloured second highlight of real hair) and fades towards the roots of the cards
    (v = 0.5, in the shade of the hair above them); a little sheen gives the soft rim of
    fibres. Base colour and alpha stay wired straight from the texture (exporters follow
    that link).
    """
    amount = float(record.extras.get("anisotropy", HAIR_ANISOTROPY))
    bsdf.inputs["Anisotropic"].default_value = amount
    bsdf.inputs["Anisotropic Rotation"].default_value = 0.25
    tangent = tree.nodes.new("ShaderNodeTangent")
    tangent.direction_type, tangent.uv_map, tangent.location = "UV_MAP", UV_MAP, (-300, -550)
    tree.links.new(tangent.outputs["Tangent"], bsdf.inputs["Tangent"])
    if "Sheen Weight" in bsdf.inputs and "sheen" not in record.extras:
        bsdf.inputs["Sheen Weight"].default_value = HAIR_SHEEN
        bsdf.inputs["Sheen Roughness"].default_value = 0.4
    colour = bsdf.inputs["Base Color"].links
    if colour and "Specular Tint" in bsdf.inputs:
        # Tinted by a light version of the hair's colour (its ``HAIR_TINT_GAMMA`` power):
        # tinted by the colour itself, dark hair (albedo ~0.03) had no highlight at all and
        # a dark brown beard rendered as a black mat.
        tint = tree.nodes.new("ShaderNodeGamma")
        tint.name = tint.label = "Hair Specular Tint"
        tint.location = (-300, -350)
        tint.inputs["Gamma"].default_value = HAIR_TINT_GAMMA
        tree.links.new(colour[0].from_socket, tint.inputs["Color"])
        tree.links.new(tint.outputs["Color"], bsdf.inputs["Specular Tint"])
    # Roots darker in the highlight: v in [0, 0.5] runs tip to root on the cards; the
    # scalp caps (v > 0.5) are all root.
    uv = tree.nodes.new("ShaderNodeUVMap")
    uv.uv_map, uv.location = UV_MAP, (-700, -700)
    split = tree.nodes.new("ShaderNodeSeparateXYZ")
    split.location = (-500, -700)
    tree.links.new(uv.outputs["UV"], split.inputs["Vector"])
    fade = tree.nodes.new("ShaderNodeMapRange")
    fade.location = (-300, -750)
    tree.links.new(split.outputs["Y"], fade.inputs["Value"])
    # Blender 4.0 renamed the Principled BSDF's "Specular" to "Specular IOR Level".
    specular = bsdf.inputs.get("Specular IOR Level") or bsdf.inputs["Specular"]
    level = float(specular.default_value)
    fade.inputs["From Min"].default_value, fade.inputs["From Max"].default_value = 0.0, 0.5
    fade.inputs["To Min"].default_value, fade.inputs["To Max"].default_value = level, 0.4 * level
    tree.links.new(fade.outputs["Result"], specular)
    amount = float(record.extras.get("translucency", HAIR_TRANSLUCENCY))
    if amount > 0:
        translucency(tree, bsdf, amount)


def translucency(tree, bsdf: bpy.types.Node, amount: float = HAIR_TRANSLUCENCY) -> None:
    """Cycles shades a hair material as its Principled BSDF plus a Translucent BSDF (light
    through the card from its far side) in the colour ``amount * c ** HAIR_THROUGH_GAMMA
    * (1 - c)`` of the hair's colour c: a share of the light the fibres do not reflect,
    so reflected and passed-on light add up to at most what reaches the card (added in
    the hair's colour, a white card in a white furnace sent on 1.29 times the light;
    mixed in, taking ``amount`` of the reflection away, blond hair lit from the front
    rendered some 30 % darker). It is cut out by the same alpha, on a Material Output of
    its own (target Cycles). The Principled BSDF stays wired to the material's first
    output (target All): EEVEE draws it, and the FBX and USD exporters look for a
    Principled BSDF linked straight to an output."""
    nodes, links = tree.nodes, tree.links
    share = float(np.clip(amount, 0.0, 1.0))
    # Light through a fibre crosses it once, where light reflected diffusely from the hair
    # has crossed many: the transmitted colour is the hair's own raised to a power below
    # one (lighter, more saturated, never above 1: ``HAIR_THROUGH_GAMMA``).
    tint = nodes.new("ShaderNodeGamma")
    tint.location = (-200, -450)
    tint.inputs["Gamma"].default_value = HAIR_THROUGH_GAMMA
    unreflected = nodes.new("ShaderNodeVectorMath")  # 1 - c: the light not reflected
    unreflected.operation, unreflected.location = "SUBTRACT", (-200, -600)
    unreflected.inputs[0].default_value = (1.0, 1.0, 1.0)
    colour = bsdf.inputs["Base Color"]
    if colour.links:
        links.new(colour.links[0].from_socket, tint.inputs["Color"])
        links.new(colour.links[0].from_socket, unreflected.inputs[1])
    else:
        tint.inputs["Color"].default_value = tuple(colour.default_value)
        unreflected.inputs[1].default_value = tuple(colour.default_value)[:3]
    product = nodes.new("ShaderNodeVectorMath")
    product.operation, product.location = "MULTIPLY", (0, -500)
    links.new(tint.outputs["Color"], product.inputs[0])
    links.new(unreflected.outputs["Vector"], product.inputs[1])
    scaled = nodes.new("ShaderNodeVectorMath")
    scaled.name = scaled.label = "Hair Translucency"
    scaled.operation, scaled.location = "SCALE", (150, -500)
    scaled.inputs["Scale"].default_value = share
    links.new(product.outputs["Vector"], scaled.inputs[0])
    through = nodes.new("ShaderNodeBsdfTranslucent")
    through.location = (300, -450)
    links.new(scaled.outputs["Vector"], through.inputs["Color"])
    fibre = nodes.new("ShaderNodeAddShader")
    fibre.location = (450, -250)
    links.new(bsdf.outputs["BSDF"], fibre.inputs[0])
    links.new(through.outputs["BSDF"], fibre.inputs[1])
    # Cut out where the Principled BSDF is (its alpha), so the gaps between strands stay
    # see-through: the Translucent BSDF has no alpha of its own.
    cut_out = nodes.new("ShaderNodeMixShader")
    cut_out.location = (650, -250)
    clear = nodes.new("ShaderNodeBsdfTransparent")
    clear.location = (450, -450)
    alpha = bsdf.inputs["Alpha"]
    if alpha.links:
        links.new(alpha.links[0].from_socket, cut_out.inputs["Fac"])
    else:
        cut_out.inputs["Fac"].default_value = alpha.default_value
    links.new(clear.outputs["BSDF"], cut_out.inputs[1])
    links.new(fibre.outputs["Shader"], cut_out.inputs[2])
    output = nodes.new("ShaderNodeOutputMaterial")
    output.target, output.location = "CYCLES", (850, -250)
    links.new(cut_out.outputs["Shader"], output.inputs["Surface"])


def allow_transparent_layers(scene: bpy.types.Scene, layers: int = 64) -> None:
    """Let Cycles see through ``layers`` stacked cut-outs (hair cards, lashes).

    Cycles stops at ``transparent_max_bounces`` (8 by default) and shades what is left
    black, so the tips of long hair, where many cards overlap, would render black. Only
    raises the limit.
    """
    cycles = getattr(scene, "cycles", None)
    if cycles is not None and cycles.transparent_max_bounces < layers:
        cycles.transparent_max_bounces = layers


def plain(name: str, colour: Sequence[float], roughness: float = 0.6) -> bpy.types.Material:
    """A Principled material of one linear RGB colour."""
    mat, bsdf = _principled(name)
    bsdf.inputs["Base Color"].default_value = (*colour[:3], 1.0)
    bsdf.inputs["Roughness"].default_value = roughness
    mat.diffuse_color = (*colour[:3], 1.0)
    return mat


def _principled(name: str) -> tuple[bpy.types.Material, bpy.types.Node]:
    mat = bpy.data.materials.new(name)
    if bpy.app.version < (5, 0):  # always node-based from 5.0 (use_nodes deprecated)
        mat.use_nodes = True
    nodes = mat.node_tree.nodes
    bsdf = nodes.get("Principled BSDF")
    if bsdf is None:  # a default tree without one
        bsdf = nodes.new("ShaderNodeBsdfPrincipled")
        output = nodes.get("Material Output") or nodes.new("ShaderNodeOutputMaterial")
        mat.node_tree.links.new(bsdf.outputs["BSDF"], output.inputs["Surface"])
    return mat, bsdf


def _set_extras(bsdf: bpy.types.Node, extras: dict) -> None:
    for key, socket in _EXTRAS.items():
        if key in extras and socket in bsdf.inputs:
            value = extras[key]
            target = bsdf.inputs[socket]
            target.default_value = value if np.ndim(value) == 0 else list(value)[:3]


def _link_colour(mat: bpy.types.Material, bsdf: bpy.types.Node, record) -> None:
    image = record.base_color_texture
    if image is None:
        return
    tree = mat.node_tree
    image = tinted(image, record.base_color)
    node = _image_node(tree, image_from_array(f"{record.name} colour", image), (-700, 300))
    # Straight into Base Color: exporters (FBX, USD) follow no node in between.
    tree.links.new(node.outputs["Color"], bsdf.inputs["Base Color"])
    bsdf.inputs["Base Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    mat.diffuse_color = (*_mean_colour(image), 1.0)
    if image.ndim == 3 and image.shape[2] == 4:
        alpha = node.outputs["Alpha"]
        if record.alpha_mode == "MASK":
            alpha = _math(tree, "GREATER_THAN", alpha, record.alpha_cutoff, (-300, 100))
        if record.alpha_mode != "OPAQUE":
            tree.links.new(alpha, bsdf.inputs["Alpha"])


def tinted(image: np.ndarray, factor: Sequence[float]) -> np.ndarray:
    """(H, W, C) uint8 sRGB image times a linear RGB ``factor`` (glTF's baseColorFactor),
    multiplied in linear light and encoded back to sRGB; alpha kept. The image itself when
    the factor is white."""
    rgb = np.asarray([float(c) for c in factor[:3]], np.float32)
    if np.all(np.abs(rgb - 1.0) < 1e-6):
        return image
    srgb = np.asarray(image[..., :3], np.float32) / 255.0
    linear = np.where(srgb <= 0.04045, srgb / 12.92, ((srgb + 0.055) / 1.055) ** 2.4) * rgb
    back = np.where(linear <= 0.0031308, linear * 12.92,
                    1.055 * np.maximum(linear, 0.0031308) ** (1 / 2.4) - 0.055)  # fmt: skip
    out = np.array(image, copy=True)
    out[..., :3] = np.clip(np.rint(back * 255.0), 0, 255).astype(np.uint8)
    return out


def _mean_colour(image: np.ndarray) -> tuple[float, float, float]:
    """Linear mean colour of an sRGB uint8 image (for the viewport's solid colour)."""
    srgb = np.asarray(image[..., :3], np.float32).reshape(-1, 3).mean(axis=0) / 255.0
    return tuple(float(c) for c in np.where(srgb <= 0.04045, srgb / 12.92,
                                            ((srgb + 0.055) / 1.055) ** 2.4))  # fmt: skip


def _link_roughness(tree, bsdf: bpy.types.Node, record) -> None:
    image = record.roughness_texture
    if image is None:
        return
    node = _image_node(tree, image_from_array(f"{record.name} roughness", image, True),
                       (-700, 0))  # fmt: skip
    value = node.outputs["Color"]
    if abs(record.roughness - 1.0) > 1e-6:
        value = _math(tree, "MULTIPLY", value, record.roughness, (-300, 0))
    tree.links.new(value, bsdf.inputs["Roughness"])


def _link_normal(tree, bsdf: bpy.types.Node, record) -> None:
    image = record.normal_texture
    if image is None:
        return
    node = _image_node(tree, image_from_array(f"{record.name} normal", image, True), (-700, -300))
    normal_map = tree.nodes.new("ShaderNodeNormalMap")
    normal_map.location = (-300, -300)
    normal_map.inputs["Strength"].default_value = float(record.normal_scale)
    tree.links.new(node.outputs["Color"], normal_map.inputs["Color"])
    tree.links.new(normal_map.outputs["Normal"], bsdf.inputs["Normal"])


def _math(tree, operation: str, socket, value: float, location) -> bpy.types.NodeSocket:
    node = tree.nodes.new("ShaderNodeMath")
    node.operation, node.location = operation, location
    tree.links.new(socket, node.inputs[0])
    node.inputs[1].default_value = float(value)
    return node.outputs["Value"]


def _image_node(tree, image: bpy.types.Image, location) -> bpy.types.Node:
    node = tree.nodes.new("ShaderNodeTexImage")
    node.image, node.location = image, location
    return node


def image_from_array(name: str, array: np.ndarray, non_color: bool = False) -> bpy.types.Image:
    """A packed Blender image from (H, W) or (H, W, 1|2|3|4) uint8 or float 0..1, row 0 on top.

    non_color: data textures (normal, roughness) that must not be colour-managed.
    The image is packed into the .blend so saving or exporting keeps it. An image whose
    alpha is 1 everywhere is made (and packed) without an alpha channel: importers (FBX's)
    wire a texture's alpha to the BSDF whenever the file has one, which turned the opaque
    skin into a cut-out on re-import.
    """
    rgba = to_rgba(array)
    height, width = rgba.shape[:2]
    opaque = bool(np.all(rgba[..., 3] >= 1.0))
    image = bpy.data.images.new(name, width, height, alpha=not opaque)
    if opaque:
        image.alpha_mode = "NONE"
    if non_color:  # before the pixels: changing a generated image's colour space clears them
        image.colorspace_settings.name = "Non-Color"
    image.pixels.foreach_set(np.ascontiguousarray(rgba[::-1]).ravel())  # Blender: bottom-up
    image.pack()
    return image


def to_rgba(array: np.ndarray) -> np.ndarray:
    """(H, W[, C]) uint8 or float -> (H, W, 4) float32 in 0..1 (grey and RGB get alpha 1)."""
    a = np.asarray(array)
    a = a.astype(np.float32) / 255.0 if a.dtype == np.uint8 else a.astype(np.float32)
    if a.ndim == 2:
        a = a[..., None]
    if a.shape[-1] in (1, 2):  # grey (+ alpha)
        a = np.concatenate([np.repeat(a[..., :1], 3, axis=-1), a[..., 1:]], axis=-1)
    if a.shape[-1] == 3:
        a = np.concatenate([a, np.ones(a.shape[:2] + (1,), np.float32)], axis=-1)
    return np.clip(a, 0.0, 1.0)
