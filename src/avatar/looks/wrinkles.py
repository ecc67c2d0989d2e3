"""Skin relief in the base mesh's UV space: pores everywhere, wrinkles that come with age.

Where a wrinkle goes is a question about the face, not the texture, so the face's pixels
are first given their place on the default body (``uv_positions``: each pixel of the UV map
-> the 3D point of the default body it covers, found by rasterising the head's triangles).
Wrinkles are then drawn as functions of that position relative to the eyes: horizontal
forehead lines, frown lines between the brows, crow's feet fanning from the outer eye
corners, lines under the eyes, nasolabial folds, marionette lines, lines on the upper lip and
rings round the neck. Their depth grows with the age macro (none before ~30 years, full at
90). ``relief`` returns a height field in millimetres; ``normal_map`` turns it into a
tangent-space normal map (+Y up, as ``avatar.material`` wants).

The layout depends only on the base mesh's UVs, never on the body shape, so it is computed
once per size and cached on disk (``assets.cache_root()``).
"""

from __future__ import annotations

import functools
import logging

import numpy as np

from avatar.body import assets

log = logging.getLogger(__name__)

HEAD_BELOW_EYES = 0.24  # m: the head and neck, the part of the skin that wrinkles here
# Millimetres per pixel of the face in a 1024 px skin map (the face spans ~360 px of it).
FACE_MM_PER_PIXEL_1024 = 0.55


def age_amount(age: float) -> float:
    """How far wrinkles have come, 0..1, from MakeHuman's age macro (0.5 = 25 years,
    1 = 90 years): none until ~30 years, then growing to full depth at 90."""
    return float(np.clip((age - 0.56) / 0.44, 0.0, 1.0) ** 1.2)


# ---------------------------------------------------------------------------- layout


def uv_positions(size: int) -> np.ndarray:
    """(size, size, 3) float32: per pixel of the skin's UV map, the point of the default
    body (metres, relative to the midpoint between the eyes: x left of the body, y back,
    z up) that the pixel covers; NaN where no head or neck triangle lies. Cached."""
    return _positions(int(size))


@functools.lru_cache(maxsize=2)
def _positions(size: int) -> np.ndarray:
    from avatar.body.model import BodyModel  # the model loads once per process anyway
    from avatar.body.shaped import default_vertices

    model = BodyModel.shared()
    cache = assets.cache_root() / "skin" / f"uv-positions-v1-{size}.npy"
    if cache.is_file():
        try:
            out = np.load(cache).astype(np.float32)
            if out.shape == (size, size, 3):
                return out
        except (OSError, ValueError):
            log.warning("ignoring unreadable skin layout cache %s", cache)
    base = model.base
    v = default_vertices(model).astype(np.float64)
    eyes = [v[np.unique(base.faces[base.face_groups[g]])].mean(0)
            for g in ("helper-l-eye", "helper-r-eye")]  # fmt: skip
    centre = (eyes[0] + eyes[1]) / 2
    rows = base.face_groups["body"]
    assert base.uvs is not None and base.face_uvs is not None  # base.obj has one UV set
    quads, quad_uvs = base.faces[rows], base.face_uvs[rows]
    head = v[quads].mean(axis=1)[:, 2] > centre[2] - HEAD_BELOW_EYES
    out = rasterise(base.uvs[quad_uvs[head]], v[quads[head]] - centre, size)
    try:
        cache.parent.mkdir(parents=True, exist_ok=True)
        tmp = cache.with_suffix(".tmp.npy")
        np.save(tmp, out.astype(np.float16))
        tmp.replace(cache)  # atomic for parallel workers
    except OSError as exc:
        log.warning("cannot cache the skin layout in %s: %s", cache, exc)
    return out


def rasterise(uvs: np.ndarray, values: np.ndarray, size: int) -> np.ndarray:
    """Draw quads into UV space: (Q, 4, 2) corner UVs and (Q, 4, C) corner values ->
    (size, size, C) float32 image (row 0 = v 1) of the values interpolated over each quad's
    two triangles; NaN where nothing is drawn. Vectorised per bucket of triangle size."""
    tri_uv = np.concatenate([uvs[:, [0, 1, 2]], uvs[:, [0, 2, 3]]])
    tri_val = np.concatenate([values[:, [0, 1, 2]], values[:, [0, 2, 3]]])
    pix = np.stack([tri_uv[..., 0] * size, (1.0 - tri_uv[..., 1]) * size], -1)  # (T, 3, 2)
    out = np.full((size, size, values.shape[-1]), np.nan, np.float32)
    lo = np.floor(pix.min(axis=1)).astype(int)
    extent = np.ceil(pix.max(axis=1)).astype(int) - lo + 1
    span = extent.max(axis=1)
    for k in (4, 8, 16, 32, 64, 128):
        pick = (span <= k) & (span > k // 2) if k > 4 else span <= k
        if k == 128:
            pick = span > 64
        if not pick.any():
            continue
        _draw(out, pix[pick], tri_val[pick], lo[pick], max(k, int(span[pick].max())))
    return out


def _draw(out, pix, val, lo, k: int) -> None:
    """Fill the pixels whose centres lie in each triangle (T, 3, 2) with its barycentric
    blend of ``val`` (T, 3, C); every triangle's pixels lie in a k x k box from ``lo``."""
    size = out.shape[0]
    oy, ox = np.mgrid[0:k, 0:k]
    for chunk in range(0, len(pix), max(1, 400_000 // (k * k))):
        p, v, o = (a[chunk : chunk + max(1, 400_000 // (k * k))] for a in (pix, val, lo))
        cx = o[:, 0, None, None] + ox[None] + 0.5  # (T, k, k) pixel centres
        cy = o[:, 1, None, None] + oy[None] + 0.5
        a, b, c = p[:, 0], p[:, 1], p[:, 2]
        den = (b[:, 1] - c[:, 1]) * (a[:, 0] - c[:, 0]) + (c[:, 0] - b[:, 0]) * (a[:, 1] - c[:, 1])
        ok = np.abs(den) > 1e-12
        den = np.where(ok, den, 1.0)[:, None, None]
        w0 = ((b[:, 1] - c[:, 1])[:, None, None] * (cx - c[:, 0, None, None])
              + (c[:, 0] - b[:, 0])[:, None, None] * (cy - c[:, 1, None, None])) / den
        w1 = ((c[:, 1] - a[:, 1])[:, None, None] * (cx - c[:, 0, None, None])
              + (a[:, 0] - c[:, 0])[:, None, None] * (cy - c[:, 1, None, None])) / den
        w2 = 1.0 - w0 - w1
        inside = (w0 >= -1e-4) & (w1 >= -1e-4) & (w2 >= -1e-4) & ok[:, None, None]
        inside &= (cx >= 0) & (cx < size) & (cy >= 0) & (cy < size)
        t, i, j = np.nonzero(inside)
        blend = (w0[t, i, j, None] * v[t, 0] + w1[t, i, j, None] * v[t, 1]
                 + w2[t, i, j, None] * v[t, 2])  # fmt: skip
        out[(cy[t, i, j]).astype(int), (cx[t, i, j]).astype(int)] = blend


# ---------------------------------------------------------------------------- relief


def _smooth(x: np.ndarray, a: float, b: float) -> np.ndarray:
    """0 below a, 1 above b, smoothstep between (b < a flips it)."""
    t = np.clip((x - a) / (b - a), 0.0, 1.0)
    return t * t * (3 - 2 * t)


def _band(x: np.ndarray, a: float, b: float, soft: float) -> np.ndarray:
    """1 inside [a, b], fading to 0 over ``soft`` outside it."""
    return _smooth(x, a - soft, a) * _smooth(x, b + soft, b)


def _grooves(phase: np.ndarray, sharpness: float = 6.0) -> np.ndarray:
    """Narrow valleys (1 at the groove, 0 between) once per unit of ``phase``."""
    return ((0.5 + 0.5 * np.cos(2 * np.pi * phase)) ** sharpness).astype(np.float32)


def _segment_distance(x, z, a, b) -> np.ndarray:
    """Distance in the (x, z) plane from points to the segment a-b (metres)."""
    ax, az = a
    dx, dz = b[0] - ax, b[1] - az
    t = np.clip(((x - ax) * dx + (z - az) * dz) / (dx * dx + dz * dz), 0, 1)
    return np.hypot(x - ax - t * dx, z - az - t * dz)


def wrinkle_depth(positions: np.ndarray) -> np.ndarray:
    """(H, W) float32 wrinkle depth in millimetres (>= 0, deepest ~0.35 mm) at full age
    for ``uv_positions``; 0 where positions are NaN. Deterministic."""
    out = np.zeros(positions.shape[:2], np.float32)
    drawn = np.isfinite(positions[..., 0])
    out[drawn] = _depth(positions[drawn].astype(np.float32))  # a quarter of the pixels
    return out


def _depth(p: np.ndarray) -> np.ndarray:
    """(N,) wrinkle depth (mm) at (N, 3) positions relative to the eyes' midpoint."""
    x, y, z = np.abs(p[:, 0]), p[:, 1], p[:, 2]
    front = _smooth(y, 0.05, 0.02)  # the face, not the sides and back of the head
    wobble = 0.0012 * np.sin(x * 120.0 + 1.7) + 0.0004 * np.sin(x * 330.0)
    depth = np.zeros(x.shape, np.float32)
    # Forehead: horizontal lines, broken and wavy, deepest above the brows' middle.
    fore = _band(z, 0.025, 0.062, 0.008) * _smooth(x, 0.055, 0.035) * front
    depth += 0.3 * fore * _grooves((z + wobble) / 0.0085) * (0.6 + 0.4 * np.cos(x * 70.0))
    # Frown lines: two short vertical grooves between the brows.
    frown = _band(z, 0.004, 0.03, 0.006) * front
    depth += 0.3 * frown * np.exp(-(((x - 0.0065) / 0.0012) ** 2))
    # Crow's feet: grooves fanning out from each outer eye corner.
    cx, cz = x - 0.041, z + 0.002
    r, theta = np.hypot(cx, cz), np.arctan2(cz, cx)
    crow = _band(r, 0.006, 0.02, 0.006) * (cx > -0.002) * _smooth(np.abs(theta), 1.3, 0.9)
    depth += 0.3 * crow * _grooves(theta / 0.2 + 30.0 * r)
    # Under the eyes: arcs following the lower lid.
    arc = np.hypot((x - 0.029) / 1.5, z)
    under = _band(arc, 0.011, 0.02, 0.004) * (z < 0.0) * _smooth(x, 0.05, 0.04) * front
    depth += 0.18 * under * _grooves(arc / 0.0035)
    # Nasolabial folds (nose wing to mouth corner) and marionette lines (corner to chin).
    naso = _segment_distance(x, z, (0.017, -0.033), (0.03, -0.066))
    depth += 0.35 * np.exp(-((naso / 0.0022) ** 2)) * front
    mario = _segment_distance(x, z, (0.028, -0.062), (0.022, -0.088))
    depth += 0.2 * np.exp(-((mario / 0.002) ** 2)) * front
    # Upper lip: fine vertical lines above the lip.
    lip = _band(z, -0.05, -0.041, 0.003) * _smooth(x, 0.018, 0.012) * front
    depth += 0.12 * lip * _grooves(x / 0.0032 + 0.5 * np.sin(z * 300), 10.0)
    # Neck: rings round its front and sides.
    neck = _band(z, -0.19, -0.12, 0.015) * _smooth(y, 0.06, 0.03)
    depth += 0.25 * neck * _grooves((z + 0.6 * wobble) / 0.014, 4.0)
    # Crepey skin: soft, irregular creases everywhere on the head (sums of slanted waves).
    crepe = np.sin((x * 0.8 + z) * 900.0 + np.sin(y * 700.0)) * np.sin((x - z * 0.6) * 1300.0)
    depth += 0.04 * np.clip(crepe, 0, None) ** 2
    return depth.astype(np.float32)


def normal_map(height_mm: np.ndarray, mm_per_pixel: float) -> np.ndarray:
    """(H, W) height in millimetres (up = out of the skin) -> (H, W, 3) uint8 tangent-space
    normal map, +X along u (columns), +Y along v (up the image), wrapping at the edges."""
    h = height_mm.astype(np.float32)
    du = (np.roll(h, -1, axis=1) - np.roll(h, 1, axis=1)) / (2 * mm_per_pixel)
    dv = (np.roll(h, 1, axis=0) - np.roll(h, -1, axis=0)) / (2 * mm_per_pixel)  # rows go down
    n = np.stack([-du, -dv, np.ones_like(h)], axis=-1)
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    return np.rint((n * 0.5 + 0.5) * 255).astype(np.uint8)
