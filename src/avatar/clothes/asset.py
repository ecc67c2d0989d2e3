"""Load a MakeHuman/MPFB garment (``.mhclo`` + ``.obj`` + ``.mhmat`` [+ ``.mhw``]) as a Garment.

Everything is checked before anything is returned: the OBJ exists and has one vertex per
reference, the diffuse texture exists, the weights file parses. Errors are FormatErrors
naming the offending file, so a broken garment is never half-added to a character.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from avatar.clothes.fitting import Garment
from avatar.errors import FormatError
from avatar.io import images, mhclo, mhmat, mhw, obj
from avatar.io.mhclo import ProxyFile
from avatar.material import Material

FACE_PROXIES = ("eyebrows", "eyelashes")  # drawn on the skin by design: no push-out


def read_garment(path: str | os.PathLike[str]) -> Garment:
    """A Garment from a ``.mhclo`` file and the files it names (all validated)."""
    path = Path(path)
    proxy = mhclo.read(path)
    mesh = _read_mesh(path, proxy)
    material = _read_material(path, proxy)
    bone_weights = None
    if proxy.vertexboneweights_file:
        bone_weights = mhw.read(_sibling(path, proxy.vertexboneweights_file, "weights file"))
        if len(bone_weights.vertex) and bone_weights.vertex.max() >= len(mesh.vertices):
            raise FormatError(
                bone_weights_path(path, proxy),
                0,
                "weights name a vertex the garment OBJ does not have",
            )
    category = _category(path, proxy)
    return Garment(
        name=proxy.name or path.stem,
        mesh=mesh,
        binding=proxy.binding,
        material=material,
        z_depth=proxy.z_depth,
        delete_verts=proxy.delete_verts,
        bone_weights=bone_weights,
        collide=category not in FACE_PROXIES,
        category=category,
        tags=proxy.tags,
        source=str(path),
        licence=licence_of(proxy),
    )


def bone_weights_path(path: Path, proxy: ProxyFile) -> Path:
    return path.parent / proxy.vertexboneweights_file


def _sibling(path: Path, name: str, what: str) -> Path:
    target = path.parent / name
    if not target.is_file():
        raise FormatError(path, 0, f"{what} {name!r} not found next to it")
    return target


def _read_mesh(path: Path, proxy: ProxyFile):
    obj_path = _sibling(path, proxy.obj_file or path.with_suffix(".obj").name, "obj_file")
    mesh = obj.read(obj_path, axes=obj.MAKEHUMAN)
    if len(mesh.vertices) != len(proxy.binding):
        raise FormatError(
            path,
            0,
            f"{len(proxy.binding)} vertex references but {obj_path.name} has "
            f"{len(mesh.vertices)} vertices",
        )
    return mesh


def _read_material(path: Path, proxy: ProxyFile) -> Material | None:
    if not proxy.material:
        return None
    mat_path = _sibling(path, proxy.material, "material")
    return material_from_file(mat_path)


def material_from_file(mat_path: str | os.PathLike[str]) -> Material:
    """A Material from a ``.mhmat`` (diffuse, normal and alpha; FormatError if the diffuse
    texture is missing)."""
    mat_path = Path(mat_path)
    mf = mhmat.read(mat_path)
    textures = mhmat.texture_paths(mf, mat_path.parent, mat_path)
    diffuse = _image(textures.get("diffuseTexture"))
    normal = _image(textures.get("normalmapTexture"))
    if normal is not None:
        normal = normal[..., :3] if normal.ndim == 3 else np.repeat(normal[..., None], 3, 2)
    transparent = mf.flag("transparent") or (
        diffuse is not None and diffuse.ndim == 3 and diffuse.shape[2] == 4
    )
    r, g, b = mf.color("diffuseColor")
    return Material(
        name=mf.name or mat_path.stem,
        base_color=(r, g, b, float(mf.number("opacity", 1.0) or 1.0)),
        base_color_texture=diffuse,
        normal_texture=normal,
        normal_scale=float(mf.number("normalmapIntensity", 1.0) or 1.0),
        roughness=float(mf.number("roughness", 0.8) or 0.8),
        alpha_mode="MASK" if transparent else "OPAQUE",
        double_sided=not mf.flag("backfaceCull", True) or transparent,
    )


def _image(path: Path | None) -> np.ndarray | None:
    return None if path is None else images.read(path)


def _category(path: Path, proxy: ProxyFile) -> str:
    for part in reversed(path.parts[:-1]):
        if part.lower() in ("clothes", "hair", "eyebrows", "eyelashes", "proxymeshes"):
            return part.lower()
    tags = " ".join(proxy.tags)
    return next((k for k in FACE_PROXIES if k[:-1] in tags), "clothes")


def licence_of(proxy: ProxyFile) -> str:
    """The licence a MakeHuman asset declares (``license`` line or its comment header)."""
    for key, value in proxy.meta:
        if key == "license":
            return value
    text = " ".join(proxy.comments)
    if "CC0" in text:
        return "CC0"
    if "AGPL" in text:
        return "AGPL"
    if "CC-BY" in text or "CC BY" in text:
        return "CC-BY"
    return ""
