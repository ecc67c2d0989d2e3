"""glTF 2.0 / GLB writer and reader: meshes, PBR materials, skeleton, skin, morphs, animation.

Spec: https://registry.khronos.org/glTF/specs/2.0/glTF-2.0.html . The suffix picks the
container: ``.glb`` (one binary file) or ``.gltf`` (JSON with the buffer as a side-car
``.bin`` or, with ``embed=True``, a data URI).

Frames. glTF is Y-up; Avatar is Z-up. This module and ``gltf_skin`` are the only places
that convert: glTF ``(x, y, z) = (x, z, -y)``, the rotation ``AXES``. Positions, normals
and morph deltas are rotated; bones keep their own local axes (see ``gltf_skin``), as
Blender's exporter does, so importing into Blender gives back Avatar's bone rolls and pose
quaternions exactly, and any viewer skins the mesh identically.

Vertices. Avatar meshes carry UVs per face corner; glTF carries one UV per vertex, so a
vertex on a UV seam becomes several glTF vertices. Quads are split along their 0-2
diagonal. The source vertex of every glTF vertex is written as the float attribute
``_AVATAR_VERTEX`` (glTF's application-specific attribute prefix), so ``read`` rebuilds the
original vertex array, skin and morphs exactly.
"""

from __future__ import annotations

import base64
import logging
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pygltflib as g

from avatar.errors import FormatError
from avatar.io import atomic, gltf_materials, gltf_morphs, gltf_skin, gltf_weights
from avatar.io import gltf_accessors as acc
from avatar.mesh import Mesh, vertex_normals
from avatar.part import MeshPart
from avatar.rig.skeleton import Animation, Skeleton

log = logging.getLogger(__name__)

AXES = gltf_skin.AXES
VERTEX_ID = "_AVATAR_VERTEX"


@dataclass(frozen=True)
class GltfFile:
    """What ``read`` returns: the parts, the skeleton (or None), the animations by name, and
    animation name -> part name -> (T, targets) keyed morph weights (``weights`` channels)."""

    parts: list[MeshPart]
    skeleton: Skeleton | None = None
    animations: dict[str, Animation] = field(default_factory=dict)
    morph_weights: dict[str, dict[str, np.ndarray]] = field(default_factory=dict)


def write(
    path: str | os.PathLike[str],
    parts: Sequence[MeshPart],
    skeleton: Skeleton | None = None,
    animations: Sequence[Animation] | Mapping[str, Animation] = (),
    *,
    morph_weights: Mapping[str, Mapping[str, np.ndarray]] | None = None,
    embed: bool = False,
    vertex_ids: bool = True,
    generator: str = "Avatar",
    max_influences: int = gltf_weights.MAX_INFLUENCES,
) -> None:
    """Write parts (and a skeleton with animations) as ``.glb`` or ``.gltf``.

    parts: the meshes; a part with ``skin`` is bound to ``skeleton`` (required then).
    animations: Animation records (named ``animation_<i>``) or a name -> Animation mapping;
        their bone names must exist in ``skeleton``. Key times are ``frame / fps``.
    morph_weights: animation name -> part name -> (frames, targets) weights of that part's
        morph targets (in ``part.morphs`` order), keyed with STEP interpolation in that
        animation (e.g. per-frame garment corrections, ``avatar.clothes.bake``).
    embed: for ``.gltf``, put the buffer in a data URI instead of a side-car ``.bin``.
    vertex_ids: write ``_AVATAR_VERTEX`` so ``read`` can merge seam vertices back.
    max_influences: joints per vertex, 8 (JOINTS_0 and JOINTS_1) or 4 (JOINTS_0 only, for
        engines that read one set, e.g. three.js); the largest are kept, renormalised.
    Parts named ``<name>_LOD1``, ``_LOD2``, ... are levels of detail of part ``<name>``
    (the naming Unity and Unreal import as LOD groups): written like any part.
    """
    if max_influences not in gltf_weights.INFLUENCE_LIMITS:
        raise ValueError(f"max_influences is 4 or 8, not {max_influences}")
    path = Path(path)
    if path.suffix.lower() not in (".glb", ".gltf"):
        raise ValueError(f"glTF files end in .glb or .gltf, not {path.suffix!r}")
    if isinstance(animations, Mapping):
        named = dict(animations)
    else:
        named = {f"animation_{i}": a for i, a in enumerate(animations)}
    if any(p.skin is not None for p in parts) and skeleton is None:
        raise ValueError("skinned parts need a skeleton")
    gltf = g.GLTF2(asset=g.Asset(version="2.0", generator=generator))
    packer = acc.Packer(gltf)
    gltf.scenes.append(g.Scene(name="Scene", nodes=[]))
    skin_index = None
    if skeleton is not None:
        skin_index = gltf_skin.add_skeleton(gltf, packer, skeleton)
        for name, animation in named.items():
            gltf_skin.add_animation(gltf, packer, skeleton, animation, name)
    materials = gltf_materials.Materials(gltf, packer)
    materials.encode_all(part.material for part in parts)
    nodes = {}
    for part in parts:
        nodes[part.name] = _add_part(gltf, packer, part, materials, skin_index, vertex_ids,
                                     max_influences)  # fmt: skip
    gltf_morphs.add_channels(gltf, packer, list(named), nodes, morph_weights or {})
    _save(gltf, bytes(packer.blob), path, embed)


def _save(gltf: g.GLTF2, blob: bytes, path: Path, embed: bool) -> None:
    """Attach the buffer and write the file in the container the suffix names.

    Each file is written beside its final name and renamed into place, so an interrupted
    or failed write never leaves a truncated file (or replaces a good one).
    """
    buffer = g.Buffer(byteLength=len(blob))
    gltf.buffers.append(buffer)
    if path.suffix.lower() == ".glb":
        gltf.set_binary_blob(blob)
        atomic.write_all({path: lambda tmp: gltf.save_binary(str(tmp))})
        return
    if embed:
        buffer.uri = "data:application/octet-stream;base64," + base64.b64encode(blob).decode()
        atomic.write_all({path: lambda tmp: tmp.write_text(gltf.gltf_to_json())})
        return
    buffer.uri = path.with_suffix(".bin").name
    atomic.write_all({path.with_suffix(".bin"): lambda tmp: tmp.write_bytes(blob),
                      path: lambda tmp: tmp.write_text(gltf.gltf_to_json())})  # fmt: skip


# ---------------------------------------------------------------------------- geometry


def split_vertices(mesh: Mesh) -> tuple[np.ndarray, np.ndarray | None, np.ndarray]:
    """Give every (vertex, UV) pair its own index, as glTF needs.

    Returns source (G,) int64 Avatar vertex per glTF vertex (ascending), uv (G,) int64 UV
    index per glTF vertex (None without UVs), and triangles (T, 3) of glTF vertex indices.
    Degenerate triangles (a padded quad's repeated index) are dropped.
    """
    tris, tri_uv = _triangulate(mesh.faces, mesh.face_uvs)
    if tri_uv is None or mesh.uvs is None:
        source, corners = np.unique(tris.reshape(-1), return_inverse=True)
        return source, None, corners.reshape(-1, 3)
    # Equal UV values under different indices (per-corner UV lists) are one UV: no seam.
    _, first, same = np.unique(mesh.uvs, axis=0, return_index=True, return_inverse=True)
    tri_uv = first[same.reshape(-1)[tri_uv]]
    key = tris.reshape(-1).astype(np.int64) * len(mesh.uvs) + tri_uv.reshape(-1)
    unique, corners = np.unique(key, return_inverse=True)
    return unique // len(mesh.uvs), unique % len(mesh.uvs), corners.reshape(-1, 3)


def _triangulate(faces: np.ndarray, face_uvs: np.ndarray | None):
    """(F, 3|4) faces -> (T, 3) triangles and matching UV triangles; quads split 0-2."""
    pick = [[0, 1, 2]] if faces.shape[1] == 3 else [[0, 1, 2], [0, 2, 3]]
    tris = np.concatenate([faces[:, p] for p in pick])
    uvs = None if face_uvs is None else np.concatenate([face_uvs[:, p] for p in pick])
    keep = (tris[:, 0] != tris[:, 1]) & (tris[:, 1] != tris[:, 2]) & (tris[:, 0] != tris[:, 2])
    return tris[keep], (None if uvs is None else uvs[keep])


def _add_part(
    gltf, packer, part: MeshPart, materials, skin_index, vertex_ids: bool, max_influences: int
) -> int:
    """One part -> one mesh with one primitive, and a node at the scene root (its index)."""
    mesh = part.mesh
    source, uv_index, triangles = split_vertices(mesh)
    normals = (
        part.normals if part.normals is not None else vertex_normals(mesh.vertices, mesh.faces)
    )
    positions, normals = _to_gltf(mesh.vertices[source]), _unit(_to_gltf(normals[source]))
    attributes = g.Attributes(
        POSITION=packer.accessor(positions, acc.ARRAY_BUFFER, bounds=True),
        NORMAL=packer.accessor(normals, acc.ARRAY_BUFFER),
    )
    if uv_index is not None and mesh.uvs is not None:
        uv = mesh.uvs[uv_index].astype(np.float32)
        uv[:, 1] = 1.0 - uv[:, 1]  # glTF's UV origin is the image's top-left corner
        attributes.TEXCOORD_0 = packer.accessor(uv, acc.ARRAY_BUFFER)
        if part.material is not None and part.material.normal_texture is not None:
            tangents = _tangents(positions, normals, uv, triangles)
            attributes.TANGENT = packer.accessor(tangents, acc.ARRAY_BUFFER)
    if part.skin is not None:
        _add_skin_attributes(attributes, packer, part.skin, source, gltf_skin.joint_count(gltf),
                             max_influences)  # fmt: skip
    if vertex_ids:
        setattr(attributes, VERTEX_ID, packer.accessor(source.astype(np.float32), acc.ARRAY_BUFFER))
    index_type = np.uint16 if len(source) < 65535 else np.uint32
    primitive = g.Primitive(
        attributes=attributes,
        indices=packer.accessor(triangles.reshape(-1).astype(index_type), acc.ELEMENT_ARRAY_BUFFER),
        material=materials.index(part.material or gltf_materials.DEFAULT),
        mode=4,
    )
    gmesh = g.Mesh(name=part.name, primitives=[primitive])
    if part.morphs:
        primitive.targets = [
            {"POSITION": packer.sparse_accessor(_to_gltf(np.asarray(d)[source]))}
            for d in part.morphs.values()
        ]
        gmesh.weights = [0.0] * len(part.morphs)
        gmesh.extras = {"targetNames": list(part.morphs)}
    gltf.meshes.append(gmesh)
    node = g.Node(name=part.name, mesh=len(gltf.meshes) - 1, skin=skin_index if part.skin else None)
    gltf.nodes.append(node)
    gltf.scenes[0].nodes.append(len(gltf.nodes) - 1)
    return len(gltf.nodes) - 1


def _add_skin_attributes(attributes, packer, skin, source, joint_count: int, limit: int) -> None:
    """JOINTS_0/WEIGHTS_0 (and _1 for more than four influences) for the glTF vertices."""
    joints, weights = gltf_weights.pack_weights(skin[0][source], skin[1][source], joint_count,
                                                limit)  # fmt: skip
    for set_index in range(joints.shape[1] // 4):
        cols = slice(4 * set_index, 4 * set_index + 4)
        setattr(
            attributes, f"JOINTS_{set_index}", packer.accessor(joints[:, cols], acc.ARRAY_BUFFER)
        )
        setattr(
            attributes, f"WEIGHTS_{set_index}", packer.accessor(weights[:, cols], acc.ARRAY_BUFFER)
        )


def _tangents(p, n, uv, triangles: np.ndarray) -> np.ndarray:
    """(G, 4) float32 tangents (xyz, handedness w) from positions, normals and glTF UVs.

    Per-triangle tangents (Lengyel's method) summed per vertex, made orthogonal to the
    normal. glTF says viewers generate MikkTSpace tangents when none are given; writing
    them keeps normal maps consistent across viewers (and the validator quiet).
    """
    p, n, uv = (np.asarray(x, dtype=np.float64) for x in (p, n, uv))
    # A normal map's +Y is "up" in the image, i.e. towards decreasing glTF v: measure the
    # bitangent along the image's up direction.
    uv = uv * np.array([1.0, -1.0])
    e1, e2 = p[triangles[:, 1]] - p[triangles[:, 0]], p[triangles[:, 2]] - p[triangles[:, 0]]
    d1, d2 = uv[triangles[:, 1]] - uv[triangles[:, 0]], uv[triangles[:, 2]] - uv[triangles[:, 0]]
    r = d1[:, 0] * d2[:, 1] - d2[:, 0] * d1[:, 1]
    r = np.where(np.abs(r) > 1e-20, 1.0 / np.where(r == 0, 1, r), 0.0)[:, None]
    t_face = (e1 * d2[:, 1:2] - e2 * d1[:, 1:2]) * r
    b_face = (e2 * d1[:, 0:1] - e1 * d2[:, 0:1]) * r
    t, b = np.zeros_like(p), np.zeros_like(p)
    for k in range(3):
        np.add.at(t, triangles[:, k], t_face)
        np.add.at(b, triangles[:, k], b_face)
    t -= n * np.sum(n * t, axis=1, keepdims=True)
    length = np.linalg.norm(t, axis=1, keepdims=True)
    fallback = np.cross(n, [[0.0, 0.0, 1.0]])  # any unit vector orthogonal to the normal
    fallback[np.linalg.norm(fallback, axis=1) < 1e-6] = (1.0, 0.0, 0.0)
    t = np.where(length > 1e-12, t / np.maximum(length, 1e-300), fallback)
    t /= np.linalg.norm(t, axis=1, keepdims=True)
    w = np.where(np.sum(np.cross(n, t) * b, axis=1) < 0.0, -1.0, 1.0)
    return np.concatenate([t, w[:, None]], axis=1).astype(np.float32)


def _to_gltf(v: np.ndarray) -> np.ndarray:
    """(N, 3) Avatar (x, y, z) -> float32 glTF (x, z, -y); exact, no rounding."""
    v = np.asarray(v, dtype=np.float32)
    return np.stack([v[:, 0], v[:, 2], -v[:, 1]], axis=1)


def _from_gltf(v: np.ndarray) -> np.ndarray:
    """Inverse of ``_to_gltf``."""
    v = np.asarray(v, dtype=np.float32)
    return np.stack([v[:, 0], -v[:, 2], v[:, 1]], axis=1)


def _unit(n: np.ndarray) -> np.ndarray:
    """Normalise in float32 precision (the validator checks unit length of NORMAL)."""
    length = np.linalg.norm(n.astype(np.float64), axis=1, keepdims=True)
    out = n / np.where(length > 1e-12, length, 1.0)
    out[length[:, 0] <= 1e-12] = (0.0, 1.0, 0.0)  # degenerate: any unit vector is valid
    return out.astype(np.float32)


# ---------------------------------------------------------------------------- reading


def read(path: str | os.PathLike[str]) -> GltfFile:
    """Read a glTF/GLB file written by Avatar (or any file using the same features).

    Returns parts in Avatar's frame (triangles; UVs per corner; vertices merged back through
    ``_AVATAR_VERTEX`` when present), the skin's skeleton, every animation and the morph
    weights keyed in them (by part name).
    Raises FormatError on unreadable files.
    """
    path = Path(path)
    try:
        gltf = g.GLTF2().load(str(path))
    except Exception as exc:  # pygltflib raises assorted errors on bad JSON/GLB
        raise FormatError(path, 0, f"cannot parse glTF: {exc}") from None
    if gltf is None:
        raise FormatError(path, 0, "cannot parse glTF")
    try:
        buffers = [acc.buffer_bytes(gltf, i, path.parent) for i in range(len(gltf.buffers))]
        skeleton, joint_nodes = gltf_skin.read_skeleton(gltf, buffers)
        parts = [_read_part(gltf, buffers, node, joint_nodes) for node in _scene_mesh_nodes(gltf)]
        animations = gltf_skin.read_animations(gltf, buffers, skeleton, joint_nodes)
        keyed = gltf_morphs.read_weights(gltf, buffers)
    except (IndexError, KeyError, ValueError, TypeError, OSError) as exc:
        raise FormatError(path, 0, f"invalid glTF content: {exc}") from None
    morph_weights = {
        clip: {_node_name(gltf, n): w for n, w in by_node.items()}
        for clip, by_node in keyed.items()
    }
    return GltfFile([p for group in parts for p in group], skeleton, animations, morph_weights)


def _node_name(gltf: g.GLTF2, n: int) -> str:
    """The part name ``_read_part`` gives a mesh node's (first) primitive."""
    node = gltf.nodes[n]
    return node.name or gltf.meshes[node.mesh].name or f"mesh_{node.mesh}"


def _scene_mesh_nodes(gltf: g.GLTF2) -> list[int]:
    """Indices of nodes that hold a mesh, in node order."""
    return [i for i, n in enumerate(gltf.nodes) if n.mesh is not None]


def _read_part(gltf, buffers, node_index: int, joint_nodes: list[int]) -> list[MeshPart]:
    """The primitives of one mesh node as parts (one part per primitive)."""
    node = gltf.nodes[node_index]
    gmesh = gltf.meshes[node.mesh]
    names = (gmesh.extras or {}).get("targetNames", [])
    skin_joints = gltf.skins[node.skin].joints if node.skin is not None else []
    parts = []
    for k, prim in enumerate(gmesh.primitives):
        name = node.name or gmesh.name or f"mesh_{node.mesh}"
        parts.append(
            _read_primitive(
                gltf,
                buffers,
                prim,
                name if k == 0 else f"{name}.{k}",
                names,
                skin_joints,
                joint_nodes,
            )
        )
    return parts


def _read_primitive(gltf, buffers, prim, name, target_names, skin_joints, joint_nodes):
    """One triangle primitive -> MeshPart in Avatar's frame."""
    attr = prim.attributes
    get = lambda key: acc.unpack(gltf, buffers, getattr(attr, key))  # noqa: E731
    has = lambda key: getattr(attr, key, None) is not None  # noqa: E731
    positions = _from_gltf(get("POSITION"))
    count = len(positions)
    corners = (
        acc.unpack(gltf, buffers, prim.indices).astype(np.int64)
        if prim.indices is not None
        else np.arange(count)
    )
    source = get(VERTEX_ID).astype(np.int64) if has(VERTEX_ID) else np.arange(count)
    size = int(source.max()) + 1 if count else 0

    def merge(values: np.ndarray) -> np.ndarray:
        out = np.zeros((size,) + values.shape[1:], dtype=values.dtype)
        out[source] = values
        return out

    uvs = None
    if has("TEXCOORD_0"):
        uvs = get("TEXCOORD_0").astype(np.float32)
        uvs[:, 1] = 1.0 - uvs[:, 1]
    mesh = Mesh(
        vertices=merge(positions),
        faces=source[corners].reshape(-1, 3).astype(np.int32),
        uvs=uvs,
        face_uvs=None if uvs is None else corners.reshape(-1, 3).astype(np.int32),
    )
    skin = _read_skin(gltf, buffers, attr, skin_joints, joint_nodes, merge)
    morphs = {
        (target_names[i] if i < len(target_names) else f"target_{i}"): merge(
            _from_gltf(acc.unpack(gltf, buffers, t["POSITION"]))
        )
        for i, t in enumerate(prim.targets or [])
    }
    normals = merge(_from_gltf(get("NORMAL"))) if has("NORMAL") else None
    material = gltf_materials.read_material(gltf, buffers, prim.material)
    return MeshPart(name, mesh, material, skin, morphs, normals)


def _read_skin(gltf, buffers, attr, skin_joints, joint_nodes, merge):
    """JOINTS_n/WEIGHTS_n -> (indices, weights) into the skeleton's joint order, or None."""
    sets = [n for n in range(8) if getattr(attr, f"JOINTS_{n}", None) is not None]
    if not sets or not skin_joints:
        return None
    to_skeleton = np.array([joint_nodes.index(n) for n in skin_joints])
    idx = np.concatenate([acc.unpack(gltf, buffers, getattr(attr, f"JOINTS_{n}")) for n in sets], 1)
    w = np.concatenate([acc.unpack(gltf, buffers, getattr(attr, f"WEIGHTS_{n}")) for n in sets], 1)
    if w.dtype != np.float32:  # normalised unsigned integers
        w = w.astype(np.float32) / np.float32(np.iinfo(w.dtype).max)
    return merge(to_skeleton[idx.astype(np.int64)].astype(np.int32)), merge(w.astype(np.float32))
