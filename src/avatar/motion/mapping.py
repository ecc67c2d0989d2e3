"""The bone mapping of one clip onto one rig, as an animator sees and edits it.

    found = mapping.rows(clip_skeleton, clip, human.skeleton)        # auto, as retarget does
    found = mapping.rows(clip_skeleton, clip, human.skeleton, table)  # a user's mapping
    table = mapping.table_of([(r.source, r.role) for r in found])    # back to a bone map
    mapping.save("my_rig.json", table)                                # bonemap's file format

A row per source (clip) bone: the Avatar bone it drives and why (``how``): "role" when both
play the same canonical role (``avatar.motion.bonemap``: the roles a retarget aims
segments by), "name" when the bones have the same name (``retarget(match_names=True)``),
"" when the source bone drives nothing. Editing a row means giving its source bone the
role of another Avatar bone (``roles_of`` lists them), or none.

A user's mapping is saved in bonemap's own file format (``{"name", "description",
"bones": {canonical: [source bone names]}}``), so the same file works as
``retarget(source_map=path)``, ``avatar retarget --source-map`` and in the extension.
"""

from __future__ import annotations

import json
import os
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from avatar.errors import FormatError, ParameterError, unknown_name
from avatar.io import atomic
from avatar.motion import bonemap
from avatar.motion.pairs import make_pairs
from avatar.rig.kinematics import world_pose
from avatar.rig.skeleton import Animation, Skeleton

_SAMPLES = 32  # clip frames used to infer roles by topology (as the retargeter's heads)


@dataclass(frozen=True)
class Row:
    """One source bone: the Avatar bone it drives ("" none), its role, and how it pairs."""

    source: str
    target: str
    role: str  # canonical role ("" when it has none)
    how: str  # "role", "name" or ""


def rows(
    source: Skeleton,
    clip: Animation | None,
    target: Skeleton,
    table: Mapping[str, Sequence[str]] | None = None,
    match_names: bool = True,
) -> list[Row]:
    """The mapping a retarget of ``clip`` onto ``target`` uses, one row per source bone in
    the clip's order.

    table: {canonical: [source names]} (a user's mapping), or None for the automatic one
        (shipped conventions, then topology; ``clip`` (T, J) helps when its rest pose is
        not upright, as in ``retarget``).
    match_names: also pair same-named bones, as ``retarget(match_names=...)``.
    Raises ParameterError for a table with unknown roles or a skeleton without hips.
    """
    heads = None
    if clip is not None and clip.frames:
        pick = np.unique(np.linspace(0, clip.frames - 1, min(clip.frames, _SAMPLES)).astype(int))
        heads = world_pose(source, clip.rotations[pick], clip.translations[pick])[1]
    smap = bonemap.detect(source, dict(table) if table is not None else "auto", heads)
    tmap = bonemap.detect(target)
    by_source = {p.source: p for p in make_pairs(source, smap, target, tmap, match_names)}
    out = []
    for j, name in enumerate(source.names):
        p = by_source.get(j)
        if p is None:
            out.append(Row(name, "", "", ""))
        elif p.role.startswith("="):
            out.append(Row(name, target.names[p.target], "", "name"))
        else:
            out.append(Row(name, target.names[p.target], p.role, "role"))
    return out


def roles_of(target: Skeleton) -> dict[str, str]:
    """Avatar bone name -> the canonical role it plays, for every bone that has one (the
    bones a source bone can be mapped onto), in the rig's bone order."""
    tmap = bonemap.detect(target)
    role = {j: r for r, j in tmap.bones.items()}
    return {target.names[j]: role[j] for j in sorted(role)}


def table_of(assigned: Iterable[tuple[str, str]]) -> dict[str, list[str]]:
    """{canonical: [source name]} from (source bone, role) pairs ("" roles skipped).

    Raises ParameterError for an unknown role or one given to two source bones."""
    table: dict[str, list[str]] = {}
    for source, role in assigned:
        if not role:
            continue
        if role not in bonemap.NEXT:
            raise unknown_name("canonical bone", role, bonemap.NEXT)
        if role in table:
            raise ParameterError(f"{role} is mapped twice ({table[role][0]} and {source})")
        table[role] = [source]
    return table


def save(
    path: str | os.PathLike[str],
    table: Mapping[str, Sequence[str]],
    name: str | None = None,
    description: str = "",
) -> Path:
    """Write a {canonical: [source names]} table as a bone map file (atomically).

    The file is bonemap's format, canonical roles in ``bonemap.NEXT``'s order; returns its
    Path. Raises ParameterError for an unknown role (nothing written)."""
    path = Path(path)
    unknown = [r for r in table if r not in bonemap.NEXT]
    if unknown:
        raise unknown_name("canonical bone", unknown[0], bonemap.NEXT)
    bones = {r: list(table[r]) for r in bonemap.NEXT if r in table}
    data = {"name": name or path.stem, "description": description, "bones": bones}
    atomic.write_text(path, json.dumps(data, indent=1) + "\n")
    return path


def load(path: str | os.PathLike[str]) -> dict[str, list[str]]:
    """A bone map file -> {canonical: [source names]}.

    Raises ParameterError for a missing file, FormatError for one that is not a bone map."""
    path = Path(path)
    if not path.is_file():
        raise ParameterError(f"{path}: no such bone map file")
    try:
        return bonemap.load(path)
    except UnicodeDecodeError:
        raise FormatError(str(path), 0, "not a text (JSON) bone map") from None
