"""Realistic bodies: sex, age, stature and build drawn from population statistics, turned
into MakeHuman macros exactly.

Statistics (rounded world averages of adult and adolescent surveys, e.g. NCD-RisC 2016 and
WHO growth references): ages uniform over 11-80 years; adult stature N(175, 7.5) cm for men
and N(162, 7) cm for women, adolescents following the mean growth curve below with 6% of
it as spread; BMI N(26, 4.5) for adults, N(20, 3) for adolescents, clipped to 16-42. The
weight macro is the BMI's percentile in its population (0.5 = the median build); muscle
N(0.5, 0.15). Stature is solved exactly: for fixed other parameters a MakeHuman body's
height is piecewise linear in the height macro (its targets blend linearly on [0, 0.5] and
[0.5, 1]), so three body evaluations invert it.
"""

from __future__ import annotations

import math

import numpy as np

from avatar.body.model import BODY_VERTICES, BodyModel
from avatar.body.shaped import rest_vertices

# mean stature (cm) by age in years: (age, women, men); adults from 18
GROWTH = ((11, 145.0, 144.0), (13, 156.0, 156.0), (15, 161.0, 170.0), (17, 162.0, 175.0),
          (18, 162.0, 175.0))  # fmt: skip
ADULT = {"f": (162.0, 7.0), "m": (175.0, 7.5)}


def age_macro(years: float) -> float:
    """MakeHuman's age macro for an age in years (1 -> 0, 11 -> 0.1875, 25 -> 0.5, 90 -> 1)."""
    if years <= 11:
        return max(0.0, (years - 1) / 10 * 0.1875)
    if years <= 25:
        return 0.1875 + (years - 11) / 14 * 0.3125
    return min(1.0, 0.5 + (years - 25) / 65 * 0.5)


def draw(rng: np.random.Generator, model: BodyModel, base: dict[str, float]) -> dict[str, float]:
    """Macros of one person: ``base`` (ethnicity, attributes) plus gender, age, muscle,
    weight and the height macro that gives the drawn stature."""
    male = bool(rng.uniform() < 0.5)
    years = float(rng.uniform(11.0, 80.0))
    mean, sd = ADULT["m" if male else "f"]
    if years < 18:
        ages = [g[0] for g in GROWTH]
        mean = float(np.interp(years, ages, [g[2 if male else 1] for g in GROWTH]))
        sd = 0.06 * mean
    stature = float(np.clip(rng.normal(mean, sd), 120.0, 210.0)) / 100.0
    bmi_mean, bmi_sd = (26.0, 4.5) if years >= 18 else (20.0, 3.0)
    bmi = float(np.clip(rng.normal(bmi_mean, bmi_sd), 16.0, 42.0))
    weight = 0.5 * (1.0 + math.erf((bmi - bmi_mean) / (bmi_sd * math.sqrt(2.0))))
    params = dict(base)
    params |= {
        "gender": float(rng.uniform(0.85, 1.0) if male else rng.uniform(0.0, 0.15)),
        "age": age_macro(years),
        "muscle": float(np.clip(rng.normal(0.5, 0.15), 0.0, 1.0)),
        "weight": float(np.clip(weight, 0.02, 0.98)),
    }  # fmt: skip
    params["height"] = height_macro(model, params, stature)
    return params


def stature_of(model: BodyModel, params: dict[str, float]) -> float:
    """Standing height (m) of a body: the top of its skin above the floor."""
    values = model.resolve(params)
    return float(rest_vertices(model, values)[:BODY_VERTICES, 2].max())


def height_macro(model: BodyModel, params: dict[str, float], stature: float) -> float:
    """The height macro (0..1) that gives ``stature`` metres with the other ``params``
    (clamped to what the model can reach)."""
    levels = (0.0, 0.5, 1.0)
    heights = [stature_of(model, params | {"height": h}) for h in levels]
    return float(np.interp(stature, heights, levels))
