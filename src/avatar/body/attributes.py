"""The paper's seven semantic attributes, computed the paper's way.

Each attribute is the first principal component of MakeHuman bodies in which only that
attribute's modifiers vary (uniformly over their ranges; everything else at its default).
Slider units are standard deviations of those sampled bodies along the component: value
``s`` adds ``s * sigma * u`` to the body, ``u`` the unit component over all 19,158 vertices
(helpers included, so joints and clothes follow). Range -3..3; positive means more of the
attribute (the sign makes the component correlate positively with the modifiers' values).

``Avatar2020Basis`` loads the 2020 add-on's own basis files so its bodies can be reproduced.
"""

from __future__ import annotations

import logging
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from avatar.errors import FormatError
from avatar.io.obj import to_avatar_frame

if TYPE_CHECKING:
    from avatar.body.model import BodyModel

log = logging.getLogger(__name__)
SAMPLES = 96
SEED = 2020


@dataclass(frozen=True)
class Attribute:
    """A semantic attribute: the modifiers varied to find it and the body they vary on.

    A modifier name containing ``{s}`` stands for its left and right versions, which vary
    together so the body stays symmetric.
    """

    name: str
    modifiers: tuple[str, ...]
    base: dict[str, float] = field(default_factory=dict)


ATTRIBUTES: tuple[Attribute, ...] = (
    Attribute(
        "breast",
        ("cupsize", "firmness", "breast/breast-volume-vert-down|up", "breast/breast-dist-decr|incr",
         "breast/breast-point-decr|incr"),
        {"gender": 0.0},
    ),
    Attribute(
        "shoulders_fat",
        ("torso/torso-scale-horiz-decr|incr", "torso/torso-scale-depth-decr|incr",
         "torso/torso-vshape-decr|incr", "measure/measure-shoulder-dist-decr|incr",
         "measure/measure-frontchest-dist-decr|incr"),
    ),
    Attribute(
        "limbs_fat",
        ("armslegs/{s}-upperarm-fat-decr|incr", "armslegs/{s}-lowerarm-fat-decr|incr",
         "armslegs/{s}-upperleg-fat-decr|incr", "armslegs/{s}-lowerleg-fat-decr|incr",
         "measure/measure-upperarm-circ-decr|incr", "measure/measure-thigh-circ-decr|incr",
         "measure/measure-calf-circ-decr|incr"),
    ),
    Attribute(
        "hips_fat",
        ("hip/hip-scale-horiz-decr|incr", "hip/hip-scale-depth-decr|incr",
         "measure/measure-hips-circ-decr|incr", "buttocks/buttocks-volume-decr|incr"),
    ),
    Attribute("weight", ("weight",)),
    Attribute("strength", ("muscle",)),
    Attribute(
        "belly",
        ("stomach/stomach-pregnant-decr|incr", "measure/measure-waist-circ-decr|incr",
         "stomach/stomach-navel-in|out"),
    ),
)  # fmt: skip
BY_NAME = {a.name: a for a in ATTRIBUTES}


def _expand(name: str) -> list[str]:
    return [name.format(s=s) for s in ("l", "r")] if "{s}" in name else [name]


def compute_component(model: BodyModel, attr: Attribute, samples: int = SAMPLES) -> np.ndarray:
    """(V, 3) float32 first principal component of ``attr``'s bodies, scaled by its sigma."""
    rng = np.random.default_rng([SEED, ATTRIBUTES.index(attr)])
    groups = [_expand(m) for m in attr.modifiers]
    params = model.parameters
    bodies, drives = [], []
    for _ in range(samples):
        values = dict(attr.base)
        drive = 0.0
        for names in groups:
            p = params[model.canonical(names[0])]
            v = rng.uniform(p.minimum, p.maximum)
            drive += (v - 0.5 * (p.minimum + p.maximum)) / (p.maximum - p.minimum)
            values |= {model.canonical(n): v for n in names}
        bodies.append(model.shape(values).reshape(-1).astype(np.float64))
        drives.append(drive)
    x = np.asarray(bodies)
    x -= x.mean(axis=0)
    _, s, vt = np.linalg.svd(x, full_matrices=False)
    sigma = s[0] / np.sqrt(samples - 1)
    u = vt[0]
    if np.dot(x @ u, np.asarray(drives) - np.mean(drives)) < 0:
        u = -u
    explained = s[0] ** 2 / np.sum(s**2)
    log.info("attribute %s: sigma %.4f m, explains %.1f%%", attr.name, sigma, 100 * explained)
    return (u * sigma).reshape(-1, 3).astype(np.float32)


def basis(model: BodyModel) -> dict[str, np.ndarray]:
    """Every attribute's scaled component (name -> (V, 3)), cached beside the compiled assets."""
    if model._attributes:
        return model._attributes
    path = model.assets.folder / f"attributes-{SAMPLES}-{SEED}.npz"
    if path.is_file():
        with np.load(path) as data:
            model._attributes.update({k: data[k] for k in data.files})
    if set(model._attributes) != set(BY_NAME):
        comps = {a.name: compute_component(model, a) for a in ATTRIBUTES}
        tmp = path.with_name(path.name + ".tmp.npz")
        np.savez(tmp, **comps)
        os.replace(tmp, path)
        model._attributes.update(comps)
    return model._attributes


def attribute_displacement(model: BodyModel, values: dict[str, float]) -> np.ndarray:
    """(V, 3) float32 displacement of the attribute sliders ``{name: value}``."""
    b = basis(model)
    out = np.zeros_like(model.base.vertices)
    for name, v in values.items():
        out += np.float32(v) * b[name]
    return out


# --------------------------------------------------------------------- the 2020 add-on's basis

# slider -> (basis part, sign, minimum, maximum), as the 2020 add-on exposed them.
AVATAR2020_SLIDERS = {
    "breast": ("breast", 1.0, 0.0, 1.0),
    "shoulders_fat": ("torso", 1.0, -0.3, 0.3),
    "limbs_fat": ("armslegs", 1.0, 0.0, 1.0),
    "hips_fat": ("hip", -1.0, 0.0, 1.0),
    "weight": ("muscle", -1.0, -0.5, 1.5),
    "strength": ("strength", 1.0, 0.0, 0.5),
}


@dataclass(frozen=True)
class Avatar2020Basis:
    """The 2020 add-on's mean body and slider directions over the 13,380 body vertices.

    mean: (13380, 3) float32 in Avatar's frame (metres, Z-up).
    directions: slider name -> (13380, 3) displacement per unit of slider (sign applied).
    """

    mean: np.ndarray
    directions: dict[str, np.ndarray]

    @classmethod
    def load(cls, folder: str | os.PathLike[str]) -> Avatar2020Basis:
        """Read ``StandardModel.txt`` and ``<part>.eigenbody0.txt`` files from ``folder``."""
        folder = Path(folder)
        mean = _read_body_txt(folder / "StandardModel.txt")
        dirs = {}
        for slider, (part, sign, _, _) in AVATAR2020_SLIDERS.items():
            path = folder / f"{part}.eigenbody0.txt"
            if path.is_file():
                dirs[slider] = (sign * (_read_body_txt(path) - mean)).astype(np.float32)
        return cls(mean, dirs)

    def body(self, sliders: dict[str, float]) -> np.ndarray:
        """(13380, 3) body vertices for slider values (clamped to the add-on's ranges)."""
        out = self.mean.astype(np.float64).copy()
        for name, value in sliders.items():
            lo, hi = AVATAR2020_SLIDERS[name][2:]
            out += float(np.clip(value, lo, hi)) * self.directions[name]
        return out.astype(np.float32)


def _read_body_txt(path: Path) -> np.ndarray:
    try:
        values = np.array(path.read_text().split(), dtype=np.float64)
    except OSError as exc:
        raise FormatError(path, 0, f"cannot read: {exc.strerror}") from None
    except ValueError:
        raise FormatError(path, 0, "non-numeric value in a basis file") from None
    if values.size != 13380 * 3:
        raise FormatError(path, 0, f"expected {13380 * 3} numbers, found {values.size}")
    return to_avatar_frame(values.reshape(-1, 3)).astype(np.float32)
