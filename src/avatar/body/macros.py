"""MakeHuman 1.1 macro modifiers: slider values -> weights of the macro targets.

A macro target's file name lists the levels it belongs to, e.g.
``universal-female-young-maxmuscle-averageweight``; its weight is the product of those
levels' weights (MakeHuman 1.1 ``humanmodifier.MacroModifier``, exact, no rounding).
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

# Avatar name -> (MakeHuman .mhm modifier name, default). All range over [0, 1].
MACROS: dict[str, tuple[str, float]] = {
    "gender": ("macrodetails/Gender", 0.5),
    "age": ("macrodetails/Age", 0.5),
    "muscle": ("macrodetails-universal/Muscle", 0.5),
    "weight": ("macrodetails-universal/Weight", 0.5),
    "height": ("macrodetails-height/Height", 0.5),
    "proportions": ("macrodetails-proportions/BodyProportions", 0.5),
    "cupsize": ("breast/BreastSize", 0.5),
    "firmness": ("breast/BreastFirmness", 0.5),
    "african": ("macrodetails/African", 1 / 3),
    "asian": ("macrodetails/Asian", 1 / 3),
    "caucasian": ("macrodetails/Caucasian", 1 / 3),
}
RACES = ("african", "asian", "caucasian")
# Age in years at the slider's breakpoints (MakeHuman: 1, 11, 25, 90 years).
AGE_YEARS = ((0.0, 1.0), (0.1875, 11.0), (0.5, 25.0), (1.0, 90.0))
MACRO_FOLDERS = ("macrodetails", "macrodetails/height", "macrodetails/proportions", "breast")


def _three_levels(v: float, low: str, mid: str, high: str) -> dict[str, float]:
    lo = max(0.0, 1.0 - 2.0 * v)
    hi = max(0.0, 2.0 * v - 1.0)
    return {low: lo, mid: 1.0 - lo - hi, high: hi}


def _age_levels(age: float) -> dict[str, float]:
    if age < 0.5:
        young = max(0.0, (age - 0.1875) * 3.2)
        baby = max(0.0, 1.0 - age * 5.333)
        child = max(0.0, min(1.0, 5.333 * age) - young)
        return {"baby": baby, "child": child, "young": young, "old": 0.0}
    old = max(0.0, age * 2.0 - 1.0)
    return {"baby": 0.0, "child": 0.0, "young": 1.0 - old, "old": old}


def normalise_races(values: Mapping[str, float]) -> dict[str, float]:
    """Race values scaled to sum 1 (all equal when all are zero), as MakeHuman does."""
    r = np.array([max(0.0, float(values.get(k, 1 / 3))) for k in RACES])
    r = np.full(3, 1 / 3) if r.sum() <= 0 else r / r.sum()
    return dict(zip(RACES, r.tolist(), strict=True))


def level_weights(values: Mapping[str, float]) -> dict[str, float]:
    """Macro slider values (0..1) -> weight of every level name used in target file names."""
    v = {k: float(np.clip(values.get(k, d), 0.0, 1.0)) for k, (_, d) in MACROS.items()}
    g = v["gender"]
    levels: dict[str, float] = {"female": 1.0 - g, "male": g, "universal": 1.0}
    levels |= _age_levels(v["age"])
    levels |= _three_levels(v["muscle"], "minmuscle", "averagemuscle", "maxmuscle")
    levels |= _three_levels(v["weight"], "minweight", "averageweight", "maxweight")
    levels |= _three_levels(v["height"], "minheight", "averageheight", "maxheight")
    levels |= _three_levels(
        v["proportions"], "uncommonproportions", "regularproportions", "idealproportions"
    )
    levels |= _three_levels(v["cupsize"], "mincup", "averagecup", "maxcup")
    levels |= _three_levels(v["firmness"], "minfirmness", "averagefirmness", "maxfirmness")
    levels |= normalise_races(v)
    return levels


def is_macro_target(name: str) -> bool:
    """Whether a target name (``folder/file``) is driven by macros rather than a slider."""
    folder = name.rsplit("/", 1)[0]
    if folder == "breast":
        return "cup" in name or "firmness" in name.rsplit("/", 1)[1]
    return folder in MACRO_FOLDERS


class MacroTable:
    """Precomputed level membership of every macro target, for vectorised weighting."""

    def __init__(self, target_names: list[str]):
        self.columns = [i for i, n in enumerate(target_names) if is_macro_target(n)]
        self.components = [target_names[i].rsplit("/", 1)[1].split("-") for i in self.columns]
        names = sorted({c for comps in self.components for c in comps})
        self.level_names = names
        col = {n: k for k, n in enumerate(names)}
        # Each target's weight is a product over up to 7 levels; pad with a constant-1 level.
        width = max(len(c) for c in self.components)
        self.factor_index = np.full((len(self.columns), width), len(names), dtype=np.int64)
        for t, comps in enumerate(self.components):
            self.factor_index[t, : len(comps)] = [col[c] for c in comps]
        self.columns_arr = np.asarray(self.columns, dtype=np.int64)

    def weights(self, values: Mapping[str, float]) -> np.ndarray:
        """(M,) weight of each macro target (in ``self.columns`` order)."""
        levels = level_weights(values)
        vec = np.array([levels.get(n, 0.0) for n in self.level_names] + [1.0])
        return np.prod(vec[self.factor_index], axis=1)


def age_years(age: float) -> float:
    """MakeHuman's age slider (0..1) -> years (piecewise linear: 1, 11, 25, 90)."""
    xs, ys = zip(*AGE_YEARS, strict=True)
    return float(np.interp(age, xs, ys))


def age_slider(years: float) -> float:
    """Inverse of ``age_years``."""
    xs, ys = zip(*AGE_YEARS, strict=True)
    return float(np.interp(years, ys, xs))
