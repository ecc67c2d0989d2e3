"""MakeHuman 1.1 character files (``.mhm``): read/write every statement MakeHuman writes.

Format: one ``key value...`` statement per line, ``#`` comments (MakeHuman 1.1's
``apps/human.py`` and its library plugins' save handlers). The statements:

    version v1.1.1                      name <text>            uuid <uuid>
    tags <words>                        camera <6 numbers>
    modifier <group/name> <value>       skeleton <file>.mhskel
    eyebrows|eyes|eyelashes|hair|teeth|tongue|genitals|proxy <name> <uuid>   (one each)
    clothesHideFaces True|False         clothes <name> <uuid>   (any number)
    pose <file>                         expression <file>.mhpose
    skinMaterial <file>.mhmat           material <proxy name> <uuid> <file>.mhmat
    subdivide True|False

Avatar-only parameters (``pca/*``, ``expression/*``) are written as
``avatar-param <name> <value>``, a key MakeHuman ignores. Any other statement is kept
verbatim, so a MakeHuman file survives read -> write. ``dumps`` writes the statements in
``ORDER`` (MakeHuman 1.1's: header, modifiers, skeleton, the single proxies,
clothesHideFaces, clothes, pose, expression, materials, subdivide last).
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from pathlib import Path

from avatar.errors import FormatError
from avatar.io import atomic

AVATAR_KEY = "avatar-param"
# Proxy libraries of which a character has at most one, in the order they are written.
SINGLE_PROXIES = ("eyebrows", "eyes", "hair", "eyelashes", "teeth", "tongue", "genitals", "proxy")
TEXT_KEYS = ("name", "uuid", "tags", "camera", "pose", "expression", "skinMaterial")
BOOLEAN_KEYS = ("clothesHideFaces", "subdivide")
ORDER = ("version", "name", "uuid", "tags", "camera", "modifier", AVATAR_KEY, "skeleton",
         *SINGLE_PROXIES, "clothesHideFaces", "clothes", "pose", "expression", "skinMaterial",
         "material")  # fmt: skip
RIG_OF_SKELETON = {
    "default.mhskel": "default",
    "default_no_toes.mhskel": "default_no_toes",
    "game_engine.mhskel": "game_engine",
    "game_engine_with_breast.mhskel": "game_engine_with_breast",
    "cmu_mb.mhskel": "cmu_mb",
    "mixamo.mhskel": "mixamo",
}
# MakeHuman's default eyes (the proxy every MakeHuman human wears) and their material.
DEFAULT_EYES = ("HighPolyEyes", "2c12f43b-1303-432c-b7ce-d78346baf2e6")


@dataclass(frozen=True)
class ProxyRef:
    """A proxy statement: ``<kind> <name> <uuid>`` (uuid "" when the line has none)."""

    kind: str
    name: str
    uuid: str = ""

    def line(self) -> str:
        return " ".join(x for x in (self.kind, self.name, self.uuid) if x)


@dataclass(frozen=True)
class MaterialRef:
    """``material <proxy name> <uuid> <file>``: the material a proxy wears."""

    proxy: str
    uuid: str
    file: str


@dataclass
class CharacterFile:
    """A parsed ``.mhm``. ``text`` holds name/uuid/tags/camera/pose/expression/skinMaterial;
    ``flags`` clothesHideFaces/subdivide; ``proxies`` every proxy line in file order
    (``clothes`` any number of times, the other kinds once); ``other`` unknown lines."""

    version: str = "v1.1.1"
    modifiers: dict[str, float] = field(default_factory=dict)
    avatar_params: dict[str, float] = field(default_factory=dict)
    skeleton: str | None = None
    text: dict[str, str] = field(default_factory=dict)
    flags: dict[str, bool] = field(default_factory=dict)
    proxies: list[ProxyRef] = field(default_factory=list)
    materials: list[MaterialRef] = field(default_factory=list)
    other: list[tuple[str, str]] = field(default_factory=list)  # (key, rest of line)

    @property
    def name(self) -> str:
        return self.text.get("name", "")

    @property
    def rig(self) -> str | None:
        """Avatar rig name for the ``skeleton`` line (None when absent or unknown)."""
        if not self.skeleton:
            return None
        return RIG_OF_SKELETON.get(Path(self.skeleton).name.lower())

    @property
    def clothes(self) -> list[ProxyRef]:
        return [p for p in self.proxies if p.kind == "clothes"]

    def proxy(self, kind: str) -> ProxyRef | None:
        """The (single) proxy of a kind, e.g. "hair", or None."""
        return next((p for p in self.proxies if p.kind == kind), None)


def loads(text: str, path: str | os.PathLike[str] | None = None) -> CharacterFile:
    """Parse ``.mhm`` text. Raises FormatError naming the line on malformed statements."""
    out = CharacterFile()
    for lineno, raw in enumerate(text.splitlines(), 1):
        line = raw.strip()
        if not line or line.startswith("#"):
            continue
        key, _, rest = line.partition(" ")
        rest = rest.strip()
        if key in ("modifier", AVATAR_KEY):
            name, value = _modifier(rest, path, lineno)
            (out.modifiers if key == "modifier" else out.avatar_params)[name] = value
        elif key == "version":
            out.version = rest
        elif key == "skeleton":
            out.skeleton = rest or None
        elif key in TEXT_KEYS:
            out.text[key] = rest
        elif key in BOOLEAN_KEYS:
            out.flags[key] = _boolean(key, rest, path, lineno)
        elif key == "clothes" or key in SINGLE_PROXIES:
            out.proxies.append(_proxy(key, rest, out, path, lineno))
        elif key == "material":
            words = rest.split(maxsplit=2)
            if len(words) != 3:
                raise FormatError(path, lineno, f"expected 'material <proxy> <uuid> <file>', "
                                  f"got {rest!r}")  # fmt: skip
            out.materials.append(MaterialRef(*words))
        else:
            out.other.append((key, rest))
    return out


def _modifier(rest: str, path: str | os.PathLike[str] | None, lineno: int) -> tuple[str, float]:
    parts = rest.split()
    if len(parts) != 2:
        raise FormatError(path, lineno, f"expected 'modifier <name> <value>', got {rest!r}")
    try:
        value = float(parts[1])
    except ValueError:
        raise FormatError(path, lineno, f"modifier value {parts[1]!r} is not a number") from None
    if not math.isfinite(value):
        raise FormatError(path, lineno, f"modifier value {parts[1]!r} is not finite")
    return parts[0], value


def _boolean(key: str, rest: str, path, lineno: int) -> bool:
    word = rest.lower()
    if word not in ("true", "false", "yes", "no", "1", "0"):
        raise FormatError(path, lineno, f"{key} must be True or False, got {rest!r}")
    return word in ("true", "yes", "1")


def _proxy(key: str, rest: str, out: CharacterFile, path, lineno: int) -> ProxyRef:
    words = rest.split()
    if not 1 <= len(words) <= 2:
        raise FormatError(path, lineno, f"expected '{key} <name> <uuid>', got {rest!r}")
    if key != "clothes" and out.proxy(key) is not None:
        raise FormatError(path, lineno, f"a second {key!r} line (a character has one)")
    return ProxyRef(key, words[0], words[1] if len(words) > 1 else "")


def statements(character: CharacterFile) -> list[str]:
    """The file's statements (no comments) in MakeHuman's order (``ORDER``)."""
    by_key: dict[str, list[str]] = {k: [] for k in ORDER}
    by_key["version"].append(f"version {character.version}")
    for key, value in character.text.items():
        by_key[key].append(f"{key} {value}".rstrip())
    by_key["modifier"] += [f"modifier {k} {_number(v)}" for k, v in character.modifiers.items()]
    by_key[AVATAR_KEY] += [f"{AVATAR_KEY} {k} {_number(v)}"
                           for k, v in character.avatar_params.items()]  # fmt: skip
    if character.skeleton:
        by_key["skeleton"].append(f"skeleton {character.skeleton}")
    for p in character.proxies:
        by_key[p.kind].append(p.line())
    if "clothesHideFaces" in character.flags:
        by_key["clothesHideFaces"].append(f"clothesHideFaces {character.flags['clothesHideFaces']}")
    by_key["material"] += [f"material {m.proxy} {m.uuid} {m.file}" for m in character.materials]
    lines = [line for key in ORDER for line in by_key[key]]
    lines += [f"{k} {r}".rstrip() for k, r in character.other]
    if "subdivide" in character.flags:
        lines.append(f"subdivide {character.flags['subdivide']}")
    return lines


def dumps(character: CharacterFile) -> str:
    """``.mhm`` text; values with 6 decimals as MakeHuman writes them (repr when finer)."""
    return "\n".join(["# Written by Avatar", *statements(character)]) + "\n"


def _number(v: float) -> str:
    text = f"{v:.6f}"
    return text if float(text) == v else repr(float(v))


def read(path: str | os.PathLike[str]) -> CharacterFile:
    try:
        text = Path(path).read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise FormatError(path, 0, f"cannot read character file: {exc}") from None
    return loads(text, path)


def write(path: str | os.PathLike[str], character: CharacterFile) -> None:
    """Write a ``.mhm`` file atomically."""
    atomic.write_text(path, dumps(character))
