"""Bone correspondence: skeleton bone names -> canonical human bones.

Canonical bones (``hips``, ``spine``, ``chest``, ``neck``, ``head``, ``clavicle.L``,
``upperarm.L``, ``forearm.L``, ``hand.L``, ``thigh.L``, ``shin.L``, ``foot.L``, ``toe.L``,
fingers ``thumb1.L`` .. ``pinky3.L``, and the ``.R`` twins) name a bone by its anatomical
job: its head sits at the joint and it turns the segment up to ``NEXT[bone]``.

Conventions are JSON files (``avatar/data/bonemaps/*.json``: ``{"name", "description",
"bones": {canonical: [candidate names, first present wins]}}``); a user file of the same
shape can be passed anywhere a convention name is accepted. Names match case-insensitively
after dropping any ``prefix:`` (``mixamorig:Hips``, ``mixamorig1:Hips``).

When names match no convention well (any body bone missing), the roles are inferred from
the hierarchy and geometry (``avatar.rig.topology``): fully when names found under half
of the body bones, otherwise only the missing ones; ``BoneMap.inferred`` says which.
"""

from __future__ import annotations

import functools
import json
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from types import MappingProxyType

import numpy as np

from avatar.errors import FormatError, ParameterError, unknown_name
from avatar.rig import topology
from avatar.rig.skeleton import Skeleton

_TRUNK = {"hips": "spine", "spine": "chest", "chest": "neck", "neck": "head", "head": None}
_LIMBS = {"clavicle": "upperarm", "upperarm": "forearm", "forearm": "hand", "hand": "middle1",
          "thigh": "shin", "shin": "foot", "foot": "toe", "toe": None}  # fmt: skip
_FINGERS = ("thumb", "index", "middle", "ring", "pinky")


def _canonical() -> dict[str, str | None]:
    out: dict[str, str | None] = dict(_TRUNK)
    for side in ("L", "R"):
        for bone, nxt in _LIMBS.items():
            out[f"{bone}.{side}"] = f"{nxt}.{side}" if nxt else None
        for f in _FINGERS:
            for i in (1, 2, 3):
                out[f"{f}{i}.{side}"] = f"{f}{i + 1}.{side}" if i < 3 else None
    return out


NEXT: dict[str, str | None] = _canonical()
"""canonical bone -> the canonical bone at the far end of its segment (None: its tail)."""

CORE = tuple(b for b in NEXT if not b.startswith(_FINGERS))
"""The 21 body bones every humanoid convention has; fingers are optional."""

# Trunk chains whose in-between bones share the bend (spines and necks of any length).
CHAINS = (("spine", "chest"), ("neck", "head"))


def normalise(name: str) -> str:
    """Match key of a bone name: no ``prefix:`` or ``Armature|``, lower case."""
    return name.rsplit(":", 1)[-1].rsplit("|", 1)[-1].strip().lower()


@dataclass(frozen=True)
class BoneMap:
    """Which bone of one skeleton plays each canonical role.

    convention: the convention's name (or the user file's path).
    bones: canonical name -> bone index in the skeleton.
    missing: canonical body bones (``CORE``) the skeleton lacks under this convention.
    inferred: canonical bones found from the hierarchy and geometry, not by name.
    """

    convention: str
    bones: dict[str, int]
    missing: tuple[str, ...]
    inferred: tuple[str, ...] = ()

    def name_of(self, skeleton: Skeleton, canonical: str) -> str:
        return skeleton.names[self.bones[canonical]]


def conventions() -> dict[str, dict[str, list[str]]]:
    """All shipped conventions: name -> {canonical: candidate names} (a fresh copy)."""
    return {name: {k: list(v) for k, v in table.items()} for name, table in _shipped().items()}


@functools.cache
def _shipped() -> Mapping[str, Mapping[str, tuple[str, ...]]]:
    """The shipped convention files, read and checked once per process (``detect`` runs
    per clip and per body; reading the eight files cost ~2.5 ms a call). Read-only."""
    folder = resources.files("avatar") / "data" / "bonemaps"
    out = {}
    for entry in sorted(folder.iterdir(), key=lambda e: e.name):
        if entry.name.endswith(".json"):
            data = _parse(entry.read_text(encoding="utf-8"), entry.name)
            bones = {k: tuple(v) for k, v in data["bones"].items()}
            out[data["name"]] = MappingProxyType(bones)
    return MappingProxyType(out)


def _parse(text: str, path: str) -> dict:
    """A convention file's JSON, checked: unknown canonical names are errors, not typos."""
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise FormatError(path, exc.lineno, exc.msg) from None
    bones = data.get("bones") if isinstance(data, dict) else None
    if not isinstance(bones, dict):
        raise FormatError(path, 0, 'a bone map needs {"bones": {canonical: [names]}}')
    for key, names in bones.items():
        if key not in NEXT:
            raise FormatError(path, 0, str(unknown_name("canonical bone", key, NEXT)))
        if isinstance(names, str):
            bones[key] = [names]
        elif not (isinstance(names, list) and all(isinstance(n, str) for n in names)):
            raise FormatError(path, 0, f"{key}: expected a name or a list of names")
    data.setdefault("name", Path(path).stem)
    return data


def _checked(table: dict) -> dict[str, list[str]]:
    """A {canonical: names} table checked as a file's would be (ParameterError if not)."""
    try:
        return _parse(json.dumps({"name": "custom", "bones": table}), "bone map")["bones"]
    except FormatError as exc:
        raise ParameterError(str(exc)) from None


def load(path: str | os.PathLike[str]) -> dict[str, list[str]]:
    """A user's bone map file -> {canonical: candidate names}."""
    return _parse(Path(path).read_text(encoding="utf-8"), str(path))["bones"]


def apply(skeleton: Skeleton, table: Mapping[str, Sequence[str]], name: str = "custom") -> BoneMap:
    """Resolve a {canonical: candidates} table against a skeleton's bone names."""
    return _resolve(_name_index(skeleton), table, name)


def _name_index(skeleton: Skeleton) -> dict[str, int]:
    """Normalised bone name -> first bone index with it."""
    index: dict[str, int] = {}
    for j, n in enumerate(skeleton.names):
        index.setdefault(normalise(n), j)
    return index


def _resolve(index: dict[str, int], table: Mapping[str, Sequence[str]], name: str) -> BoneMap:
    bones: dict[str, int] = {}
    for canonical, candidates in table.items():
        for cand in candidates:
            found = index.get(normalise(cand))
            if found is not None:
                bones[canonical] = found
                break
    missing = tuple(b for b in CORE if b not in bones)
    return BoneMap(name, bones, missing)


Convention = str | os.PathLike[str] | Mapping[str, Sequence[str]]
"""A convention name, a bone map file, "topology", "auto", or a {canonical: names} table."""


def detect(
    skeleton: Skeleton,
    convention: Convention = "auto",
    heads: np.ndarray | None = None,
) -> BoneMap:
    """The bone map of a skeleton: by convention name, user file, table, "topology" or "auto".

    "auto" scores every shipped convention by the body bones it finds and keeps the best;
    when that lacks body bones, the hierarchy and geometry fill them in (see
    ``topology.infer``; ``heads`` (T, J, 3), e.g. a clip's posed heads, help when the rest
    pose is not upright). Raises ParameterError for an unknown convention name or a
    skeleton without recognisable hips.
    """
    known = _shipped()
    if isinstance(convention, Mapping):  # a table, e.g. a mapping edited in the extension
        return apply(skeleton, _checked(dict(convention)), "custom")
    if convention == "topology":
        return _by_topology(skeleton, heads)
    if convention != "auto":
        key = str(convention)
        if key in known:
            return apply(skeleton, known[key], key)
        if Path(key).suffix == ".json" or os.sep in key:
            return apply(skeleton, load(key), key)
        raise unknown_name("bone map convention", key, [*known, "topology"])
    index = _name_index(skeleton)
    maps = [_resolve(index, table, name) for name, table in known.items()]
    best = max(maps, key=lambda m: (len(CORE) - len(m.missing), len(m.bones)))
    if best.missing:
        best = _fill(best, skeleton, heads)
    if "hips" not in best.bones:
        raise ParameterError(
            f"cannot find the hips of this skeleton (best convention {best.convention!r} "
            f"lacks {', '.join(best.missing)}); pass a bone map file"
        )
    return best


def _by_topology(skeleton: Skeleton, heads: np.ndarray | None) -> BoneMap:
    bones = topology.infer(skeleton, heads)
    return BoneMap("topology", bones, tuple(b for b in CORE if b not in bones), tuple(bones))


def _fill(named: BoneMap, skeleton: Skeleton, heads: np.ndarray | None) -> BoneMap:
    """Names found under half the body bones: trust the topology for all; otherwise add
    what topology finds for the missing roles on bones no name claimed."""
    inferred = _by_topology(skeleton, heads)
    if len(CORE) - len(named.missing) < len(CORE) / 2:
        return inferred if len(inferred.bones) >= len(named.bones) else named
    used = set(named.bones.values())
    extra = {r: j for r, j in inferred.bones.items() if r not in named.bones and j not in used}
    if not extra:
        return named
    bones = {**named.bones, **extra}
    missing = tuple(b for b in CORE if b not in bones)
    return BoneMap(f"{named.convention}+topology", bones, missing, tuple(extra))
