"""Wavefront OBJ read/write (positions, UVs, polygon faces, groups) and its ``.mtl``.

Spec: https://paulbourke.net/dataformats/obj/ (and the MTL spec beside it). Avatar reads the
subset MakeHuman writes: ``v``, ``vt``, ``f`` (v, v/vt, v/vt/vn, v//vn), ``g``/``o`` groups;
other statements are ignored. Coordinates are returned as stored; unit/axis conversion is
the caller's choice through ``axes``. ``write_parts`` writes a whole character: one ``o``
object per part with its ``usemtl`` material, a ``.mtl`` beside it and each texture as a PNG
(``map_Kd`` colour, ``map_Bump`` normal map, ``map_Pr`` roughness: the PBR extension
Blender's importer reads), all committed together (``atomic.write_all``).
"""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from functools import partial
from pathlib import Path

import numpy as np

from avatar.errors import FormatError
from avatar.io import atomic, png
from avatar.material import Material
from avatar.mesh import Mesh
from avatar.part import MeshPart

MAKEHUMAN = "makehuman"  # Y-up decimetres -> Avatar's Z-up metres


def to_avatar_frame(v: np.ndarray) -> np.ndarray:
    """MakeHuman (x, y, z) in dm, Y-up, +Z forward -> Avatar (x, -z, y) in m, Z-up, -Y forward."""
    v = np.asarray(v, dtype=np.float64)
    return np.stack([v[..., 0], -v[..., 2], v[..., 1]], axis=-1) * 0.1


def from_avatar_frame(v: np.ndarray) -> np.ndarray:
    """Inverse of ``to_avatar_frame``."""
    v = np.asarray(v, dtype=np.float64) * 10.0
    return np.stack([v[..., 0], v[..., 2], -v[..., 1]], axis=-1)


def loads(text: str, path: str | os.PathLike[str] | None = None, axes: str | None = None) -> Mesh:
    """Parse OBJ text into a Mesh. ``axes="makehuman"`` converts dm Y-up to m Z-up.

    Faces must all have the same vertex count (3 or 4); a mixed mesh is split by padding
    triangles into degenerate quads (last index repeated).
    """
    verts: list[list[float]] = []
    uvs: list[list[float]] = []
    faces: list[list[int]] = []
    face_uvs: list[list[int]] = []
    groups: dict[str, list[int]] = {}
    current: str | None = None
    for lineno, raw in enumerate(text.splitlines(), 1):
        parts = raw.split()
        if not parts or parts[0].startswith("#"):
            continue
        key = parts[0]
        try:
            if key == "v":
                if len(parts) < 4:
                    raise ValueError("a vertex needs x y z")
                verts.append([float(x) for x in parts[1:4]])
            elif key == "vt":
                if len(parts) < 3:
                    raise ValueError("a texture coordinate needs u v")
                uvs.append([float(x) for x in parts[1:3]])
            elif key == "f":
                _parse_face(parts[1:], len(verts), len(uvs), faces, face_uvs)
                if current is not None:
                    groups.setdefault(current, []).append(len(faces) - 1)
            elif key in ("g", "o"):
                current = " ".join(parts[1:]) or None
        except (ValueError, IndexError) as exc:
            raise FormatError(path, lineno, f"bad {key!r} line: {exc}") from None
    if not verts:
        raise FormatError(path, 0, "no vertices")
    v = np.asarray(verts, dtype=np.float64)
    if not np.all(np.isfinite(v)):
        raise FormatError(path, 0, "non-finite vertex coordinates")
    if axes == MAKEHUMAN:
        v = to_avatar_frame(v)
    f = _pad(faces)
    has_uv = bool(uvs) and all(len(u) == len(fc) for u, fc in zip(face_uvs, faces, strict=True))
    fuv = _pad(face_uvs) if has_uv and face_uvs else None
    face_groups = {k: np.asarray(x, dtype=np.int32) for k, x in groups.items()}
    vertex_groups = {k: np.unique(f[x]).astype(np.int32) for k, x in face_groups.items()}
    return Mesh(
        vertices=v.astype(np.float32),
        faces=f,
        uvs=np.asarray(uvs, dtype=np.float32) if fuv is not None else None,
        face_uvs=fuv,
        groups=vertex_groups,
        face_groups=face_groups,
    )


def _parse_face(
    items: list[str], nv: int, nt: int, faces: list[list[int]], face_uvs: list[list[int]]
) -> None:
    if len(items) < 3:
        raise ValueError("a face needs at least 3 vertices")
    vi: list[int] = []
    ti: list[int] = []
    for item in items:
        fields = item.split("/")
        vi.append(_resolve(int(fields[0]), nv))
        if len(fields) > 1 and fields[1]:
            ti.append(_resolve(int(fields[1]), nt))
    faces.append(vi)
    if ti:
        if len(ti) != len(vi):
            raise ValueError("some corners of the face have a UV and some not")
        face_uvs.append(ti)


def _resolve(index: int, count: int) -> int:
    """OBJ indices are 1-based; negative ones count back from the latest element."""
    i = index - 1 if index > 0 else count + index
    if index == 0 or not 0 <= i < count:
        raise ValueError(f"index {index} out of range (have {count})")
    return i


def _pad(faces: list[list[int]]) -> np.ndarray:
    if not faces:
        return np.zeros((0, 3), dtype=np.int32)
    n = max(len(f) for f in faces)
    if n > 4:
        raise ValueError("polygons with more than 4 corners are not supported")
    return np.asarray([f + [f[-1]] * (n - len(f)) for f in faces], dtype=np.int32)


def read(path: str | os.PathLike[str], axes: str | None = None) -> Mesh:
    """Read an OBJ file (see ``loads``)."""
    try:
        text = Path(path).read_text(encoding="utf-8", errors="replace")
    except OSError as exc:
        raise FormatError(path, 0, f"cannot read: {exc.strerror}") from None
    return loads(text, path, axes)


def dumps(mesh: Mesh, axes: str | None = None, name: str = "avatar") -> str:
    """OBJ text of a mesh (positions, UVs, faces; one group per face group)."""
    v = from_avatar_frame(mesh.vertices) if axes == MAKEHUMAN else mesh.vertices
    lines = [f"# written by avatar\no {name}"]
    lines += [f"v {x:.6f} {y:.6f} {z:.6f}" for x, y, z in v]
    has_uv = mesh.uvs is not None and mesh.face_uvs is not None
    if has_uv:
        lines += [f"vt {u:.6f} {w:.6f}" for u, w in mesh.uvs]  # type: ignore[union-attr]
    order = _face_order(mesh)
    for group, index in order:
        if group:
            lines.append(f"g {group}")
        for i in index:
            f = _unpad(mesh.faces[i])
            if has_uv:
                t = mesh.face_uvs[i][: len(f)]  # type: ignore[index]
                lines.append("f " + " ".join(f"{a + 1}/{b + 1}" for a, b in zip(f, t, strict=True)))
            else:
                lines.append("f " + " ".join(str(a + 1) for a in f))
    return "\n".join(lines) + "\n"


def _face_order(mesh: Mesh) -> list[tuple[str | None, np.ndarray]]:
    if not mesh.face_groups:
        return [(None, np.arange(len(mesh.faces)))]
    seen = np.zeros(len(mesh.faces), dtype=bool)
    out: list[tuple[str | None, np.ndarray]] = []
    for name, idx in mesh.face_groups.items():
        idx = idx[~seen[idx]]
        seen[idx] = True
        out.append((name, idx))
    rest = np.flatnonzero(~seen)
    if len(rest):
        out.append(("rest", rest))
    return out


def _unpad(face: np.ndarray) -> list[int]:
    f = [int(x) for x in face]
    while len(f) > 3 and f[-1] == f[-2]:
        f.pop()
    return f


def write(path: str | os.PathLike[str], mesh: Mesh, axes: str | None = None) -> None:
    """Write a mesh as OBJ (atomically: a temporary file renamed into place)."""
    atomic.write_text(path, dumps(mesh, axes, name=Path(path).stem))


# ---------------------------------------------------------------------------- characters


def write_parts(path: str | os.PathLike[str], parts: Sequence[MeshPart]) -> list[Path]:
    """Write parts as one OBJ (an ``o`` object each, in order), its ``.mtl`` and textures.

    Textures are PNG files beside the OBJ named ``<stem>_<material>_<map>.png``. Every file
    is written to a temporary name and renamed into place only when all were written.
    Returns the paths written (OBJ first, then the ``.mtl``, then textures).
    """
    path = Path(path)
    mtl = path.with_suffix(".mtl")
    names = _material_names([p.material for p in parts])
    textures: dict[Path, np.ndarray] = {}
    library = []
    for material, name in names.values():
        maps = {kind: path.with_name(f"{path.stem}_{_safe(name)}_{kind}.png")
                for kind in material.textures()}  # fmt: skip
        textures.update({maps[k]: image for k, image in material.textures().items()})
        library.append(_mtl_entry(material, name, {k: p.name for k, p in maps.items()}))
    body = _objects(parts, names, mtl.name)
    materials = "\n".join(library)
    writers: dict[atomic.StrPath, Callable[[Path], object]] = {
        path: lambda tmp: tmp.write_text(body, encoding="utf-8"),
        mtl: lambda tmp: tmp.write_text(materials, encoding="utf-8"),
    }
    for file, image in textures.items():
        writers[file] = partial(_write_png, image=image)
    atomic.write_all(writers)
    return [Path(p) for p in writers]


def _write_png(tmp: Path, image: np.ndarray) -> None:
    tmp.write_bytes(png.encode(image))


def _material_names(materials: Sequence[Material | None]) -> dict[int, tuple[Material, str]]:
    """id(material) -> (material, a name unique in the file), in first-use order."""
    out: dict[int, tuple[Material, str]] = {}
    taken: set[str] = set()
    for m in [m or DEFAULT_MATERIAL for m in materials]:
        if id(m) in out:
            continue
        name, i = _safe(m.name) or "material", 1
        while name in taken:
            name, i = f"{_safe(m.name)}.{i:03d}", i + 1
        taken.add(name)
        out[id(m)] = (m, name)
    return out


DEFAULT_MATERIAL = Material("default")
TEXTURE_KEYS = {"base_color_texture": "map_Kd", "normal_texture": "map_Bump",
                "roughness_texture": "map_Pr"}  # fmt: skip


def _safe(name: str) -> str:
    """A name usable in MTL statements and file names (no spaces or separators)."""
    return "".join(c if c.isalnum() or c in "-_." else "_" for c in name)


def _mtl_entry(m: Material, name: str, maps: dict[str, str]) -> str:
    """One ``newmtl`` block: colour (Kd), opacity (d), roughness (Pr), metallic (Pm), maps."""
    r, g, b, a = m.base_color
    lines = [f"newmtl {name}", f"Kd {r:.6f} {g:.6f} {b:.6f}", "Ka 0 0 0", "Ks 0.5 0.5 0.5",
             f"Ns {max(0.0, (1.0 - m.roughness)) * 1000:.1f}", f"d {a:.6f}", "illum 2",
             f"Pr {m.roughness:.6f}", f"Pm {m.metallic:.6f}"]  # fmt: skip
    for field, statement in TEXTURE_KEYS.items():
        if field in maps:
            scale = f"-bm {m.normal_scale:g} " if field == "normal_texture" else ""
            lines.append(f"{statement} {scale}{maps[field]}")
    return "\n".join(lines) + "\n"


def _objects(parts: Sequence[MeshPart], names: dict[int, tuple[Material, str]], mtl: str) -> str:
    """The OBJ text: ``mtllib``, then each part's vertices, UVs, material and faces."""
    lines = ["# written by avatar", f"mtllib {mtl}"]
    v_base = t_base = 0
    for part in parts:
        mesh = part.mesh
        lines.append(f"o {_safe(part.name)}")
        lines += [f"v {x:.6f} {y:.6f} {z:.6f}" for x, y, z in np.asarray(mesh.vertices)]
        has_uv = mesh.uvs is not None and mesh.face_uvs is not None
        if has_uv:
            lines += [f"vt {u:.6f} {w:.6f}" for u, w in mesh.uvs]  # type: ignore[union-attr]
        lines.append(f"usemtl {names[id(part.material or DEFAULT_MATERIAL)][1]}")
        for i, face in enumerate(mesh.faces):
            f = _unpad(face)
            if has_uv:
                t = mesh.face_uvs[i][: len(f)]  # type: ignore[index]
                lines.append("f " + " ".join(f"{a + 1 + v_base}/{c + 1 + t_base}"
                                             for a, c in zip(f, t, strict=True)))  # fmt: skip
            else:
                lines.append("f " + " ".join(str(a + 1 + v_base) for a in f))
        v_base += len(mesh.vertices)
        t_base += len(mesh.uvs) if has_uv else 0  # type: ignore[arg-type]
    return "\n".join(lines) + "\n"


def read_mtl(path: str | os.PathLike[str]) -> dict[str, dict[str, str]]:
    """A ``.mtl`` file as material name -> statement -> the rest of its line.

    Raises FormatError naming the line for a statement before any ``newmtl``.
    """
    try:
        text = Path(path).read_text(encoding="utf-8", errors="replace")
    except OSError as exc:
        raise FormatError(path, 0, f"cannot read: {exc.strerror}") from None
    out: dict[str, dict[str, str]] = {}
    current: dict[str, str] | None = None
    for lineno, raw in enumerate(text.splitlines(), 1):
        words = raw.split(maxsplit=1)
        if not words or words[0].startswith("#"):
            continue
        rest = words[1].strip() if len(words) > 1 else ""
        if words[0] == "newmtl":
            current = out.setdefault(rest, {})
        elif current is None:
            raise FormatError(path, lineno, f"{words[0]!r} before any 'newmtl'")
        else:
            current[words[0]] = rest
    return out
