"""A garment's picture for a library grid, drawn with numpy (no renderer needed): the item
as worn by the default body, seen from the front, in its own colours and cut-outs.

    image = thumbnail.garment_picture("tshirt", size=128)   # (128, 128, 4) uint8 RGBA
    path = thumbnail.write_picture("tshirt")                # a cached PNG (Blender's grid)

A fabric swatch told a T-shirt from a tank top only by its name; the picture shows the
cut (sleeves, hood, hem length, a brim), the colour and, for hair and brows, the style.
Every face is sampled on a grid fine enough for the picture (``_samples``), each sample
takes its colour from the item's colour texture at its UV (an alpha-cut item drops the
samples under its cutoff, so hair shows strands), shaded by its face's normal under a key
light; samples go into a z-buffer at twice the size and are averaged down. The body is
drawn as a half-transparent grey ghost, for scale and so that the cloth's inside does not
show through its openings; the framing is the item's own extent (a head for hair).
Footwear is seen from the wearer's left, in profile, where a shoe reads as a shoe; hair
three-quarters from the front, where a ponytail or a bun shows.
"""

from __future__ import annotations

import functools
import hashlib
import os
from pathlib import Path

import numpy as np

from avatar.body.model import BodyModel
from avatar.body.shaped import PART_GROUPS, Body, default_body
from avatar.clothes.fitting import FittedGarment
from avatar.geometry.splat import splat
from avatar.material import Material

_LIGHT = np.array([-0.45, -0.75, 0.5]) / np.linalg.norm([-0.45, -0.75, 0.5])
_AMBIENT = 0.4
_BODY_GREY = 0.30  # the mannequin's linear grey, drawn at _BODY_ALPHA (a ghost for scale)
_BODY_ALPHA = 0.5
_FOOT_HIGH = 0.3  # m above the soles: an uncategorised item no higher is footwear
_FOOTWEAR_TAGS = {"shoes", "shoe", "boots", "sneakers", "sandals", "footwear"}
_SUPER = 2  # supersampling factor
_MARGIN = 1.12  # the frame's span over the item's larger extent
_MIN_SPAN = 0.11  # m: brows and lashes are framed on the eyes, not on a few millimetres


SIZE = 128  # px: the Dress panel's grid shows them at about 96 px


def picture_path(item: str, size: int = SIZE) -> Path:
    """Where the cached picture of library ``item`` (a built-in's name or a garment file's
    path) lives: under Avatar's cache folder, named for this code's version
    (``disk_cache.code_fingerprint``), so a changed garment gets a new picture; a user
    garment's name also carries its folder's state, so an edited asset does too."""
    from avatar.body.assets import cache_root

    stem, version = _key(item), _code()
    if stem != item:
        version += _folder_state(Path(item))
    return cache_root() / "thumbnails" / f"{stem}-{size}-{version}.png"


def _key(item: str) -> str:
    """A picture's file-name stem: a built-in's name, or a garment file's stem and a digest
    of its path (two folders' ``shirt.mhclo`` are two pictures)."""
    if os.sep not in item and "/" not in item and not item.lower().endswith(".mhclo"):
        return item
    path = Path(item).resolve()
    digest = hashlib.sha256(str(path).encode()).hexdigest()[:8]
    return f"user-{path.stem}-{digest}"


def _folder_state(garment: Path) -> str:
    """A digest of the names, sizes and times of the files beside a garment file (its mesh,
    textures and material): what, changed, changes its picture."""
    h = hashlib.sha256()
    try:
        for path in sorted(garment.resolve().parent.iterdir()):
            if path.is_file():
                stat = path.stat()
                h.update(f"{path.name}|{stat.st_size}|{stat.st_mtime_ns}".encode())
    except OSError:  # unreadable: the picture is drawn again next time
        h.update(b"?")
    return h.hexdigest()[:6]


@functools.cache
def _code() -> str:
    """This code's version (hashing the sources takes a while; they do not change)."""
    from avatar.clothes.disk_cache import code_fingerprint

    return code_fingerprint()[:12]


def write_picture(name: str, size: int = SIZE, path: str | os.PathLike[str] | None = None,
                  body: Body | None = None, folders=()) -> Path:  # fmt: skip
    """Draw item ``name``'s picture and write it as a PNG (atomically) at ``path`` (default
    ``picture_path``, where older code's pictures of the item are removed); returns the
    path."""
    from avatar.io import png

    out = Path(path) if path is not None else picture_path(name, size)
    image = garment_picture(name, size, body, folders)
    out.parent.mkdir(parents=True, exist_ok=True)
    png.write(out, image)
    if path is None:  # older code's (or files') pictures of this item are not read again
        for old in out.parent.glob(f"{_key(name)}-{size}-*.png"):
            if old != out:
                old.unlink(missing_ok=True)
    return out


def draw_missing(names: list[str] | None = None, size: int = SIZE) -> list[Path]:
    """Draw the cached pictures of ``names`` (built-in names or garment file paths; default:
    every built-in) that are missing; returns the paths written. ``python -m
    avatar.clothes.thumbnail [ITEM...]`` runs it: the Blender extension starts it as a
    separate process, which needs none of the CLI's extras."""
    from avatar.clothes import library

    names = names if names is not None else [e.name for e in library.builtin_entries()]
    return [write_picture(name, size) for name in names if not picture_path(name, size).is_file()]


def garment_picture(name: str, size: int = SIZE, body: Body | None = None,
                    folders=()) -> np.ndarray:  # fmt: skip
    """(size, size, 4) uint8 picture of the library item ``name`` (found also in asset
    ``folders``) worn by ``body`` (default: the default body, all macros 0.5). Raises as
    ``library.load_garment`` for a bad name."""
    from avatar.clothes import library

    body = body or default_body(BodyModel.shared())
    garment = library.load_garment(name, folders, texture_size=256, model=body.model)
    (fitted,) = library.dress(body, [garment])
    return picture(fitted, body, size)


def picture(fitted: FittedGarment, body, size: int = 128) -> np.ndarray:
    """(size, size, 4) uint8 RGBA picture of ``fitted`` on ``body`` (its rest pose), framed
    on the item. Row 0 is the top of the picture; the background is transparent."""
    skin = body.vertices.astype(np.float64)
    item = fitted.mesh.vertices.astype(np.float64)
    yaw = _yaw(fitted, item[:, 2].max() - skin[:, 2].min())
    view = _view(yaw)
    seen = item @ view.T
    framed = seen[item[:, 0] > 0] if yaw == 90 else seen  # the left shoe: it hides the right
    low, high = framed[:, [0, 2]].min(axis=0), framed[:, [0, 2]].max(axis=0)
    span = max(float((high - low).max()) * _MARGIN, _MIN_SPAN)
    corner = (low + high) / 2 - span / 2  # (x, z) of the picture's bottom-left
    pixel = span / (size * _SUPER)
    frame = (corner, span, view)
    points, colours = _item_samples(fitted, pixel, frame)
    body_points, shade, _ = _samples(skin, _skin_quads(body), None, pixel, frame)
    body_colours = np.repeat(shade[:, None], 3, axis=1) * _BODY_GREY
    alpha = np.concatenate([np.ones(len(points)), np.full(len(body_points), _BODY_ALPHA)])
    return _draw(
        np.concatenate([points, body_points]) @ view.T,
        np.concatenate([colours, body_colours]),
        alpha,
        size,
        corner,
        span,
    )


def _yaw(fitted: FittedGarment, top: float) -> int:
    """Degrees the camera turns from the front towards the wearer's left: footwear in
    profile (where a shoe reads as a shoe), hair three-quarters (a ponytail or bun hides
    behind the head from the front), the rest from the front. A MakeHuman garment is
    only "clothes": its tags or its height tell footwear."""
    category = fitted.garment.category
    if category == "footwear" or _FOOTWEAR_TAGS & set(fitted.garment.tags):
        return 90
    if category in ("", "clothes") and top < _FOOT_HIGH:
        return 90
    return 55 if category == "hair" else 0


def _view(yaw: int) -> np.ndarray:
    """(3, 3) rows: the picture's right, depth (away from the camera) and up, for a camera
    turned ``yaw`` degrees from the front (-Y) towards the wearer's left (+X); at 90 the
    toes (-Y) point left."""
    a = np.radians(yaw)
    return np.array([[np.cos(a), np.sin(a), 0.0], [-np.sin(a), np.cos(a), 0.0],
                     [0.0, 0.0, 1.0]])  # fmt: skip


def _skin_quads(body) -> np.ndarray:
    base = body.model.base
    return base.faces[np.concatenate([base.face_groups[g] for g in PART_GROUPS["body"]])]


def _item_samples(fitted: FittedGarment, pixel: float,
                  frame: tuple) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """(N, 3) points on the item and (N, 3) their linear colours, cut-outs dropped."""
    mesh = fitted.mesh
    faces = mesh.faces if mesh.faces.shape[1] == 4 else mesh.faces[:, [0, 1, 2, 2]]
    face_uvs = mesh.face_uvs
    if face_uvs is not None and face_uvs.shape[1] == 3:
        face_uvs = face_uvs[:, [0, 1, 2, 2]]
    uv_corners = mesh.uvs[face_uvs] if face_uvs is not None and mesh.uvs is not None else None
    points, shade, uvs = _samples(mesh.vertices.astype(np.float64), faces, uv_corners, pixel,
                                  frame)  # fmt: skip
    colour, alpha = _texture(fitted.material, uvs, len(points))
    keep = alpha >= _cutoff(fitted.material)
    return points[keep], colour[keep] * shade[keep, None]


def _samples(vertices: np.ndarray, quads: np.ndarray, uv_corners: np.ndarray | None,
             pixel: float, frame: tuple) -> tuple:  # fmt: skip
    """Points on a grid over every quad (F, 4) (a triangle repeats its last corner) seen in
    ``frame`` ((x, z) corner, span, view rows), dense enough that neighbours are under a
    pixel apart; (N,) their face's brightness (the side facing the camera lit); (N, 2)
    their UVs when ``uv_corners`` (F, 4, 2) is given. Quads outside the frame are skipped
    (most of the body, for a head's or a foot's picture)."""
    corner, span, view = frame
    seen = (vertices @ view.T)[:, [0, 2]][quads]  # (F, 4, 2) on the picture's plane
    inside = np.all((seen.max(axis=1) >= corner) & (seen.min(axis=1) <= corner + span), axis=1)
    quads = quads[inside]
    if uv_corners is not None:
        uv_corners = uv_corners[inside]
    if len(quads) == 0:
        return np.zeros((0, 3)), np.zeros(0), None if uv_corners is None else np.zeros((0, 2))
    away = view[1]
    corners = vertices[quads]
    normal = np.cross(corners[:, 2] - corners[:, 0], corners[:, 3] - corners[:, 1])
    normal /= np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), 1e-12)
    normal[normal @ away > 0] *= -1  # light the side that faces the camera
    brightness = _AMBIENT + (1 - _AMBIENT) * np.clip(normal @ _LIGHT, 0.0, 1.0)
    # Steps along each of the quad's two directions by its longer side in that direction:
    # a hair card 2 cm long and 1 mm wide needs many samples along it, few across.
    edge = np.linalg.norm(corners - np.roll(corners, -1, axis=1), axis=2)  # ab, bc, cd, da
    along = np.maximum(edge[:, 0], edge[:, 2])
    across = np.maximum(edge[:, 1], edge[:, 3])
    steps = np.clip(np.ceil(np.stack([along, across], 1) / pixel * 1.5), 1, 64).astype(int)
    points, shade, uvs = [], [], []
    pairs, group = np.unique(steps, axis=0, return_inverse=True)
    for k, (n, m) in enumerate(pairs):
        rows = np.flatnonzero(group.ravel() == k)
        s, t = np.meshgrid(np.linspace(0, 1, n + 1), np.linspace(0, 1, m + 1))
        w = _bilinear(s.ravel(), t.ravel())  # (S, 4)
        points.append(np.einsum("sk,fkd->fsd", w, corners[rows]).reshape(-1, 3))
        shade.append(np.repeat(brightness[rows], len(w)))
        if uv_corners is not None:
            uvs.append(np.einsum("sk,fkd->fsd", w, uv_corners[rows]).reshape(-1, 2))
    return (np.concatenate(points), np.concatenate(shade),
            np.concatenate(uvs) if uv_corners is not None else None)  # fmt: skip


def _bilinear(s: np.ndarray, t: np.ndarray) -> np.ndarray:
    """(S, 4) weights of corners a, b, c, d at (s, t) of a quad a-b-c-d."""
    return np.stack([(1 - s) * (1 - t), s * (1 - t), s * t, (1 - s) * t], axis=1)


def _texture(material: Material | None, uvs: np.ndarray | None,
             count: int) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """(N, 3) linear colour and (N,) alpha of the material at ``uvs`` (nearest texel)."""
    factor = np.array(material.base_color if material else (0.8, 0.8, 0.8, 1.0))
    image = material.base_color_texture if material is not None else None
    if image is None or uvs is None:
        return np.tile(factor[:3], (count, 1)), np.full(count, factor[3])
    h, w = image.shape[:2]
    row = np.clip(((1 - uvs[:, 1]) % 1.0 * h).astype(int), 0, h - 1)
    col = np.clip((uvs[:, 0] % 1.0 * w).astype(int), 0, w - 1)
    texel = image.reshape(h, w, -1)[row, col].astype(np.float64) / 255
    colour = _linear(texel[:, :3]) * factor[:3]
    alpha = (texel[:, 3] if texel.shape[1] == 4 else np.ones(count)) * factor[3]
    return colour, alpha


def _cutoff(material: Material | None) -> float:
    if material is None or material.alpha_mode == "OPAQUE":
        return -1.0
    return material.alpha_cutoff if material.alpha_mode == "MASK" else 0.5


def _linear(srgb: np.ndarray) -> np.ndarray:
    return np.where(srgb <= 0.04045, srgb / 12.92, ((srgb + 0.055) / 1.055) ** 2.4)


def _srgb(linear: np.ndarray) -> np.ndarray:
    linear = np.clip(linear, 0.0, 1.0)
    return np.where(linear <= 0.0031308, linear * 12.92, 1.055 * linear ** (1 / 2.4) - 0.055)


def _draw(points: np.ndarray, colours: np.ndarray, alpha: np.ndarray, size: int,
          corner: np.ndarray, span: float) -> np.ndarray:  # fmt: skip
    """Z-buffered splat of ``points`` seen from -Y, the square ``span`` m from ``corner``
    (x, z) filling the picture, into (size, size, 4) uint8 sRGB with alpha."""
    big = size * _SUPER
    scale = big / span
    col = np.floor((points[:, 0] - corner[0]) * scale).astype(np.int64)
    row = np.floor(big - (points[:, 2] - corner[1]) * scale).astype(np.int64)
    rgba = np.concatenate([colours, alpha[:, None]], axis=1)
    out = splat(col, row, points[:, 1], rgba, size, _SUPER)
    out[..., :3] = _srgb(out[..., :3])
    return np.round(out * 255).astype(np.uint8)


def _main(items: list[str]) -> int:
    """Draw the missing pictures of ``items`` (default: every built-in), one at a time, so
    that a broken user garment costs only its own picture (a line on stderr, exit 1)."""
    import sys

    from avatar.clothes import library
    from avatar.errors import AvatarError

    failed = 0
    for item in items or [e.name for e in library.builtin_entries()]:
        try:
            for path in draw_missing([item]):
                sys.stdout.write(f"wrote {path}\n")
        except (AvatarError, OSError) as exc:
            message = str(exc) if item in str(exc) else f"{item}: {exc}"  # names the file
            sys.stderr.write(message.splitlines()[0] + "\n")
            failed = 1
    return failed


if __name__ == "__main__":
    import sys

    sys.exit(_main(sys.argv[1:]))
