"""Sample i of a dataset as plain data: a pure function of (config, seed, i).

``sample(config, i)`` draws with ``numpy.random.default_rng([seed, i])`` only, so shards are
reproducible and order-independent: sample 7 is the same whether it is rendered first, last,
alone or on another machine. ``check(config)`` resolves every name and path the config
refers to (garments, BVH files and folders, background folders) before anything renders.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

from avatar.body.model import BodyModel
from avatar.camera import CameraModel, look_at
from avatar.clothes import library
from avatar.dataset import population
from avatar.dataset.config import Config
from avatar.errors import AvatarError, FormatError

SENSOR_MM = 36.0
WALK_SECONDS = 2.0  # the built-in walk's length: one stride cycle at cadence 1
WALK_FPS = 30.0
IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".exr", ".hdr", ".tif", ".tiff")
LOOK_AT_HEIGHT = 0.9  # m: the camera aims at about hip height of an adult


@dataclass(frozen=True)
class Person:
    """One person of a sample.

    params: body parameters (Avatar names); clothes: library names, lowest layer first.
    motion: "walk", a BVH path, or a pose name ("rest", "a-pose", "t-pose");
    frame: the frame of the motion shown (0 for poses).
    position: (x, y) metres on the floor; yaw_deg: turn about Z (0 faces -Y, the camera
    at azimuth 0).
    """

    params: dict[str, float]
    rig: str
    clothes: tuple[str, ...]
    motion: str
    frame: int
    position: tuple[float, float]
    yaw_deg: float


@dataclass(frozen=True)
class Sample:
    """Everything that decides sample ``index``'s image and labels."""

    index: int
    seed: int
    people: tuple[Person, ...]
    camera: CameraModel
    light: dict
    background: dict
    samples: int
    engine: str


def sample(config: Config, index: int) -> Sample:
    """Sample ``index`` of the dataset ``config`` describes (see module docstring)."""
    rng = np.random.default_rng([config.seed, index])
    count = int(rng.integers(config.people.count[0], config.people.count[1] + 1))
    people = tuple(_person(config, rng, k, count) for k in range(count))
    return Sample(index, config.seed, people, _camera(config, rng), _light(config, rng),
                  _background(config, rng), config.render.samples,
                  config.render.engine)  # fmt: skip


def _uniform(rng: np.random.Generator, pair: tuple[float, float]) -> float:
    return float(rng.uniform(pair[0], pair[1])) if pair[1] > pair[0] else float(pair[0])


def _person(config: Config, rng: np.random.Generator, k: int, count: int) -> Person:
    bodies = config.bodies
    params = {name: _uniform(rng, pair) for name, pair in bodies.ranges.items()}
    if bodies.ethnicity == "mixed":
        mix = rng.dirichlet([0.7, 0.7, 0.7])
        params |= dict(zip(("african", "asian", "caucasian"), map(float, mix), strict=True))
    for name in ("breast", "shoulders_fat", "limbs_fat", "hips_fat", "weight", "strength",
                 "belly"):  # fmt: skip
        value = float(np.clip(rng.normal(0.0, bodies.attributes_sigma), -3.0, 3.0))
        params[f"pca/{name}"] = value if bodies.attributes_sigma > 0 else 0.0
    if bodies.mode == "population":  # sex, age, stature and build from statistics
        params = population.draw(rng, BodyModel.shared(), params)
    clothes = _outfit(config, rng)
    motion, frame = _motion(config, rng)
    x = (k - (count - 1) / 2) * config.people.spacing
    y = float(rng.uniform(-0.3, 0.3)) if count > 1 else 0.0
    yaw = float(rng.uniform(-30.0, 30.0))
    return Person(params, bodies.rig, clothes, motion, frame, (x, y), yaw)


def _pick(rng: np.random.Generator, names: tuple[str, ...]) -> str:
    return names[int(rng.integers(len(names)))] if names else ""


def _outfit(config: Config, rng: np.random.Generator) -> tuple[str, ...]:
    """One item per slot, in layer order; a dress replaces the top and the bottom (the
    rules that keep outfits plausible: no shorts over trousers, one top)."""
    c = config.clothes
    dressed = c.dresses and rng.uniform() < c.dress_probability
    # Every draw happens whatever is chosen, so one slot's list never shifts the others'.
    top, bottom, dress = _pick(rng, c.tops), _pick(rng, c.bottoms), _pick(rng, c.dresses)
    shoes, hair, hat = _pick(rng, c.shoes), _pick(rng, c.hair), _pick(rng, c.headwear)
    items = [dress] if dressed else [bottom, top]
    items += [shoes, hair, hat, *c.face]
    return tuple(dict.fromkeys(i for i in items if i))


def _motion(config: Config, rng: np.random.Generator) -> tuple[str, int]:
    m = config.motion
    use_pose = m.poses and rng.uniform() < m.pose_probability
    pose, clip = _pick(rng, m.poses), _pick(rng, m.clips)
    position = float(rng.uniform())  # where in the clip, as a fraction of its length
    if use_pose:
        return pose, 0
    if clip == "walk":
        return "walk", int(position * WALK_SECONDS * WALK_FPS)
    files = clip_files(clip)
    path = files[int(position * len(files)) % len(files)]
    frames = clip_frames(path)
    return str(path), int(rng.integers(frames))


def _camera(config: Config, rng: np.random.Generator) -> CameraModel:
    c = config.camera
    focal = _uniform(rng, c.focal_mm)
    distance = _uniform(rng, c.distance)
    elevation = math.radians(_uniform(rng, c.elevation_deg))
    azimuth = math.radians(_uniform(rng, c.azimuth_deg))
    target = np.array([0.0, 0.0, LOOK_AT_HEIGHT]) + rng.normal(0.0, c.look_at_jitter / 2, 3)
    # azimuth 0: in front of a person facing -Y, i.e. on the -Y side looking at +Y
    direction = np.array([math.sin(azimuth) * math.cos(elevation),
                          -math.cos(azimuth) * math.cos(elevation), math.sin(elevation)])
    eye = target + distance * direction
    width, height = config.render.resolution
    return CameraModel(focal, SENSOR_MM, SENSOR_MM * 2 / 3, "AUTO", 0.0, 0.0, (width, height),
                       100, (1.0, 1.0), look_at(eye, target))  # fmt: skip


def _light(config: Config, rng: np.random.Generator) -> dict:
    return {
        "kind": _pick(rng, config.lights.kinds),
        "strength": _uniform(rng, config.lights.strength),
        "elevation_deg": float(rng.uniform(25.0, 75.0)),
        "azimuth_deg": float(rng.uniform(-180.0, 180.0)),
        "warmth": float(rng.uniform(-1.0, 1.0)),
    }


def _background(config: Config, rng: np.random.Generator) -> dict:
    kind = _pick(rng, config.background.kinds)
    colour = [float(x) for x in rng.uniform(0.15, 0.75, 3)]
    out = {"kind": kind, "colour": colour, "seed": int(rng.integers(2**31))}
    if kind in ("images", "hdri"):
        files = background_files(config.background.folder)
        out["image"] = str(files[int(rng.integers(len(files)))])
    return out


@lru_cache(maxsize=64)
def clip_files(clip: str) -> tuple[Path, ...]:
    """The BVH files a ``motion.clips`` entry names: a file, or a folder's *.bvh (sorted)."""
    path = Path(clip)
    if path.is_dir():
        files = tuple(sorted(path.rglob("*.bvh")))
        if not files:
            raise AvatarError(f"motion.clips: no .bvh files in folder {clip}")
        return files
    if not path.is_file():
        raise AvatarError(f"motion.clips: no such BVH file or folder: {clip}")
    return (path,)


@lru_cache(maxsize=1024)
def clip_frames(path: Path) -> int:
    """Frame count of a BVH file, read from its MOTION header only."""
    with open(path, encoding="utf-8", errors="replace") as f:
        for lineno, line in enumerate(f, 1):
            words = line.replace(":", " ").split()
            if len(words) == 2 and words[0].lower() == "frames":
                try:
                    frames = int(words[1])
                except ValueError:
                    break
                if frames < 1:
                    raise FormatError(path, lineno, "the clip has no frames")
                return frames
    raise FormatError(path, 0, "no 'Frames:' line in the MOTION section")


@lru_cache(maxsize=16)
def background_files(folder: str) -> tuple[Path, ...]:
    root = Path(folder)
    if not folder or not root.is_dir():
        raise AvatarError(f"background.folder: no such folder: {folder!r}")
    files = tuple(sorted(p for p in root.rglob("*") if p.suffix.lower() in IMAGE_SUFFIXES))
    if not files:
        raise AvatarError(f"background.folder: no images in {folder}")
    return files


def check(config: Config) -> None:
    """Resolve every name and path the config refers to; raise one clear error before any
    rendering starts (unknown garment, missing BVH or background folder, bad pose)."""
    c = config.clothes
    for key in ("tops", "bottoms", "dresses", "shoes", "hair", "headwear", "face"):
        for name in getattr(c, key):
            if name:
                try:
                    library.find_garment(name)
                except AvatarError as exc:
                    raise AvatarError(f"{config.source}: clothes.{key}: {exc}") from None
    for clip in config.motion.clips:
        if clip != "walk":
            for path in clip_files(clip):
                clip_frames(path)
    for pose in config.motion.poses:
        if pose not in ("rest", "a-pose", "t-pose") and not Path(pose).is_file():
            raise AvatarError(f"{config.source}: motion.poses: unknown pose {pose!r} "
                              "(rest, a-pose, t-pose or a pose file)")  # fmt: skip
    if any(k in ("images", "hdri") for k in config.background.kinds):
        background_files(config.background.folder)
