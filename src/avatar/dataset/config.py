"""The dataset config: a TOML file, validated into frozen records before anything renders.

``avatar dataset init CONFIG.toml`` writes ``EXAMPLE`` (every key, documented). Errors name the
file, the line and the key (``avatar: error: ds.toml:14: camera.distance: ...``).
"""

from __future__ import annotations

import hashlib
import os
import re
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from avatar.body.assets import RIG_NAMES
from avatar.errors import FormatError

ENGINES = ("CYCLES", "BLENDER_EEVEE", "BLENDER_WORKBENCH")
LIGHTS = ("sun", "area", "sky")
BACKGROUNDS = ("solid", "procedural", "images", "hdri")
POSES = ("rest", "a-pose", "t-pose")

EXAMPLE = """\
# Avatar dataset config (TOML). Sample i is a pure function of (seed, i): any shard, any
# order, any machine gives the same sample. Ranges are [low, high], drawn uniformly.

seed = 0
count = 100                      # samples (avatar dataset run -n overrides)

[render]
resolution = [256, 256]          # width, height in pixels
engine = "CYCLES"                # CYCLES (CPU, or a GPU when Blender reports one),
                                 # BLENDER_EEVEE, BLENDER_WORKBENCH
samples = 16                     # Cycles samples per pixel of the RGB image
recycle_every = 50               # a worker restarts its Blender after this many samples

[bodies]
mode = "uniform"                 # "uniform": macros drawn from the ranges below;
                                 # "population": sex, age 11-80, stature and BMI drawn from
                                 # adult/child statistics (see avatar.dataset.population)
gender = [0.0, 1.0]              # MakeHuman macros, 0..1 (gender 0 = female)
age = [0.1875, 1.0]              # 0.1875 = 11 years, 0.5 = 25, 1 = 90
muscle = [0.0, 1.0]
weight = [0.0, 1.0]
height = [0.0, 1.0]
proportions = [0.3, 1.0]
ethnicity = "mixed"              # "mixed" (random African/Asian/Caucasian mix) or "even"
attributes_sigma = 0.7           # the seven pca/* attributes ~ N(0, sigma), clipped to +-3
rig = "default"

[clothes]
# One item drawn from each list (an empty string wears nothing from it); a dress replaces
# the top and the bottom; names are Avatar's library (avatar clothes list).
tops = ["tshirt", "longsleeve", "tanktop", "hoodie", "jacket"]
bottoms = ["jeans", "trousers", "shorts", "leggings", "skirt"]
dress_probability = 0.15
dresses = ["dress"]
shoes = ["shoes", "shoes", "shoes", ""]
hair = ["hair-short", "hair-long", "hair-ponytail", ""]
headwear = ["", "", "", "cap"]
face = ["eyebrows", "eyelashes"]  # worn by everyone

[motion]
# "walk" (built in), or BVH files / folders of them, retargeted onto each body; one frame
# of the clip is drawn per sample. poses: static poses drawn instead, with this probability.
clips = ["walk"]
pose_probability = 0.2
poses = ["a-pose", "t-pose"]

[camera]
focal_mm = [28.0, 45.0]          # lens on a 36 mm sensor
distance = [3.5, 6.0]            # metres from the look-at point (about hip height)
elevation_deg = [-5.0, 25.0]
azimuth_deg = [-180.0, 180.0]    # 0 = in front of the person
look_at_jitter = 0.15            # metres of random offset of the look-at point

[lights]
kinds = ["sun", "area", "sky"]   # one drawn per sample
strength = [0.6, 1.6]            # relative to a studio default

[background]
kinds = ["solid", "procedural"]  # solid, procedural, images (folder), hdri (folder)
folder = ""                      # images or HDRIs for those kinds

[people]
count = [1, 1]                   # persons per image, each with its own instance id
spacing = 0.9                    # metres between persons
"""


@dataclass(frozen=True)
class Render:
    resolution: tuple[int, int] = (256, 256)
    engine: str = "CYCLES"
    samples: int = 16
    recycle_every: int = 50


@dataclass(frozen=True)
class Bodies:
    ranges: Mapping[str, tuple[float, float]] = field(default_factory=dict)
    mode: str = "uniform"
    ethnicity: str = "mixed"
    attributes_sigma: float = 0.7
    rig: str = "default"


@dataclass(frozen=True)
class Clothes:
    tops: tuple[str, ...] = ()
    bottoms: tuple[str, ...] = ()
    dress_probability: float = 0.0
    dresses: tuple[str, ...] = ()
    shoes: tuple[str, ...] = ()
    hair: tuple[str, ...] = ()
    headwear: tuple[str, ...] = ()
    face: tuple[str, ...] = ()


@dataclass(frozen=True)
class Motion:
    clips: tuple[str, ...] = ("walk",)
    pose_probability: float = 0.0
    poses: tuple[str, ...] = ()


@dataclass(frozen=True)
class Camera:
    focal_mm: tuple[float, float] = (35.0, 50.0)
    distance: tuple[float, float] = (3.0, 4.0)
    elevation_deg: tuple[float, float] = (0.0, 15.0)
    azimuth_deg: tuple[float, float] = (-180.0, 180.0)
    look_at_jitter: float = 0.1


@dataclass(frozen=True)
class Lights:
    kinds: tuple[str, ...] = ("sun",)
    strength: tuple[float, float] = (1.0, 1.0)


@dataclass(frozen=True)
class Background:
    kinds: tuple[str, ...] = ("solid",)
    folder: str = ""


@dataclass(frozen=True)
class People:
    count: tuple[int, int] = (1, 1)
    spacing: float = 0.9


@dataclass(frozen=True)
class Config:
    """A validated dataset config; ``digest`` identifies it in provenance records."""

    seed: int
    count: int
    render: Render
    bodies: Bodies
    clothes: Clothes
    motion: Motion
    camera: Camera
    lights: Lights
    background: Background
    people: People
    digest: str
    source: str = ""  # the config file, for messages


_DEFAULTS: dict[str, Any] = tomllib.loads(EXAMPLE)
_DEFAULTS["bodies"] = {**_DEFAULTS["bodies"], "cupsize": [0.0, 1.0], "firmness": [0.0, 1.0]}

MACRO_KEYS = ("gender", "age", "muscle", "weight", "height", "proportions", "cupsize",
              "firmness")  # fmt: skip


def load(path: str | os.PathLike[str], **overrides: Any) -> Config:
    """Read and validate a config file; ``overrides`` (``seed``, ``count``, ``resolution``,
    ``samples``, ``engine``) replace its values, as the CLI's flags do."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise FormatError(path, 0, f"cannot read the config: {exc.strerror or exc}") from None
    return loads(text, str(path), **overrides)


def loads(text: str, source: str = "<config>", **overrides: Any) -> Config:
    """Validate config ``text`` (see ``load``)."""
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        line = int(getattr(exc, "lineno", 0) or _line_of_message(str(exc)))
        raise FormatError(source, line, f"invalid TOML: {exc}") from None
    v = _Validator(text, source, data)
    for name, table in data.items():  # unknown keys are errors before defaults fill in
        if isinstance(table, dict) and name in _DEFAULTS:
            v.only_keys(name, set(table), set(_DEFAULTS[name]))
    # Every key missing from the file takes EXAMPLE's value (varied bodies, outfits, ...).
    data = {**_DEFAULTS, **{k: ({**_DEFAULTS[k], **t} if isinstance(t, dict) and
                                isinstance(_DEFAULTS.get(k), dict) else t)
                            for k, t in data.items()}}  # fmt: skip
    v.data = data
    render = v.section("render", {"resolution", "engine", "samples", "recycle_every"})
    bodies = v.section("bodies", {*MACRO_KEYS, "mode", "ethnicity", "attributes_sigma", "rig"})
    clothes = v.section("clothes", {"tops", "bottoms", "dress_probability", "dresses", "shoes",
                                    "hair", "headwear", "face"})  # fmt: skip
    motion = v.section("motion", {"clips", "pose_probability", "poses"})
    camera = v.section("camera", {"focal_mm", "distance", "elevation_deg", "azimuth_deg",
                                  "look_at_jitter"})  # fmt: skip
    lights = v.section("lights", {"kinds", "strength"})
    background = v.section("background", {"kinds", "folder"})
    people = v.section("people", {"count", "spacing"})
    v.only_keys("", set(data), {"seed", "count", "render", "bodies", "clothes", "motion",
                                "camera", "lights", "background", "people"})  # fmt: skip
    resolution = overrides.get("resolution") or v.size("render.resolution", render)
    config = Config(
        seed=int(_given(overrides, "seed", v.integer("seed", data, 0, 0, 2**63 - 1))),
        count=int(_given(overrides, "count", v.integer("count", data, 100, 1, 10**9))),
        render=Render(
            resolution=(int(resolution[0]), int(resolution[1])),
            engine=_given(overrides, "engine", v.choice("render.engine", render, "CYCLES",
                                                        ENGINES)),  # fmt: skip
            samples=int(_given(overrides, "samples", v.integer("render.samples", render, 16,
                                                               1, 4096))),  # fmt: skip
            recycle_every=v.integer("render.recycle_every", render, 50, 1, 100000),
        ),
        bodies=Bodies(
            ranges={k: v.pair(f"bodies.{k}", bodies, None, float, 0.0, 1.0)
                    for k in MACRO_KEYS if k in bodies},  # fmt: skip
            mode=v.choice("bodies.mode", bodies, "uniform", ("uniform", "population")),
            ethnicity=v.choice("bodies.ethnicity", bodies, "mixed", ("mixed", "even")),
            attributes_sigma=v.number("bodies.attributes_sigma", bodies, 0.7, 0.0, 3.0),
            rig=v.choice("bodies.rig", bodies, "default", RIG_NAMES),
        ),
        clothes=Clothes(
            **{k: v.names(f"clothes.{k}", clothes) for k in
               ("tops", "bottoms", "dresses", "shoes", "hair", "headwear", "face")},
            dress_probability=v.number("clothes.dress_probability", clothes, 0.0, 0.0, 1.0),
        ),  # fmt: skip
        motion=Motion(
            clips=v.names("motion.clips", motion, ("walk",)) or ("walk",),
            pose_probability=v.number("motion.pose_probability", motion, 0.0, 0.0, 1.0),
            poses=v.names("motion.poses", motion),
        ),
        camera=Camera(
            focal_mm=v.pair("camera.focal_mm", camera, (35.0, 50.0), float, 5.0, 500.0),
            distance=v.pair("camera.distance", camera, (3.0, 4.0), float, 0.3, 100.0),
            elevation_deg=v.pair("camera.elevation_deg", camera, (0.0, 15.0), float, -89.0,
                                 89.0),  # fmt: skip
            azimuth_deg=v.pair("camera.azimuth_deg", camera, (-180.0, 180.0), float, -360.0,
                               360.0),  # fmt: skip
            look_at_jitter=v.number("camera.look_at_jitter", camera, 0.1, 0.0, 5.0),
        ),
        lights=Lights(
            kinds=v.choices("lights.kinds", lights, ("sun",), LIGHTS),
            strength=v.pair("lights.strength", lights, (1.0, 1.0), float, 0.0, 100.0),
        ),
        background=Background(
            kinds=v.choices("background.kinds", background, ("solid",), BACKGROUNDS),
            folder=str(background.get("folder", "")),
        ),
        people=People(
            count=v.pair("people.count", people, (1, 1), int, 1, 16),
            spacing=v.number("people.spacing", people, 0.9, 0.2, 10.0),
        ),
        digest=_digest(text, overrides),
        source=source,
    )
    return config


def avatar_version() -> str:
    """The installed Avatar's version (provenance records)."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("avatar")
    except PackageNotFoundError:  # a source checkout on sys.path
        return "0+unknown"


def _digest(text: str, overrides: Mapping[str, Any]) -> str:
    """The config's identity: its text and the flags that override it (a resumed run must
    be the same dataset)."""
    given = sorted((k, repr(v)) for k, v in overrides.items() if v is not None)
    return hashlib.sha256((text + repr(given)).encode("utf-8")).hexdigest()[:16]


def _given(overrides: Mapping[str, Any], key: str, default: Any) -> Any:
    value = overrides.get(key)
    return default if value is None else value


def _line_of_message(message: str) -> int:
    m = re.search(r"line (\d+)", message)
    return int(m.group(1)) if m else 0


class _Validator:
    """Typed reads of config values; errors name the file, the key's line and the key."""

    def __init__(self, text: str, source: str, data: Mapping[str, Any]):
        self.lines, self.source, self.data = text.splitlines(), source, data

    def fail(self, key: str, message: str) -> FormatError:
        return FormatError(self.source, self.line_of(key), f"{key}: {message}")

    def line_of(self, key: str) -> int:
        """1-based line where ``key`` is written: ``section.name`` inside its table, a
        top-level name before any table, or a table's header; 0 when not found."""
        section, _, name = key.rpartition(".")
        current = ""
        for i, line in enumerate(self.lines, 1):
            s = line.strip()
            header = re.match(r"^\[([^\]]+)\]", s)
            if header:
                current = header.group(1).strip()
                if not section and current == name:
                    return i
            elif current == section and re.match(rf"^{re.escape(name)}\s*=", s):
                return i
        return 0

    def section(self, name: str, allowed: set[str]) -> dict[str, Any]:
        value = self.data.get(name, {})
        if not isinstance(value, dict):
            raise self.fail(name, "must be a table ([" + name + "])")
        self.only_keys(name, set(value), allowed)
        return value

    def only_keys(self, section: str, keys: set[str], allowed: set[str]) -> None:
        import difflib

        for key in sorted(keys - allowed):
            close = difflib.get_close_matches(key, sorted(allowed), n=3)
            hint = f"; did you mean {', '.join(close)}?" if close else ""
            full = f"{section}.{key}" if section else key
            raise self.fail(full, f"unknown key{hint}")

    def number(self, key: str, table: Mapping[str, Any], default: float, lo: float,
               hi: float) -> float:  # fmt: skip
        value = table.get(key.rpartition(".")[2], default)
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise self.fail(key, f"must be a number, got {value!r}")
        if not lo <= value <= hi:
            raise self.fail(key, f"must be within [{lo:g}, {hi:g}], got {value:g}")
        return float(value)

    def integer(self, key: str, table: Mapping[str, Any], default: int, lo: int,
                hi: int) -> int:  # fmt: skip
        value = table.get(key.rpartition(".")[2], default)
        if isinstance(value, bool) or not isinstance(value, int):
            raise self.fail(key, f"must be a whole number, got {value!r}")
        if not lo <= value <= hi:
            raise self.fail(key, f"must be within [{lo}, {hi}], got {value}")
        return int(value)

    def pair(self, key: str, table: Mapping[str, Any], default: Any, kind: type, lo: float,
             hi: float) -> Any:  # fmt: skip
        value = table.get(key.rpartition(".")[2], default)
        ok = isinstance(value, list | tuple) and len(value) == 2 and all(
            isinstance(x, int | float) and not isinstance(x, bool) for x in value)
        if not ok or (kind is int and not all(float(x).is_integer() for x in value)):
            raise self.fail(key, f"must be [low, high] ({kind.__name__}s), got {value!r}")
        low, high = kind(value[0]), kind(value[1])
        if not (lo <= low <= high <= hi):
            raise self.fail(key, f"must satisfy {lo:g} <= low <= high <= {hi:g}, got {value!r}")
        return (low, high)

    def size(self, key: str, table: Mapping[str, Any]) -> tuple[int, int]:
        value = table.get(key.rpartition(".")[2], [256, 256])
        ok = isinstance(value, list) and len(value) == 2 and all(
            isinstance(x, int) and not isinstance(x, bool) and 16 <= x <= 8192 for x in value)
        if not ok:
            raise self.fail(key, f"must be [width, height], 16..8192 pixels, got {value!r}")
        return int(value[0]), int(value[1])

    def choice(self, key: str, table: Mapping[str, Any], default: str, allowed) -> str:
        value = table.get(key.rpartition(".")[2], default)
        if value not in allowed:
            raise self.fail(key, f"must be one of {', '.join(allowed)}, got {value!r}")
        return str(value)

    def choices(self, key: str, table: Mapping[str, Any], default: tuple[str, ...],
                allowed) -> tuple[str, ...]:  # fmt: skip
        values = self.names(key, table, default)
        for value in values:
            if value not in allowed:
                raise self.fail(key, f"{value!r} is not one of {', '.join(allowed)}")
        if not values:
            raise self.fail(key, "must list at least one")
        return values

    def names(self, key: str, table: Mapping[str, Any],
              default: tuple[str, ...] = ()) -> tuple[str, ...]:  # fmt: skip
        value = table.get(key.rpartition(".")[2], list(default))
        if not isinstance(value, list) or not all(isinstance(x, str) for x in value):
            raise self.fail(key, f"must be a list of strings, got {value!r}")
        return tuple(value)
