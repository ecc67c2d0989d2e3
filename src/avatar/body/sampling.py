"""Random bodies: parameter sets drawn from a seed, plausible or anywhere in range.

    params = random_params(model, seed=7)                  # a plausible adult or child
    params = random_params(model, seed=7, realistic=False)  # every slider uniform in range

Randomness is explicit (``numpy.random.default_rng(seed)``): one seed, one body.
"""

from __future__ import annotations

import numpy as np

from avatar.body import macros

# Plausible bodies: macros around the default with these standard deviations (clipped to
# 0..1), ages skewed to adults, races a Dirichlet mix, attributes mild.
REALISTIC_SPREAD = {"muscle": 0.15, "weight": 0.17, "height": 0.17, "proportions": 0.15,
                    "cupsize": 0.18, "firmness": 0.18}  # fmt: skip
ATTRIBUTE_SPREAD = 0.6  # standard deviations of the semantic attributes (themselves in sd)
LOCAL_SPREAD = 0.12  # of each local modifier, realistic mode only touches proportions


def random_params(model, seed: int = 0, realistic: bool = True) -> dict[str, float]:
    """A random body's parameters (canonical names) for ``model`` (a ``BodyModel``).

    realistic: macros near typical values (gender 0 or 1 leaning, ages mostly adult,
        weight and muscle within a couple of standard deviations), races a random mix, the
        seven attributes mild; no local modifiers. False: every macro, attribute and local
        modifier uniform over its whole range (for stress tests and datasets of extremes).
    """
    rng = np.random.default_rng(seed)
    params = model.parameters
    if not realistic:
        out = {}
        for name, p in params.items():
            if p.kind in ("macro", "attribute", "modifier"):
                out[name] = float(rng.uniform(p.minimum, p.maximum))
        return _normalised_races(out)
    out = {"gender": float(np.clip(rng.beta(0.6, 0.6), 0, 1)),
           "age": float(np.clip(rng.choice([rng.uniform(0.1875, 0.5), rng.uniform(0.5, 0.9),
                                            rng.uniform(0.05, 0.1875)], p=[0.55, 0.35, 0.1]),
                                0, 1))}  # fmt: skip
    for name, spread in REALISTIC_SPREAD.items():
        out[name] = float(np.clip(rng.normal(0.5, spread), 0.0, 1.0))
    mix = rng.dirichlet(np.full(len(macros.RACES), 0.7))
    out.update({race: float(v) for race, v in zip(macros.RACES, mix, strict=True)})
    for name, p in params.items():
        if p.kind == "attribute":
            out[name] = float(np.clip(rng.normal(0.0, ATTRIBUTE_SPREAD), p.minimum, p.maximum))
    return out


def _normalised_races(values: dict[str, float]) -> dict[str, float]:
    total = sum(values.get(r, 0.0) for r in macros.RACES)
    if total > 0:
        for r in macros.RACES:
            values[r] = values.get(r, 0.0) / total
    return values
