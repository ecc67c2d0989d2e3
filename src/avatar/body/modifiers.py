"""Local modifiers: MakeHuman's named sliders over pairs of local targets.

Names are MakeHuman 1.1's ``.mhm`` modifier names (``torso/torso-scale-depth-decr|incr``,
``armslegs/l-lowerarm-scale-depth-decr|incr``, ``head/head-oval``, ``measure/...``), derived
from the asset's ``targets/target.json`` so a user's MakeHuman files load unchanged.
A bipolar modifier ranges over [-1, 1]: negative values weight the first target, positive
ones the second. A unipolar one ranges over [0, 1].
"""

from __future__ import annotations

from dataclasses import dataclass

# Folders whose modifiers MakeHuman files under another group name.
GROUP_OF_FOLDER = {"arms": "armslegs", "legs": "armslegs", "hands": "armslegs", "feet": "armslegs"}


@dataclass(frozen=True)
class Modifier:
    """One slider: ``name`` drives target ``negative`` for v < 0 and ``positive`` for v > 0."""

    name: str
    negative: str | None  # target name, e.g. "torso/torso-scale-depth-decr"
    positive: str
    group: str

    @property
    def minimum(self) -> float:
        return -1.0 if self.negative else 0.0

    @property
    def short_name(self) -> str:
        """The name without group and sides: ``torso-scale-depth``, ``l-lowerarm-scale-depth``."""
        stem = self.name.split("/", 1)[1]
        if self.negative is None:
            return stem
        return stem.split("|")[0].rsplit("-", 1)[0]


def _group(folder: str, target: str) -> str:
    if target.startswith("measure-"):
        return "measure"
    return GROUP_OF_FOLDER.get(folder, folder)


def modifiers_from_target_json(target_json: dict, target_names: list[str]) -> list[Modifier]:
    """Every local modifier described by ``target.json`` whose target files exist."""
    folder_of = {n.rsplit("/", 1)[1]: n.rsplit("/", 1)[0] for n in target_names}
    out: dict[str, Modifier] = {}
    for folder, section in target_json.items():
        for cat in section.get("categories", []):
            for neg, pos in _pairs(cat):
                if pos not in folder_of or (neg and neg not in folder_of):
                    continue
                group = _group(folder, pos)
                if neg:
                    stem, low = neg.rsplit("-", 1)
                    high = pos[len(stem) + 1 :]
                    name = f"{group}/{stem}-{low}|{high}"
                else:
                    name = f"{group}/{pos}"
                out[name] = Modifier(
                    name,
                    f"{folder_of[neg]}/{neg}" if neg else None,
                    f"{folder_of[pos]}/{pos}",
                    group,
                )
    return sorted(out.values(), key=lambda m: m.name)


def _pairs(cat: dict) -> list[tuple[str | None, str]]:
    """(negative, positive) target stems of a target.json category."""
    opp = cat.get("opposites") or {}
    pairs: list[tuple[str | None, str]] = []
    for side in ("left", "right", "unsided"):
        neg, pos = opp.get(f"negative-{side}", ""), opp.get(f"positive-{side}", "")
        if neg and pos:
            pairs.append((neg, pos))
    if pairs:
        return pairs
    targets = cat.get("targets", [])
    if len(targets) == 1:
        return [(None, targets[0])]
    # No opposites listed (eye-eyefold-concave-convex): the category name gives the order.
    parts = cat["name"].rsplit("-", 2)
    if len(parts) == 3:
        _, low, high = parts
        for prefix in sorted({t.rsplit("-", 1)[0] for t in targets}):
            if f"{prefix}-{low}" in targets and f"{prefix}-{high}" in targets:
                pairs.append((f"{prefix}-{low}", f"{prefix}-{high}"))
    return pairs
