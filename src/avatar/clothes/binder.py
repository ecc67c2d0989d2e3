"""Bind any garment mesh to the body, MakeClothes-style, so it fits every body afterwards.

For each garment vertex: the closest point on the reference surface (the skin, or a helper
such as ``helper-tights``) gives a triangle and barycentric weights; what is left over is
the offset, divided by the per-axis scale S of the authoring body (MakeHuman's reference
pairs), so ``fit(bind(...), authoring body)`` gives the garment back to float precision.
"""

from __future__ import annotations

import os
import uuid as uuidlib
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

from avatar.body.shaped import Body
from avatar.clothes.binding import Binding, axis_scale, make_binding
from avatar.errors import AvatarError
from avatar.geometry import collision
from avatar.io import mhclo, mhmat, obj
from avatar.mesh import Mesh

# MakeHuman's standard reference pairs (x: hand to hand width, y: front-back, z: height),
# as Avatar axes; the lengths are measured on the authoring body.
SCALE_REFS = np.array([[5399, 11998], [962, 5320], [791, 881]], dtype=np.int32)
MAX_DISTANCE = 0.5  # m: the farthest a garment vertex may be from the authoring body's skin
MIN_GARMENT_SIZE = 0.02  # m: the smallest extent a frame may give a garment (lashes ~0.04)


def bind(
    garment_vertices: np.ndarray,
    body_vertices: np.ndarray,
    body_faces: np.ndarray,
    max_distance: float = MAX_DISTANCE,
) -> Binding:
    """A Binding of N garment vertices to the body they were modelled on.

    garment_vertices: (N, 3) metres, Avatar frame, on the authoring body.
    body_vertices: (V, 3) all base-mesh vertices of the authoring body (19,158 for hm08).
    body_faces: (F, 3|4) the reference surface (skin faces, or a helper's faces).
    max_distance: m; a vertex further than this from the surface cannot be bound.
    Raises AvatarError naming the first unbindable vertex; nothing is half-built.
    """
    x = np.asarray(body_vertices, dtype=np.float64)
    p = np.asarray(garment_vertices, dtype=np.float64)
    if p.ndim != 2 or p.shape[1] != 3 or len(p) == 0 or not np.all(np.isfinite(p)):
        raise AvatarError("a garment needs (N, 3) finite vertex positions")
    surface = collision.body_surface(body_faces)
    used = np.unique(surface.triangles)
    tree = cKDTree(x[used])
    _, nearest = tree.query(p, k=4)
    cand = surface.rings[used[nearest]].reshape(len(p), -1)
    tri = surface.triangles[cand]
    corners = x[tri]
    pc = p[:, None, :]
    bary = collision.closest_on_triangles(pc, *(corners[..., i, :] for i in range(3)))
    close = np.einsum("ncj,ncjd->ncd", bary, corners)
    dist = np.linalg.norm(pc - close, axis=-1)
    best = np.argmin(dist, axis=1)
    rows = np.arange(len(p))
    far = dist[rows, best] > max_distance
    if far.any():
        i = int(np.flatnonzero(far)[0])
        raise AvatarError(
            f"garment vertex {i} is {dist[i, best[i]]:.2f} m from the body (limit "
            f"{max_distance} m): was it modelled on this body, in the frame given?"
        )
    weights = bary[rows, best]
    indices = tri[rows, best]
    refs, lengths = None, None
    if len(x) > SCALE_REFS.max():  # an hm08 body: offsets scale with it as in MakeHuman
        refs = SCALE_REFS
        lengths = np.abs(x[refs[:, 0], [0, 1, 2]] - x[refs[:, 1], [0, 1, 2]])
    binding = make_binding(indices, weights, np.zeros_like(p), refs, lengths)
    offsets = (p - close[rows, best]) / axis_scale(binding, x)
    return make_binding(indices, weights, offsets, refs, lengths)


def save(
    folder: str | os.PathLike[str],
    name: str,
    mesh: Mesh,
    binding: Binding,
    material: mhmat.MaterialFile | None = None,
    z_depth: int = 50,
    tags: tuple[str, ...] = (),
    delete_verts: np.ndarray | None = None,
) -> Path:
    """Write ``name.mhclo`` + ``name.obj`` (+ ``name.mhmat``) into folder; returns the .mhclo.

    The OBJ holds the garment as authored (MakeHuman units), as MakeClothes writes it.
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    obj.write(folder / f"{name}.obj", mesh, axes=obj.MAKEHUMAN)
    if material is None:
        material = mhmat.MaterialFile((("name", name), ("diffuseColor", "0.8 0.8 0.8")))
    mhmat.write(folder / f"{name}.mhmat", material)
    proxy = mhclo.ProxyFile(
        name=name,
        binding=binding,
        uuid=str(uuidlib.uuid5(uuidlib.NAMESPACE_URL, f"avatar:{name}")),
        obj_file=f"{name}.obj",
        material=f"{name}.mhmat",
        z_depth=z_depth,
        tags=tuple(t.lower() for t in tags),
        delete_verts=np.zeros(0, np.int32) if delete_verts is None else delete_verts,
        meta=(("author", "avatar"),),
    )
    path = folder / f"{name}.mhclo"
    mhclo.write(path, proxy)
    return path


# Frames a garment OBJ may come in: name -> (metres per unit, Y-up). Y-up files (MakeHuman,
# Blender's default OBJ export) face +Z; Avatar's frame is Z-up metres facing -Y.
FRAMES = {"avatar": (1.0, False), "y-up": (1.0, True), "makehuman": (0.1, True),
          "y-up-cm": (0.01, True), "z-up-cm": (0.01, False)}  # fmt: skip


def in_body_frame(
    vertices: np.ndarray, body_vertices: np.ndarray, frame: str = "auto"
) -> tuple[np.ndarray, str]:
    """(N, 3) garment vertices in Avatar's frame, and the frame they came in.

    frame: a ``FRAMES`` name, or "auto": of the frames giving the mesh at least garment
    size (``MIN_GARMENT_SIZE``), the one that puts it closest to the body (median distance
    to its nearest body vertex).
    """
    v = np.asarray(vertices, dtype=np.float64)
    if frame != "auto":
        if frame not in FRAMES:
            raise AvatarError(f"unknown frame {frame!r}; one of: auto, {', '.join(FRAMES)}")
        scale, y_up = FRAMES[frame]
        out = np.stack([v[:, 0], -v[:, 2], v[:, 1]], axis=1) if y_up else v
        return out * scale, frame
    if v.ndim != 2 or v.shape[1] != 3 or len(v) == 0 or not np.all(np.isfinite(v)):
        raise AvatarError("a garment needs (N, 3) finite vertex positions")
    tree = cKDTree(np.asarray(body_vertices, dtype=np.float64))
    tries = {name: in_body_frame(v, body_vertices, name)[0] for name in FRAMES}
    # A reading that makes the mesh smaller than any garment is not a candidate: a mesh far
    # from the body read in centimetres shrinks to a speck that lands close to the body.
    sizes = {name: float(np.ptp(p, axis=0).max()) for name, p in tries.items()}
    plausible = [n for n in FRAMES if sizes[n] >= MIN_GARMENT_SIZE] or list(FRAMES)
    gap = {name: float(np.median(tree.query(tries[name])[0])) for name in plausible}
    best = min(gap, key=gap.__getitem__)
    return tries[best], best


def bind_obj(
    path: str | os.PathLike[str],
    body: Body,
    folder: str | os.PathLike[str],
    name: str | None = None,
    frame: str = "auto",
    tags: tuple[str, ...] = (),
    z_depth: int = 50,
    texture: str | os.PathLike[str] | None = None,
) -> Path:
    """Bind a garment OBJ modelled on ``body`` (e.g. ``Human.body``) and save it in folder
    as ``name.mhclo`` + ``.obj`` + ``.mhmat`` (with ``texture`` copied beside them); from
    then on it fits every body. Returns the .mhclo path; on any error nothing is written."""
    import shutil

    path = Path(path)
    name = name or path.stem
    mesh = obj.read(path)
    authored = np.asarray(body.vertices, dtype=np.float64)
    vertices, found = in_body_frame(mesh.vertices, authored, frame)
    base = body.model.base
    try:
        binding = bind(vertices, authored, base.faces[base.face_groups["body"]])
    except AvatarError as exc:
        raise AvatarError(f"{path}: {exc} (read as frame {found!r})") from None
    entries = [("name", name), ("diffuseColor", "0.8 0.8 0.8")]
    if texture is not None and not Path(texture).is_file():
        raise AvatarError(f"{texture}: texture file not found")
    if texture is not None:
        entries.append(("diffuseTexture", f"{name}{Path(texture).suffix.lower()}"))
    out = save(folder, name, mesh.with_vertices(vertices.astype(np.float32)), binding,
               mhmat.MaterialFile(tuple(entries)), z_depth, tags)  # fmt: skip
    if texture is not None:
        shutil.copyfile(texture, Path(folder) / entries[-1][1])
    return out
