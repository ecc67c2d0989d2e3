"""glTF 2.0 PBR materials and their textures (spec section 3.9), written and read.

Textures are embedded as PNG images in buffer views, each distinct image once. Avatar's
roughness map becomes the green channel of glTF's metallic-roughness texture.
"""

from __future__ import annotations

import base64
import hashlib
import os
from collections.abc import Iterable
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pygltflib as g

from avatar.io import gltf_accessors as acc
from avatar.io import images, png
from avatar.material import Material

DEFAULT = Material("default")


class Materials:
    """Adds materials and their textures once each (images deduplicated by content)."""

    def __init__(self, gltf: g.GLTF2, packer: acc.Packer):
        self.gltf, self.packer = gltf, packer
        self.by_id: dict[int, int] = {}
        self.images: dict[bytes, int] = {}
        self.encoded: dict[bytes, bytes] = {}  # image key -> PNG bytes (``encode_all``)

    def encode_all(self, materials: Iterable[Material | None]) -> None:
        """Encode every distinct texture of ``materials`` as PNG at once, on all cores
        (zlib releases the GIL; compression is most of a textured export's time). The
        file is the same byte for byte: images are still added in first-use order."""
        todo: dict[bytes, np.ndarray] = {}
        for m in materials:
            for image in _images(m):
                key = _key(image)
                if key not in self.encoded:
                    todo.setdefault(key, image)
        if not todo:
            return
        with ThreadPoolExecutor(max_workers=min(len(todo), os.cpu_count() or 1)) as pool:
            self.encoded.update(zip(todo, pool.map(png.encode, todo.values()), strict=True))

    def index(self, material: Material) -> int:
        if id(material) not in self.by_id:
            self.gltf.materials.append(self._material(material))
            self.by_id[id(material)] = len(self.gltf.materials) - 1
        return self.by_id[id(material)]

    def _material(self, m: Material) -> g.Material:
        pbr = g.PbrMetallicRoughness(
            baseColorFactor=[float(c) for c in m.base_color],
            metallicFactor=float(m.metallic),
            roughnessFactor=float(m.roughness),
        )
        if m.base_color_texture is not None:
            pbr.baseColorTexture = g.TextureInfo(index=self._texture(m.base_color_texture, m.name))
        if m.roughness_texture is not None:
            pbr.metallicRoughnessTexture = g.TextureInfo(
                index=self._texture(_pack_roughness(m.roughness_texture), m.name + "_rough")
            )
        out = g.Material(
            name=self._unique_name(m.name),
            pbrMetallicRoughness=pbr,
            alphaMode=m.alpha_mode,
            doubleSided=bool(m.double_sided),
            extras=dict(m.extras),
        )
        if m.alpha_mode == "MASK":
            out.alphaCutoff = float(m.alpha_cutoff)
        else:
            out.alphaCutoff = None
        if m.normal_texture is not None:
            out.normalTexture = g.NormalMaterialTexture(
                index=self._texture(m.normal_texture, m.name + "_normal"), scale=m.normal_scale
            )
        return out

    def _unique_name(self, name: str) -> str:
        taken = {m.name for m in self.gltf.materials}
        out, i = name, 1
        while out in taken:
            out, i = f"{name}.{i:03d}", i + 1
        return out

    def _texture(self, image: np.ndarray, name: str) -> int:
        """A texture for the image (one PNG per distinct image); return the texture index."""
        key = _key(image)
        if key not in self.images:
            if not self.gltf.samplers:
                self.gltf.samplers.append(g.Sampler(magFilter=9729, minFilter=9987))
            data = self.encoded.pop(key, None) or png.encode(image)
            source = self.packer.image(data, name)
            self.gltf.textures.append(g.Texture(sampler=0, source=source, name=name))
            self.images[key] = len(self.gltf.textures) - 1
        return self.images[key]


def _key(image: np.ndarray) -> bytes:
    """A content key of an image (pixels and shape)."""
    return hashlib.blake2b(image.tobytes() + repr(image.shape).encode(), digest_size=16).digest()


def _images(m: Material | None) -> list[np.ndarray]:
    """The images ``Materials`` will embed for a material, as it embeds them."""
    if m is None:
        return []
    out = [m.base_color_texture] if m.base_color_texture is not None else []
    if m.roughness_texture is not None:
        out.append(_pack_roughness(m.roughness_texture))
    if m.normal_texture is not None:
        out.append(m.normal_texture)
    return out


def _pack_roughness(rough: np.ndarray) -> np.ndarray:
    """(H, W) roughness -> glTF's metallic-roughness image: G roughness, B metallic (1)."""
    image = np.empty(rough.shape[:2] + (3,), dtype=np.uint8)
    image[..., 0] = 255
    image[..., 1] = rough.reshape(rough.shape[:2])
    image[..., 2] = 255  # metallic comes from the factor alone
    return image


# ---------------------------------------------------------------------------- reading


def read_material(gltf, buffers, index: int | None) -> Material | None:
    """glTF material -> Material (textures decoded), or None when the primitive has none."""
    if index is None:
        return None
    m = gltf.materials[index]
    pbr = m.pbrMetallicRoughness or g.PbrMetallicRoughness()
    image = lambda info: _read_texture(gltf, buffers, info.index) if info else None  # noqa: E731
    rough = image(pbr.metallicRoughnessTexture)
    return Material(
        name=m.name or f"material_{index}",
        base_color=_rgba(pbr.baseColorFactor),
        base_color_texture=image(pbr.baseColorTexture),
        normal_texture=_rgb(image(m.normalTexture)),
        normal_scale=float(m.normalTexture.scale or 1.0) if m.normalTexture else 1.0,
        roughness=float(1.0 if pbr.roughnessFactor is None else pbr.roughnessFactor),
        metallic=float(1.0 if pbr.metallicFactor is None else pbr.metallicFactor),
        roughness_texture=None if rough is None else np.ascontiguousarray(rough[..., 1]),
        alpha_mode=m.alphaMode or "OPAQUE",
        alpha_cutoff=float(m.alphaCutoff if m.alphaCutoff is not None else 0.5),
        double_sided=bool(m.doubleSided),
        extras=dict(m.extras or {}),
    )


def _read_texture(gltf, buffers, texture_index: int) -> np.ndarray:
    """Decode a texture's image (PNG or JPEG, from a buffer view, data URI or file)."""
    img = gltf.images[gltf.textures[texture_index].source]
    if img.bufferView is not None:
        data = acc.view_bytes(gltf, buffers, img.bufferView)
    elif img.uri and img.uri.startswith("data:"):
        data = base64.b64decode(img.uri.split(",", 1)[1])
    else:
        raise ValueError(f"external image files are not read ({img.uri})")
    pixels = images.decode(data)
    return pixels if pixels.ndim == 3 else np.repeat(pixels[..., None], 3, axis=2)


def _rgba(factor) -> tuple[float, float, float, float]:
    r, g_, b, a = (float(c) for c in (factor or (1.0, 1.0, 1.0, 1.0)))
    return (r, g_, b, a)


def _rgb(image: np.ndarray | None) -> np.ndarray | None:
    return None if image is None else np.ascontiguousarray(image[..., :3])
